//! The Metropolis random walk that ADGI uses to place probe updates (ADGI sec. 3.3,
//! Algorithm 1 and appendix A, Algorithm 5).

use crate::error::WalkError;
use crate::math;

/// The standard normal quantile Φ⁻¹(u) of a uniform `u` in [0, 1).
///
/// Φ⁻¹(u) = √2 · erf⁻¹(2u − 1), with erf⁻¹ from M. Giles' single-precision approximation
/// (*Approximating the erfinv function*, GPU Computing Gems Jade, 2011): two polynomials in
/// w = −ln(1 − x²), relative error below 4·10⁻⁷ on (−1, 1) in exact arithmetic. One uniform gives
/// one normal variate with no rejection, so a walk in `D` dimensions takes exactly `D` uniforms.
///
/// `u` is clamped to [2⁻²⁵, 1 − 2⁻²⁴] (the largest f32 below 1), so the tails end at about
/// −5.6 and +5.4 instead of ±∞; NaN maps to 0.
///
/// # Example
/// ```
/// use mcg_markov_guide::standard_normal_from_uniform;
/// assert_eq!(standard_normal_from_uniform(0.5), 0.0);
/// assert!((standard_normal_from_uniform(0.975) - 1.959_964).abs() < 1e-5);
/// ```
#[inline]
#[must_use]
pub fn standard_normal_from_uniform(u: f32) -> f32 {
    const LOW: f32 = NORMAL_QUANTILE_U_MIN; // 2⁻²⁵
    const HIGH: f32 = 1.0 - 1.0 / 16_777_216.0; // 1 − 2⁻²⁴
    if u.is_nan() {
        return 0.0;
    }
    let u = u.clamp(LOW, HIGH);
    // (1 − x)(1 + x) = 4u(1 − u) with x = 2u − 1 avoids the cancellation of 1 − x² near |x| = 1.
    let x = 2.0 * u - 1.0;
    let w = -math::ln(4.0 * u * (1.0 - u));
    let p = if w < NORMAL_QUANTILE_SWITCH {
        horner(&NORMAL_QUANTILE_CENTRAL, w - 2.5)
    } else {
        horner(&NORMAL_QUANTILE_TAIL, math::sqrt(w) - 3.0)
    };
    core::f32::consts::SQRT_2 * p * x
}

/// Giles' erf⁻¹ polynomial in `w − 2.5` for `w = −ln(1 − x²) <` [`NORMAL_QUANTILE_SWITCH`]
/// (the central region), highest degree first ([`standard_normal_from_uniform`]).
pub const NORMAL_QUANTILE_CENTRAL: [f32; 9] = [
    2.810_226_4e-8,
    3.432_739_4e-7,
    -3.523_387_7e-6,
    -4.391_506_5e-6,
    2.185_808_7e-4,
    -1.253_725e-3,
    -4.177_681_6e-3,
    2.466_407_3e-1,
    1.501_409_4,
];

/// Giles' erf⁻¹ polynomial in `√w − 3` for `w ≥` [`NORMAL_QUANTILE_SWITCH`] (the tails),
/// highest degree first.
pub const NORMAL_QUANTILE_TAIL: [f32; 9] = [
    -2.002_142_6e-4,
    1.009_505_6e-4,
    1.349_343_2e-3,
    -3.673_428_4e-3,
    5.739_507_7e-3,
    -7.622_461_3e-3,
    9.438_870_5e-3,
    1.001_674,
    2.832_976_8,
];

/// Where Giles' erf⁻¹ switches from the central polynomial to the tail's: `w = 5`.
pub const NORMAL_QUANTILE_SWITCH: f32 = 5.0;

/// The smallest uniform [`standard_normal_from_uniform`] reads, 2⁻²⁵ (smaller ones are clamped
/// to it; the largest is 1 − 2⁻²⁴).
pub const NORMAL_QUANTILE_U_MIN: f32 = 1.0 / 33_554_432.0;

/// `c[0]·tⁿ + … + c[n]` by Horner's rule, each step `c[i] + p · t` rounded twice (no FMA).
#[inline(always)]
fn horner(c: &[f32; 9], t: f32) -> f32 {
    let mut p = c[0];
    for &ci in &c[1..] {
        p = ci + p * t;
    }
    p
}

/// The persisted state of one Metropolis chain: its position x ∈ ℝᴰ and the target value h(x)
/// last computed there (ADGI Alg. 1 line 2, `S[j]`).
///
/// A chain whose `target` is 0 (for example a zeroed one) accepts the first proposal with
/// h > 0, so chains can be started anywhere in the domain; start them at positions drawn from
/// the caller's uniforms over the domain.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MetropolisChain<const D: usize> {
    /// The current position x.
    pub x: [f32; D],
    /// h(x), the (unnormalised, non-negative) target at `x` when it was last evaluated.
    pub target: f32,
}

impl<const D: usize> MetropolisChain<D> {
    /// A chain at `x` whose target value is not yet known (0).
    #[inline]
    #[must_use]
    pub const fn new(x: [f32; D]) -> Self {
        Self { x, target: 0.0 }
    }
}

/// The uniforms of one random-walk step: one per dimension for the Gaussian proposal, and one
/// for the acceptance test.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StepUniforms<const D: usize> {
    /// Uniforms in [0, 1) turned into the proposal's normal variates.
    pub proposal: [f32; D],
    /// Uniform in [0, 1) of the acceptance test (ε in ADGI Alg. 5 line 5).
    pub accept: f32,
}

/// A random walk with Gaussian proposals x' = x + σ ⊙ 𝒩(0, 1) and Metropolis acceptance
/// min(1, h(x')/h(x)) (ADGI appendix A, Algorithm 5).
///
/// The proposal is symmetric, so the walk's stationary distribution is h normalised, for any
/// non-negative h with finite integral that the walk can reach. Targets are taken as given:
/// NaN, infinite or negative values of h count as 0, so a bad evaluation is never accepted
/// and never sticks to the chain.
///
/// # Example
/// ```
/// use mcg_markov_guide::{MetropolisChain, RandomWalk, StepUniforms};
///
/// // A 2-D walk on the unit square with target h(x) = x₀ + x₁.
/// let walk = RandomWalk::new([0.1, 0.1])?;
/// let mut chain = MetropolisChain::new([0.5, 0.5]);
/// let h = |x: &[f32; 2]| {
///     if x.iter().all(|c| (0.0..1.0).contains(c)) { x[0] + x[1] } else { 0.0 }
/// };
/// chain.target = h(&chain.x);
/// let accepted = walk.step(&mut chain, h, &StepUniforms { proposal: [0.7, 0.6], accept: 0.3 });
/// assert!(accepted && chain.x[0] > 0.5 && chain.x[1] > 0.5);
/// # Ok::<(), mcg_markov_guide::WalkError>(())
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RandomWalk<const D: usize> {
    step: [f32; D],
}

impl<const D: usize> RandomWalk<D> {
    /// A walk with per-dimension step sizes σ (standard deviations of the proposal), each in
    /// (0, [`RandomWalk::STEP_MAX`]] = (0, 10³⁰].
    ///
    /// # Errors
    /// [`WalkError::StepNotFinite`] or [`WalkError::StepNotPositive`] for a σ that is NaN,
    /// infinite, zero or negative; [`WalkError::StepAboveMax`] for σ > 10³⁰ (σ·Φ⁻¹(u), up to
    /// 5.6σ, must stay finite); [`WalkError::NoDimensions`] when `D = 0`.
    pub fn new(step: [f32; D]) -> Result<Self, WalkError> {
        if D == 0 {
            return Err(WalkError::NoDimensions);
        }
        for (dimension, s) in step.into_iter().enumerate() {
            if !s.is_finite() {
                return Err(WalkError::StepNotFinite { dimension, step: s });
            }
            if !(s > 0.0) {
                return Err(WalkError::StepNotPositive { dimension, step: s });
            }
            if s > Self::STEP_MAX {
                return Err(WalkError::StepAboveMax {
                    dimension,
                    step: s,
                    maximum: Self::STEP_MAX,
                });
            }
        }
        Ok(Self { step })
    }

    /// The largest accepted step size σ, 10³⁰: far beyond any scene scale, and small enough
    /// that a step σ·Φ⁻¹(u) (|Φ⁻¹(u)| ≤ 5.6) is a finite f32.
    pub const STEP_MAX: f32 = 1.0e30;

    /// The per-dimension step sizes σ.
    #[inline]
    #[must_use]
    pub const fn step_sizes(&self) -> [f32; D] {
        self.step
    }

    /// The proposal x' = x + σ ⊙ Φ⁻¹(u) (ADGI Alg. 5 line 2).
    ///
    /// Each coordinate saturates at ±`f32::MAX`, so a finite `x` always gives a finite
    /// proposal (NaN in `x` stays NaN; `u` is handled as in [`standard_normal_from_uniform`]).
    #[inline]
    #[must_use]
    pub fn propose(&self, x: &[f32; D], u: &[f32; D]) -> [f32; D] {
        core::array::from_fn(|i| {
            (x[i] + self.step[i] * standard_normal_from_uniform(u[i])).clamp(-f32::MAX, f32::MAX)
        })
    }

    /// One random-walk step (ADGI Alg. 5): proposes, evaluates `target` once at the proposal,
    /// and accepts with probability min(1, h(x')/h(x)). Returns whether the proposal was
    /// accepted; on rejection the chain is unchanged.
    ///
    /// A chain whose stored `target` is 0 accepts any proposal with h(x') > 0.
    #[inline]
    pub fn step<F>(
        &self,
        chain: &mut MetropolisChain<D>,
        mut target: F,
        u: &StepUniforms<D>,
    ) -> bool
    where
        F: FnMut(&[f32; D]) -> f32,
    {
        let proposal = self.propose(&chain.x, &u.proposal);
        let h = crate::math::finite_non_negative_or_zero(target(&proposal));
        // Accept when ε < h'/h, written without the division: ε·h < h' (and h' > 0, so a zero
        // target never moves the chain). With h = 0 every h' > 0 is accepted.
        let accepted = h > 0.0 && u.accept * chain.target < h;
        if accepted {
            chain.x = proposal;
            chain.target = h;
        }
        accepted
    }

    /// One frame of ADGI's Algorithm 1: re-evaluates h at the persisted position (the target
    /// may have changed since the last frame), runs `schedule.iterations` steps, discards the
    /// positions after the first `schedule.burn_in` steps and hands each later position to
    /// `emit` (rejected proposals repeat the current position, as a Metropolis sample should).
    /// Returns the number of emitted samples, `iterations − burn_in`.
    ///
    /// `uniforms` is called once per step.
    ///
    /// Algorithm 1 writes the emission test as `i > K` for a 0-based step index, which would
    /// drop K + 1 samples; we follow the text ("we reject initial K samples per frame").
    pub fn run_frame<F, U, E>(
        &self,
        chain: &mut MetropolisChain<D>,
        schedule: FrameSchedule,
        mut target: F,
        mut uniforms: U,
        mut emit: E,
    ) -> u32
    where
        F: FnMut(&[f32; D]) -> f32,
        U: FnMut() -> StepUniforms<D>,
        E: FnMut(&[f32; D]),
    {
        chain.target = crate::math::finite_non_negative_or_zero(target(&chain.x));
        for i in 0..schedule.iterations {
            self.step(chain, &mut target, &uniforms());
            if i >= schedule.burn_in {
                emit(&chain.x);
            }
        }
        schedule.iterations - schedule.burn_in
    }
}

impl RandomWalk<5> {
    /// ADGI's static chain over probe position and direction (sec. 4.8): σ = (s, s, s, a, a)
    /// with s the probe spacing (ADGI: "proportional to the size of a voxel in the probe grid";
    /// we take the factor 1) and a = √(π/256) ≈ 0.111 in the units of the two direction
    /// coordinates (radians of a spherical parametrisation, or ≈ texel-sized steps of an
    /// octahedral map in [−1, 1]²).
    ///
    /// # Errors
    /// As [`RandomWalk::new`], for a spacing that is not finite and positive.
    pub fn adgi_static(probe_spacing: f32) -> Result<Self, WalkError> {
        Self::adgi(probe_spacing, 1.0, 1.0)
    }

    /// ADGI's dynamic chain (sec. 4.9): steps 3× (position) and 6× (direction) those of
    /// [`RandomWalk::adgi_static`], so the chain can follow a moving target.
    ///
    /// # Errors
    /// As [`RandomWalk::new`], for a spacing that is not finite and positive.
    pub fn adgi_dynamic(probe_spacing: f32) -> Result<Self, WalkError> {
        Self::adgi(probe_spacing, 3.0, 6.0)
    }

    fn adgi(
        probe_spacing: f32,
        position_scale: f32,
        direction_scale: f32,
    ) -> Result<Self, WalkError> {
        let s = probe_spacing * position_scale;
        let a = ADGI_DIRECTION_STEP * direction_scale;
        Self::new([s, s, s, a, a])
    }
}

/// The angular step of ADGI's static chain, √(π/256) (ADGI sec. 4.8).
pub const ADGI_DIRECTION_STEP: f32 = 0.110_778_37;

/// How many steps a chain runs per frame and how many of them are discarded (ADGI Alg. 1:
/// `M` and `K`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FrameSchedule {
    iterations: u32,
    burn_in: u32,
}

impl FrameSchedule {
    /// Our default: 8 steps per frame, the first 2 discarded (the paper gives no numbers; chains
    /// persist between frames, so a short burn-in suffices when the target changes slowly).
    pub const DEFAULT: Self = Self {
        iterations: 8,
        burn_in: 2,
    };

    /// `iterations` steps per frame (M), the first `burn_in` (K) discarded.
    ///
    /// # Errors
    /// [`WalkError::BurnInTooLong`] unless `burn_in < iterations` (Algorithm 1 requires
    /// M ≥ 2 and K < M; we only need one emitted sample, so M = 1, K = 0 is accepted too).
    pub const fn new(iterations: u32, burn_in: u32) -> Result<Self, WalkError> {
        if burn_in >= iterations {
            return Err(WalkError::BurnInTooLong {
                burn_in,
                iterations,
            });
        }
        Ok(Self {
            iterations,
            burn_in,
        })
    }

    /// M, the steps per frame.
    #[inline]
    #[must_use]
    pub const fn iterations(&self) -> u32 {
        self.iterations
    }

    /// K, the discarded steps at the start of each frame.
    #[inline]
    #[must_use]
    pub const fn burn_in(&self) -> u32 {
        self.burn_in
    }
}

impl Default for FrameSchedule {
    /// [`FrameSchedule::DEFAULT`].
    fn default() -> Self {
        Self::DEFAULT
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::string::ToString;

    /// Φ⁻¹ in f64: bisection on Φ, computed by composite Simpson integration of the density.
    fn reference_quantile(u: f64) -> f64 {
        fn cdf(x: f64) -> f64 {
            let n = 20_000;
            let h = x / n as f64;
            let f = |t: f64| (-0.5 * t * t).exp();
            let mut s = f(0.0) + f(x);
            for i in 1..n {
                let t = i as f64 * h;
                s += if i % 2 == 1 { 4.0 } else { 2.0 } * f(t);
            }
            0.5 + s * h / 3.0 / (2.0 * core::f64::consts::PI).sqrt()
        }
        let (mut lo, mut hi) = (-7.0, 7.0);
        for _ in 0..60 {
            let mid = 0.5 * (lo + hi);
            if cdf(mid) < u {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        0.5 * (lo + hi)
    }

    #[test]
    fn normal_quantile_is_accurate() {
        for &u in &[
            1e-6_f32, 1e-4, 0.001, 0.01, 0.025, 0.1, 0.3, 0.5, 0.7, 0.9, 0.975, 0.999, 0.99999,
        ] {
            let got = standard_normal_from_uniform(u) as f64;
            let want = reference_quantile(u as f64);
            mcg_test_support::assert_close!(
                got,
                want,
                2e-5 * want.abs().max(1.0),
                "Φ⁻¹({u}) = {got}, want {want}"
            );
        }
        assert_eq!(standard_normal_from_uniform(0.5), 0.0);
        assert!(standard_normal_from_uniform(0.0).is_finite());
        assert!(standard_normal_from_uniform(1.0).is_finite());
        assert_eq!(standard_normal_from_uniform(f32::NAN), 0.0);
        // Odd symmetry.
        for &u in &[0.01_f32, 0.2, 0.4] {
            let a = standard_normal_from_uniform(u);
            let b = standard_normal_from_uniform(1.0 - u);
            assert!((a + b).abs() < 1e-5);
        }
    }

    #[test]
    fn rejects_bad_steps() {
        assert!(matches!(
            RandomWalk::new([1.0, f32::NAN]),
            Err(WalkError::StepNotFinite { dimension: 1, step }) if step.is_nan()
        ));
        assert_eq!(
            RandomWalk::new([1.0, 0.0]),
            Err(WalkError::StepNotPositive {
                dimension: 1,
                step: 0.0
            })
        );
        assert_eq!(
            RandomWalk::new([-1.0]),
            Err(WalkError::StepNotPositive {
                dimension: 0,
                step: -1.0
            })
        );
        assert_eq!(RandomWalk::<0>::new([]), Err(WalkError::NoDimensions));
        assert_eq!(
            FrameSchedule::new(4, 4),
            Err(WalkError::BurnInTooLong {
                burn_in: 4,
                iterations: 4
            })
        );
        assert_eq!(
            FrameSchedule::new(4, 5).unwrap_err().to_string(),
            "burn-in 5 is not shorter than the 4 steps per frame"
        );
        assert!(RandomWalk::adgi_static(0.5).is_ok());
        assert!(RandomWalk::adgi_static(-0.5).is_err());
    }

    #[test]
    fn adgi_presets_scale_as_in_the_paper() {
        let s = RandomWalk::adgi_static(0.5).unwrap().step_sizes();
        let d = RandomWalk::adgi_dynamic(0.5).unwrap().step_sizes();
        assert_eq!(s, [0.5, 0.5, 0.5, ADGI_DIRECTION_STEP, ADGI_DIRECTION_STEP]);
        assert_eq!(d[0], 1.5);
        mcg_test_support::assert_close!(d[3], 6.0 * ADGI_DIRECTION_STEP, 1e-7);
        mcg_test_support::assert_close!(
            ADGI_DIRECTION_STEP as f64,
            (core::f64::consts::PI / 256.0).sqrt(),
            1e-7
        );
    }

    #[test]
    fn huge_steps_are_rejected_and_proposals_stay_finite() {
        // Issue 14 row 11: σ = f32::MAX was accepted, `propose` returned ∞ and an accepting
        // chain ended at NaN.
        assert_eq!(
            RandomWalk::new([f32::MAX]),
            Err(WalkError::StepAboveMax {
                dimension: 0,
                step: f32::MAX,
                maximum: 1e30
            })
        );
        assert_eq!(
            RandomWalk::new([0.1, 1.1e30]),
            Err(WalkError::StepAboveMax {
                dimension: 1,
                step: 1.1e30,
                maximum: 1e30
            })
        );
        let walk = RandomWalk::new([RandomWalk::<1>::STEP_MAX]).unwrap();
        let mut chain = MetropolisChain::new([0.0]);
        for i in 0..64 {
            for x in [0.0, f32::MAX, -f32::MAX, 3e38] {
                for u in [0.0, 1e-30, 0.5, 1.0 - 1e-7, 1.0, f32::NAN] {
                    let p = walk.propose(&[x], &[u]);
                    assert!(p[0].is_finite(), "x {x} u {u}: {p:?}");
                }
            }
            let u = StepUniforms {
                proposal: [if i % 2 == 0 { 1e-9 } else { 1.0 - 1e-7 }],
                accept: 0.0,
            };
            walk.step(&mut chain, |_| 1.0, &u);
            assert!(chain.x[0].is_finite(), "step {i}: {chain:?}");
        }
    }

    #[test]
    fn bad_targets_never_stick() {
        let walk = RandomWalk::new([0.1]).unwrap();
        let mut chain = MetropolisChain::new([0.0]);
        chain.target = 1.0;
        for bad in [f32::NAN, f32::INFINITY, -1.0, 0.0] {
            let u = StepUniforms {
                proposal: [0.9],
                accept: 0.0,
            };
            assert!(!walk.step(&mut chain, |_| bad, &u));
            assert_eq!(
                chain,
                MetropolisChain {
                    x: [0.0],
                    target: 1.0
                }
            );
        }
        // A zero-target chain takes any positive proposal.
        let mut chain = MetropolisChain::new([0.0]);
        assert!(walk.step(
            &mut chain,
            |_| 1e-30,
            &StepUniforms {
                proposal: [0.9],
                accept: 0.99
            }
        ));
    }

    #[test]
    fn run_frame_emits_after_burn_in() {
        let walk = RandomWalk::new([0.2, 0.2]).unwrap();
        let mut chain = MetropolisChain::new([0.0, 0.0]);
        let schedule = FrameSchedule::new(10, 3).unwrap();
        let mut emitted = 0;
        let mut k = 0u32;
        let n = walk.run_frame(
            &mut chain,
            schedule,
            |x| (-(x[0] * x[0] + x[1] * x[1])).exp(),
            || {
                k += 1;
                let t = (k as f32 * 0.618_034).fract();
                StepUniforms {
                    proposal: [t, 1.0 - t],
                    accept: (k as f32 * 0.414_214).fract(),
                }
            },
            |_| emitted += 1,
        );
        assert_eq!((n, emitted), (7, 7));
        assert_eq!(k, 10);
        assert!(chain.target > 0.0);
    }

    #[test]
    fn value_stability() {
        let walk = RandomWalk::new([0.5, 2.0]).unwrap();
        let p = walk.propose(&[1.0, -1.0], &[0.8, 0.25]);
        // 1 + 0.5·Φ⁻¹(0.8), −1 + 2·Φ⁻¹(0.25).
        mcg_test_support::assert_close!(p[0], (1.0 + 0.5 * 0.841_621_2), 2e-6, "{p:?}");
        mcg_test_support::assert_close!(p[1], (-1.0 + 2.0 * -0.674_489_75), 4e-6, "{p:?}");
    }
}
