//! Section "Stochastic and marginal MIS": MCMM Fig. 16 and MMIS Fig. 1 in miniature.
//!
//! Two experiments on [`mcg_smis`]:
//! 1. `convergence`: a population of adaptive Markov chains (lobes that follow their own
//!    samples, one chain per pixel, tiles of 8 pixels) estimated with TSMIS (cyclic shift,
//!    MCMM eq. 8) and SSMIS (xor permutation, MCMM eq. 9), with and without the shuffle. The
//!    error of each pixel's running mean is plotted against samples per pixel (MCMM Fig. 16).
//! 2. `mmis_variance`: the canonical MMIS experiment (West et al. 2022 Fig. 1, bottom): four
//!    marginal techniques with 1-D technique spaces, one defensive, budget N = 64; the variance
//!    of MMISₙ for n = 1…16 against classical MIS with exact marginals.

use mcg_smis::{CyclicShift, Mmis, Technique, XorPermutation, smis, smis_one_sample};
use rand::{Rng, RngExt, SeedableRng};
use rand_pcg::Pcg64Mcg;

use super::Context;
use crate::plot::{self, Axis, LineChart, PALETTE, Series, SeriesLabelPosition};
use crate::report::{Section, Table};
use crate::{Result, group_thousands};

/// Builds the section.
pub fn build(ctx: &Context<'_>) -> Result<Section> {
    let mut section = Section::new("smis", "Stochastic and marginal MIS");
    section
        .paragraph(
            "Markov chain guiding samples from lobes whose parameters t come from Markov chains \
             with an unknown equilibrium density p(t), so the density of a sample cannot be \
             evaluated. Stochastic MIS (SMIS) divides by a sum of the conditional densities of \
             the drawn lobes instead; p(t) cancels. `mcg_smis` implements the n-sample estimator \
             (MCMM eq. 8), the one-sample estimator with uniform selection (MCMM eq. 9), marginal \
             MIS over several technique spaces (MMIS eq. 6), defensive mixtures and the path form:",
        )
        .formula(
            "⟨I⟩_SMIS = Σᵢ f(xᵢ) / Σⱼ p(xᵢ | tⱼ)        ⟨I⟩¹_SMIS = f(x) / ((1/n) Σⱼ p(x | tⱼ))",
        )
        .paragraph(
            "Both are unbiased only if no lobe tⱼ depends on a sample the estimator uses (MCMM \
             appendix A) — which a chain that advances with its own sample violates. MCMM \
             decorrelates by permuting chain states between the pixels of a tile: a cyclic \
             shift by one lane after every step (TSMIS, `CyclicShift`) or a random xor mask \
             (SSMIS, `XorPermutation`). This section reproduces the paper's convergence plot \
             (MCMM Fig. 16) and West et al.'s canonical MMIS experiment (MMIS Fig. 1) in \
             miniature.",
        );
    convergence(ctx, &mut section)?;
    mmis_variance(ctx, &mut section)?;
    Ok(section)
}

// ---------------------------------------------------------------------------------------------
// Techniques used here
// ---------------------------------------------------------------------------------------------

/// Techniques on [0, 1): a defensive-mixed Laplace lobe (the chains), a tent and a uniform box
/// (the MMIS experiment).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Line {
    /// `eps + (1 − eps) · e^{−|x − c|/s} / Z` on [0, 1), Z its truncated mass.
    Laplace {
        /// Centre.
        c: f32,
        /// Scale.
        s: f32,
        /// Weight of the uniform part.
        eps: f32,
    },
    /// Triangular density on [a, a + w).
    Tent {
        /// Left end.
        a: f32,
        /// Width.
        w: f32,
    },
    /// Uniform on [a, a + w).
    Boxcar {
        /// Left end.
        a: f32,
        /// Width.
        w: f32,
    },
}

fn laplace_mass(c: f32, s: f32) -> f32 {
    s * (2.0 - (-c / s).exp() - (-(1.0 - c) / s).exp())
}

impl Technique for Line {
    type Sample = f32;
    type Uniform = f32;

    fn pdf(&self, x: &f32) -> f32 {
        let x = *x;
        if !(0.0..1.0).contains(&x) {
            return 0.0;
        }
        match *self {
            Line::Laplace { c, s, eps } => {
                eps + (1.0 - eps) * (-(x - c).abs() / s).exp() / laplace_mass(c, s)
            }
            Line::Tent { a, w } => {
                let y = (x - a) / w;
                if (0.0..1.0).contains(&y) {
                    2.0 / w * (1.0 - (2.0 * y - 1.0).abs())
                } else {
                    0.0
                }
            }
            Line::Boxcar { a, w } => {
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
            Line::Laplace { c, s, eps } => {
                if u < eps {
                    u / eps
                } else {
                    let mass = (u - eps) / (1.0 - eps) * laplace_mass(c, s);
                    let left = s * (1.0 - (-c / s).exp());
                    if mass < left {
                        c + s * ((-c / s).exp() + mass / s).ln()
                    } else {
                        c - s * (1.0 - (mass - left) / s).max(f32::MIN_POSITIVE).ln()
                    }
                }
            }
            Line::Tent { a, w } => {
                let y = if u < 0.5 {
                    (0.5 * u).sqrt()
                } else {
                    1.0 - (0.5 * (1.0 - u)).sqrt()
                };
                a + w * y
            }
            Line::Boxcar { a, w } => a + u * w,
        };
        x.clamp(0.0, 1.0 - f32::EPSILON / 2.0)
    }
}

// ---------------------------------------------------------------------------------------------
// 1. MCMM Fig. 16: convergence with and without decorrelation
// ---------------------------------------------------------------------------------------------

/// Pixels per tile (one GPU subgroup would hold up to 32).
pub const TILE: usize = 8;
/// TSMIS history length n ≤ [`TILE`].
pub const TSMIS_STEPS: usize = 4;
/// Tiles in the convergence experiment.
pub const TILES: usize = 64;

/// How chain states become estimates.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Scheme {
    /// TSMIS with the cyclic shift.
    TsmisShuffled,
    /// SSMIS with the xor permutation.
    SsmisShuffled,
    /// TSMIS without the shift.
    TsmisUnshuffled,
    /// SSMIS without the permutation.
    SsmisUnshuffled,
}

impl Scheme {
    /// All four, in plotting order.
    pub const ALL: [Scheme; 4] = [
        Scheme::TsmisShuffled,
        Scheme::SsmisShuffled,
        Scheme::TsmisUnshuffled,
        Scheme::SsmisUnshuffled,
    ];

    /// Legend label.
    pub fn label(self) -> &'static str {
        match self {
            Scheme::TsmisShuffled => "4-TSMIS, cyclic shift",
            Scheme::SsmisShuffled => "8-SSMIS, xor permutation",
            Scheme::TsmisUnshuffled => "4-TSMIS, no shuffle",
            Scheme::SsmisUnshuffled => "8-SSMIS, no permutation",
        }
    }

    fn shuffled(self) -> bool {
        matches!(self, Scheme::TsmisShuffled | Scheme::SsmisShuffled)
    }
}

/// Integrand of pixel `lane` of a tile: `0.2 + 4 e^{−|x − b|/0.02}`, b = 0.3 + 0.05·lane.
pub fn pixel_integrand(lane: usize, x: f64) -> f64 {
    0.2 + 4.0 * (-(x - bump(lane)).abs() / 0.02).exp()
}

fn bump(lane: usize) -> f64 {
    0.3 + 0.05 * lane as f64
}

/// Exact ∫₀¹ of [`pixel_integrand`].
pub fn pixel_integral(lane: usize) -> f64 {
    let (b, w) = (bump(lane), 0.02);
    0.2 + 4.0 * w * (2.0 - (-b / w).exp() - (-(1.0 - b) / w).exp())
}

#[derive(Clone, Copy, Debug)]
struct Chain {
    center: f32,
    score: f32,
}

impl Chain {
    /// `0.2 · U(0, 1) + 0.8 · Laplace(center, 0.02)`: MCMM's defensive probability 0.2.
    fn technique(self) -> Line {
        Line::Laplace {
            c: self.center,
            s: 0.02,
            eps: 0.2,
        }
    }

    /// MCMM Alg. 3: move the lobe to the sample with probability min(1, f / score).
    fn advance(&mut self, x: f32, f: f32, u: f32) {
        if u * self.score < f {
            *self = Chain {
                center: x,
                score: f,
            };
        }
    }
}

/// One tile's chains through one frame; adds each pixel's estimate to `out` and returns the
/// samples per pixel taken.
fn frame<R: Rng>(
    scheme: Scheme,
    chains: &mut [Chain; TILE],
    rng: &mut R,
    out: &mut [f64],
) -> usize {
    match scheme {
        Scheme::TsmisShuffled | Scheme::TsmisUnshuffled => {
            let shift = CyclicShift::new(TILE as u32, 1).expect("valid tile");
            let mut t = [[Line::Boxcar { a: 0.0, w: 1.0 }; TSMIS_STEPS]; TILE];
            let mut xs = [[0.0_f32; TSMIS_STEPS]; TILE];
            let mut fs = [[0.0_f32; TSMIS_STEPS]; TILE];
            for step in 0..TSMIS_STEPS {
                for lane in 0..TILE {
                    let technique = chains[lane].technique();
                    let x = technique.sample(rng.random());
                    let f = pixel_integrand(lane, f64::from(x)) as f32;
                    (t[lane][step], xs[lane][step], fs[lane][step]) = (technique, x, f);
                    chains[lane].advance(x, f, rng.random());
                }
                if scheme.shuffled() {
                    shift.apply(chains);
                }
            }
            for lane in 0..TILE {
                out[lane] += f64::from(smis(&t[lane], &xs[lane], &fs[lane]));
            }
            TSMIS_STEPS
        }
        Scheme::SsmisShuffled | Scheme::SsmisUnshuffled => {
            if scheme.shuffled() {
                XorPermutation::from_uniform(TILE as u32, rng.random())
                    .expect("valid tile")
                    .apply(chains);
            }
            let set: [Line; TILE] = std::array::from_fn(|l| chains[l].technique());
            for lane in 0..TILE {
                let x = set[lane].sample(rng.random());
                let f = pixel_integrand(lane, f64::from(x)) as f32;
                out[lane] += f64::from(smis_one_sample(&set, &x, f));
                chains[lane].advance(x, f, rng.random());
            }
            1
        }
    }
}

/// Relative RMS error over all pixels at each checkpoint of samples per pixel, and the final
/// mean relative bias with its standard error.
#[derive(Clone, Debug)]
pub struct Convergence {
    /// Which scheme.
    pub scheme: Scheme,
    /// `(samples per pixel, relative RMSE)`.
    pub points: Vec<(f64, f64)>,
    /// Mean over pixels of (estimate − exact)/exact at the last checkpoint.
    pub bias: f64,
    /// Standard error of [`Convergence::bias`] over tiles.
    pub bias_error: f64,
}

/// Runs `scheme` on [`TILES`] tiles up to `max_spp` samples per pixel.
pub fn convergence_run(scheme: Scheme, max_spp: usize, seed: u64) -> Convergence {
    let mut rng = Pcg64Mcg::seed_from_u64(seed);
    let pixels = TILES * TILE;
    let mut chains: Vec<[Chain; TILE]> = (0..TILES)
        .map(|_| {
            std::array::from_fn(|lane| {
                let center = rng.random::<f32>();
                Chain {
                    center,
                    score: pixel_integrand(lane, f64::from(center)) as f32,
                }
            })
        })
        .collect();
    let exact: Vec<f64> = (0..TILE).map(pixel_integral).collect();
    let mut sums = vec![0.0; pixels];
    let (mut spp, mut frames) = (0, 0);
    let mut next_checkpoint = TSMIS_STEPS;
    let mut points = Vec::new();
    let relative =
        |sums: &[f64], frames: usize, p: usize| sums[p] / frames as f64 / exact[p % TILE] - 1.0;
    while spp < max_spp {
        let mut taken = 0;
        for (tile, c) in chains.iter_mut().enumerate() {
            taken = frame(
                scheme,
                c,
                &mut rng,
                &mut sums[tile * TILE..(tile + 1) * TILE],
            );
        }
        frames += 1;
        spp += taken;
        if spp >= next_checkpoint {
            let mse = (0..pixels)
                .map(|p| relative(&sums, frames, p).powi(2))
                .sum::<f64>()
                / pixels as f64;
            points.push((spp as f64, mse.sqrt()));
            next_checkpoint *= 2;
        }
    }
    let per_tile: Vec<f64> = (0..TILES)
        .map(|t| {
            (0..TILE)
                .map(|l| relative(&sums, frames, t * TILE + l))
                .sum::<f64>()
                / TILE as f64
        })
        .collect();
    let bias = per_tile.iter().sum::<f64>() / TILES as f64;
    let var = per_tile.iter().map(|b| (b - bias).powi(2)).sum::<f64>() / (TILES - 1) as f64;
    Convergence {
        scheme,
        points,
        bias,
        bias_error: (var / TILES as f64).sqrt(),
    }
}

fn convergence(ctx: &Context<'_>, section: &mut Section) -> Result<()> {
    let pixels = TILES * TILE;
    let budget = (ctx.config.samples / 128).clamp(256, 8192);
    let max_spp = 1_usize << budget.ilog2();
    let bar = ctx.progress(Scheme::ALL.len() as u64, "SMIS: adaptive chains");
    let runs: Vec<Convergence> = Scheme::ALL
        .iter()
        .enumerate()
        .map(|(i, &s)| {
            let r = convergence_run(s, max_spp, ctx.config.seed.wrapping_add(0x5301 + i as u64));
            bar.inc(1);
            r
        })
        .collect();
    bar.finish_and_clear();

    let mut series: Vec<Series> = runs
        .iter()
        .enumerate()
        .map(|(i, r)| {
            Series::line(
                r.scheme.label(),
                PALETTE[i % PALETTE.len()],
                r.points.clone(),
            )
        })
        .collect();
    let first = runs[0].points.first().map_or(1.0, |p| p.1);
    series.push(Series::line(
        "∝ 1/√spp",
        plotters::style::RGBColor(150, 150, 150),
        vec![
            (TSMIS_STEPS as f64, first),
            (
                max_spp as f64,
                first * (TSMIS_STEPS as f64 / max_spp as f64).sqrt(),
            ),
        ],
    ));
    let lo = runs
        .iter()
        .flat_map(|r| r.points.iter().map(|p| p.1))
        .fold(f64::INFINITY, f64::min)
        .max(1e-6);
    let hi = runs
        .iter()
        .flat_map(|r| r.points.iter().map(|p| p.1))
        .fold(0.0, f64::max);
    let chart = LineChart {
        title: "Relative RMS error of per-pixel estimates (MCMM Fig. 16 in miniature)".to_owned(),
        x: Axis::log10("samples per pixel", TSMIS_STEPS as f64..max_spp as f64),
        y: Axis::log10(
            "relative RMSE",
            10f64.powf(lo.log10().floor())..10f64.powf(hi.log10().ceil()),
        ),
        series,
        legend: SeriesLabelPosition::LowerLeft,
    };
    let file = "smis-convergence.png";
    plot::line_chart(&ctx.figure_path(file), (1100, 640), &chart)?;

    let mut table = Table::new(
        &format!(
            "Error at {} samples per pixel over {} pixels ({} tiles of {TILE}); bias = mean over \
             pixels of (estimate − exact)/exact, ± its standard error over tiles",
            group_thousands(max_spp),
            group_thousands(pixels),
            TILES
        ),
        [
            "estimator",
            "relative RMSE",
            "relative bias",
            "bias / standard error",
            "log-log slope (last 4 points)",
        ],
    );
    for r in &runs {
        table.push_row([
            r.scheme.label().to_owned(),
            format!("{:.2e}", r.points.last().map_or(f64::NAN, |p| p.1)),
            format!("{:+.2} % ± {:.2} %", 100.0 * r.bias, 100.0 * r.bias_error),
            format!("{:+.1}", r.bias / r.bias_error),
            format!("{:+.2}", slope(&r.points, 4)),
        ]);
    }
    let shuffled_ok = runs
        .iter()
        .filter(|r| r.scheme.shuffled())
        .all(|r| (r.bias / r.bias_error).abs() < 5.0 && slope(&r.points, 4) < -0.35);
    let unshuffled_biased = runs
        .iter()
        .filter(|r| !r.scheme.shuffled())
        .all(|r| (r.bias / r.bias_error).abs() > 5.0);
    let verdict = if shuffled_ok && unshuffled_biased {
        format!(
            "Reproduced: with the shuffle both estimators keep converging (slopes {:+.2} and \
             {:+.2}, close to the −0.5 of an unbiased Monte Carlo estimate) with a bias within \
             5 standard errors of zero, while without it the error stalls at a bias of {:+.0} % \
             (TSMIS) and {:+.0} % (SSMIS), as MCMM Fig. 16's red line does.",
            slope(&runs[0].points, 4),
            slope(&runs[1].points, 4),
            100.0 * runs[2].bias,
            100.0 * runs[3].bias
        )
    } else {
        "Not reproduced in this run: see the table — a shuffled estimator shows a bias or no \
         convergence, or an unshuffled one shows no significant bias."
            .to_owned()
    };
    section
        .heading("Decorrelating adaptive chains (MCMM Fig. 16)")
        .paragraph(
            "A tile of 8 pixels; pixel l integrates its own function 0.2 + 4·e^(−|x − b_l|/0.02) on \
             [0, 1) with b_l = 0.3 + 0.05·l (every pixel sees its own light). Each pixel holds one \
             Markov chain: the centre c of a lobe 0.2·U(0, 1) + 0.8·Laplace(c, 0.02) (MCMM's \
             defensive probability 0.2). A chain samples its lobe and moves the lobe onto the \
             sample with probability min(1, f(x)/score) (MCMM Alg. 3), so the next lobe depends \
             on the sample just drawn. 4-TSMIS evaluates eq. 8 over the 4 (lobe, sample) pairs a \
             pixel saw in a frame; 8-SSMIS evaluates eq. 9 over the tile's 8 lobes after each \
             step. Without the shuffle, a TSMIS pixel's history is its own chain (each sample's \
             denominator contains the next lobe, centred on that very sample: biased low), and \
             an SSMIS pixel always samples its own chain, adapted to its own light (a \
             non-uniform selection: biased high).",
        )
        .figure(
            file,
            &format!(
                "Relative RMS error over {} pixels of the running mean against samples per pixel \
                 (log-log, seed {:#x}); the grey line has the slope −1/2 of an unbiased estimator.",
                group_thousands(pixels),
                ctx.config.seed
            ),
        )
        .table(table)
        .paragraph(&verdict);
    Ok(())
}

/// Least-squares slope of log y against log x over the last `k` points.
fn slope(points: &[(f64, f64)], k: usize) -> f64 {
    let tail = &points[points.len().saturating_sub(k)..];
    let n = tail.len() as f64;
    if n < 2.0 {
        return f64::NAN;
    }
    let (xs, ys): (Vec<f64>, Vec<f64>) = tail.iter().map(|&(x, y)| (x.ln(), y.ln())).unzip();
    let mx = xs.iter().sum::<f64>() / n;
    let my = ys.iter().sum::<f64>() / n;
    let sxy: f64 = xs.iter().zip(&ys).map(|(x, y)| (x - mx) * (y - my)).sum();
    let sxx: f64 = xs.iter().map(|x| (x - mx).powi(2)).sum();
    sxy / sxx
}

// ---------------------------------------------------------------------------------------------
// 2. MMIS Fig. 1: variance of MMIS_n against classical MIS
// ---------------------------------------------------------------------------------------------

/// A marginal technique: t ~ U(0, 1), x | t a tent on [lo + t·span, lo + t·span + width);
/// `span = 0` is the defensive uniform technique.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Marginal {
    /// Left end at t = 0.
    pub lo: f64,
    /// Travel of the tent over t ∈ [0, 1].
    pub span: f64,
    /// Width of the tent.
    pub width: f64,
}

impl Marginal {
    fn conditional(&self, t: f64) -> Line {
        if self.span == 0.0 {
            Line::Boxcar {
                a: self.lo as f32,
                w: self.width as f32,
            }
        } else {
            Line::Tent {
                a: (self.lo + t * self.span) as f32,
                w: self.width as f32,
            }
        }
    }

    fn tent_cdf(&self, y: f64) -> f64 {
        let v = (y / self.width).clamp(0.0, 1.0);
        if v < 0.5 {
            2.0 * v * v
        } else {
            1.0 - 2.0 * (1.0 - v) * (1.0 - v)
        }
    }

    /// The closed-form x-marginal (T(x − lo) − T(x − lo − span))/span.
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

/// The four techniques: three feature techniques, each covering only part of [0, 1), and the
/// defensive uniform one.
pub const TECHNIQUES: [Marginal; 4] = [
    Marginal {
        lo: 0.0,
        span: 0.25,
        width: 0.15,
    },
    Marginal {
        lo: 0.3,
        span: 0.2,
        width: 0.1,
    },
    Marginal {
        lo: 0.55,
        span: 0.35,
        width: 0.1,
    },
    Marginal {
        lo: 0.0,
        span: 0.0,
        width: 1.0,
    },
];

/// The integrand: a background and three triangular bumps.
pub fn fig1_integrand(x: f64) -> f64 {
    let tri = |c: f64, r: f64| (1.0 - (x - c).abs() / r).max(0.0);
    0.05 + 2.0 * tri(0.2, 0.1) + 4.0 * tri(0.42, 0.05) + 3.0 * tri(0.75, 0.1)
}

/// Its exact integral.
pub const FIG1_INTEGRAL: f64 = 0.75;
/// The sample budget N.
pub const BUDGET: usize = 64;
/// The n of MMISₙ shown.
pub const NS: [usize; 5] = [1, 2, 4, 8, 16];

/// One budget-N estimate: `None` is classical MIS with exact marginals, `Some(n)` is MMISₙ
/// averaged over N/(nT) realizations.
pub fn fig1_estimate<R: Rng>(n: Option<usize>, rng: &mut R) -> f64 {
    let t_count = TECHNIQUES.len();
    match n {
        None => {
            let per = BUDGET / t_count;
            let mut sum = 0.0;
            for tech in &TECHNIQUES {
                for _ in 0..per {
                    let x = f64::from(tech.conditional(rng.random()).sample(rng.random()));
                    let d: f64 = TECHNIQUES
                        .iter()
                        .map(|t| per as f64 * t.marginal_pdf(x))
                        .sum();
                    sum += fig1_integrand(x) / d;
                }
            }
            sum
        }
        Some(n) => {
            let realizations = BUDGET / (n * t_count);
            let mut pairs = [Line::Boxcar { a: 0.0, w: 1.0 }; BUDGET];
            let mut xs = [0.0_f32; BUDGET];
            let mut fs = [0.0_f32; BUDGET];
            let m = n * t_count;
            let mut total = 0.0;
            for _ in 0..realizations {
                for (i, tech) in TECHNIQUES.iter().enumerate() {
                    for j in 0..n {
                        let c = tech.conditional(rng.random());
                        let x = c.sample(rng.random());
                        (pairs[i * n + j], xs[i * n + j]) = (c, x);
                        fs[i * n + j] = fig1_integrand(f64::from(x)) as f32;
                    }
                }
                let spaces: [&[Line]; 4] = std::array::from_fn(|i| &pairs[i * n..(i + 1) * n]);
                total += f64::from(Mmis::new(&spaces).estimate(&xs[..m], &fs[..m]));
            }
            total / realizations as f64
        }
    }
}

/// Mean, its standard error, variance and the variance's standard error of `R` estimates.
fn moments(values: &[f64]) -> (f64, f64, f64, f64) {
    let r = values.len() as f64;
    let mean = values.iter().sum::<f64>() / r;
    let m2 = values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / r;
    let m4 = values.iter().map(|v| (v - mean).powi(4)).sum::<f64>() / r;
    let s2 = m2 * r / (r - 1.0);
    let se2 = ((m4 - s2 * s2 * (r - 3.0) / (r - 1.0)) / r).max(0.0).sqrt();
    (mean, (s2 / r).sqrt(), s2, se2)
}

fn mmis_variance(ctx: &Context<'_>, section: &mut Section) -> Result<()> {
    let realizations = (ctx.config.samples / 50).max(400);
    let bar = ctx.progress(NS.len() as u64 + 1, "SMIS: MMIS variance");
    let mut rows = Vec::new();
    for (k, n) in std::iter::once(None)
        .chain(NS.iter().map(|&n| Some(n)))
        .enumerate()
    {
        let mut rng = Pcg64Mcg::seed_from_u64(ctx.config.seed.wrapping_add(0x5310 + k as u64));
        let values: Vec<f64> = (0..realizations)
            .map(|_| fig1_estimate(n, &mut rng))
            .collect();
        rows.push((n, moments(&values)));
        bar.inc(1);
    }
    bar.finish_and_clear();
    let (_, (_, _, mis, mis_se)) = rows[0];

    let mut table = Table::new(
        &format!(
            "Variance of one budget-N = {BUDGET} estimate over {} independent estimates (± its \
             standard error); PDF evaluations per estimate: MIS N·T, MMISₙ n·N·T",
            group_thousands(realizations)
        ),
        [
            "estimator",
            "pdf evaluations",
            "mean (exact 0.75)",
            "variance",
            "variance / MIS",
        ],
    );
    for &(n, (mean, mean_se, var, var_se)) in &rows {
        let (name, evals) = match n {
            None => (
                "classical MIS (exact marginals)".to_owned(),
                BUDGET * TECHNIQUES.len(),
            ),
            Some(n) => (format!("MMIS_{n}"), n * BUDGET * TECHNIQUES.len()),
        };
        table.push_row([
            name,
            evals.to_string(),
            format!("{mean:.4} ± {mean_se:.4}"),
            format!("{var:.3e} ± {var_se:.1e}"),
            format!("{:.3}", var / mis),
        ]);
    }

    let points: Vec<(f64, f64)> = rows[1..]
        .iter()
        .map(|&(n, (_, _, v, _))| (n.unwrap_or(1) as f64, v))
        .collect();
    let hi = rows.iter().map(|r| r.1.2).fold(0.0_f64, f64::max);
    let chart = LineChart {
        title: "Variance of MMISₙ at budget N = 64 (MMIS Fig. 1, bottom)".to_owned(),
        x: Axis::log10(
            "n (technique-sample pairs per technique and realization)",
            0.8..20.0,
        ),
        y: Axis::linear("variance", 0.0..hi * 1.15),
        series: vec![
            Series::line("MMISₙ", PALETTE[0], points.clone()),
            Series::dots("", PALETTE[0], points),
            Series::line(
                "classical MIS reference",
                PALETTE[1],
                vec![(0.8, mis), (20.0, mis)],
            ),
        ],
        legend: SeriesLabelPosition::UpperRight,
    };
    let file = "smis-mmis-variance.png";
    plot::line_chart(&ctx.figure_path(file), (1000, 560), &chart)?;

    let ratios: Vec<f64> = rows[1..].iter().map(|r| r.1.2 / mis).collect();
    let falling = rows[1..]
        .windows(2)
        .all(|w| w[1].1.2 < w[0].1.2 + 3.0 * (w[0].1.3.powi(2) + w[1].1.3.powi(2)).sqrt());
    let (first, first_se) = (rows[1].1.2, rows[1].1.3);
    let (last, last_se) = (rows[NS.len()].1.2, rows[NS.len()].1.3);
    let starts_above = first - mis > 5.0 * (first_se.powi(2) + mis_se.powi(2)).sqrt();
    let reaches = last < mis + 3.0 * (last_se.powi(2) + mis_se.powi(2)).sqrt();
    let below = mis - last > 3.0 * (last_se.powi(2) + mis_se.powi(2)).sqrt();
    let verdict = if falling && starts_above && reaches {
        format!(
            "Reproduced: the variance of MMISₙ falls monotonically with n, from {:.2}× the MIS \
             reference at n = 1 to {:.2}× at n = {}, so the additional variance of the stochastic \
             approximation vanishes as n grows, as in MMIS Fig. 1.{}",
            ratios[0],
            ratios[ratios.len() - 1],
            NS[NS.len() - 1],
            if below {
                " Unlike the paper's plot it does not stop at the reference but goes below it: \
                 given the drawn t's, MMIS is balance-heuristic MIS over the narrow conditional \
                 tents, which weights these samples better than the wide marginals do."
            } else {
                ""
            }
        )
    } else {
        format!(
            "Not reproduced in this run (variance / MIS = {}): see the table.",
            ratios
                .iter()
                .map(|r| format!("{r:.2}"))
                .collect::<Vec<_>>()
                .join(", ")
        )
    };

    section
        .heading("Marginal MIS against classical MIS (MMIS Fig. 1)")
        .paragraph(
            "West et al.'s canonical experiment: four marginal techniques on [0, 1) with 1-D \
             technique spaces. Technique i draws t ~ U(0, 1) and then x from a tent of width \
             0.1-0.15 that slides with t over part of the domain; the first three each cover one \
             feature of the integrand (a background 0.05 and three triangular bumps, ∫ = 0.75) \
             and miss the rest, the fourth is a defensive uniform technique. With a total \
             budget of N = 64 samples, MMISₙ (eq. 6, `mcg_smis::Mmis`) draws n technique-sample \
             pairs per technique and averages N/(nT) realizations; the reference is classical \
             MIS with the balance heuristic and the exact (closed-form) x-marginals, which a \
             renderer could not evaluate.",
        )
        .figure(
            file,
            "Variance of one budget-64 estimate against n; the horizontal line is the classical \
             MIS reference.",
        )
        .table(table)
        .paragraph(&verdict);
    Ok(())
}
