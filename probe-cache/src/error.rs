//! Errors returned by the validating constructors and table functions of this crate: one type
//! per concept, each convertible into the crate-level [`ProbeError`] (so `?` into
//! `Result<_, ProbeError>` works for all of them).

use core::fmt;

use glam::{UVec3, Vec3, Vec4};
use mcg_markov_guide::WalkError;

/// Why a probe lattice or its proxy grid was rejected ([`crate::ProbeGrid::new`],
/// [`crate::ProxyGrid::new`]). Variants carry the values that were rejected.
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub enum GridError {
    /// The grid origin has a NaN or infinite component.
    OriginNotFinite {
        /// The origin given.
        origin: Vec3,
    },
    /// A probe spacing component is NaN, infinite, or not positive.
    SpacingNotPositive {
        /// The spacing given.
        spacing: Vec3,
    },
    /// A probe count along an axis is zero, or the total probe count overflows `u32`.
    CountsOutOfRange {
        /// The counts given.
        counts: UVec3,
    },
    /// A proxy block size is zero.
    ProxyBlockZero,
}

impl fmt::Display for GridError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            GridError::OriginNotFinite { origin } => {
                write!(f, "probe grid origin {origin} is not finite")
            }
            GridError::SpacingNotPositive { spacing } => {
                write!(f, "probe spacing {spacing} is not a positive finite vector")
            }
            GridError::CountsOutOfRange { counts } => write!(
                f,
                "probe counts {counts} must be at least 1 per axis and at most 2^32 - 1 in total"
            ),
            GridError::ProxyBlockZero => f.write_str("proxy block size is zero"),
        }
    }
}

impl core::error::Error for GridError {}

/// Why the parameters of the heuristics ([`crate::HeuristicParams`]) or of the guiding
/// function ([`crate::GuideParams`]) were rejected. Variants name the parameter and carry its
/// value.
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub enum ParameterError {
    /// A heuristic parameter (camera threshold k, voxel diagonal s, radiance range β,
    /// lighting weight μ) is NaN, infinite or out of its range.
    HeuristicOutOfRange {
        /// The parameter's name, e.g. `"voxel_diagonal"`.
        parameter: &'static str,
        /// Its value.
        value: f32,
    },
    /// A guiding-function parameter (α, exponent cap) is NaN, infinite or out of its range.
    GuideOutOfRange {
        /// The parameter's name, `"alpha"` or `"exponent_cap"`.
        parameter: &'static str,
        /// Its value.
        value: f32,
    },
}

impl fmt::Display for ParameterError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ParameterError::HeuristicOutOfRange { parameter, value } => write!(
                f,
                "heuristic parameter {parameter} = {value} is out of range"
            ),
            ParameterError::GuideOutOfRange { parameter, value } => write!(
                f,
                "guiding function parameter {parameter} = {value} is out of range"
            ),
        }
    }
}

impl core::error::Error for ParameterError {}

/// Why a table, a texel map or a word slice does not fit the layout it is used with.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum LayoutError {
    /// A per-probe (or per-proxy) table does not have one entry per cell and octant, or two
    /// tables that must match differ in length.
    TableLengthMismatch {
        /// The length required (the first table's length where tables must match).
        expected: usize,
        /// The first length that differs.
        found: usize,
    },
    /// A texel map's side length leaves no interior texel or exceeds the maximum.
    MapSizeOutOfRange {
        /// The side length given.
        side: u32,
        /// The smallest side accepted (1, or 3 with a border).
        minimum: u32,
        /// The largest side accepted, [`crate::MAX_MAP_SIDE`].
        maximum: u32,
    },
    /// A word slice handed to [`crate::ProbeTexels::from_words`] (or copied out) does not have
    /// one word per stored texel of the grid.
    WordCountMismatch {
        /// The grid's stored texel count.
        expected: usize,
        /// The slice's length.
        found: usize,
    },
}

impl LayoutError {
    /// `Ok` when every length in `found` equals `expected`, else
    /// [`LayoutError::TableLengthMismatch`] with the first that differs.
    pub(crate) fn check_tables(expected: usize, found: &[usize]) -> Result<(), LayoutError> {
        match found.iter().find(|&&n| n != expected) {
            None => Ok(()),
            Some(&found) => Err(LayoutError::TableLengthMismatch { expected, found }),
        }
    }

    /// `Ok` when `found == expected`, else [`LayoutError::WordCountMismatch`].
    pub(crate) fn check_words(expected: usize, found: usize) -> Result<(), LayoutError> {
        if expected == found {
            Ok(())
        } else {
            Err(LayoutError::WordCountMismatch { expected, found })
        }
    }
}

impl fmt::Display for LayoutError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            LayoutError::TableLengthMismatch { expected, found } => write!(
                f,
                "table length {found} does not match the expected {expected} \
                 (cells times 8 octants, or the first table's length)"
            ),
            LayoutError::MapSizeOutOfRange {
                side,
                minimum,
                maximum,
            } => write!(f, "texel map side {side} is not in {minimum}..={maximum}"),
            LayoutError::WordCountMismatch { expected, found } => write!(
                f,
                "word slice length {found} does not match the grid's {expected} stored texels"
            ),
        }
    }
}

impl core::error::Error for LayoutError {}

/// Why a set of Metropolis chains ([`crate::ProbeChains`], [`crate::ChainKind::walk`]) could
/// not be built.
#[derive(Clone, Copy, Debug, PartialEq)]
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
/// [`crate::Frustum`]) or the pilot schedule ([`crate::PilotSchedule::new`]). Variants carry
/// the values that were rejected.
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub enum ControlError {
    /// A temporal trigger's decay θ is not in [0, 1).
    TriggerDecayOutOfRange {
        /// The θ given.
        decay: f32,
    },
    /// A frustum plane has a NaN or infinite component or a zero or non-finite normal.
    ClipPlaneInvalid {
        /// The plane's index (0..6).
        index: usize,
        /// The plane given, (n, d).
        plane: Vec4,
    },
    /// A clip box bound is NaN or `min > max` on an axis.
    ClipBoxInvalid {
        /// The lower corner given.
        min: Vec3,
        /// The upper corner given.
        max: Vec3,
    },
    /// A pilot schedule holds its directions for fewer than 2 frames.
    PilotHoldTooShort {
        /// The hold given, in frames.
        hold: u32,
    },
    /// An ADGI probe update gets no more rays per probe than its pilot rays
    /// ([`crate::ProbeUpdater::new`]).
    RayBudgetBelowPilots {
        /// The rays per probe given.
        rays_per_probe: u32,
        /// The pilot rays per probe (8).
        pilots: u32,
    },
    /// A probe update gets zero rays per probe.
    RayBudgetZero,
    /// The dynamic share of an ADGI probe update is NaN or outside [0, 1].
    DynamicShareOutOfRange {
        /// The share given.
        share: f32,
    },
    /// An ADGI probe update traces zero rays per dynamic sample octant.
    DynamicRaysZero,
    /// A probe update's DDGI moving-average window N_max is zero.
    MaxCountZero,
    /// The refill weight κ of an ADGI probe update is NaN, infinite or negative.
    RefillWeightOutOfRange {
        /// The κ given.
        weight: f32,
    },
    /// The pulse threshold of a change detector is NaN, infinite or negative.
    PulseThresholdOutOfRange {
        /// The threshold given.
        threshold: f32,
    },
}

impl fmt::Display for ControlError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ControlError::TriggerDecayOutOfRange { decay } => {
                write!(f, "temporal trigger decay {decay} is not in [0, 1)")
            }
            ControlError::ClipPlaneInvalid { index, plane } => write!(
                f,
                "clip plane {index} = {plane} is not finite or has a zero normal"
            ),
            ControlError::ClipBoxInvalid { min, max } => {
                write!(f, "clip box from {min} to {max} is NaN or inverted")
            }
            ControlError::PilotHoldTooShort { hold } => write!(
                f,
                "pilot directions are held for {hold} frames, at least 2 are needed"
            ),
            ControlError::RayBudgetBelowPilots {
                rays_per_probe,
                pilots,
            } => write!(
                f,
                "{rays_per_probe} rays per probe leave none after the {pilots} pilot rays"
            ),
            ControlError::RayBudgetZero => f.write_str("ray budget is zero rays per probe"),
            ControlError::DynamicShareOutOfRange { share } => {
                write!(f, "dynamic share {share} is not in [0, 1]")
            }
            ControlError::DynamicRaysZero => f.write_str("dynamic samples trace zero rays"),
            ControlError::MaxCountZero => f.write_str("moving-average window N_max is zero"),
            ControlError::RefillWeightOutOfRange { weight } => {
                write!(f, "refill weight {weight} is not a finite number >= 0")
            }
            ControlError::PulseThresholdOutOfRange { threshold } => {
                write!(f, "pulse threshold {threshold} is not a finite number >= 0")
            }
        }
    }
}

impl core::error::Error for ControlError {}

/// Any error of this crate: the error of the concept that failed, for callers that collect
/// them with `?`. Its message and [`source`](core::error::Error::source) are those of the
/// wrapped error.
#[derive(Clone, Copy, Debug, PartialEq)]
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
        let walk = WalkError::StepAboveMax {
            dimension: 0,
            step: 2e30,
            maximum: 1e30,
        };
        let e = ProbeError::from(ChainError::ChainStep(walk));
        assert_eq!(e.to_string(), ChainError::ChainStep(walk).to_string());
        assert_eq!(e.source().map(ToString::to_string), Some(walk.to_string()));
        let origin = Vec3::new(0.0, f32::INFINITY, 1.0);
        let g = ProbeError::from(GridError::OriginNotFinite { origin });
        assert_eq!(g, ProbeError::Grid(GridError::OriginNotFinite { origin }));
        assert_eq!(g.to_string(), "probe grid origin [0, inf, 1] is not finite");
        assert!(g.source().is_none());
    }
}
