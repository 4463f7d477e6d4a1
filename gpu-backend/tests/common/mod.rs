//! Shared by the GPU test files: the skip-or-context preamble, fixed-seed random inputs, the
//! tolerances of the vMF comparisons and the ADGI parity tests' probe grid and cache.
#![allow(dead_code)] // each test file uses a part

use glam::{IVec3, UVec3, Vec3};
use mcg_gpu_backend::GpuContext;
use mcg_gpu_backend::guides::adgi::{GpuProbeCache, ProbeCacheConfig};
use mcg_gpu_backend::testing::gpu_or_skip;
use mcg_hashgrid::CellKey;
use mcg_probe_cache::ProbeGrid;
use rand::{Rng, RngExt, SeedableRng};
use rand_pcg::Pcg64;

/// The shared context and a generator seeded with `seed`, or `None` (after printing why) when
/// there is no adapter and `MCG_REQUIRE_GPU` is not `1`.
pub fn gpu_and_rng(test: &str, seed: u64) -> Option<(&'static GpuContext, Pcg64)> {
    gpu_or_skip(test).map(|ctx| (ctx, Pcg64::seed_from_u64(seed)))
}

pub const EPS: f64 = f32::EPSILON as f64;

/// Tolerances of the vMF comparisons, from WGSL's accuracy table (WGSL spec, "Floating Point
/// Accuracy"): `exp(x)` within 3 + 2|x| ULP, `log(x)` within 2⁻²¹ absolute on [0.5, 2] and
/// 3 ULP elsewhere, division 2.5 ULP, `sqrt` 2.5 ULP (as 1/inverseSqrt); +, −, × correctly
/// rounded, but a compiler may fuse a multiply and an add (one rounding less), so every
/// argument computed from a few products may differ by a few ε relative. The CPU's own
/// `exp`/`ln` (≤ 1 ULP) are folded into the same terms.
pub mod tolerance {
    use super::EPS;

    /// Relative error bound of C(κ) = g(−2κ)/(4π) on the GPU (`vmf_normalization`).
    pub fn normalization(kappa: f64) -> f64 {
        if kappa > 9.0 {
            return 4.0 * EPS;
        }
        let x = 2.0 * kappa;
        if x > 0.5 {
            // expm1 = exp(−x) − 1 with |exp(−x) − 1| ≥ 0.39: the exp error of u = e^{−x}
            // relative to |u − 1| grows by u/|u − 1| ≤ 1.6; then the division.
            1.6 * (4.0 + 2.0 * x) * EPS + 5.0 * EPS
        } else if x == 0.0 {
            0.0
        } else {
            // expm1's Taylor series (`VMF_EXP_M1_SERIES`, remainder 1.1·10⁻⁸ relative): eight
            // roundings of Horner's scheme, then the division. Kahan's (u − 1)·x/ln u, which
            // the WGSL used before, is only bounded by log's 2⁻²¹ absolute error relative to
            // |ln u| ≈ x (240 % at κ = 10⁻⁷), and an NVIDIA H200 came near that bound.
            16.0 * EPS
        }
    }

    /// Relative error bound of `exp(y)` whose argument y carries a relative error of a few
    /// ε (it is a product of three factors on both sides).
    pub fn exp_of_product(y: f64) -> f64 {
        (4.0 + 2.0 * y.abs()) * EPS + 4.0 * EPS * y.abs()
    }

    /// Relative error bound of the pdf C(κ) e^{−κ|ω − μ|²/2}.
    pub fn pdf(kappa: f64, exponent: f64) -> f64 {
        normalization(kappa) + exp_of_product(exponent) + 2.0 * EPS
    }

    /// Absolute error bound of r = cos θ − 1 from `vmf_cos_theta_minus_one`.
    pub fn cos_theta_minus_one(kappa: f64, xi: f64, r: f64) -> f64 {
        if kappa < 1e-7 {
            return 2.0 * EPS;
        }
        // Error of the scale expm1(−2κ) relative to itself (it sets x = ξ·scale): exp's
        // above κ = 0.25, the series' below (see `normalization`).
        let scale = if kappa > 17.0 {
            0.0
        } else if kappa > 0.25 {
            1.6 * (4.0 + 4.0 * kappa) * EPS
        } else {
            16.0 * EPS
        };
        let x = xi * (-2.0 * kappa).exp_m1();
        if x >= -0.5 {
            // ln(1 + x) by the atanh series (`vmf_ln_1p_near`): s = x/(2 + x) within 4 ε,
            // the series' roundings and the division by κ: relative to r, plus x's error.
            return r.abs() * (scale + 24.0 * EPS);
        }
        // The tail: ln u of u = (1 − ξ) + ξ e^{−2κ} < ½, 3 ULP (|ln u| ≤ 2κ + 17); the decay
        // inside u adds (3 + 4κ) ULP of decay/u ≤ 1; then the division by κ.
        let u_ln = (2.0 * kappa).min(17.0 + 2.0 * kappa);
        let ln_abs = 4.0 * EPS * u_ln + (4.0 + 4.0 * kappa.min(17.0)) * EPS;
        ln_abs / kappa + r.abs() * (scale + 8.0 * EPS)
    }

    /// Absolute error bound of A₃(κ) on the GPU: the series below 0.5 (a few roundings),
    /// above it 2/expm1(2κ), whose relative error is exp's 3 + 4κ ULP (×1.6 for the − 1).
    pub fn mean_cosine(kappa: f64) -> f64 {
        if kappa < 0.5 {
            8.0 * EPS
        } else {
            2.0 / (2.0 * kappa).exp_m1() * (1.6 * (4.0 + 4.0 * kappa) * EPS) + 8.0 * EPS
        }
    }

    /// Distance bound between the GPU's and the CPU's unit sample for an error `dr` in r:
    /// cos θ moves by dr, sin θ = √(−r(2 + r)) by at most √(2|dr| + dr²), plus the frame's
    /// and sqrt's rounding.
    pub fn direction(dr: f64) -> f64 {
        dr + (2.0 * dr + dr * dr).sqrt() + 32.0 * EPS
    }
}

pub fn random_unit(rng: &mut impl Rng) -> Vec3 {
    loop {
        let v = Vec3::new(
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
        );
        if v.length_squared() > 1e-4 && v.length_squared() <= 1.0 {
            return v.normalize();
        }
    }
}

/// Concentrations on both sides of every switch point of the CPU code (κ_tiny = 10⁻⁷, the
/// series/closed forms at 0.25 and 0.5, C(κ) saturating at 9, sampling saturating at 17) and
/// across [0, 10⁶].
pub const KAPPAS: [f32; 22] = [
    0.0, 1e-9, 0.99e-7, 1.01e-7, 1e-4, 0.01, 0.2, 0.2499, 0.2501, 0.4999, 0.5001, 1.0, 3.0, 8.999,
    9.001, 16.99, 17.01, 50.0, 300.0, 1e4, 2e5, 1e6,
];

pub fn random_key(rng: &mut impl Rng) -> CellKey {
    let cell = IVec3::new(
        rng.random_range(-40..40),
        rng.random_range(-40..40),
        rng.random_range(-40..40),
    );
    let key = CellKey::new(cell, rng.random_range(0..12), rng.random_range(0..7));
    if rng.random_bool(0.1) {
        key.with_extra(rng.random())
    } else {
        key
    }
}

/// Distance in units in the last place between two non-negative finite floats.
pub fn ulps(a: f32, b: f32) -> u32 {
    a.to_bits().abs_diff(b.to_bits())
}

/// The 7 × 5 × 4 probe grid of the ADGI parity tests (guiding values, composed heuristics
/// words): origin, spacing and probe counts all differ per axis, so a mixed-up axis shows.
pub fn adgi_grid() -> ProbeGrid {
    ProbeGrid::new(
        Vec3::new(-1.0, 0.5, 0.0),
        Vec3::new(0.5, 0.75, 1.0),
        UVec3::new(7, 5, 4),
    )
    .unwrap()
}

/// ADGI's probe cache on `grid` (`ProbeCacheConfig::adgi`, one blend ray per probe).
pub fn adgi_cache(ctx: &GpuContext, grid: ProbeGrid) -> GpuProbeCache {
    GpuProbeCache::new(ctx, &ProbeCacheConfig::adgi(grid, 1)).unwrap()
}
