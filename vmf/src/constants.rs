//! The numeric constants of the lobe code — switch points, series and polynomial
//! coefficients — defined once, as typed `pub const`s the Rust code uses and as two tables
//! ([`F32_CONSTANTS`], [`U32_CONSTANTS`]) that `mcg-gpu-backend` emits into its generated WGSL
//! prelude, so its shader twin switches at the same points and evaluates the same polynomials
//! without typing a value twice.

/// Below this κ, sampling uses the κ → 0 limit `cos θ − 1 = −2ξ` (its error is O(κ) relative,
/// under f32 resolution here).
pub const KAPPA_TINY: f32 = 1.0e-7;

/// Above this κ, e^{−2κ} < 2⁻²⁵ vanishes next to 1 in f32: 1 − e^{−2κ} rounds to exactly 1,
/// so C(κ) = κ/(2π) and expm1(−2κ) = −1 exactly.
pub const KAPPA_SATURATED: f32 = 9.0;

/// Above this κ, e^{−2κ} < 2⁻⁴⁹: next to 1 − ξ ≥ 2⁻²⁴ it is below half an ulp, so the
/// inverse CDF drops it even in the far tail ξ → 1.
pub const KAPPA_SAMPLE_SATURATED: f32 = 17.0;

/// Above this κ the sampler forms expm1(−2κ) as `e^{−2κ} − 1` (|2κ| > ½: no cancellation);
/// below it by Kahan's expm1.
pub const KAPPA_DIRECT_EXPM1: f32 = 0.25;

/// Below this κ, A₃(κ), its derivative and 1 − A₃(κ) come from their Taylor series (the
/// closed forms cancel).
pub const SERIES_LIMIT: f32 = 0.5;

/// Kahan's expm1 is used for |x| ≤ this; above, `exp(x) − 1` loses nothing (|result| ≥ 0.39).
pub const EXP_M1_KAHAN_LIMIT: f32 = 0.5;

/// 1/k!, k = 1 … 8: expm1(x)/x = Σ x^(k−1)/k! to x⁷/8!, the remainder below 1.1·10⁻⁸ for
/// |x| ≤ [`EXP_M1_KAHAN_LIMIT`]. The WGSL twin's expm1 there: Kahan's form needs a log that
/// is accurate relative to ln u near 1, and WGSL promises only 2⁻²¹ absolute (on an NVIDIA
/// H200 that made lobes with κ ≈ 10⁻⁷ sample and weigh wrong by tens of per cent).
pub const EXP_M1_SERIES: [f32; 8] = [
    1.0,
    1.0 / 2.0,
    1.0 / 6.0,
    1.0 / 24.0,
    1.0 / 120.0,
    1.0 / 720.0,
    1.0 / 5040.0,
    1.0 / 40320.0,
];

/// 1/(2k + 1), k = 0 … 6: ln(1 + x) = 2 atanh(s) = 2s Σ s^(2k)/(2k + 1), s = x/(2 + x), to
/// s¹³/13, the remainder below 1.5·10⁻⁸ |s| for x ∈ [−½, 0] (|s| ≤ ⅓). The WGSL twin's ln(1 + x)
/// near the peak of the inverse CDF ([`crate::Vmf::sample`]), for the reason of
/// [`EXP_M1_SERIES`].
pub const LN_1P_SERIES: [f32; 7] = [
    1.0,
    1.0 / 3.0,
    1.0 / 5.0,
    1.0 / 7.0,
    1.0 / 9.0,
    1.0 / 11.0,
    1.0 / 13.0,
];

/// Coefficients of A₃(κ)/κ in powers of κ²: 1/3, −1/45, 2/945, −1/4725, 2/93555 (the odd
/// series of coth κ − 1/κ), evaluated by Horner's scheme.
pub const MEAN_COSINE_SERIES: [f32; 5] = [
    1.0 / 3.0,
    -1.0 / 45.0,
    2.0 / 945.0,
    -1.0 / 4725.0,
    2.0 / 93555.0,
];

/// Coefficients of dA₃/dκ in powers of κ²: 1/3, −1/15, 2/189, −1/675.
pub const MEAN_COSINE_DERIVATIVE_SERIES: [f32; 4] =
    [1.0 / 3.0, -1.0 / 15.0, 2.0 / 189.0, -1.0 / 675.0];

/// Newton iterations of [`kappa_from_mean_cosine_exact`](crate::kappa_from_mean_cosine_exact)
/// at most.
pub const NEWTON_MAX_ITERATIONS: u32 = 16;

/// From this mean cosine r on, Newton solves 1 − A₃(κ) = 1 − r instead of A₃(κ) = r.
pub const NEWTON_COMPLEMENT_FROM: f32 = 0.5;

/// Newton stops once a step moves κ by at most this fraction of κ.
pub const NEWTON_RELATIVE_STEP: f32 = 1e-7;

/// sin x ≈ x + x³(s₀ + x²(s₁ + x² s₂)) on [−π/4, π/4] (Cephes' `sinf`, S. Moshier).
pub const SIN_POLY: [f32; 3] = [-1.666_665_5e-1, 8.332_161e-3, -1.951_529_6e-4];

/// cos x ≈ 1 − x²/2 + x⁴(c₀ + x²(c₁ + x² c₂)) on [−π/4, π/4] (Cephes' `cosf`).
pub const COS_POLY: [f32; 3] = [4.166_664_6e-2, -1.388_731_6e-3, 2.443_315_7e-5];

/// 1/(2i + 1) for i = 0 ..= 4: atanh s = s Σ s^{2i}/(2i + 1), the series of the `ln` of
/// [`sample_batch`](crate::sample_batch) (ln m = 2 atanh((m − 1)/(m + 1))). The shader twin
/// uses WGSL's `log`, so these are not in the WGSL tables.
pub const ATANH_SERIES: [f32; 5] = [1.0, 1.0 / 3.0, 1.0 / 5.0, 1.0 / 7.0, 1.0 / 9.0];

/// eʳ ≈ 1 + r + r² P(r), P(r) = Σ pᵢ rⁱ (i = 0 ..= 5, highest first here), on
/// |r| ≤ ½ ln 2 (Cephes' `expf`, S. Moshier): the `exp` of [`sample_batch`](crate::sample_batch).
pub const EXP_POLY: [f32; 6] = [
    1.987_569_1e-4,
    1.398_2e-3,
    8.333_452e-3,
    4.166_579_6e-2,
    1.666_666_5e-1,
    0.5,
];

/// ln 2 = `LN2_HI + LN2_LO`, the high part exact in f32 for small integer multiples
/// (Cody and Waite's range reduction of [`EXP_POLY`]).
pub const LN2_HI: f32 = 0.693_359_4;

/// See [`LN2_HI`].
pub const LN2_LO: f32 = -2.121_944_4e-4;

/// Every `f32` constant of this crate by its WGSL name (`VMF_` prefix, array entries
/// suffixed `_0`, `_1`, …), for the GPU backend's generated prelude.
pub const F32_CONSTANTS: &[(&str, f32)] = &[
    ("VMF_KAPPA_MAX", crate::KAPPA_MAX),
    ("VMF_UNIFORM_SPHERE_PDF", crate::UNIFORM_SPHERE_PDF),
    ("VMF_CLAMPED_COSINE_KAPPA", crate::CLAMPED_COSINE_KAPPA),
    ("VMF_KAPPA_TINY", KAPPA_TINY),
    ("VMF_KAPPA_SATURATED", KAPPA_SATURATED),
    ("VMF_KAPPA_SAMPLE_SATURATED", KAPPA_SAMPLE_SATURATED),
    ("VMF_KAPPA_DIRECT_EXPM1", KAPPA_DIRECT_EXPM1),
    ("VMF_SERIES_LIMIT", SERIES_LIMIT),
    ("VMF_EXP_M1_KAHAN_LIMIT", EXP_M1_KAHAN_LIMIT),
    ("VMF_EXP_M1_SERIES_0", EXP_M1_SERIES[0]),
    ("VMF_EXP_M1_SERIES_1", EXP_M1_SERIES[1]),
    ("VMF_EXP_M1_SERIES_2", EXP_M1_SERIES[2]),
    ("VMF_EXP_M1_SERIES_3", EXP_M1_SERIES[3]),
    ("VMF_EXP_M1_SERIES_4", EXP_M1_SERIES[4]),
    ("VMF_EXP_M1_SERIES_5", EXP_M1_SERIES[5]),
    ("VMF_EXP_M1_SERIES_6", EXP_M1_SERIES[6]),
    ("VMF_EXP_M1_SERIES_7", EXP_M1_SERIES[7]),
    ("VMF_LN_1P_SERIES_0", LN_1P_SERIES[0]),
    ("VMF_LN_1P_SERIES_1", LN_1P_SERIES[1]),
    ("VMF_LN_1P_SERIES_2", LN_1P_SERIES[2]),
    ("VMF_LN_1P_SERIES_3", LN_1P_SERIES[3]),
    ("VMF_LN_1P_SERIES_4", LN_1P_SERIES[4]),
    ("VMF_LN_1P_SERIES_5", LN_1P_SERIES[5]),
    ("VMF_LN_1P_SERIES_6", LN_1P_SERIES[6]),
    ("VMF_MEAN_COSINE_SERIES_0", MEAN_COSINE_SERIES[0]),
    ("VMF_MEAN_COSINE_SERIES_1", MEAN_COSINE_SERIES[1]),
    ("VMF_MEAN_COSINE_SERIES_2", MEAN_COSINE_SERIES[2]),
    ("VMF_MEAN_COSINE_SERIES_3", MEAN_COSINE_SERIES[3]),
    ("VMF_MEAN_COSINE_SERIES_4", MEAN_COSINE_SERIES[4]),
    (
        "VMF_MEAN_COSINE_DERIVATIVE_SERIES_0",
        MEAN_COSINE_DERIVATIVE_SERIES[0],
    ),
    (
        "VMF_MEAN_COSINE_DERIVATIVE_SERIES_1",
        MEAN_COSINE_DERIVATIVE_SERIES[1],
    ),
    (
        "VMF_MEAN_COSINE_DERIVATIVE_SERIES_2",
        MEAN_COSINE_DERIVATIVE_SERIES[2],
    ),
    (
        "VMF_MEAN_COSINE_DERIVATIVE_SERIES_3",
        MEAN_COSINE_DERIVATIVE_SERIES[3],
    ),
    ("VMF_NEWTON_COMPLEMENT_FROM", NEWTON_COMPLEMENT_FROM),
    ("VMF_NEWTON_RELATIVE_STEP", NEWTON_RELATIVE_STEP),
    ("VMF_SIN_POLY_0", SIN_POLY[0]),
    ("VMF_SIN_POLY_1", SIN_POLY[1]),
    ("VMF_SIN_POLY_2", SIN_POLY[2]),
    ("VMF_COS_POLY_0", COS_POLY[0]),
    ("VMF_COS_POLY_1", COS_POLY[1]),
    ("VMF_COS_POLY_2", COS_POLY[2]),
];

/// Every `u32` constant of this crate by its WGSL name, for the GPU backend's prelude.
pub const U32_CONSTANTS: &[(&str, u32)] = &[("VMF_NEWTON_MAX_ITERATIONS", NEWTON_MAX_ITERATIONS)];

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tables_are_unique_prefixed_and_match_the_typed_constants() {
        let names: std::vec::Vec<&str> = F32_CONSTANTS
            .iter()
            .map(|(n, _)| *n)
            .chain(U32_CONSTANTS.iter().map(|(n, _)| *n))
            .collect();
        for (i, a) in names.iter().enumerate() {
            assert!(a.starts_with("VMF_"), "{a}");
            assert!(!names[i + 1..].contains(a), "duplicate {a}");
        }
        let get = |name: &str| F32_CONSTANTS.iter().find(|(n, _)| *n == name).unwrap().1;
        assert_eq!(get("VMF_KAPPA_SATURATED"), KAPPA_SATURATED);
        assert_eq!(get("VMF_MEAN_COSINE_SERIES_4"), 2.0 / 93555.0);
        assert_eq!(get("VMF_COS_POLY_2"), COS_POLY[2]);
        assert!(F32_CONSTANTS.iter().all(|(_, v)| v.is_finite()));
    }
}
