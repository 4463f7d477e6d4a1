//! Errors returned by the validating constructors of this crate.

use core::fmt;

/// Why [`AdaptiveGrid::new`](crate::AdaptiveGrid::new) or
/// [`StaticGrid::new`](crate::StaticGrid::new) rejected its parameters. Variants carry the
/// values that were rejected.
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub enum GridError {
    /// tan(α/2) of the angular resolution is NaN, infinite, zero or negative.
    TanHalfAngleNotPositive {
        /// The tan(α/2) given.
        tan_half_angle: f32,
    },
    /// The finest (or the static) cell width is NaN, infinite, zero or negative.
    WidthNotPositive {
        /// The width given.
        width: f32,
    },
    /// The width ratio `power` is NaN, infinite or not greater than 1.
    PowerNotAboveOne {
        /// The ratio given.
        power: f32,
    },
    /// `steps` (levels per factor `power` in width) is zero.
    StepsZero,
    /// `max_level` exceeds [`MAX_LEVEL`](crate::constants::MAX_LEVEL) (255, the key's 8 bits).
    MaxLevelTooLarge {
        /// The level given.
        max_level: u32,
        /// The highest level a key holds, [`MAX_LEVEL`](crate::constants::MAX_LEVEL).
        maximum: u32,
    },
    /// The coarsest cell width `w_min · POWER^(max_level/STEPS)`, or the width ratio
    /// `POWER^(max_level/STEPS)` alone, is not below e^88.5 ≈ 2.7·10³⁸ (it would overflow f32).
    CoarsestWidthNotFinite {
        /// The parameters given (`min_width`, `power`, `steps` and `max_level` decide).
        params: crate::LevelParams,
    },
}

impl fmt::Display for GridError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            GridError::TanHalfAngleNotPositive { tan_half_angle } => write!(
                f,
                "tan of the half angle = {tan_half_angle} is not a positive finite number"
            ),
            GridError::WidthNotPositive { width } => {
                write!(f, "cell width {width} is not a positive finite number")
            }
            GridError::PowerNotAboveOne { power } => write!(
                f,
                "level width ratio {power} is not a finite number above 1"
            ),
            GridError::StepsZero => f.write_str("levels per width ratio is zero"),
            GridError::MaxLevelTooLarge { max_level, maximum } => {
                write!(f, "maximum level {max_level} is above {maximum}")
            }
            GridError::CoarsestWidthNotFinite { params } => write!(
                f,
                "coarsest cell width {} * {}^({}/{}) overflows f32",
                params.min_width, params.power, params.max_level, params.steps
            ),
        }
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
    MaxProbesAboveCapacity {
        /// The probe limit given.
        max_probes: u32,
        /// The table's capacity.
        capacity: u32,
    },
}

impl fmt::Display for TableError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            TableError::CapacityZero => f.write_str("table capacity is zero"),
            TableError::MaxProbesZero => f.write_str("probe limit is zero"),
            TableError::MaxProbesAboveCapacity {
                max_probes,
                capacity,
            } => write!(
                f,
                "probe limit {max_probes} exceeds the table capacity {capacity}"
            ),
        }
    }
}

impl core::error::Error for TableError {}
