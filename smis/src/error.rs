//! Errors returned by the validating constructors of this crate.

use core::fmt;

/// Why a constructor of this crate rejected its parameters. Variants carry the values that
/// explain them.
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub enum SmisError {
    /// A probability (the defensive probability p) is NaN or outside [0, 1].
    ProbabilityOutOfRange {
        /// The probability given.
        probability: f32,
    },
    /// A defensive mixture with p < 1 was given an empty stochastic set, so the (1 − p) branch
    /// would have nothing to sample.
    EmptyTechniqueSet,
    /// A list of classical techniques and its list of sample counts differ in length.
    CountsLengthMismatch {
        /// The number of classical techniques (the length the counts must have).
        expected: usize,
        /// The number of sample counts given.
        found: usize,
    },
    /// A tile size is 0.
    TileSizeZero,
    /// A tile size exceeds [`MAX_TILE_SIZE`](crate::MAX_TILE_SIZE) (32, a GPU subgroup).
    TileSizeTooLarge {
        /// The tile size given.
        size: u32,
        /// The largest tile size, [`MAX_TILE_SIZE`](crate::MAX_TILE_SIZE).
        maximum: u32,
    },
    /// An xor permutation was asked for a tile size that is not a power of two (xor with a mask
    /// maps a lane outside such a tile).
    TileSizeNotPowerOfTwo {
        /// The tile size given.
        size: u32,
    },
    /// A shift or xor mask is not smaller than the tile size.
    OffsetOutOfRange {
        /// The shift or mask given.
        offset: u32,
        /// The tile size it must be smaller than.
        size: u32,
    },
}

impl fmt::Display for SmisError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            SmisError::ProbabilityOutOfRange { probability } => {
                write!(f, "probability {probability} is not in [0, 1]")
            }
            SmisError::EmptyTechniqueSet => f.write_str("stochastic technique set is empty"),
            SmisError::CountsLengthMismatch { expected, found } => write!(
                f,
                "{found} sample counts given for {expected} classical techniques"
            ),
            SmisError::TileSizeZero => f.write_str("tile size is zero"),
            SmisError::TileSizeTooLarge { size, maximum } => {
                write!(f, "tile size {size} exceeds {maximum}")
            }
            SmisError::TileSizeNotPowerOfTwo { size } => {
                write!(f, "tile size {size} is not a power of two")
            }
            SmisError::OffsetOutOfRange { offset, size } => write!(
                f,
                "shift or mask {offset} is not smaller than the tile size {size}"
            ),
        }
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
            SmisError::ProbabilityOutOfRange { probability: 1.5 },
            SmisError::EmptyTechniqueSet,
            SmisError::TileSizeZero,
            SmisError::TileSizeTooLarge {
                size: 33,
                maximum: 32,
            },
            SmisError::TileSizeNotPowerOfTwo { size: 12 },
            SmisError::OffsetOutOfRange { offset: 8, size: 8 },
        ] {
            let m = e.to_string();
            assert!(m.chars().next().unwrap().is_lowercase(), "{m}");
        }
        assert_eq!(
            SmisError::CountsLengthMismatch {
                expected: 2,
                found: 1
            }
            .to_string(),
            "1 sample counts given for 2 classical techniques"
        );
        assert_eq!(
            SmisError::ProbabilityOutOfRange { probability: 1.5 }.to_string(),
            "probability 1.5 is not in [0, 1]"
        );
    }
}
