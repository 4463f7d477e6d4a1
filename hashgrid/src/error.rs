//! Errors returned by the validating constructors of this crate.

use core::fmt;

/// Why [`AdaptiveGrid::new`](crate::AdaptiveGrid::new) or
/// [`StaticGrid::new`](crate::StaticGrid::new) rejected its parameters.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum GridError {
    /// tan(α/2) of the angular resolution is NaN, infinite, zero or negative.
    TanHalfAngleNotPositive,
    /// The finest (or the static) cell width is NaN, infinite, zero or negative.
    WidthNotPositive,
    /// The width ratio `power` is NaN, infinite or not greater than 1.
    PowerNotAboveOne,
    /// `steps` (levels per factor `power` in width) is zero.
    StepsZero,
    /// `max_level` exceeds [`MAX_LEVEL`](crate::constants::MAX_LEVEL) (255, the key's 8 bits).
    MaxLevelTooLarge,
    /// The coarsest cell width `w_min · POWER^(max_level/STEPS)`, or the width ratio
    /// `POWER^(max_level/STEPS)` alone, is not below e^88.5 ≈ 2.7·10³⁸ (it would overflow f32).
    CoarsestWidthNotFinite,
}

impl fmt::Display for GridError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            GridError::TanHalfAngleNotPositive => {
                "tan of the half angle is not a positive finite number"
            }
            GridError::WidthNotPositive => "cell width is not a positive finite number",
            GridError::PowerNotAboveOne => "level width ratio is not a finite number above 1",
            GridError::StepsZero => "levels per width ratio is zero",
            GridError::MaxLevelTooLarge => "maximum level does not fit in 8 bits",
            GridError::CoarsestWidthNotFinite => "coarsest cell width overflows f32",
        })
    }
}

impl core::error::Error for GridError {}

/// Why [`HashTable::new`](crate::HashTable::new) or
/// [`ConcurrentTable::new`](crate::ConcurrentTable::new) rejected its parameters.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum TableError {
    /// The capacity is zero.
    CapacityZero,
    /// The probe limit is zero.
    MaxProbesZero,
    /// The probe limit exceeds the capacity (a probe would visit a slot twice).
    MaxProbesAboveCapacity,
}

impl fmt::Display for TableError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            TableError::CapacityZero => "table capacity is zero",
            TableError::MaxProbesZero => "probe limit is zero",
            TableError::MaxProbesAboveCapacity => "probe limit exceeds the table capacity",
        })
    }
}

impl core::error::Error for TableError {}
