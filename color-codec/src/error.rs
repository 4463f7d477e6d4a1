//! Errors returned by the validating constructors of this crate.

use core::fmt;

/// Why a constructor of this crate rejected its parameters.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum CodecError {
    /// The log codec's range parameter β is NaN or outside
    /// [[`LogCodec::BETA_MIN`](crate::LogCodec::BETA_MIN), [`LogCodec::BETA_MAX`](crate::LogCodec::BETA_MAX)] = [0.14, 80].
    BetaOutOfRange,
    /// The log codec's scale parameter γ is NaN, infinite, or not positive.
    GammaNotPositive,
    /// The log codec's γ is below [`LogCodec::gamma_min`](crate::LogCodec::gamma_min)`(β)`, so
    /// the largest encodable value (e^β − 1)/γ (or 1/γ) would overflow f32.
    MaxValueOverflows,
    /// A value field is narrower than 1 bit or wider than [`MAX_FIELD_BITS`](crate::MAX_FIELD_BITS).
    FieldWidthOutOfRange,
    /// The count field is narrower than 1 bit or wider than [`MAX_FIELD_BITS`](crate::MAX_FIELD_BITS).
    CountWidthOutOfRange,
    /// The field widths of a packed layout do not add up to 32 bits.
    WidthsDoNotSumTo32,
    /// The moving average's N_max is zero.
    MaxCountZero,
}

impl fmt::Display for CodecError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            CodecError::BetaOutOfRange => "log codec beta is not in [0.14, 80]",
            CodecError::GammaNotPositive => "log codec gamma is not a positive finite number",
            CodecError::MaxValueOverflows => {
                "log codec gamma is too small for beta: (e^beta - 1)/gamma overflows f32"
            }
            CodecError::FieldWidthOutOfRange => "value field width is not in 1..=16 bits",
            CodecError::CountWidthOutOfRange => "count field width is not in 1..=16 bits",
            CodecError::WidthsDoNotSumTo32 => "field widths do not sum to 32 bits",
            CodecError::MaxCountZero => "moving average maximum count is zero",
        })
    }
}

impl core::error::Error for CodecError {}
