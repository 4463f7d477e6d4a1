//! Techniques, integrands with closed-form integrals and small experiments for the
//! `smis_*` suites (estimators of mcg-smis).
//!
//! - [`LineTechnique`] on [0, 1) and [`SphereTechnique`] on S²: one enum per domain, so that
//!   sets mixing classical, full-support and compact-support techniques share one type (as
//!   `mcg_smis::Mmis` and `mcg_smis::Defensive` need).
//! - [`line_integrands`] and [`sphere_integrands`]: test functions with analytic integrals,
//!   smooth, peaky, multi-modal and discontinuous, with the locations of their features (where a
//!   "guided" technique distribution puts some of its lobes).
//! - [`AdaptiveTile`]: MCMM Fig. 16 in miniature, a tile of Markov chains whose lobes follow
//!   their own samples, estimated with TSMIS or SSMIS with or without the decorrelating shuffle;
//!   [`convergence_run`] follows the error of a population of tiles over growing sample counts.
//! - [`fig1_estimate`]: MMIS Fig. 1 (bottom), MMISₙ against classical MIS at a fixed budget,
//!   with [`variance_with_error`] for the variance of repeated estimates.
//!
//! The demo's section "Stochastic and marginal MIS" (`mcg-demo`) shows these same experiments;
//! the `smis_decorrelation` and `smis_mmis_fig1` suites pin their behaviour.

use std::f64::consts::PI;

use glam::{DVec3, Vec2, Vec3};
use mcg_smis::{CyclicShift, Technique, XorPermutation, smis, smis_one_sample};
use mcg_vmf::{Frame, UNIFORM_SPHERE_PDF, Vmf, uniform_sphere};
use rand::{Rng, RngExt};

// ---------------------------------------------------------------------------------------------
// Techniques on [0, 1)
// ---------------------------------------------------------------------------------------------

/// A sampling technique on [0, 1) (density with respect to length).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LineTechnique {
    /// The uniform density 1 (classical, full support).
    Uniform,
    /// `eps · 1 + (1 − eps) · L(x)`, L the Laplace density e^{−|x − c|/s} truncated to [0, 1)
    /// and renormalised. Full support when eps > 0 or the truncation keeps it positive (always).
    Laplace {
        /// Centre c ∈ [0, 1].
        c: f32,
        /// Scale s > 0.
        s: f32,
        /// Weight of the uniform density mixed in (a defensive part inside the technique).
        eps: f32,
    },
    /// Triangular density on [a, a + w) ⊂ [0, 1), peak 2/w at a + w/2: compact support.
    Tent {
        /// Left end.
        a: f32,
        /// Width.
        w: f32,
    },
    /// Uniform on [a, a + w) ⊂ [0, 1): compact support.
    Boxcar {
        /// Left end.
        a: f32,
        /// Width.
        w: f32,
    },
}

impl LineTechnique {
    /// Laplace lobe with its truncation mass Z = s (2 − e^{−c/s} − e^{−(1−c)/s}).
    fn laplace_mass(c: f32, s: f32) -> f32 {
        s * (2.0 - (-c / s).exp() - (-(1.0 - c) / s).exp())
    }
}

impl Technique for LineTechnique {
    type Sample = f32;
    type Uniform = f32;

    fn pdf(&self, x: &f32) -> f32 {
        let x = *x;
        if !(0.0..1.0).contains(&x) {
            return 0.0;
        }
        match *self {
            LineTechnique::Uniform => 1.0,
            LineTechnique::Laplace { c, s, eps } => {
                let z = Self::laplace_mass(c, s);
                eps + (1.0 - eps) * (-(x - c).abs() / s).exp() / z
            }
            LineTechnique::Tent { a, w } => {
                let y = (x - a) / w;
                if (0.0..1.0).contains(&y) {
                    2.0 / w * (1.0 - (2.0 * y - 1.0).abs())
                } else {
                    0.0
                }
            }
            LineTechnique::Boxcar { a, w } => {
                if x >= a && x < a + w {
                    1.0 / w
                } else {
                    0.0
                }
            }
        }
    }

    fn sample(&self, u: f32) -> f32 {
        let x = match *self {
            LineTechnique::Uniform => u,
            LineTechnique::Laplace { c, s, eps } => {
                if u < eps {
                    u / eps
                } else {
                    let v = (u - eps) / (1.0 - eps);
                    let z = Self::laplace_mass(c, s);
                    let left = s * (1.0 - (-c / s).exp());
                    let mass = v * z;
                    if mass < left {
                        c + s * ((-c / s).exp() + mass / s).ln()
                    } else {
                        c - s * (1.0 - (mass - left) / s).max(f32::MIN_POSITIVE).ln()
                    }
                }
            }
            LineTechnique::Tent { a, w } => {
                let y = if u < 0.5 {
                    (0.5 * u).sqrt()
                } else {
                    1.0 - (0.5 * (1.0 - u)).sqrt()
                };
                a + w * y
            }
            LineTechnique::Boxcar { a, w } => a + u * w,
        };
        x.clamp(0.0, 1.0 - f32::EPSILON / 2.0)
    }
}

// ---------------------------------------------------------------------------------------------
// Techniques on S²
// ---------------------------------------------------------------------------------------------

/// A sampling technique on S² (density per steradian).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SphereTechnique {
    /// The uniform density 1/(4π) (classical, full support).
    Uniform,
    /// `eps/(4π) + (1 − eps) · V(ω | μ, κ)`: a vMF lobe with a uniform part mixed in.
    Lobe {
        /// The vMF lobe.
        vmf: Vmf,
        /// Weight of the uniform density.
        eps: f32,
    },
    /// Uniform on the cap {ω : ω·axis ≥ cos_max}: compact support.
    Cap {
        /// Cap axis (unit).
        axis: Vec3,
        /// Cosine of the cap's half angle, in (−1, 1).
        cos_max: f32,
    },
}

impl Technique for SphereTechnique {
    type Sample = Vec3;
    type Uniform = Vec2;

    fn pdf(&self, w: &Vec3) -> f32 {
        match *self {
            SphereTechnique::Uniform => UNIFORM_SPHERE_PDF,
            SphereTechnique::Lobe { vmf, eps } => {
                eps * UNIFORM_SPHERE_PDF + (1.0 - eps) * vmf.pdf(*w)
            }
            SphereTechnique::Cap { axis, cos_max } => {
                if w.dot(axis) >= cos_max {
                    1.0 / (std::f32::consts::TAU * (1.0 - cos_max))
                } else {
                    0.0
                }
            }
        }
    }

    fn sample(&self, u: Vec2) -> Vec3 {
        match *self {
            SphereTechnique::Uniform => uniform_sphere(u),
            SphereTechnique::Lobe { vmf, eps } => {
                if u.x < eps {
                    uniform_sphere(Vec2::new(u.x / eps, u.y))
                } else {
                    vmf.sample(Vec2::new((u.x - eps) / (1.0 - eps), u.y))
                }
            }
            SphereTechnique::Cap { axis, cos_max } => {
                let z = 1.0 - u.y * (1.0 - cos_max);
                let r = (1.0 - z * z).max(0.0).sqrt();
                let (s, c) = (std::f32::consts::TAU * u.x).sin_cos();
                Frame::from_normal(axis).to_world(Vec3::new(r * c, r * s, z))
            }
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Integrands with closed-form integrals
// ---------------------------------------------------------------------------------------------

/// A test function on [0, 1) with its exact integral.
#[derive(Clone, Copy, Debug)]
pub struct LineIntegrand {
    /// Short name for messages.
    pub name: &'static str,
    /// f(x) in f64.
    pub f: fn(f64) -> f64,
    /// ∫₀¹ f(x) dx in closed form.
    pub integral: f64,
    /// Locations of the features (peaks, modes, steps) a guided lobe may start from.
    pub features: &'static [f64],
}

fn lorentz_integral(c: f64, w: f64) -> f64 {
    w * (((1.0 - c) / w).atan() + (c / w).atan())
}

/// Twelve functions on [0, 1): constant, polynomial, smooth, peaky (exponential, Lorentzian
/// peaks of width 0.01 and 0.005, a spike of width 0.01 and height 100), multi-modal
/// (sin², two peaks, five cosine modes), discontinuous (a step) and with an infinite slope
/// (√x).
#[must_use]
pub fn line_integrands() -> Vec<LineIntegrand> {
    vec![
        LineIntegrand {
            name: "constant",
            f: |_| 1.0,
            integral: 1.0,
            features: &[0.5],
        },
        LineIntegrand {
            name: "x^2",
            f: |x| x * x,
            integral: 1.0 / 3.0,
            features: &[0.9],
        },
        LineIntegrand {
            name: "sin(pi x)",
            f: |x| (PI * x).sin(),
            integral: 2.0 / PI,
            features: &[0.5],
        },
        LineIntegrand {
            name: "exp(-20x)",
            f: |x| (-20.0 * x).exp(),
            integral: (1.0 - (-20.0_f64).exp()) / 20.0,
            features: &[0.0],
        },
        LineIntegrand {
            name: "lorentz(0.3, 0.01)",
            f: |x| 1.0 / (1.0 + ((x - 0.3) / 0.01).powi(2)),
            integral: lorentz_integral(0.3, 0.01),
            features: &[0.3],
        },
        LineIntegrand {
            name: "two lorentz peaks",
            f: |x| {
                1.0 / (1.0 + ((x - 0.2) / 0.02).powi(2))
                    + 2.0 / (1.0 + ((x - 0.75) / 0.005).powi(2))
            },
            integral: lorentz_integral(0.2, 0.02) + 2.0 * lorentz_integral(0.75, 0.005),
            features: &[0.2, 0.75],
        },
        LineIntegrand {
            name: "sin^2(6 pi x)",
            f: |x| (6.0 * PI * x).sin().powi(2),
            integral: 0.5,
            features: &[0.25 / 3.0, 0.75 / 3.0, 1.25 / 3.0, 1.75 / 3.0, 2.25 / 3.0],
        },
        LineIntegrand {
            name: "step on [0.4, 0.6)",
            f: |x| if (0.4..0.6).contains(&x) { 1.0 } else { 0.0 },
            integral: 0.2,
            features: &[0.45, 0.55],
        },
        LineIntegrand {
            name: "sqrt(x)",
            f: f64::sqrt,
            integral: 2.0 / 3.0,
            features: &[0.8],
        },
        LineIntegrand {
            name: "1 + cos(10 pi x)",
            f: |x| 1.0 + (10.0 * PI * x).cos(),
            integral: 1.0,
            features: &[0.2, 0.4, 0.6, 0.8],
        },
        LineIntegrand {
            name: "30 x^2 (1-x)^2",
            f: |x| 30.0 * x * x * (1.0 - x) * (1.0 - x),
            integral: 1.0,
            features: &[0.5],
        },
        LineIntegrand {
            name: "spike 100 on [0.71, 0.72)",
            f: |x| {
                if (0.71..0.72).contains(&x) {
                    100.0
                } else {
                    0.0
                }
            },
            integral: 1.0,
            features: &[0.715],
        },
    ]
}

/// A test function on S² with its exact integral.
#[derive(Clone, Copy, Debug)]
pub struct SphereIntegrand {
    /// Short name for messages.
    pub name: &'static str,
    /// f(ω) in f64 for unit ω.
    pub f: fn(DVec3) -> f64,
    /// ∫_{S²} f(ω) dω in closed form.
    pub integral: f64,
    /// Directions of the features (need not be unit; normalised by the user).
    pub features: &'static [[f64; 3]],
}

/// Reference vMF density in f64, `κ/(2π(1 − e^{−2κ})) e^{κ(μ·ω − 1)}` for unit μ.
fn vmf64(mu: DVec3, kappa: f64, w: DVec3) -> f64 {
    kappa / (2.0 * PI * (-(-2.0 * kappa).exp_m1())) * (kappa * (mu.dot(w) - 1.0)).exp()
}

fn dir(v: [f64; 3]) -> DVec3 {
    DVec3::from_array(v).normalize()
}

const A: [f64; 3] = [1.0, 2.0, 2.0];
const B: [f64; 3] = [-2.0, 1.0, -0.5];
const C: [f64; 3] = [0.3, -1.0, 0.2];

/// Eleven functions on S²: constant, clamped cosine, polynomials, exponential, a glossy
/// cos⁸ lobe, vMF peaks of κ = 50 and 500 (peaky), a two-lobe mixture (multi-modal), and a
/// cap indicator (discontinuous).
#[must_use]
pub fn sphere_integrands() -> Vec<SphereIntegrand> {
    vec![
        SphereIntegrand {
            name: "constant",
            f: |_| 1.0,
            integral: 4.0 * PI,
            features: &[[0.0, 0.0, 1.0]],
        },
        SphereIntegrand {
            name: "max(0, z)",
            f: |w| w.z.max(0.0),
            integral: PI,
            features: &[[0.0, 0.0, 1.0]],
        },
        SphereIntegrand {
            name: "z^2",
            f: |w| w.z * w.z,
            integral: 4.0 * PI / 3.0,
            features: &[[0.0, 0.0, 1.0], [0.0, 0.0, -1.0]],
        },
        SphereIntegrand {
            name: "x^2 y^2",
            f: |w| w.x * w.x * w.y * w.y,
            integral: 4.0 * PI / 15.0,
            features: &[[1.0, 1.0, 0.0], [-1.0, 1.0, 0.0]],
        },
        SphereIntegrand {
            name: "(1 + x)^3",
            f: |w| (1.0 + w.x).powi(3),
            integral: 8.0 * PI,
            features: &[[1.0, 0.0, 0.0]],
        },
        SphereIntegrand {
            name: "exp(3z)",
            f: |w| (3.0 * w.z).exp(),
            integral: 4.0 * PI * 3.0_f64.sinh() / 3.0,
            features: &[[0.0, 0.0, 1.0]],
        },
        SphereIntegrand {
            name: "max(0, z)^8",
            f: |w| w.z.max(0.0).powi(8),
            integral: 2.0 * PI / 9.0,
            features: &[[0.0, 0.0, 1.0]],
        },
        SphereIntegrand {
            name: "vmf(A, 50)",
            f: |w| vmf64(dir(A), 50.0, w),
            integral: 1.0,
            features: &[A],
        },
        SphereIntegrand {
            name: "vmf(B, 500)",
            f: |w| vmf64(dir(B), 500.0, w),
            integral: 1.0,
            features: &[B],
        },
        SphereIntegrand {
            name: "0.3 vmf(A, 100) + 0.7 vmf(C, 20)",
            f: |w| 0.3 * vmf64(dir(A), 100.0, w) + 0.7 * vmf64(dir(C), 20.0, w),
            integral: 1.0,
            features: &[A, C],
        },
        SphereIntegrand {
            name: "cap z > 0.9",
            f: |w| if w.z > 0.9 { 1.0 } else { 0.0 },
            integral: 2.0 * PI * 0.1,
            features: &[[0.0, 0.0, 1.0]],
        },
    ]
}

// ---------------------------------------------------------------------------------------------
// Technique distributions p(t)
// ---------------------------------------------------------------------------------------------

/// Draws a "guided" Laplace lobe: with probability 1/2 its centre is near one of `features`
/// (jitter ±0.05), otherwise uniform; scale log-uniform in [0.01, 0.3]; eps = 0.1. This p(t)
/// is arbitrary — SMIS never evaluates it — but puts lobes where the integrand lives, as a
/// converged guide would.
pub fn draw_line_lobe<R: Rng + ?Sized>(rng: &mut R, features: &[f64]) -> LineTechnique {
    let c = if rng.random::<bool>() {
        let k = rng.random_range(0..features.len());
        (features[k] + 0.1 * (rng.random::<f64>() - 0.5)).clamp(0.0, 1.0)
    } else {
        rng.random::<f64>()
    };
    let s = 0.01 * 30.0_f64.powf(rng.random::<f64>());
    LineTechnique::Laplace {
        c: c as f32,
        s: s as f32,
        eps: 0.1,
    }
}

/// Draws a boxcar of width in [0.1, 0.4] placed uniformly inside [0, 1) (compact support).
pub fn draw_line_boxcar<R: Rng + ?Sized>(rng: &mut R) -> LineTechnique {
    let w = 0.1 + 0.3 * rng.random::<f32>();
    let a = (1.0 - w) * rng.random::<f32>();
    LineTechnique::Boxcar { a, w }
}

/// Draws a guided vMF lobe: with probability 1/2 its mean is near one of `features` (a vMF
/// perturbation with κ = 50), otherwise uniform; κ log-uniform in [1, 500]; eps = 0.1.
pub fn draw_sphere_lobe<R: Rng + ?Sized>(rng: &mut R, features: &[[f64; 3]]) -> SphereTechnique {
    let u = Vec2::new(rng.random(), rng.random());
    let mu = if rng.random::<bool>() {
        let k = rng.random_range(0..features.len());
        let f = dir(features[k]).as_vec3();
        Vmf::new(f, 50.0).expect("valid lobe").sample(u)
    } else {
        uniform_sphere(u)
    };
    let kappa = 500.0_f32.powf(rng.random::<f32>());
    SphereTechnique::Lobe {
        vmf: Vmf::new(mu, kappa).expect("valid lobe"),
        eps: 0.1,
    }
}

/// Draws a cap of half-angle between 40° and 100° around a uniform axis (compact support).
pub fn draw_sphere_cap<R: Rng + ?Sized>(rng: &mut R) -> SphereTechnique {
    let axis = uniform_sphere(Vec2::new(rng.random(), rng.random()));
    let angle = (40.0 + 60.0 * rng.random::<f32>()).to_radians();
    SphereTechnique::Cap {
        axis,
        cos_max: angle.cos(),
    }
}

/// Two uniforms in [0, 1) as a `Vec2`.
pub fn uniform2<R: Rng + ?Sized>(rng: &mut R) -> Vec2 {
    Vec2::new(rng.random(), rng.random())
}

// ---------------------------------------------------------------------------------------------
// MCMM Fig. 16 in miniature: a tile of adaptive chains
// ---------------------------------------------------------------------------------------------

/// How a tile of chains is turned into per-lane estimates (MCMM sec. 4.2).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Decorrelation {
    /// TSMIS: n steps per frame; after each step the states shift cyclically by one lane; each
    /// lane evaluates n-sample SMIS (MCMM eq. 8) over the n (lobe, sample) pairs it saw.
    TsmisShuffled,
    /// The same estimator without the shift: each lane's history is its own chain's.
    TsmisUnshuffled,
    /// SSMIS: every step a random xor mask permutes the states; each lane samples the state it
    /// now holds and evaluates one-sample SMIS (MCMM eq. 9) over all states of the tile.
    SsmisShuffled,
    /// The same estimator without the permutation: each lane always samples its own chain.
    SsmisUnshuffled,
}

impl Decorrelation {
    /// All four, shuffled ones first.
    pub const ALL: [Decorrelation; 4] = [
        Decorrelation::TsmisShuffled,
        Decorrelation::SsmisShuffled,
        Decorrelation::TsmisUnshuffled,
        Decorrelation::SsmisUnshuffled,
    ];

    /// Label for messages and plots.
    #[must_use]
    pub fn label(self) -> &'static str {
        match self {
            Decorrelation::TsmisShuffled => "TSMIS, cyclic shift",
            Decorrelation::TsmisUnshuffled => "TSMIS, no shift",
            Decorrelation::SsmisShuffled => "SSMIS, xor permutation",
            Decorrelation::SsmisUnshuffled => "SSMIS, no permutation",
        }
    }

    /// Whether the scheme permutes the states between lanes (the two unbiased schemes).
    #[must_use]
    pub fn is_shuffled(self) -> bool {
        matches!(
            self,
            Decorrelation::TsmisShuffled | Decorrelation::SsmisShuffled
        )
    }

    /// How many (lobe, sample) pairs one estimate divides by: [`TSMIS_STEPS`] for TSMIS (the
    /// lane's history), [`TILE`] for SSMIS (all lobes of the tile); the n of "n-TSMIS".
    #[must_use]
    pub fn estimator_size(self) -> usize {
        match self {
            Decorrelation::TsmisShuffled | Decorrelation::TsmisUnshuffled => TSMIS_STEPS,
            Decorrelation::SsmisShuffled | Decorrelation::SsmisUnshuffled => TILE,
        }
    }
}

/// Lanes per tile of [`AdaptiveTile`].
pub const TILE: usize = 8;
/// TSMIS history length n (≤ [`TILE`], so a lane's history holds n different chains).
pub const TSMIS_STEPS: usize = 4;
/// Scale of every chain's Laplace lobe.
pub const CHAIN_SCALE: f32 = 0.02;
/// Weight of the defensive uniform inside every chain's technique (MCMM Alg. 2 uses 0.2).
pub const CHAIN_DEFENSIVE: f32 = 0.2;

/// Integrand of lane `lane`: `0.2 + 4 e^{−|x − b|/0.02}` with its bump at b = 0.3 + 0.05·lane
/// (each pixel sees its own light).
#[must_use]
pub fn lane_integrand(lane: usize, x: f64) -> f64 {
    let b = 0.3 + 0.05 * lane as f64;
    0.2 + 4.0 * (-(x - b).abs() / 0.02).exp()
}

/// ∫₀¹ of [`lane_integrand`] in closed form.
#[must_use]
pub fn lane_integral(lane: usize) -> f64 {
    let b = 0.3 + 0.05 * lane as f64;
    let w = 0.02;
    0.2 + 4.0 * w * (2.0 - (-b / w).exp() - (-(1.0 - b) / w).exp())
}

/// One Markov chain: the centre of its lobe and the score it was accepted with.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ChainState {
    /// Centre c of the Laplace lobe (the auxiliary variable t).
    pub center: f32,
    /// f at the centre, in the lane where it was accepted (MCMM Alg. 3's S.f).
    pub score: f32,
}

impl ChainState {
    /// The chain's technique p(x | t): `0.2 · 1 + 0.8 · Laplace(center, 0.02)`.
    #[must_use]
    pub fn technique(&self) -> LineTechnique {
        LineTechnique::Laplace {
            c: self.center,
            s: CHAIN_SCALE,
            eps: CHAIN_DEFENSIVE,
        }
    }
}

/// A tile of [`TILE`] pixels (lanes), each with its own integrand ([`lane_integrand`]) and one
/// Markov chain state. A chain samples its lobe, and the sample advances it: accepted with
/// probability min(1, f(x)/score) (MCMM Alg. 3), the lobe moves to the sample. So a chain's
/// next lobe depends on its own last sample — the dependency MCMM sec. 4.2 removes by shuffling
/// states between lanes.
#[derive(Clone, Debug)]
pub struct AdaptiveTile {
    states: [ChainState; TILE],
}

impl AdaptiveTile {
    /// Chains started at uniform centres.
    pub fn new<R: Rng + ?Sized>(rng: &mut R) -> Self {
        let states = std::array::from_fn(|lane| {
            let center = rng.random::<f32>();
            ChainState {
                center,
                score: lane_integrand(lane, f64::from(center)) as f32,
            }
        });
        Self { states }
    }

    /// The current states, lane by lane.
    #[must_use]
    pub fn states(&self) -> &[ChainState; TILE] {
        &self.states
    }

    /// Advances the chain in `lane` with sample `x` whose value in that lane is `f`.
    fn advance<R: Rng + ?Sized>(&mut self, lane: usize, x: f32, f: f32, rng: &mut R) {
        let s = &mut self.states[lane];
        if rng.random::<f32>() * s.score < f {
            *s = ChainState {
                center: x,
                score: f,
            };
        }
    }

    /// Runs one frame with the given scheme and adds each lane's estimate of its integral to
    /// `out[lane]`; returns the samples per lane it took (n for TSMIS, 1 for SSMIS).
    pub fn frame<R: Rng + ?Sized>(
        &mut self,
        scheme: Decorrelation,
        rng: &mut R,
        out: &mut [f64; TILE],
    ) -> usize {
        match scheme {
            Decorrelation::TsmisShuffled | Decorrelation::TsmisUnshuffled => {
                let shift = CyclicShift::new(TILE as u32, 1).expect("valid shift");
                let mut techniques = [[LineTechnique::Uniform; TSMIS_STEPS]; TILE];
                let mut samples = [[0.0_f32; TSMIS_STEPS]; TILE];
                let mut values = [[0.0_f32; TSMIS_STEPS]; TILE];
                for step in 0..TSMIS_STEPS {
                    for lane in 0..TILE {
                        let t = self.states[lane].technique();
                        let x = t.sample(rng.random());
                        let f = lane_integrand(lane, f64::from(x)) as f32;
                        techniques[lane][step] = t;
                        samples[lane][step] = x;
                        values[lane][step] = f;
                        self.advance(lane, x, f, rng);
                    }
                    if scheme == Decorrelation::TsmisShuffled {
                        shift.apply(&mut self.states);
                    }
                }
                for lane in 0..TILE {
                    out[lane] += f64::from(smis(&techniques[lane], &samples[lane], &values[lane]));
                }
                TSMIS_STEPS
            }
            Decorrelation::SsmisShuffled | Decorrelation::SsmisUnshuffled => {
                if scheme == Decorrelation::SsmisShuffled {
                    XorPermutation::from_uniform(TILE as u32, rng.random())
                        .expect("valid tile")
                        .apply(&mut self.states);
                }
                let set: [LineTechnique; TILE] =
                    std::array::from_fn(|l| self.states[l].technique());
                for lane in 0..TILE {
                    let x = set[lane].sample(rng.random());
                    let f = lane_integrand(lane, f64::from(x)) as f32;
                    out[lane] += f64::from(smis_one_sample(&set, &x, f));
                    self.advance(lane, x, f, rng);
                }
                1
            }
        }
    }
}

/// How the per-pixel running means of a population of [`AdaptiveTile`]s converge (MCMM
/// Fig. 16 in miniature): the result of [`convergence_run`].
#[derive(Clone, Debug, PartialEq)]
pub struct Convergence {
    /// The scheme that made the estimates.
    pub scheme: Decorrelation,
    /// `(samples per pixel, relative RMSE)` at every checkpoint: the root mean square over all
    /// pixels of (running mean − exact)/exact, after [`TSMIS_STEPS`]·2ᵏ samples per pixel.
    pub points: Vec<(f64, f64)>,
    /// Mean over all pixels of (running mean − exact)/exact at the end of the run.
    pub bias: f64,
    /// Standard error of [`Convergence::bias`]: the spread of the tiles' lane-averaged relative
    /// errors / √tiles (the tiles are independent; the lanes of one tile are not).
    pub bias_error: f64,
}

impl Convergence {
    /// Least-squares slope of ln(RMSE) against ln(samples per pixel) over the last `k`
    /// checkpoints (NaN with fewer than two): −1/2 for an unbiased Monte Carlo estimate, 0 for
    /// an error that has stalled at a bias.
    #[must_use]
    pub fn tail_slope(&self, k: usize) -> f64 {
        let tail = &self.points[self.points.len().saturating_sub(k)..];
        let n = tail.len() as f64;
        if tail.len() < 2 {
            return f64::NAN;
        }
        let (xs, ys): (Vec<f64>, Vec<f64>) = tail.iter().map(|&(x, y)| (x.ln(), y.ln())).unzip();
        let mx = xs.iter().sum::<f64>() / n;
        let my = ys.iter().sum::<f64>() / n;
        let sxy: f64 = xs.iter().zip(&ys).map(|(x, y)| (x - mx) * (y - my)).sum();
        let sxx: f64 = xs.iter().map(|x| (x - mx).powi(2)).sum();
        sxy / sxx
    }

    /// The relative RMSE at the last checkpoint (NaN if there is none).
    #[must_use]
    pub fn final_rmse(&self) -> f64 {
        self.points.last().map_or(f64::NAN, |p| p.1)
    }
}

/// Runs `tiles` independent [`AdaptiveTile`]s (started with [`AdaptiveTile::new`], one after
/// the other) frame by frame with `scheme` until every pixel has at least `max_spp` samples,
/// and records the error of each pixel's running mean of its frame estimates at
/// [`TSMIS_STEPS`], 2·[`TSMIS_STEPS`], 4·[`TSMIS_STEPS`], … samples per pixel
/// ([`Convergence`]). Every frame runs all tiles in order, so the random stream, and hence the
/// result, is fixed by `rng`'s state. Needs `tiles ≥ 2` for the bias's standard error.
pub fn convergence_run<R: Rng + ?Sized>(
    scheme: Decorrelation,
    tiles: usize,
    max_spp: usize,
    rng: &mut R,
) -> Convergence {
    let mut population: Vec<AdaptiveTile> = (0..tiles).map(|_| AdaptiveTile::new(rng)).collect();
    let exact: [f64; TILE] = std::array::from_fn(lane_integral);
    let mut sums = vec![[0.0_f64; TILE]; tiles];
    let (mut spp, mut frames) = (0, 0);
    let mut next_checkpoint = TSMIS_STEPS;
    let mut points = Vec::new();
    let relative = |sums: &[f64; TILE], frames: usize, lane: usize| {
        sums[lane] / frames as f64 / exact[lane] - 1.0
    };
    while spp < max_spp {
        let mut taken = 0;
        for (tile, sum) in population.iter_mut().zip(&mut sums) {
            taken = tile.frame(scheme, rng, sum);
        }
        frames += 1;
        spp += taken;
        if spp >= next_checkpoint {
            let squares: f64 = sums
                .iter()
                .flat_map(|s| (0..TILE).map(move |lane| relative(s, frames, lane).powi(2)))
                .sum();
            points.push((spp as f64, (squares / (tiles * TILE) as f64).sqrt()));
            next_checkpoint *= 2;
        }
    }
    let per_tile: Vec<f64> = sums
        .iter()
        .map(|s| (0..TILE).map(|lane| relative(s, frames, lane)).sum::<f64>() / TILE as f64)
        .collect();
    let bias = per_tile.iter().sum::<f64>() / tiles as f64;
    let var = per_tile.iter().map(|b| (b - bias).powi(2)).sum::<f64>() / (tiles - 1) as f64;
    Convergence {
        scheme,
        points,
        bias,
        bias_error: (var / tiles as f64).sqrt(),
    }
}

// ---------------------------------------------------------------------------------------------
// MMIS Fig. 1 (bottom): four marginal techniques with 1-D technique spaces
// ---------------------------------------------------------------------------------------------

/// A marginal technique of the MMIS canonical experiment: t ~ U(0, 1), then x | t is a tent
/// (triangular density) on [lo + t·span, lo + t·span + width). Its x-marginal,
/// (T(x − lo) − T(x − lo − span))/span with T the tent's CDF, is known in closed form
/// ([`MarginalBoxcar::marginal_pdf`]); the classical MIS reference evaluates it.
/// `span = 0` with `lo = 0`, `width = 1` is the defensive technique (uniform x for every t).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MarginalBoxcar {
    /// Left end of the box at t = 0.
    pub lo: f64,
    /// How far the box moves as t goes from 0 to 1.
    pub span: f64,
    /// Width of the box.
    pub width: f64,
}

impl MarginalBoxcar {
    /// The conditional technique p(x | t).
    #[must_use]
    pub fn conditional(&self, t: f64) -> LineTechnique {
        if self.span == 0.0 {
            return LineTechnique::Boxcar {
                a: self.lo as f32,
                w: self.width as f32,
            };
        }
        LineTechnique::Tent {
            a: (self.lo + t * self.span) as f32,
            w: self.width as f32,
        }
    }

    /// CDF of the tent on [0, w).
    fn tent_cdf(&self, y: f64) -> f64 {
        let v = (y / self.width).clamp(0.0, 1.0);
        if v < 0.5 {
            2.0 * v * v
        } else {
            1.0 - 2.0 * (1.0 - v) * (1.0 - v)
        }
    }

    /// The marginal p(x) = ∫₀¹ p(x | t) dt = (T(x − lo) − T(x − lo − span)) / span.
    #[must_use]
    pub fn marginal_pdf(&self, x: f64) -> f64 {
        if self.span == 0.0 {
            return if x >= self.lo && x < self.lo + self.width {
                1.0 / self.width
            } else {
                0.0
            };
        }
        (self.tent_cdf(x - self.lo) - self.tent_cdf(x - self.lo - self.span)) / self.span
    }
}

/// The four techniques of the experiment: three that each cover one feature of
/// [`fig1_integrand`] but not the whole domain, and the defensive uniform one.
pub const FIG1_TECHNIQUES: [MarginalBoxcar; 4] = [
    MarginalBoxcar {
        lo: 0.0,
        span: 0.25,
        width: 0.15,
    },
    MarginalBoxcar {
        lo: 0.3,
        span: 0.2,
        width: 0.1,
    },
    MarginalBoxcar {
        lo: 0.55,
        span: 0.35,
        width: 0.1,
    },
    MarginalBoxcar {
        lo: 0.0,
        span: 0.0,
        width: 1.0,
    },
];

/// Integrand of the experiment: a small background and three triangular bumps, one per
/// feature technique: `0.05 + Σ h_k · max(0, 1 − |x − c_k|/r_k)`.
#[must_use]
pub fn fig1_integrand(x: f64) -> f64 {
    let tri = |c: f64, r: f64| (1.0 - (x - c).abs() / r).max(0.0);
    0.05 + 2.0 * tri(0.2, 0.1) + 4.0 * tri(0.42, 0.05) + 3.0 * tri(0.75, 0.1)
}

/// ∫₀¹ [`fig1_integrand`]: 0.05 + 2·0.1 + 4·0.05 + 3·0.1.
pub const FIG1_INTEGRAL: f64 = 0.05 + 0.2 + 0.2 + 0.3;

/// Total sample budget of one estimate (the paper's N = 64).
pub const FIG1_BUDGET: usize = 64;

/// The n of the MMISₙ estimators compared in the experiment (MMIS Fig. 1 shows n = 1…16).
pub const FIG1_NS: [usize; 5] = [1, 2, 4, 8, 16];

/// One estimate of the experiment with total budget [`FIG1_BUDGET`]: `n = None` is the
/// classical MIS reference (N/T samples per technique, exact marginals, balance heuristic);
/// `Some(n)` is MMISₙ: n technique-sample pairs per technique, averaged over N/(nT)
/// independent realizations (MMIS sec. 3.2).
pub fn fig1_estimate<R: Rng + ?Sized>(n: Option<usize>, rng: &mut R) -> f64 {
    let techniques = FIG1_TECHNIQUES.len();
    match n {
        None => {
            let per = FIG1_BUDGET / techniques;
            let mut sum = 0.0;
            for tech in &FIG1_TECHNIQUES {
                for _ in 0..per {
                    let x = f64::from(tech.conditional(rng.random()).sample(rng.random()));
                    let d: f64 = FIG1_TECHNIQUES
                        .iter()
                        .map(|t| per as f64 * t.marginal_pdf(x))
                        .sum();
                    sum += fig1_integrand(x) / d;
                }
            }
            sum
        }
        Some(n) => {
            let realizations = FIG1_BUDGET / (n * techniques);
            let mut pairs = vec![LineTechnique::Uniform; n * techniques];
            let mut samples = vec![0.0_f32; n * techniques];
            let mut values = vec![0.0_f32; n * techniques];
            let mut total = 0.0;
            for _ in 0..realizations {
                for (i, tech) in FIG1_TECHNIQUES.iter().enumerate() {
                    for j in 0..n {
                        let c = tech.conditional(rng.random());
                        let x = c.sample(rng.random());
                        pairs[i * n + j] = c;
                        samples[i * n + j] = x;
                        values[i * n + j] = fig1_integrand(f64::from(x)) as f32;
                    }
                }
                let spaces: Vec<&[LineTechnique]> = pairs.chunks(n).collect();
                let mmis = mcg_smis::Mmis::new(&spaces);
                total += f64::from(mmis.estimate(&samples, &values));
            }
            total / realizations as f64
        }
    }
}

/// `realizations` independent estimates [`fig1_estimate`]`(n, rng)`, in order.
pub fn fig1_estimates<R: Rng + ?Sized>(
    n: Option<usize>,
    realizations: usize,
    rng: &mut R,
) -> Vec<f64> {
    (0..realizations).map(|_| fig1_estimate(n, rng)).collect()
}

/// The unbiased sample variance s² of `values` (R of them, R ≥ 4) and its standard error
/// √((m₄ − s⁴(R − 3)/(R − 1))/R), m₄ the fourth central moment: the error bar of a variance
/// measured from R independent estimates, as in MMIS Fig. 1.
#[must_use]
pub fn variance_with_error(values: &[f64]) -> (f64, f64) {
    let r = values.len() as f64;
    let mean = values.iter().sum::<f64>() / r;
    let m2 = values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / r;
    let m4 = values.iter().map(|v| (v - mean).powi(4)).sum::<f64>() / r;
    let s2 = m2 * r / (r - 1.0);
    let se = ((m4 - s2 * s2 * (r - 3.0) / (r - 1.0)) / r).max(0.0).sqrt();
    (s2, se)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{GaussLegendre, seeded_rng};

    #[test]
    fn line_techniques_are_normalised_and_sample_their_pdf() {
        let rule = GaussLegendre::new(64);
        for t in [
            LineTechnique::Uniform,
            LineTechnique::Laplace {
                c: 0.3,
                s: 0.05,
                eps: 0.1,
            },
            LineTechnique::Laplace {
                c: 0.0,
                s: 0.2,
                eps: 0.0,
            },
            LineTechnique::Boxcar { a: 0.2, w: 0.3 },
        ] {
            // Piecewise quadrature over 200 panels (the Laplace kink and box edges).
            let total: f64 = (0..200)
                .map(|k| {
                    let (a, b) = (k as f64 / 200.0, (k + 1) as f64 / 200.0);
                    rule.integrate(a, b, |x| f64::from(t.pdf(&(x as f32))))
                })
                .sum();
            mcg_test_support::assert_close!(total, 1.0, 2e-3, "{t:?}: {total}");
            // Inverse-CDF check: the fraction of samples below q matches the CDF.
            let mut rng = seeded_rng(0x5315_0001);
            let n = 100_000;
            let below = (0..n).filter(|_| t.sample(rng.random()) < 0.35).count() as f64 / n as f64;
            let cdf: f64 = (0..70)
                .map(|k| {
                    let (a, b) = (k as f64 * 0.005, (k + 1) as f64 * 0.005);
                    rule.integrate(a, b, |x| f64::from(t.pdf(&(x as f32))))
                })
                .sum();
            mcg_test_support::assert_close!(
                below,
                cdf,
                5.0 * (cdf * (1.0 - cdf) / n as f64).sqrt() + 1e-3
            );
        }
    }

    #[test]
    fn convergence_run_checkpoints_and_slope() {
        let mut rng = seeded_rng(0x5315_0002);
        let run = convergence_run(Decorrelation::SsmisShuffled, 4, 64, &mut rng);
        let spp: Vec<f64> = run.points.iter().map(|p| p.0).collect();
        assert_eq!(spp, [4.0, 8.0, 16.0, 32.0, 64.0]);
        assert!(run.points.iter().all(|p| p.1.is_finite() && p.1 > 0.0));
        assert!(run.bias.is_finite() && run.bias_error > 0.0);
        assert_eq!(run.final_rmse(), run.points[4].1);
        // TSMIS takes TSMIS_STEPS samples per frame: the same checkpoints, fewer frames.
        let tsmis = convergence_run(Decorrelation::TsmisShuffled, 4, 64, &mut rng);
        assert_eq!(tsmis.points.len(), 5);
        // The slope of an exact power law y = 3 x^-0.5 over its last 3 points.
        let law = Convergence {
            points: (0..6)
                .map(|k| (f64::from(1 << k), 3.0 / f64::from(1 << k).sqrt()))
                .collect(),
            ..run
        };
        assert!((law.tail_slope(3) + 0.5).abs() < 1e-12);
        assert!(law.tail_slope(1).is_nan());
        assert_eq!(Decorrelation::TsmisUnshuffled.estimator_size(), TSMIS_STEPS);
        assert_eq!(Decorrelation::SsmisShuffled.estimator_size(), TILE);
        let shuffled: Vec<bool> = Decorrelation::ALL.iter().map(|d| d.is_shuffled()).collect();
        assert_eq!(shuffled, [true, true, false, false]);
    }

    #[test]
    fn variance_with_error_of_known_values() {
        // 1, 2, 3, 4: mean 2.5, m2 = 1.25, s² = 5/3, m4 = 2.5625.
        let (s2, se) = variance_with_error(&[1.0, 2.0, 3.0, 4.0]);
        mcg_test_support::assert_close!(s2, 5.0 / 3.0, 1e-12);
        let expected = ((2.5625 - s2 * s2 * (1.0 / 3.0)) / 4.0_f64).sqrt();
        mcg_test_support::assert_close!(se, expected, 1e-12);
    }

    #[test]
    fn integrals_match_quadrature() {
        let rule = GaussLegendre::new(64);
        for g in line_integrands() {
            let q: f64 = (0..2000)
                .map(|k| {
                    let (a, b) = (k as f64 / 2000.0, (k + 1) as f64 / 2000.0);
                    rule.integrate(a, b, g.f)
                })
                .sum();
            mcg_test_support::assert_close!(
                q,
                g.integral,
                1e-6 * g.integral.max(1.0),
                "{}",
                g.name
            );
        }
        for lane in 0..TILE {
            let q: f64 = (0..2000)
                .map(|k| {
                    let (a, b) = (k as f64 / 2000.0, (k + 1) as f64 / 2000.0);
                    rule.integrate(a, b, |x| lane_integrand(lane, x))
                })
                .sum();
            mcg_test_support::assert_close!(q, lane_integral(lane), 1e-9);
        }
        let q: f64 = (0..2000)
            .map(|k| {
                let (a, b) = (k as f64 / 2000.0, (k + 1) as f64 / 2000.0);
                rule.integrate(a, b, fig1_integrand)
            })
            .sum();
        mcg_test_support::assert_close!(q, FIG1_INTEGRAL, 1e-9);
        for tech in FIG1_TECHNIQUES {
            let m: f64 = (0..2000)
                .map(|k| {
                    let (a, b) = (k as f64 / 2000.0, (k + 1) as f64 / 2000.0);
                    rule.integrate(a, b, |x| tech.marginal_pdf(x))
                })
                .sum();
            mcg_test_support::assert_close!(m, 1.0, 1e-9, "{tech:?}");
        }
        for g in sphere_integrands() {
            // Panels graded towards the first feature, uniform panels beyond, and the cap edge.
            let mut breaks = crate::graded_theta_breaks(0.05);
            breaks.extend((1..256).map(|k| PI * k as f64 / 256.0));
            breaks.push(0.9_f64.acos());
            breaks.sort_by(f64::total_cmp);
            breaks.dedup();
            let q = crate::integrate_sphere(dir(g.features[0]), &breaks, 512, g.f);
            mcg_test_support::assert_close!(q, g.integral, 1e-4 * g.integral, "{}: {q}", g.name);
        }
    }
}
