//! Every constant the GPU side needs (bit layouts, β, γ, N_max), defined once, as one table
//! that the GPU backend emits into WGSL.

use core::fmt;

use crate::heuristics_word::HeuristicsLayout;
use crate::irradiance_word::IrradianceLayout;
use crate::log_codec::LogCodec;
use crate::moving_average::MovingAverage;
use crate::visibility_word::VisibilityLayout;
use crate::{gamma5_r10g10b10a2, logluv32, math, quantize};

/// The value of a [`NamedConstant`]: WGSL `u32` or `f32`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ConstantValue {
    /// An unsigned integer (`u32` in WGSL, written with the `u` suffix).
    U32(u32),
    /// A float (`f32` in WGSL).
    F32(f32),
}

/// One entry of [`CONSTANTS`]: an upper-case name and its value.
///
/// `Display` writes the WGSL declaration, e.g. `const IRRADIANCE_R_BITS: u32 = 9u;`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NamedConstant {
    /// The WGSL identifier (upper snake case).
    pub name: &'static str,
    /// The value.
    pub value: ConstantValue,
}

impl fmt::Display for NamedConstant {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.value {
            ConstantValue::U32(v) => write!(f, "const {}: u32 = {v}u;", self.name),
            // `{:?}` keeps a decimal point (`5.0`), which WGSL needs for an f32 literal.
            ConstantValue::F32(v) => write!(f, "const {}: f32 = {v:?};", self.name),
        }
    }
}

const fn u(name: &'static str, v: u32) -> NamedConstant {
    NamedConstant {
        name,
        value: ConstantValue::U32(v),
    }
}

const fn f(name: &'static str, v: f32) -> NamedConstant {
    NamedConstant {
        name,
        value: ConstantValue::F32(v),
    }
}

const IRR: IrradianceLayout = IrradianceLayout::ADGI;
const VIS: VisibilityLayout = VisibilityLayout::ADGI;
const HEU: HeuristicsLayout = HeuristicsLayout::ADGI;

/// The codec constants of ADGI's default layouts, for the WGSL prelude: field widths and bit
/// offsets of the irradiance (sec. 4.5), visibility (sec. 4.6) and heuristics (sec. 4.3) words,
/// (β, γ) of each log codec (eq. 21), and N_max of the static and dynamic moving averages
/// (sec. 4.7, Table 3); the coefficients and reduction constants of the fast `ln`/`exp2`
/// polynomials (Cephes), the per-channel step of stochastic rounding, gamma-5's code range and
/// LogLuv32's bounds, scales and colour matrices.
/// Values are read from the typed constants, so the table cannot drift.
///
/// # Example
/// ```
/// use mcg_color_codec::CONSTANTS;
/// let prelude: Vec<String> = CONSTANTS.iter().map(|c| c.to_string()).collect();
/// assert!(prelude.contains(&"const IRRADIANCE_R_BITS: u32 = 9u;".to_string()));
/// assert!(prelude.contains(&"const IRRADIANCE_BETA: f32 = 5.0;".to_string()));
/// ```
pub const CONSTANTS: &[NamedConstant] = &[
    u("IRRADIANCE_R_BITS", IRR.widths()[0]),
    u("IRRADIANCE_G_BITS", IRR.widths()[1]),
    u("IRRADIANCE_B_BITS", IRR.widths()[2]),
    u("IRRADIANCE_COUNT_BITS", IRR.widths()[3]),
    u("IRRADIANCE_R_SHIFT", IRR.shifts()[0]),
    u("IRRADIANCE_G_SHIFT", IRR.shifts()[1]),
    u("IRRADIANCE_B_SHIFT", IRR.shifts()[2]),
    u("IRRADIANCE_COUNT_SHIFT", IRR.shifts()[3]),
    f("IRRADIANCE_BETA", LogCodec::IRRADIANCE.beta()),
    f("IRRADIANCE_GAMMA", LogCodec::IRRADIANCE.gamma()),
    u("VISIBILITY_MEAN_BITS", VIS.widths()[0]),
    u("VISIBILITY_MEAN_SQ_BITS", VIS.widths()[1]),
    u("VISIBILITY_COUNT_BITS", VIS.widths()[2]),
    u("VISIBILITY_MEAN_SHIFT", VIS.shifts()[0]),
    u("VISIBILITY_MEAN_SQ_SHIFT", VIS.shifts()[1]),
    u("VISIBILITY_COUNT_SHIFT", VIS.shifts()[2]),
    f("DISTANCE_BETA", LogCodec::DISTANCE.beta()),
    f("DISTANCE_GAMMA", LogCodec::DISTANCE.gamma()),
    f("SQUARED_DISTANCE_BETA", LogCodec::SQUARED_DISTANCE.beta()),
    f("SQUARED_DISTANCE_GAMMA", LogCodec::SQUARED_DISTANCE.gamma()),
    u("HEURISTICS_FV_BITS", HEU.widths()[0]),
    u("HEURISTICS_FS_BITS", HEU.widths()[1]),
    u("HEURISTICS_FD_BITS", HEU.widths()[2]),
    u("HEURISTICS_FLAG_BITS", HEU.widths()[3]),
    u("HEURISTICS_FV_SHIFT", HEU.shifts()[0]),
    u("HEURISTICS_FS_SHIFT", HEU.shifts()[1]),
    u("HEURISTICS_FD_SHIFT", HEU.shifts()[2]),
    u("HEURISTICS_FLAG_SHIFT", HEU.shifts()[3]),
    u(
        "MOVING_AVERAGE_STATIC_MAX_COUNT",
        MovingAverage::STATIC.max_count(),
    ),
    u(
        "MOVING_AVERAGE_DYNAMIC_MAX_COUNT",
        MovingAverage::DYNAMIC.max_count(),
    ),
    // The fast `ln` / `exp2` of the log codec and gamma-5 (`math.rs`): a GPU twin evaluates
    // the same polynomials in the same order to get the same codes.
    u("FAST_LN_SQRT_HALF_BITS", math::SQRT_HALF_BITS),
    f("FAST_LN_LN2_HI", math::LN2_HI),
    f("FAST_LN_LN2_LO", math::LN2_LO),
    f("FAST_LN_P0", math::LN_P[0]),
    f("FAST_LN_P1", math::LN_P[1]),
    f("FAST_LN_P2", math::LN_P[2]),
    f("FAST_LN_P3", math::LN_P[3]),
    f("FAST_LN_P4", math::LN_P[4]),
    f("FAST_LN_P5", math::LN_P[5]),
    f("FAST_LN_P6", math::LN_P[6]),
    f("FAST_LN_P7", math::LN_P[7]),
    f("FAST_LN_P8", math::LN_P[8]),
    f("FAST_EXP2_P1", math::EXP2_P[1]),
    f("FAST_EXP2_P2", math::EXP2_P[2]),
    f("FAST_EXP2_P3", math::EXP2_P[3]),
    f("FAST_EXP2_P4", math::EXP2_P[4]),
    f("FAST_EXP2_P5", math::EXP2_P[5]),
    f("FAST_EXP2_P6", math::EXP2_P[6]),
    // `Rounding::Stochastic` per channel: u + k·STEP mod 1.
    f("STOCHASTIC_CHANNEL_STEP", quantize::CHANNEL_STEP),
    // Gamma-5 R10G10B10A2.
    u("GAMMA5_MAX_CODE", gamma5_r10g10b10a2::GAMMA5_MAX_CODE),
    f("GAMMA5_MIN_INPUT", gamma5_r10g10b10a2::GAMMA5_MIN_INPUT),
    // LogLuv32: Le's range and bounds on Y (as the f32 thresholds an f32 Y compares against),
    // the chromaticity scale and the neutral point's codes, and the sRGB ↔ XYZ matrices
    // (column-major, `_0`..`_8`).
    u("LOGLUV_LE_MAX", logluv32::LE_MAX),
    f("LOGLUV_Y_MAX", f32_at_or_above(logluv32::Y_MAX)),
    f("LOGLUV_Y_MIN", f32_at_or_below(logluv32::Y_MIN)),
    u("LOGLUV_UV_SCALE", logluv32::UV_SCALE as u32),
    f("LOGLUV_INV_UV_SCALE", logluv32::INV_UV_SCALE),
    u(
        "LOGLUV_NEUTRAL_UE",
        (logluv32::UV_SCALE * logluv32::U_NEUTRAL) as u32,
    ),
    u(
        "LOGLUV_NEUTRAL_VE",
        (logluv32::UV_SCALE * logluv32::V_NEUTRAL) as u32,
    ),
    f("LOGLUV_SRGB_TO_XYZ_0", logluv32::SRGB_TO_XYZ.x_axis.x),
    f("LOGLUV_SRGB_TO_XYZ_1", logluv32::SRGB_TO_XYZ.x_axis.y),
    f("LOGLUV_SRGB_TO_XYZ_2", logluv32::SRGB_TO_XYZ.x_axis.z),
    f("LOGLUV_SRGB_TO_XYZ_3", logluv32::SRGB_TO_XYZ.y_axis.x),
    f("LOGLUV_SRGB_TO_XYZ_4", logluv32::SRGB_TO_XYZ.y_axis.y),
    f("LOGLUV_SRGB_TO_XYZ_5", logluv32::SRGB_TO_XYZ.y_axis.z),
    f("LOGLUV_SRGB_TO_XYZ_6", logluv32::SRGB_TO_XYZ.z_axis.x),
    f("LOGLUV_SRGB_TO_XYZ_7", logluv32::SRGB_TO_XYZ.z_axis.y),
    f("LOGLUV_SRGB_TO_XYZ_8", logluv32::SRGB_TO_XYZ.z_axis.z),
    f("LOGLUV_XYZ_TO_SRGB_0", logluv32::XYZ_TO_SRGB.x_axis.x),
    f("LOGLUV_XYZ_TO_SRGB_1", logluv32::XYZ_TO_SRGB.x_axis.y),
    f("LOGLUV_XYZ_TO_SRGB_2", logluv32::XYZ_TO_SRGB.x_axis.z),
    f("LOGLUV_XYZ_TO_SRGB_3", logluv32::XYZ_TO_SRGB.y_axis.x),
    f("LOGLUV_XYZ_TO_SRGB_4", logluv32::XYZ_TO_SRGB.y_axis.y),
    f("LOGLUV_XYZ_TO_SRGB_5", logluv32::XYZ_TO_SRGB.y_axis.z),
    f("LOGLUV_XYZ_TO_SRGB_6", logluv32::XYZ_TO_SRGB.z_axis.x),
    f("LOGLUV_XYZ_TO_SRGB_7", logluv32::XYZ_TO_SRGB.z_axis.y),
    f("LOGLUV_XYZ_TO_SRGB_8", logluv32::XYZ_TO_SRGB.z_axis.z),
];

/// The smallest f32 ≥ `x` (positive, finite): for an f32 `y`, `y as f64 >= x` ⟺ `y >= it`.
const fn f32_at_or_above(x: f64) -> f32 {
    let f = x as f32;
    if (f as f64) < x {
        f32::from_bits(f.to_bits() + 1)
    } else {
        f
    }
}

/// The largest f32 ≤ `x` (positive, finite): for an f32 `y`, `y as f64 > x` ⟺ `y > it`.
const fn f32_at_or_below(x: f64) -> f32 {
    let f = x as f32;
    if (f as f64) > x {
        f32::from_bits(f.to_bits() - 1)
    } else {
        f
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn logluv_thresholds_decide_like_the_f64_bounds() {
        let hi = f32_at_or_above(logluv32::Y_MAX);
        assert!(f64::from(hi) >= logluv32::Y_MAX);
        assert!(f64::from(f32::from_bits(hi.to_bits() - 1)) < logluv32::Y_MAX);
        let lo = f32_at_or_below(logluv32::Y_MIN);
        assert!(f64::from(lo) <= logluv32::Y_MIN);
        assert!(f64::from(f32::from_bits(lo.to_bits() + 1)) > logluv32::Y_MIN);
    }
    use std::string::ToString;

    #[test]
    fn table_is_consistent() {
        let mut names: std::vec::Vec<&str> = CONSTANTS.iter().map(|c| c.name).collect();
        names.sort_unstable();
        names.dedup();
        assert_eq!(names.len(), CONSTANTS.len(), "duplicate names");
        for c in CONSTANTS {
            assert!(
                c.name
                    .bytes()
                    .all(|b| b.is_ascii_uppercase() || b.is_ascii_digit() || b == b'_')
            );
        }
        assert_eq!(
            CONSTANTS[0].to_string(),
            "const IRRADIANCE_R_BITS: u32 = 9u;"
        );
        let beta = CONSTANTS
            .iter()
            .find(|c| c.name == "SQUARED_DISTANCE_BETA")
            .unwrap();
        assert_eq!(beta.to_string(), "const SQUARED_DISTANCE_BETA: f32 = 8.0;");
    }
}
