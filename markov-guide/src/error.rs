//! Errors returned by the validating constructors of this crate.

use core::fmt;

/// Why [`RandomWalk::new`](crate::RandomWalk::new) or
/// [`FrameSchedule::new`](crate::FrameSchedule::new) rejected its parameters. Variants carry
/// the values that were rejected.
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub enum WalkError {
    /// A step size σ is NaN or infinite.
    StepNotFinite {
        /// The dimension of the step.
        dimension: usize,
        /// The σ given.
        step: f32,
    },
    /// A step size σ is zero or negative.
    StepNotPositive {
        /// The dimension of the step.
        dimension: usize,
        /// The σ given.
        step: f32,
    },
    /// A step size σ is above [`RandomWalk::STEP_MAX`](crate::RandomWalk::STEP_MAX) (10³⁰).
    StepAboveMax {
        /// The dimension of the step.
        dimension: usize,
        /// The σ given.
        step: f32,
        /// The largest σ accepted, `RandomWalk::STEP_MAX`.
        maximum: f32,
    },
    /// The walk has no dimensions (`D = 0`).
    NoDimensions,
    /// The burn-in K is not smaller than the number of steps per frame M.
    BurnInTooLong {
        /// The burn-in K given.
        burn_in: u32,
        /// The steps per frame M given.
        iterations: u32,
    },
}

impl fmt::Display for WalkError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            WalkError::StepNotFinite { dimension, step } => write!(
                f,
                "random-walk step size {step} (dimension {dimension}) is not finite"
            ),
            WalkError::StepNotPositive { dimension, step } => write!(
                f,
                "random-walk step size {step} (dimension {dimension}) is not positive"
            ),
            WalkError::StepAboveMax {
                dimension,
                step,
                maximum,
            } => write!(
                f,
                "random-walk step size {step} (dimension {dimension}) is above {maximum}"
            ),
            WalkError::NoDimensions => f.write_str("random walk has no dimensions"),
            WalkError::BurnInTooLong {
                burn_in,
                iterations,
            } => write!(
                f,
                "burn-in {burn_in} is not shorter than the {iterations} steps per frame"
            ),
        }
    }
}

impl core::error::Error for WalkError {}

/// Why [`PixelStateBuffers::new`](crate::mcmm::PixelStateBuffers::new) could not create its
/// buffers.
#[derive(Clone, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum BufferError {
    /// The width or height exceeds `i32::MAX`, or the buffers would exceed `isize::MAX` bytes.
    DimensionAboveMax {
        /// The width given.
        width: u32,
        /// The height given.
        height: u32,
    },
    /// The allocator could not provide the buffers.
    AllocationFailed {
        /// The states one buffer needed.
        states: usize,
        /// The allocator's error (with `std`), this error's
        /// [`source`](core::error::Error::source).
        #[cfg(feature = "std")]
        source: std::collections::TryReserveError,
    },
}

impl fmt::Display for BufferError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            BufferError::DimensionAboveMax { width, height } => write!(
                f,
                "state buffers of {width} x {height} pixels are too large"
            ),
            BufferError::AllocationFailed { states, .. } => {
                write!(f, "allocating a state buffer of {states} states failed")
            }
        }
    }
}

impl core::error::Error for BufferError {
    fn source(&self) -> Option<&(dyn core::error::Error + 'static)> {
        match self {
            #[cfg(feature = "std")]
            BufferError::AllocationFailed { source, .. } => Some(source),
            _ => None,
        }
    }
}

/// Why a guide's parameter set (e.g. [`McmmParams`](crate::mcmm::McmmParams)) failed validation.
/// Variants name the parameter (its field path, e.g. `"fit.alpha_min"`) and carry its value.
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub enum ParamsError {
    /// A probability (hemisphere, BSDF or adaptive-grid probability, the cache's accumulation
    /// factor) is NaN or outside [0, 1].
    ProbabilityOutOfRange {
        /// The parameter's field path.
        parameter: &'static str,
        /// Its value.
        value: f32,
    },
    /// A length, weight, threshold or count is NaN, infinite, negative or outside its range.
    NotFiniteNonNegative {
        /// The parameter's field path.
        parameter: &'static str,
        /// Its value (a count converted to f32).
        value: f32,
    },
    /// A candidate count (or the fit's N_max) is zero.
    NoCandidates {
        /// The parameter's field path.
        parameter: &'static str,
    },
}

impl fmt::Display for ParamsError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ParamsError::ProbabilityOutOfRange { parameter, value } => {
                write!(f, "probability {parameter} = {value} is not in [0, 1]")
            }
            ParamsError::NotFiniteNonNegative { parameter, value } => write!(
                f,
                "parameter {parameter} = {value} is not finite, non-negative and in range"
            ),
            ParamsError::NoCandidates { parameter } => write!(f, "{parameter} is zero"),
        }
    }
}

impl core::error::Error for ParamsError {}

/// Why [`mcpg::Guide::new`](crate::mcpg::Guide::new) (or the irradiance cache) rejected its
/// configuration. The wrapped errors are its [`source`](core::error::Error::source).
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub enum GuideError {
    /// The MCPG constants (or the cache's accumulation factor) are invalid.
    Params(ParamsError),
    /// A grid's geometry is invalid.
    Grid(mcg_hashgrid::GridError),
    /// A table's capacity or probe limit is invalid.
    Table(mcg_hashgrid::TableError),
    /// The escaped rays' target distance is NaN, infinite, zero or negative.
    EnvironmentDistanceNotPositive {
        /// The distance given.
        distance: f32,
    },
}

impl fmt::Display for GuideError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            GuideError::Params(e) => write!(f, "guide constants: {e}"),
            GuideError::Grid(e) => write!(f, "guide grid: {e}"),
            GuideError::Table(e) => write!(f, "guide table: {e}"),
            GuideError::EnvironmentDistanceNotPositive { distance } => write!(
                f,
                "environment distance {distance} is not positive and finite"
            ),
        }
    }
}

impl core::error::Error for GuideError {
    fn source(&self) -> Option<&(dyn core::error::Error + 'static)> {
        match self {
            GuideError::Params(e) => Some(e),
            GuideError::Grid(e) => Some(e),
            GuideError::Table(e) => Some(e),
            GuideError::EnvironmentDistanceNotPositive { .. } => None,
        }
    }
}
