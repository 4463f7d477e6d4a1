//! Errors returned by the validating constructors of this crate.

use core::fmt;

use mcg_markov_guide::WalkError;

/// Why a constructor of this crate rejected its parameters.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum ProbeError {
    /// The grid origin has a NaN or infinite component.
    OriginNotFinite,
    /// A probe spacing component is NaN, infinite, or not positive.
    SpacingNotPositive,
    /// A probe count along an axis is zero, or the total probe count overflows `u32`.
    CountsOutOfRange,
    /// A heuristic parameter (camera threshold k, voxel diagonal s, radiance range β,
    /// lighting weight μ) is NaN, infinite or out of its range.
    HeuristicParameterOutOfRange,
    /// A guiding-function parameter (α, exponent cap) is NaN, infinite or out of its range.
    GuideParameterOutOfRange,
    /// A per-probe (or per-proxy) table does not have one entry per cell and octant, or two
    /// tables that must match differ in length.
    TableLengthMismatch,
    /// A proxy block size is zero.
    ProxyBlockZero,
    /// A chain set was asked for zero chains.
    NoChains,
    /// A chain step size (the probe spacing times its scale) is not finite.
    #[deprecated(note = "`ChainKind::walk` reports `ProbeError::ChainStep` with the walk's cause")]
    StepNotFinite,
    /// A chain's random walk rejected its step sizes (the probe spacing times the chain
    /// kind's scale); the walk's error says why (not finite, above `RandomWalk::STEP_MAX`, …).
    ChainStep(WalkError),
    /// A texel map's side length leaves no interior texel or exceeds the maximum.
    MapSizeOutOfRange,
    /// A word slice handed to [`crate::ProbeTexels::from_words`] (or copied out) does not have
    /// one word per stored texel of the grid.
    WordCountMismatch,
    /// A temporal trigger's decay θ is not in [0, 1).
    TriggerDecayOutOfRange,
    /// A clip volume's plane or box is NaN, degenerate or inverted.
    ClipVolumeInvalid,
    /// A pilot schedule holds its directions for fewer than 2 frames.
    PilotHoldTooShort,
}

impl fmt::Display for ProbeError {
    #[allow(deprecated)] // `StepNotFinite` keeps its message while it exists
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            ProbeError::ChainStep(cause) => {
                return write!(f, "chain step sizes rejected by the random walk: {cause}");
            }
            ProbeError::OriginNotFinite => "probe grid origin is not finite",
            ProbeError::SpacingNotPositive => "probe spacing is not a positive finite vector",
            ProbeError::CountsOutOfRange => {
                "probe counts must be at least 1 per axis and at most 2^32 - 1 in total"
            }
            ProbeError::HeuristicParameterOutOfRange => "heuristic parameter is out of range",
            ProbeError::GuideParameterOutOfRange => "guiding function parameter is out of range",
            ProbeError::TableLengthMismatch => {
                "table length does not match the cell count times 8 octants"
            }
            ProbeError::ProxyBlockZero => "proxy block size is zero",
            ProbeError::NoChains => "chain count is zero",
            ProbeError::StepNotFinite => "chain step size is not finite",
            ProbeError::MapSizeOutOfRange => {
                "texel map side must leave at least one interior texel and be at most 1024"
            }
            ProbeError::WordCountMismatch => {
                "word slice length does not match the grid's stored texel count"
            }
            ProbeError::TriggerDecayOutOfRange => "temporal trigger decay is not in [0, 1)",
            ProbeError::ClipVolumeInvalid => "clip volume plane or box is invalid",
            ProbeError::PilotHoldTooShort => "pilot directions must be held for at least 2 frames",
        })
    }
}

impl core::error::Error for ProbeError {
    fn source(&self) -> Option<&(dyn core::error::Error + 'static)> {
        match self {
            ProbeError::ChainStep(cause) => Some(cause),
            _ => None,
        }
    }
}
