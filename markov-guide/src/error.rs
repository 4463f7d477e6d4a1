//! Errors returned by the validating constructors of this crate.

use core::fmt;

/// Why [`RandomWalk::new`](crate::RandomWalk::new) or
/// [`FrameSchedule::new`](crate::FrameSchedule::new) rejected its parameters.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum WalkError {
    /// A step size σ is NaN or infinite.
    StepNotFinite,
    /// A step size σ is zero or negative.
    StepNotPositive,
    /// A step size σ is above [`RandomWalk::STEP_MAX`](crate::RandomWalk::STEP_MAX) (10³⁰).
    StepAboveMax,
    /// The walk has no dimensions (`D = 0`).
    NoDimensions,
    /// The burn-in K is not smaller than the number of steps per frame M.
    BurnInTooLong,
}

impl fmt::Display for WalkError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            WalkError::StepNotFinite => "random-walk step size is not finite",
            WalkError::StepNotPositive => "random-walk step size is not positive",
            WalkError::StepAboveMax => "random-walk step size is above 1e30",
            WalkError::NoDimensions => "random walk has no dimensions",
            WalkError::BurnInTooLong => "burn-in is not shorter than the steps per frame",
        })
    }
}

impl core::error::Error for WalkError {}

/// Why [`PixelStateBuffers::new`](crate::mcmm::PixelStateBuffers::new) could not create its
/// buffers.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum BufferError {
    /// The width or height exceeds `i32::MAX`, or the buffers would exceed `isize::MAX` bytes.
    DimensionAboveMax,
    /// The allocator could not provide the buffers.
    AllocationFailed,
}

impl fmt::Display for BufferError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            BufferError::DimensionAboveMax => "state buffer dimensions are too large",
            BufferError::AllocationFailed => "state buffer allocation failed",
        })
    }
}

impl core::error::Error for BufferError {}

/// Why a guide's parameter set (e.g. [`McmmParams`](crate::mcmm::McmmParams)) failed validation.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum ParamsError {
    /// A probability (hemisphere, BSDF or adaptive-grid probability) is NaN or outside [0, 1].
    ProbabilityOutOfRange,
    /// A length, weight or threshold is NaN, infinite or negative.
    NotFiniteNonNegative,
    /// A candidate count is zero.
    NoCandidates,
}

impl fmt::Display for ParamsError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            ParamsError::ProbabilityOutOfRange => "probability is not in [0, 1]",
            ParamsError::NotFiniteNonNegative => "parameter is not finite and non-negative",
            ParamsError::NoCandidates => "candidate count is zero",
        })
    }
}

impl core::error::Error for ParamsError {}

/// Why [`mcpg::Guide::new`](crate::mcpg::Guide::new) (or the irradiance cache) rejected its
/// configuration.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum GuideError {
    /// The MCPG constants (or the cache's accumulation factor) are invalid.
    Params(ParamsError),
    /// A grid's geometry is invalid.
    Grid(mcg_hashgrid::GridError),
    /// A table's capacity or probe limit is invalid.
    Table(mcg_hashgrid::TableError),
    /// The escaped rays' target distance is NaN, infinite, zero or negative.
    EnvironmentDistanceNotPositive,
}

impl fmt::Display for GuideError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            GuideError::Params(e) => write!(f, "guide constants: {e}"),
            GuideError::Grid(e) => write!(f, "guide grid: {e}"),
            GuideError::Table(e) => write!(f, "guide table: {e}"),
            GuideError::EnvironmentDistanceNotPositive => {
                f.write_str("environment distance is not positive and finite")
            }
        }
    }
}

impl core::error::Error for GuideError {}
