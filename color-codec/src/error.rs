//! Errors returned by the validating constructors of this crate.

use core::fmt;

/// Why a constructor of this crate rejected its parameters. Each variant carries the value that
/// was rejected.
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub enum CodecError {
    /// The log codec's range parameter β is NaN or outside
    /// [[`LogCodec::BETA_MIN`](crate::LogCodec::BETA_MIN), [`LogCodec::BETA_MAX`](crate::LogCodec::BETA_MAX)] = [0.14, 80].
    BetaOutOfRange {
        /// The β given.
        beta: f32,
    },
    /// The log codec's scale parameter γ is NaN, infinite, or not positive.
    GammaNotPositive {
        /// The γ given.
        gamma: f32,
    },
    /// The log codec's γ is below [`LogCodec::gamma_min`](crate::LogCodec::gamma_min)`(β)`, so
    /// the largest encodable value (e^β − 1)/γ (or 1/γ) would overflow f32.
    MaxValueOverflows {
        /// The γ given.
        gamma: f32,
        /// The smallest γ accepted for the β given, `LogCodec::gamma_min(β)`.
        minimum: f32,
    },
    /// A value field is narrower than 1 bit or wider than [`MAX_FIELD_BITS`](crate::MAX_FIELD_BITS)
    /// (a flag field: wider than `MAX_FIELD_BITS`).
    FieldWidthOutOfRange {
        /// The width given, in bits.
        bits: u32,
    },
    /// The count field is narrower than 1 bit or wider than [`MAX_FIELD_BITS`](crate::MAX_FIELD_BITS).
    CountWidthOutOfRange {
        /// The width given, in bits.
        bits: u32,
    },
    /// The field widths of a packed layout do not add up to 32 bits.
    WidthsDoNotSumTo32 {
        /// The sum of the widths given.
        sum: u32,
    },
    /// The moving average's N_max is zero.
    MaxCountZero,
}

impl fmt::Display for CodecError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            CodecError::BetaOutOfRange { beta } => {
                write!(f, "log codec beta = {beta} is not in [0.14, 80]")
            }
            CodecError::GammaNotPositive { gamma } => {
                write!(
                    f,
                    "log codec gamma = {gamma} is not a positive finite number"
                )
            }
            CodecError::MaxValueOverflows { gamma, minimum } => write!(
                f,
                "log codec gamma = {gamma} is below {minimum}, the smallest for its beta: \
                 (e^beta - 1)/gamma would overflow f32"
            ),
            CodecError::FieldWidthOutOfRange { bits } => {
                write!(f, "value field width {bits} is not in 1..=16 bits")
            }
            CodecError::CountWidthOutOfRange { bits } => {
                write!(f, "count field width {bits} is not in 1..=16 bits")
            }
            CodecError::WidthsDoNotSumTo32 { sum } => {
                write!(f, "field widths sum to {sum} bits, not 32")
            }
            CodecError::MaxCountZero => f.write_str("moving average maximum count is zero"),
        }
    }
}

impl core::error::Error for CodecError {}
