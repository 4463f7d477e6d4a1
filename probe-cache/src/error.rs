//! Errors returned by the validating constructors and table functions of this crate: one type
//! per concept, each convertible into the crate-level [`ProbeError`] (so `?` into
//! `Result<_, ProbeError>` works for all of them).

use core::fmt;

use mcg_markov_guide::WalkError;

/// Why a probe lattice or its proxy grid was rejected ([`crate::ProbeGrid::new`],
/// [`crate::ProxyGrid::new`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum GridError {
    /// The grid origin has a NaN or infinite component.
    OriginNotFinite,
    /// A probe spacing component is NaN, infinite, or not positive.
    SpacingNotPositive,
    /// A probe count along an axis is zero, or the total probe count overflows `u32`.
    CountsOutOfRange,
    /// A proxy block size is zero.
    ProxyBlockZero,
}

impl fmt::Display for GridError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            GridError::OriginNotFinite => "probe grid origin is not finite",
            GridError::SpacingNotPositive => "probe spacing is not a positive finite vector",
            GridError::CountsOutOfRange => {
                "probe counts must be at least 1 per axis and at most 2^32 - 1 in total"
            }
            GridError::ProxyBlockZero => "proxy block size is zero",
        })
    }
}

impl core::error::Error for GridError {}

/// Why the parameters of the heuristics ([`crate::HeuristicParams`]) or of the guiding
/// function ([`crate::GuideParams`]) were rejected.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum ParameterError {
    /// A heuristic parameter (camera threshold k, voxel diagonal s, radiance range β,
    /// lighting weight μ) is NaN, infinite or out of its range.
    HeuristicOutOfRange,
    /// A guiding-function parameter (α, exponent cap) is NaN, infinite or out of its range.
    GuideOutOfRange,
}

impl fmt::Display for ParameterError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            ParameterError::HeuristicOutOfRange => "heuristic parameter is out of range",
            ParameterError::GuideOutOfRange => "guiding function parameter is out of range",
        })
    }
}

impl core::error::Error for ParameterError {}

/// Why a table, a texel map or a word slice does not fit the layout it is used with.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum LayoutError {
    /// A per-probe (or per-proxy) table does not have one entry per cell and octant, or two
    /// tables that must match differ in length.
    TableLengthMismatch,
    /// A texel map's side length leaves no interior texel or exceeds the maximum.
    MapSizeOutOfRange,
    /// A word slice handed to [`crate::ProbeTexels::from_words`] (or copied out) does not have
    /// one word per stored texel of the grid.
    WordCountMismatch,
}

impl fmt::Display for LayoutError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            LayoutError::TableLengthMismatch => {
                "table length does not match the cell count times 8 octants"
            }
            LayoutError::MapSizeOutOfRange => {
                "texel map side must leave at least one interior texel and be at most 1024"
            }
            LayoutError::WordCountMismatch => {
                "word slice length does not match the grid's stored texel count"
            }
        })
    }
}

impl core::error::Error for LayoutError {}

/// Why a set of Metropolis chains ([`crate::ProbeChains`], [`crate::ChainKind::walk`]) could
/// not be built.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum ChainError {
    /// A chain set was asked for zero chains.
    NoChains,
    /// A chain step size (the probe spacing times its scale) is not finite.
    #[deprecated(note = "`ChainKind::walk` reports `ChainError::ChainStep` with the walk's cause")]
    StepNotFinite,
    /// A chain's random walk rejected its step sizes (the probe spacing times the chain
    /// kind's scale); the walk's error says why (not finite, above `RandomWalk::STEP_MAX`, …)
    /// and is this error's [`source`](core::error::Error::source).
    ChainStep(WalkError),
}

impl fmt::Display for ChainError {
    #[allow(deprecated)] // `StepNotFinite` keeps its message while it exists
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ChainError::NoChains => f.write_str("chain count is zero"),
            ChainError::StepNotFinite => f.write_str("chain step size is not finite"),
            ChainError::ChainStep(cause) => {
                write!(f, "chain step sizes rejected by the random walk: {cause}")
            }
        }
    }
}

impl core::error::Error for ChainError {
    fn source(&self) -> Option<&(dyn core::error::Error + 'static)> {
        match self {
            ChainError::ChainStep(cause) => Some(cause),
            _ => None,
        }
    }
}

/// Why a per-frame control was rejected: the temporal trigger
/// ([`crate::TemporalTrigger::new`]), a clip volume ([`crate::ClipVolume`],
/// [`crate::Frustum`]) or the pilot schedule ([`crate::PilotSchedule::new`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum ControlError {
    /// A temporal trigger's decay θ is not in [0, 1).
    TriggerDecayOutOfRange,
    /// A clip volume's plane or box is NaN, degenerate or inverted.
    ClipVolumeInvalid,
    /// A pilot schedule holds its directions for fewer than 2 frames.
    PilotHoldTooShort,
}

impl fmt::Display for ControlError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            ControlError::TriggerDecayOutOfRange => "temporal trigger decay is not in [0, 1)",
            ControlError::ClipVolumeInvalid => "clip volume plane or box is invalid",
            ControlError::PilotHoldTooShort => {
                "pilot directions must be held for at least 2 frames"
            }
        })
    }
}

impl core::error::Error for ControlError {}

/// Any error of this crate: the error of the concept that failed, for callers that collect
/// them with `?`. Its message and [`source`](core::error::Error::source) are those of the
/// wrapped error.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum ProbeError {
    /// The probe lattice or proxy grid.
    Grid(GridError),
    /// The heuristics' or the guiding function's parameters.
    Parameter(ParameterError),
    /// A table, texel map or word slice.
    Layout(LayoutError),
    /// The Metropolis chains.
    Chain(ChainError),
    /// The temporal trigger, a clip volume or the pilot schedule.
    Control(ControlError),
}

impl ProbeError {
    /// The wrapped error.
    fn inner(&self) -> &(dyn core::error::Error + 'static) {
        match self {
            ProbeError::Grid(e) => e,
            ProbeError::Parameter(e) => e,
            ProbeError::Layout(e) => e,
            ProbeError::Chain(e) => e,
            ProbeError::Control(e) => e,
        }
    }
}

impl fmt::Display for ProbeError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        fmt::Display::fmt(self.inner(), f)
    }
}

impl core::error::Error for ProbeError {
    fn source(&self) -> Option<&(dyn core::error::Error + 'static)> {
        self.inner().source()
    }
}

macro_rules! from_concept {
    ($($concept:ident => $variant:ident),* $(,)?) => {$(
        impl From<$concept> for ProbeError {
            fn from(e: $concept) -> Self {
                ProbeError::$variant(e)
            }
        }
    )*};
}

from_concept!(
    GridError => Grid,
    ParameterError => Parameter,
    LayoutError => Layout,
    ChainError => Chain,
    ControlError => Control,
);

#[cfg(test)]
mod tests {
    use super::*;
    use core::error::Error;

    #[test]
    fn probe_error_keeps_the_concept_message_and_the_walk_cause() {
        let e = ProbeError::from(ChainError::ChainStep(WalkError::StepAboveMax));
        assert_eq!(
            e.to_string(),
            ChainError::ChainStep(WalkError::StepAboveMax).to_string()
        );
        assert_eq!(
            e.source().map(ToString::to_string),
            Some(WalkError::StepAboveMax.to_string())
        );
        let g = ProbeError::from(GridError::OriginNotFinite);
        assert_eq!(g, ProbeError::Grid(GridError::OriginNotFinite));
        assert_eq!(g.to_string(), "probe grid origin is not finite");
        assert!(g.source().is_none());
    }
}
