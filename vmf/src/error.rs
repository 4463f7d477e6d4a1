//! Errors returned by the validating constructors of this crate.

use core::fmt;

/// Why [`Vmf::new`](crate::Vmf::new) rejected its parameters.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum VmfError {
    /// A component of the mean direction μ is NaN or infinite.
    MeanNotFinite,
    /// The mean direction μ has zero length (or is too short to normalise in f32).
    MeanZeroLength,
    /// The concentration κ is NaN or infinite.
    KappaNotFinite,
    /// The concentration κ is negative.
    KappaNegative,
    /// The concentration κ is above [`KAPPA_MAX`](crate::KAPPA_MAX) (10⁶).
    KappaAboveMax,
}

impl fmt::Display for VmfError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            VmfError::MeanNotFinite => "mean direction is not finite",
            VmfError::MeanZeroLength => "mean direction has zero length",
            VmfError::KappaNotFinite => "concentration kappa is not finite",
            VmfError::KappaNegative => "concentration kappa is negative",
            VmfError::KappaAboveMax => "concentration kappa is above KAPPA_MAX (1e6)",
        })
    }
}

impl core::error::Error for VmfError {}

/// Why [`VmfMixture::new`](crate::VmfMixture::new) rejected its weights.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum MixtureError {
    /// A component weight is NaN or infinite.
    WeightNotFinite,
    /// A component weight is negative.
    WeightNegative,
    /// The weights sum to zero (or the mixture has no components), so no component can be chosen.
    WeightsSumToZero,
}

impl fmt::Display for MixtureError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            MixtureError::WeightNotFinite => "mixture weight is not finite",
            MixtureError::WeightNegative => "mixture weight is negative",
            MixtureError::WeightsSumToZero => "mixture weights sum to zero",
        })
    }
}

impl core::error::Error for MixtureError {}
