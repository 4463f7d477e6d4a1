//! Errors returned by the validating constructors of this crate.

use core::fmt;

/// Why a constructor of this crate rejected its parameters.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum SmisError {
    /// A probability (the defensive probability p) is NaN or outside [0, 1].
    ProbabilityOutOfRange,
    /// A defensive mixture with p < 1 was given an empty stochastic set, so the (1 − p) branch
    /// would have nothing to sample.
    EmptyTechniqueSet,
    /// A list of classical techniques and its list of sample counts differ in length.
    CountsLengthMismatch,
    /// A tile size is 0.
    TileSizeZero,
    /// A tile size exceeds [`MAX_TILE_SIZE`](crate::MAX_TILE_SIZE) (32, a GPU subgroup).
    TileSizeTooLarge,
    /// An xor permutation was asked for a tile size that is not a power of two (xor with a mask
    /// maps a lane outside such a tile).
    TileSizeNotPowerOfTwo,
    /// A shift or xor mask is not smaller than the tile size.
    OffsetOutOfRange,
}

impl fmt::Display for SmisError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            SmisError::ProbabilityOutOfRange => "probability is not in [0, 1]",
            SmisError::EmptyTechniqueSet => "stochastic technique set is empty",
            SmisError::CountsLengthMismatch => "techniques and sample counts differ in length",
            SmisError::TileSizeZero => "tile size is zero",
            SmisError::TileSizeTooLarge => "tile size exceeds 32",
            SmisError::TileSizeNotPowerOfTwo => "tile size is not a power of two",
            SmisError::OffsetOutOfRange => "shift or mask is not smaller than the tile size",
        })
    }
}

impl core::error::Error for SmisError {}

#[cfg(test)]
mod tests {
    use super::*;
    use std::string::ToString;

    #[test]
    fn messages_are_lowercase() {
        for e in [
            SmisError::ProbabilityOutOfRange,
            SmisError::EmptyTechniqueSet,
            SmisError::CountsLengthMismatch,
            SmisError::TileSizeZero,
            SmisError::TileSizeTooLarge,
            SmisError::TileSizeNotPowerOfTwo,
            SmisError::OffsetOutOfRange,
        ] {
            let m = e.to_string();
            assert!(m.chars().next().unwrap().is_lowercase(), "{m}");
        }
    }
}
