//! Errors returned by the validating constructors of this crate.

use core::fmt;

use glam::Vec3;

/// Why [`Vmf::new`](crate::Vmf::new) rejected its parameters. Each variant carries the value
/// that was rejected.
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub enum VmfError {
    /// A component of the mean direction μ is NaN or infinite.
    MeanNotFinite {
        /// The mean direction given.
        mean: Vec3,
    },
    /// The mean direction μ has zero length (or is too short to normalise in f32).
    MeanZeroLength {
        /// The mean direction given.
        mean: Vec3,
    },
    /// The concentration κ is NaN or infinite.
    KappaNotFinite {
        /// The κ given.
        kappa: f32,
    },
    /// The concentration κ is negative.
    KappaNegative {
        /// The κ given.
        kappa: f32,
    },
    /// The concentration κ is above [`KAPPA_MAX`](crate::KAPPA_MAX) (10⁶).
    KappaAboveMax {
        /// The κ given.
        kappa: f32,
        /// The largest κ accepted, [`KAPPA_MAX`](crate::KAPPA_MAX).
        maximum: f32,
    },
}

impl fmt::Display for VmfError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            VmfError::MeanNotFinite { mean } => write!(f, "mean direction {mean} is not finite"),
            VmfError::MeanZeroLength { mean } => {
                write!(f, "mean direction {mean} has zero length")
            }
            VmfError::KappaNotFinite { kappa } => {
                write!(f, "concentration kappa = {kappa} is not finite")
            }
            VmfError::KappaNegative { kappa } => {
                write!(f, "concentration kappa = {kappa} is negative")
            }
            VmfError::KappaAboveMax { kappa, maximum } => write!(
                f,
                "concentration kappa = {kappa} is above the maximum {maximum}"
            ),
        }
    }
}

impl core::error::Error for VmfError {}

/// Why [`VmfMixture::new`](crate::VmfMixture::new) rejected its weights. Each variant carries
/// the offending component and its weight.
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub enum MixtureError {
    /// A component weight is NaN or infinite.
    WeightNotFinite {
        /// The component's index.
        index: usize,
        /// Its weight.
        weight: f32,
    },
    /// A component weight is negative.
    WeightNegative {
        /// The component's index.
        index: usize,
        /// Its weight.
        weight: f32,
    },
    /// The weights are finite but their sum overflows f32, so they cannot be normalised.
    WeightSumNotFinite,
    /// The weights sum to zero (or the mixture has no components), so no component can be chosen.
    WeightsSumToZero,
}

impl fmt::Display for MixtureError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            MixtureError::WeightNotFinite { index, weight } => {
                write!(f, "mixture weight {index} = {weight} is not finite")
            }
            MixtureError::WeightNegative { index, weight } => {
                write!(f, "mixture weight {index} = {weight} is negative")
            }
            MixtureError::WeightSumNotFinite => f.write_str("mixture weights sum beyond f32"),
            MixtureError::WeightsSumToZero => f.write_str("mixture weights sum to zero"),
        }
    }
}

impl core::error::Error for MixtureError {}
