//! Sampling many lobes at once: the inverse CDF of [`Vmf::sample`] in a branch-free form whose
//! loop the compiler vectorises.
//!
//! [`Vmf::sample`] branches on κ and calls the platform's `ln` (its `exp` is the inlined
//! polynomial used here too); per call that is the most accurate form near the antipode, but the
//! call keeps a loop over many lobes scalar. [`sample_batch`] computes the
//! same inverse CDF (see `cos_theta_minus_one` in `vmf.rs` for the derivation) with every
//! branch turned into a select and with an inlined `ln` (atanh series) and `exp` (Cephes' `expf`),
//! so that a loop over lobes runs several lanes at once.

use glam::{Vec2, Vec3};

use crate::Vmf;
use crate::constants::KAPPA_TINY;
use crate::math;

/// Draws `out[i]` from `lobes[i]` with the uniforms `uniforms[i]` in [0, 1)², for every `i`.
///
/// The distribution, the use of each uniform and the handling of out-of-range uniforms are
/// those of [`Vmf::sample`]; the directions agree with `lobes[i].sample(uniforms[i])` to a few
/// units in the last place (the polynomial `ln`/`exp` round differently from the platform's),
/// not bit for bit. Use it when sampling many lobes in a loop: on x86-64 it runs the batch
/// several lanes wide.
///
/// # Panics
/// If `uniforms` or `out` is not as long as `lobes`.
///
/// # Example
/// ```
/// use mcg_vmf::{Vmf, sample_batch, glam::{Vec2, Vec3}};
///
/// let lobes = [Vmf::new(Vec3::Z, 50.0)?, Vmf::new(Vec3::X, 2.0)?];
/// let uniforms = [Vec2::new(0.3, 0.7), Vec2::new(0.9, 0.1)];
/// let mut out = [Vec3::ZERO; 2];
/// sample_batch(&lobes, &uniforms, &mut out);
/// for (lobe, (w, u)) in lobes.iter().zip(out.iter().zip(uniforms)) {
///     assert!((*w - lobe.sample(u)).length() < 1e-5);
/// }
/// # Ok::<(), mcg_vmf::VmfError>(())
/// ```
pub fn sample_batch(lobes: &[Vmf], uniforms: &[Vec2], out: &mut [Vec3]) {
    assert_eq!(lobes.len(), uniforms.len(), "one uniform pair per lobe");
    assert_eq!(lobes.len(), out.len(), "one output direction per lobe");
    for ((lobe, u), w) in lobes.iter().zip(uniforms).zip(out.iter_mut()) {
        let r = cos_theta_minus_one_branch_free(lobe.kappa(), u.y);
        *w = lobe.direction_from(r, u.x);
    }
}

/// `cos θ − 1` for concentration κ at the uniform ξ: the inverse CDF
/// `r = ln(1 + ξ expm1(−2κ)) / κ` of [`Vmf::sample`], in the same three regimes (Goldberg's
/// `ln(u)·x/(u − 1)` near the peak, `u = (1 − ξ) + ξ e^{−2κ}` in the tail, the limit −2ξ
/// below κ = 10⁻⁷), each computed for every lane and selected.
/// The divisions by κ of the regimes share one division.
#[inline(always)]
fn cos_theta_minus_one_branch_free(kappa: f32, xi: f32) -> f32 {
    // Out-of-range uniforms are clamped like the scalar path (NaN → 0).
    let xi = crate::vmf::clamp_uniform(xi);
    // e^{−2κ} and expm1(−2κ). Above κ = 17 (`KAPPA_SAMPLE_SATURATED`) the scalar path
    // replaces them by 0 and −1; here that happens by itself: e^{−2κ} < 2⁻⁴⁹ makes
    // `e^{−2κ} − 1` round to −1 and vanishes next to 1 − ξ ≥ 2⁻²⁴ in the tail sum, so the
    // results are the same. The clamp keeps the polynomial's 2ⁿ a normal float.
    let (decay, scale) = math::exp_expm1_fast((-2.0 * kappa).max(-40.0));
    let x = xi * scale;
    let near = 1.0 + x;
    let tail = x < -0.5;
    let u = if tail { (1.0 - xi) + xi * decay } else { near };
    // ln(u)·x/((u − 1)κ) near the peak, ln(u)/κ in the tail, x/κ when u rounds to 1.
    let exact = u == 1.0;
    let numerator = if exact {
        x
    } else {
        math::ln_fast(u) * if tail { 1.0 } else { x }
    };
    let denominator = if tail | exact {
        kappa
    } else {
        (near - 1.0) * kappa
    };
    let r = if kappa < KAPPA_TINY {
        -2.0 * xi
    } else {
        numerator / denominator
    };
    r.clamp(-2.0, 0.0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::vmf::cos_theta_minus_one;

    /// The branch-free inverse CDF is as accurate as the scalar one: both are within
    /// 4·10⁻⁷ |r| + 10⁻⁴⁴ (about 6 ulps) of the f64 value `ln_1p(ξ expm1(−2κ))/κ` on a dense
    /// grid of κ over [0, 10⁶] (every regime boundary included) and ξ over [0, 1) (the far tail
    /// and the peak included).
    #[test]
    fn matches_the_scalar_inverse_cdf() {
        let mut kappas = std::vec![
            0.0, 1e-30, 9.9e-8, 1e-7, 1.01e-7, 0.25, 0.2500001, 17.0, 17.000002, 1e6
        ];
        let mut k = 1e-7_f32;
        while k < 1e6 {
            kappas.push(k);
            k *= 1.07;
        }
        for &kappa in &kappas {
            for i in 0..4096 {
                let xi = (i as f32 + 0.37) / 4096.0;
                // The far tail 1 − k·2⁻²⁴ (exact in f32) and the peak ξ → 0.
                let far = 1.0 - (i + 1) as f32 * 2f32.powi(-24);
                for xi in [xi, far, xi * 1e-6] {
                    let (k, x) = (f64::from(kappa), f64::from(xi));
                    let exact = if kappa < KAPPA_TINY {
                        -2.0 * x
                    } else {
                        ((x * (-2.0 * k).exp_m1()).ln_1p() / k).max(-2.0)
                    };
                    for (name, r) in [
                        ("branch-free", cos_theta_minus_one_branch_free(kappa, xi)),
                        ("scalar", cos_theta_minus_one(kappa, xi)),
                    ] {
                        mcg_test_support::assert_close!(
                            f64::from(r),
                            exact,
                            4e-7 * exact.abs() + 1e-44,
                            "{name}: kappa {kappa}, xi {xi}: {r} vs {exact}"
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn batch_matches_per_lobe_sampling() {
        let lobes: std::vec::Vec<Vmf> = [0.0, 1e-5, 0.1, 3.0, 30.0, 3e3, 1e6]
            .iter()
            .enumerate()
            .map(|(i, &k)| Vmf::new(Vec3::new(0.3, -0.5 + i as f32, 0.8), k).unwrap())
            .collect();
        let uniforms: std::vec::Vec<Vec2> = (0..lobes.len())
            .map(|i| Vec2::new(0.13 * i as f32 % 1.0, 0.71 * i as f32 % 1.0))
            .collect();
        let mut out = std::vec![Vec3::ZERO; lobes.len()];
        sample_batch(&lobes, &uniforms, &mut out);
        for ((lobe, &u), &w) in lobes.iter().zip(&uniforms).zip(&out) {
            assert!((w - lobe.sample(u)).length() < 1e-6, "{lobe:?} {u}");
            mcg_test_support::assert_close!(w.length(), 1.0, 1e-6);
        }
    }

    #[test]
    #[should_panic(expected = "one uniform pair per lobe")]
    fn mismatched_lengths_panic() {
        sample_batch(&[Vmf::uniform()], &[], &mut [Vec3::ZERO]);
    }
}
