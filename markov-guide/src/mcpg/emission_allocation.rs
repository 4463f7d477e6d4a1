//! [`EmissionAllocation`]: how many emission-only directions a renderer draws at each guided
//! vertex (mcg's extension of MCPG), and the statistics it spreads them by.

use std::sync::Mutex;

use glam::Vec3;

use super::guide::luminance;

/// The depths [`EmissionMoments`] and [`EmissionAllocation`] tell apart: vertices deeper than
/// this count as the deepest.
pub const EMISSION_DEPTHS: usize = 16;

/// The smallest mean number of directions [`EmissionPolicy::Adaptive`] gives a depth (and
/// [`EmissionPolicy::Contribution`] a class): one direction at every fourth vertex, so that its
/// second moment stays measured.
pub const MIN_PER_VERTEX: f32 = 0.25;

/// The largest K(d) of [`EmissionPolicy::Adaptive`], as a multiple of K̄.
pub const DEPTH_CAP: f32 = 4.0;

/// The largest K(class) of [`EmissionPolicy::Contribution`], as a multiple of K̄: a bound on the
/// cost of one vertex (96 directions with K̄ = 6). mcg-demo's room lit from behind a panel
/// gained a little from 4 to 16 and nothing beyond.
pub const CONTRIBUTION_CAP: f32 = 16.0;

/// How much of a class's statistics [`EmissionPolicy::Contribution`] keeps from one frame to the
/// next: its σ comes from all frames so far, the frame k frames back weighted by this to the
/// k-th power, as one frame's rare hits would make it swing.
pub const CLASS_MEMORY: f64 = 0.9;

/// The octaves of c/c̄(d) that [`EmissionPolicy::Contribution`] tells apart at each depth
/// ([`contribution_bin`]): below 1/16 of the depth's mean (with c = 0, the vertices without a
/// valid candidate), one bin per octave from 1/16 to 64, and 64 times the mean and above.
pub const CONTRIBUTION_BINS: usize = 12;

/// ⌊log₂ r⌋ + this is the bin of r = c/c̄(d) (clamped to the bins).
const BIN_OFFSET: i32 = 5;

/// The classes of one depth: its [`CONTRIBUTION_BINS`], then the vertices drawn before the
/// depth had a mean c̄(d).
const CLASSES_PER_DEPTH: usize = CONTRIBUTION_BINS + 1;

/// All classes of [`EmissionPolicy::Contribution`].
const CLASSES: usize = EMISSION_DEPTHS * CLASSES_PER_DEPTH;

/// How [`EmissionAllocation`] spreads the directions over the vertices.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum EmissionPolicy {
    /// K̄ at every vertex.
    Uniform,
    /// K(d) + 1 ∝ σ(d) over the depths, from the previous frame ([`EmissionAllocation`]).
    Adaptive,
    /// K + 1 ∝ σ over classes of depth and expected contribution, from the frames so far
    /// ([`EmissionAllocation`]) — the default. Without contributions in the statistics (a
    /// tracer that fills [`EmissionMoments::depths`] only) the same as `Adaptive`.
    #[default]
    Contribution,
}

/// One class's statistics of the emission-only directions in a frame.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct DirectionMoments {
    /// Vertices that drew their number of directions (a float, so that
    /// [`EmissionAllocation`] can age a class's counts with its sums; exact to 2⁵³).
    pub vertices: f64,
    /// Directions drawn.
    pub directions: f64,
    /// Σ of the luminance of the directions' estimates.
    pub first: f64,
    /// Σ of the squared luminance of the directions' estimates.
    pub second: f64,
}

impl DirectionMoments {
    /// A direction whose estimate has luminance `l` (a non-finite one counts as 0; most are 0,
    /// and add nothing to the sums).
    fn add_direction(&mut self, l: f64) {
        self.directions += 1.0;
        if l != 0.0 && l.is_finite() {
            self.first += l;
            self.second += l * l;
        }
    }

    fn merge(&mut self, other: &Self) {
        self.vertices += other.vertices;
        self.directions += other.directions;
        self.first += other.first;
        self.second += other.second;
    }

    /// Every count and sum times `factor`.
    fn scale(&mut self, factor: f64) {
        self.vertices *= factor;
        self.directions *= factor;
        self.first *= factor;
        self.second *= factor;
    }

    /// σ of one direction's estimate, `None` without directions.
    fn deviation(&self) -> Option<f64> {
        (self.directions > 0.0).then(|| {
            let n = self.directions;
            let mean = self.first / n;
            (self.second / n - mean * mean).max(0.0).sqrt()
        })
    }
}

/// Where a vertex's statistics go and which K it draws: its depth's slot and its class.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct EmissionClass {
    depth: usize,
    class: usize,
}

impl EmissionClass {
    /// The class of a vertex at `depth` that knows no contribution (K(d) of its depth).
    #[must_use]
    pub fn of_depth(depth: u32) -> Self {
        let depth = EmissionMoments::slot(depth);
        Self {
            depth,
            class: depth * CLASSES_PER_DEPTH + CONTRIBUTION_BINS,
        }
    }
}

/// One frame's statistics of the emission-only directions, per depth (up to
/// [`EMISSION_DEPTHS`]; deeper vertices count as the deepest) and per class of
/// [`EmissionPolicy::Contribution`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EmissionMoments {
    /// Per depth.
    pub depths: [DirectionMoments; EMISSION_DEPTHS],
    /// Per class (depth and bin, [`EmissionClass`]); empty where no contributions were
    /// measured (a tracer that fills `depths` only, such as mcg-demo's WGSL tracer).
    pub classes: [DirectionMoments; CLASSES],
    /// Σ of the vertices' expected contributions c per depth.
    pub contribution: [f64; EMISSION_DEPTHS],
}

impl Default for EmissionMoments {
    fn default() -> Self {
        Self {
            depths: [DirectionMoments::default(); EMISSION_DEPTHS],
            classes: [DirectionMoments::default(); CLASSES],
            contribution: [0.0; EMISSION_DEPTHS],
        }
    }
}

impl EmissionMoments {
    fn slot(depth: u32) -> usize {
        (depth as usize).min(EMISSION_DEPTHS - 1)
    }

    /// A vertex of class `at` ([`EmissionAllocation::class`]) and expected contribution
    /// `contribution` (a non-finite or negative one counts as 0).
    pub fn add_vertex(&mut self, at: EmissionClass, contribution: f32) {
        self.depths[at.depth].vertices += 1.0;
        self.classes[at.class].vertices += 1.0;
        if contribution.is_finite() && contribution > 0.0 {
            self.contribution[at.depth] += f64::from(contribution);
        }
    }

    /// A direction at a vertex of class `at` whose estimate (throughput included) is `value`;
    /// a non-finite value counts as 0.
    pub fn add_direction(&mut self, at: EmissionClass, value: Vec3) {
        let l = f64::from(luminance(value));
        self.depths[at.depth].add_direction(l);
        self.classes[at.class].add_direction(l);
    }

    /// Adds `other`'s counts and sums.
    pub fn merge(&mut self, other: &Self) {
        for (m, o) in self.depths.iter_mut().zip(&other.depths) {
            m.merge(o);
        }
        for (m, o) in self.classes.iter_mut().zip(&other.classes) {
            m.merge(o);
        }
        for (c, o) in self.contribution.iter_mut().zip(&other.contribution) {
            *c += o;
        }
    }
}

/// K(d) for every depth from one frame's `moments` with the mean `mean` ([`EmissionAllocation`]),
/// in [[`MIN_PER_VERTEX`], [`DEPTH_CAP`]·K̄]: K̄ everywhere when no direction met emission; a
/// depth without directions gets the largest σ of the others (so it is measured next time).
#[must_use]
pub fn allocate(mean: f32, moments: &EmissionMoments) -> [f32; EMISSION_DEPTHS] {
    spread(mean, DEPTH_CAP * mean, &moments.depths)
}

/// K + 1 ∝ σ over `classes`, the same directions in all, in [[`MIN_PER_VERTEX`], `cap`]:
/// K̄ everywhere when no direction met emission; a class with vertices but no directions
/// gets the largest σ of the others; one without vertices keeps K̄.
fn spread<const N: usize>(mean: f32, cap: f32, classes: &[DirectionMoments; N]) -> [f32; N] {
    let mut out = [mean; N];
    let largest = classes
        .iter()
        .filter_map(DirectionMoments::deviation)
        .fold(0.0_f64, f64::max);
    if !(largest > 0.0) || !(mean > 0.0) {
        return out;
    }
    let (mut vertices, mut weighted) = (0.0_f64, 0.0_f64);
    for c in classes {
        let n = c.vertices;
        vertices += n;
        weighted += n * c.deviation().unwrap_or(largest);
    }
    if !(weighted > 0.0) {
        return out;
    }
    let scale = (f64::from(mean) + 1.0) * vertices / weighted;
    for (k, c) in out.iter_mut().zip(classes) {
        if c.vertices > 0.0 {
            let s = c.deviation().unwrap_or(largest);
            *k = ((scale * s - 1.0) as f32).clamp(MIN_PER_VERTEX, cap);
        }
    }
    out
}

/// The bin of [`EmissionPolicy::Contribution`] of a vertex whose contribution is `ratio` times
/// its depth's mean: ⌊log₂ ratio⌋ + 5 in [0, [`CONTRIBUTION_BINS`]) (read from the float's
/// exponent); 0 for 0, negative and NaN ratios, the last bin for +∞.
#[must_use]
pub fn contribution_bin(ratio: f32) -> usize {
    if !(ratio > 0.0) {
        return 0;
    }
    // The biased exponent of a positive float (+∞ included) is ⌊log₂⌋ + 127; subnormals
    // read as −127, below every bin.
    let octave = (ratio.to_bits() >> 23) as i32 - 127;
    (octave + BIN_OFFSET).clamp(0, CONTRIBUTION_BINS as i32 - 1) as usize
}

/// ⌊k⌋, plus one when `u < k − ⌊k⌋` (`u` uniform in [0, 1)), so that the mean is `k` (≥ 0).
#[must_use]
pub fn round_stochastically(k: f32, u: f32) -> u32 {
    let whole = k.floor();
    whole as u32 + u32::from(u < k - whole)
}

/// How many emission-only directions a renderer draws at each guided vertex (mcg's extension
/// of MCPG): the mean K̄, the policy, this frame's K per depth and class, and the statistics
/// being gathered for the next (from many threads at once, or from a GPU tracer's sums).
///
/// MCPG knows no lights: a vertex spends its one direction either on the light or on the
/// surfaces that lead to it. A renderer can draw K more directions from the begun vertex's
/// whole mixture ([`GuidedVertex::sample_mixture`](super::GuidedVertex::sample_mixture): no new
/// lookups), trace each only for the emission it meets, and weight the emission found along
/// each of the K + 1 directions (the path's own among them) 1/(K + 1). Every direction comes
/// from the density [`GuidedVertex::pdf`](super::GuidedVertex::pdf) gives, so the estimate
/// stays unbiased for any K that is decided before the directions are traced; K may differ from
/// vertex to vertex.
///
/// A direction that only gathers the emission it meets is worth its cost where it meets
/// emission: at the vertices that see a light. Which depths those are depends on the scene —
/// in a room lit from behind a panel the camera's hits see almost none of the light and the
/// ceiling above the panel sees it whole; in a room with visible lights it is the other way
/// round. [`EmissionPolicy::Adaptive`] measures it: each frame it collects, per depth d, the
/// standard deviation σ(d) of one direction's estimate (its luminance times the path's
/// throughput: what it adds to the pixel), and the next frame spends
///
/// K(d) = (K̄ + 1) · Σ_d N_d / Σ_d N_d σ(d) · σ(d) − 1
///
/// directions on average at a vertex of depth d, N_d the vertices at that depth, K̄ the mean
/// ([`EmissionAllocation::new`]). A vertex's K + 1 directions leave the variance
/// σ(d)²/(K + 1), and this allocation minimises Σ_d N_d σ(d)²/(K(d) + 1) for the same number
/// of directions in all (a Lagrange multiplier, as for the sample counts of stratified
/// sampling). K(d) is kept in [[`MIN_PER_VERTEX`], [`DEPTH_CAP`]·K̄] (so every depth keeps
/// being measured), and a vertex draws ⌊K(d)⌋ or ⌈K(d)⌉ directions with the probabilities that
/// make their mean K(d) ([`round_stochastically`]).
///
/// [`EmissionPolicy::Contribution`] (the default) goes one step further, within each depth: a
/// vertex whose light reaches the pixel strongly gets more directions than one whose light
/// hardly counts. Its expected contribution, known before any direction is traced, is
/// c = lum(β)·sum_mc: the path throughput β to the vertex times the guide's own estimate of
/// the radiance reflected there (MCPG Alg. 1's sum_mc = Σ w̄,
/// [`GuidedVertex::weight_sum`](super::GuidedVertex::weight_sum)), the estimate from which
/// adjoint-driven splitting (Vorba and Křivánek 2016, "Adjoint-Driven Russian Roulette and
/// Splitting in Light Transport Simulation") decides how often to split a path.
/// How much c says about a direction's spread depends on the scene and on how well the guide
/// has learnt it, so it is not trusted as it is: each vertex falls into a class, its depth d
/// and the octave of c/c̄(d) ([`contribution_bin`], c̄(d) the previous frame's mean at d), and
/// the rule above runs over the classes instead of the depths, K(class) + 1 ∝ σ(class) with
/// the same directions in all. Where c predicts the spread the directions follow it; where it
/// does not, the classes' σ are alike and so are their K. A class's σ comes from all frames
/// so far, older ones weighing less ([`CLASS_MEMORY`]): from a single frame, a class whose
/// directions happened to meet no light would get almost none in the next, and its rare hits
/// would then count many times over (in mcg-demo's room with many lights that made the error
/// 1.7 times larger).
///
/// In mcg-demo's CPU path tracer (a room lit from behind a panel, 128², 8 spp × 64 frames,
/// 3 bounces, K̄ = 6) the directions cut the relative MSE about fourfold against the paper's
/// one direction, and `Contribution` cuts it by another 13 % against `Adaptive` at the same
/// cost per frame; in its room with many lights, where the guide misses lights and c says
/// little, the error is the same (`benches/README.md`).
///
/// # Use
/// One [`EmissionAllocation`] per render. Per vertex, after [`Guide::begin`](super::Guide::begin):
/// [`EmissionAllocation::class`] of the vertex's depth and c, [`EmissionAllocation::samples_at`]
/// for its K, and the statistics into the thread's own [`EmissionMoments`]
/// ([`EmissionMoments::add_vertex`], then [`EmissionMoments::add_direction`] for each direction,
/// the ones that met nothing included). At the end of a frame every thread's moments go to
/// [`EmissionAllocation::merge`] (from many threads at once), then
/// [`EmissionAllocation::end_frame`] sets the next frame's counts. A tracer that cannot measure
/// c (mcg-demo's WGSL tracer, which draws one K per depth and frame so that a SIMD group runs
/// one loop length) fills [`EmissionMoments::depths`] only; `Contribution` then spreads by depth,
/// as `Adaptive`.
///
/// ```
/// use mcg_markov_guide::glam::Vec3;
/// use mcg_markov_guide::mcpg::{EmissionAllocation, EmissionMoments, EmissionPolicy};
///
/// let mut allocation = EmissionAllocation::new(6, EmissionPolicy::Contribution);
/// for _frame in 0..3 {
///     let mut moments = EmissionMoments::default(); // one per thread
///     for i in 0..1000 {
///         // A vertex at depth 1: throughput luminance × the guide's sum_mc.
///         let c = 0.5 * (1 + i % 7) as f32;
///         let class = allocation.class(1, c);
///         moments.add_vertex(class, c);
///         let k = allocation.samples_at(class, (i as f32 + 0.5) / 1000.0);
///         for j in 0..k {
///             // The emission along the j-th direction, times the throughput and f·cos/p:
///             // here the brighter vertices meet more light.
///             let found = if (i + j as usize) % 4 == 0 { Vec3::splat(c) } else { Vec3::ZERO };
///             moments.add_direction(class, found);
///             // radiance += found / (k + 1) as f32;
///         }
///     }
///     allocation.merge(&moments);
///     allocation.end_frame();
/// }
/// // The same mean, spread towards the classes whose directions vary most.
/// let (dim, bright) = (allocation.class(1, 0.5), allocation.class(1, 3.5));
/// let draws = |class| -> u32 {
///     (0..1000).map(|i| allocation.samples_at(class, (i as f32 + 0.5) / 1000.0)).sum()
/// };
/// assert!(draws(bright) > draws(dim));
/// ```
#[derive(Debug)]
pub struct EmissionAllocation {
    mean: f32,
    policy: EmissionPolicy,
    per_depth: [f32; EMISSION_DEPTHS],
    per_class: [f32; CLASSES],
    /// The classes' statistics of the frames so far, each frame's weight
    /// [`CLASS_MEMORY`] times the next's.
    history: [DirectionMoments; CLASSES],
    /// 1/c̄(d) from the frame before; 0 where unknown (the depth's vertices then draw K(d)).
    inverse_mean: [f32; EMISSION_DEPTHS],
    gathered: Mutex<EmissionMoments>,
}

impl EmissionAllocation {
    /// `mean` directions per vertex on average, spread by `policy`; the first frame spends
    /// `mean` at every vertex.
    #[must_use]
    pub fn new(mean: u32, policy: EmissionPolicy) -> Self {
        Self {
            mean: mean as f32,
            policy,
            per_depth: [mean as f32; EMISSION_DEPTHS],
            per_class: [mean as f32; CLASSES],
            history: [DirectionMoments::default(); CLASSES],
            inverse_mean: [0.0; EMISSION_DEPTHS],
            gathered: Mutex::new(EmissionMoments::default()),
        }
    }

    /// K̄, the mean number of directions per vertex.
    #[must_use]
    pub fn mean(&self) -> u32 {
        self.mean as u32
    }

    /// How the directions are spread.
    #[must_use]
    pub fn policy(&self) -> EmissionPolicy {
        self.policy
    }

    /// K(d) of this frame, per depth: for [`EmissionPolicy::Contribution`] the mean over the
    /// depth's classes, weighted by their vertices in the frame before.
    #[must_use]
    pub fn per_depth(&self) -> &[f32; EMISSION_DEPTHS] {
        &self.per_depth
    }

    /// The class of a vertex at `depth` whose expected contribution is `contribution`
    /// (for [`EmissionPolicy::Contribution`] once its depth has a mean c̄(d); otherwise
    /// [`EmissionClass::of_depth`]).
    #[must_use]
    pub fn class(&self, depth: u32, contribution: f32) -> EmissionClass {
        let at = EmissionClass::of_depth(depth);
        let inverse = self.inverse_mean[at.depth];
        if self.policy != EmissionPolicy::Contribution || !(inverse > 0.0) {
            return at;
        }
        EmissionClass {
            depth: at.depth,
            class: at.depth * CLASSES_PER_DEPTH + contribution_bin(contribution * inverse),
        }
    }

    /// The number of directions for a vertex of class `at`: [`round_stochastically`] of its
    /// K.
    #[must_use]
    pub fn samples_at(&self, at: EmissionClass, u: f32) -> u32 {
        round_stochastically(self.per_class[at.class], u)
    }

    /// Adds one sampler's statistics of this frame.
    pub fn merge(&self, moments: &EmissionMoments) {
        self.gathered
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner)
            .merge(moments);
    }

    /// After a frame: the next frame's K per depth and class from this frame's statistics
    /// ([`allocate`] for [`EmissionPolicy::Adaptive`] and for [`EmissionPolicy::Contribution`]
    /// without classes, the classes' spread otherwise; K̄ for [`EmissionPolicy::Uniform`]), the
    /// depths' means c̄(d), and empty statistics.
    pub fn end_frame(&mut self) {
        let moments = std::mem::take(
            self.gathered
                .get_mut()
                .unwrap_or_else(std::sync::PoisonError::into_inner),
        );
        // Only a tracer that measures contributions fills the classes.
        let by_class = self.policy == EmissionPolicy::Contribution
            && moments.classes.iter().any(|c| c.vertices > 0.0);
        if by_class {
            for (h, m) in self.history.iter_mut().zip(&moments.classes) {
                h.scale(CLASS_MEMORY);
                h.merge(m);
            }
            self.per_class = spread(self.mean, CONTRIBUTION_CAP * self.mean, &self.history);
            for (d, k) in self.per_depth.iter_mut().enumerate() {
                let classes = d * CLASSES_PER_DEPTH..(d + 1) * CLASSES_PER_DEPTH;
                let (mut n, mut spent) = (0.0, 0.0);
                for (c, kc) in moments.classes[classes.clone()]
                    .iter()
                    .zip(&self.per_class[classes])
                {
                    n += c.vertices;
                    spent += c.vertices * f64::from(*kc);
                }
                *k = if n > 0.0 {
                    (spent / n) as f32
                } else {
                    self.mean
                };
            }
            for (d, inverse) in self.inverse_mean.iter_mut().enumerate() {
                let (n, sum) = (moments.depths[d].vertices, moments.contribution[d]);
                *inverse = if n > 0.0 && sum > 0.0 {
                    (n / sum) as f32
                } else {
                    0.0
                };
            }
        } else {
            if self.policy != EmissionPolicy::Uniform {
                self.per_depth = allocate(self.mean, &moments);
            }
            for (d, k) in self.per_depth.iter().enumerate() {
                self.per_class[d * CLASSES_PER_DEPTH..(d + 1) * CLASSES_PER_DEPTH].fill(*k);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Vertices, directions and Σ of squares per depth, all of mean 0.
    fn moments(per_depth: &[(u64, u64, f64)]) -> EmissionMoments {
        let mut m = EmissionMoments::default();
        for (d, &(v, n, second)) in per_depth.iter().enumerate() {
            m.depths[d] = DirectionMoments {
                vertices: v as f64,
                directions: n as f64,
                first: 0.0,
                second,
            };
        }
        m
    }

    /// K(d) + 1 ∝ σ(d) with the same directions in all: depths of σ 1 and 4 with equal
    /// vertices and K̄ = 4 get 1 and 7; the variance, not the second moment, counts; the floor
    /// and cap hold; nothing measured, or no emission met, gives K̄ everywhere.
    #[test]
    fn directions_follow_the_standard_deviation() {
        let k = allocate(4.0, &moments(&[(100, 400, 400.0), (100, 400, 6400.0)]));
        assert!(
            (k[0] - 1.0).abs() < 1e-5 && (k[1] - 7.0).abs() < 1e-5,
            "{k:?}"
        );
        let spent: f32 = k[0] * 100.0 + k[1] * 100.0;
        assert!((spent - 800.0).abs() < 1e-3);
        assert_eq!(k[5], 4.0, "a depth without vertices keeps K̄");
        let mut constant = moments(&[(100, 400, 400.0), (100, 400, 6400.0)]);
        constant.depths[1].first = 1600.0;
        let k = allocate(4.0, &constant);
        assert_eq!(k[1], MIN_PER_VERTEX, "σ(1) = 0: {k:?}");
        let k = allocate(4.0, &moments(&[(100, 400, 0.0), (100, 400, 6400.0)]));
        assert_eq!((k[0], k[1]), (MIN_PER_VERTEX, 9.0), "floor");
        let k = allocate(1.0, &moments(&[(900, 900, 0.0), (100, 400, 6400.0)]));
        assert_eq!((k[0], k[1]), (MIN_PER_VERTEX, 4.0), "cap");
        assert_eq!(
            allocate(4.0, &EmissionMoments::default()),
            [4.0; EMISSION_DEPTHS]
        );
        assert_eq!(
            allocate(4.0, &moments(&[(100, 400, 0.0), (100, 400, 0.0)])),
            [4.0; EMISSION_DEPTHS]
        );
        // A depth with vertices but no directions is treated as the best measured one.
        let k = allocate(2.0, &moments(&[(100, 0, 0.0), (100, 200, 200.0)]));
        assert_eq!((k[0], k[1]), (2.0, 2.0));
    }

    /// A vertex draws ⌊K⌋ or ⌈K⌉ directions with mean K (1.5 here); the adaptive policy takes
    /// effect at `end_frame`, the uniform one never.
    #[test]
    fn vertices_draw_the_mean_and_frames_update_it() {
        let mut a = EmissionAllocation::new(4, EmissionPolicy::Adaptive);
        assert_eq!(a.samples_at(EmissionClass::of_depth(0), 0.9), 4);
        a.merge(&moments(&[(100, 400, 400.0), (100, 400, 3600.0)]));
        a.end_frame();
        assert!((a.per_depth()[0] - 1.5).abs() < 1e-5, "{:?}", a.per_depth());
        let mean: f32 = (0..1000)
            .map(|i| a.samples_at(EmissionClass::of_depth(0), (i as f32 + 0.5) / 1000.0) as f32)
            .sum::<f32>()
            / 1000.0;
        assert!((mean - 1.5).abs() < 1e-3, "{mean}");
        let mut u = EmissionAllocation::new(4, EmissionPolicy::Uniform);
        u.merge(&moments(&[(100, 400, 400.0), (100, 400, 6400.0)]));
        u.end_frame();
        assert_eq!(u.per_depth(), &[4.0; EMISSION_DEPTHS]);
    }

    /// The class index of `bin` at `depth`.
    fn class(depth: usize, bin: usize) -> EmissionClass {
        EmissionClass {
            depth,
            class: depth * CLASSES_PER_DEPTH + bin,
        }
    }

    /// `n` vertices of class `at` with contribution `c`, each with `per_vertex` directions
    /// whose luminances alternate between 0 and `2σ` (mean σ, deviation σ).
    fn add(
        m: &mut EmissionMoments,
        at: EmissionClass,
        c: f32,
        n: u32,
        per_vertex: u32,
        sigma: f32,
    ) {
        for i in 0..n {
            m.add_vertex(at, c);
            for j in 0..per_vertex {
                let l = if (i + j) % 2 == 0 { 2.0 * sigma } else { 0.0 };
                m.add_direction(at, Vec3::splat(l));
            }
        }
    }

    /// The bins are the octaves of c/c̄ from 1/16 to 64, read from the exponent: 0 for
    /// nothing, negative, NaN and subnormal ratios, the last bin for 64 and above.
    #[test]
    fn contribution_bins_are_octaves_of_the_ratio() {
        for (ratio, bin) in [
            (0.0, 0),
            (-1.0, 0),
            (f32::NAN, 0),
            (1e-40, 0),
            (0.0624, 0),
            (0.0625, 1),
            (0.5, 4),
            (0.999, 4),
            (1.0, 5),
            (1.999, 5),
            (2.0, 6),
            (63.9, 10),
            (64.0, 11),
            (1e30, 11),
            (f32::INFINITY, 11),
        ] {
            assert_eq!(contribution_bin(ratio), bin, "{ratio}");
            if ratio > 0.0 && ratio.is_normal() {
                let octave = ratio.log2().floor() as i32;
                assert_eq!(bin as i32, (octave + 5).clamp(0, 11), "{ratio}");
            }
        }
    }

    /// `Contribution`: the first frame measures c̄(d) only (every vertex in its depth's
    /// class); the next sorts vertices by c/c̄ and K + 1 ∝ σ over the classes, the same
    /// directions in all: σ 1 and 4 at equal counts give (K + 1) in the ratio 1 : 4.
    #[test]
    fn contribution_classes_follow_their_standard_deviation() {
        let mut a = EmissionAllocation::new(4, EmissionPolicy::Contribution);
        let unknown = EmissionClass::of_depth(1);
        assert_eq!(a.class(1, 3.0), unknown, "no c̄ yet");
        let mut m = EmissionMoments::default();
        add(&mut m, unknown, 1.0, 100, 4, 2.0);
        add(&mut m, unknown, 8.0, 100, 4, 2.0);
        a.merge(&m);
        a.end_frame();
        // c̄(1) = 4.5: c = 1 falls in the octave of 2⁻³ (bin 2), c = 8 in that of 1 (bin 5).
        let (low, high) = (a.class(1, 1.0), a.class(1, 8.0));
        assert_eq!((low, high), (class(1, 2), class(1, 5)));
        assert_eq!(
            a.class(0, 1.0),
            EmissionClass::of_depth(0),
            "depth 0 had no vertices"
        );
        let mut m = EmissionMoments::default();
        add(&mut m, low, 1.0, 1000, 4, 1.0);
        add(&mut m, high, 8.0, 1000, 4, 4.0);
        a.merge(&m);
        a.end_frame();
        let k = |at: EmissionClass| a.per_class[at.class];
        let ratio = (k(high) + 1.0) / (k(low) + 1.0);
        assert!((ratio - 4.0).abs() < 1e-4, "{} {}", k(low), k(high));
        // K(1) reports the vertex-weighted mean of the depth's classes.
        let mean = (k(low) + k(high)) / 2.0;
        assert!(
            (a.per_depth()[1] - mean).abs() < 1e-4,
            "{:?}",
            a.per_depth()
        );
        let draws: f32 = (0..1000)
            .map(|i| a.samples_at(high, (i as f32 + 0.5) / 1000.0) as f32)
            .sum::<f32>()
            / 1000.0;
        assert!((draws - k(high)).abs() < 1e-2, "{draws}");
    }

    /// A class keeps its σ from earlier frames ([`CLASS_MEMORY`]): a frame in which its
    /// directions found nothing lowers its σ, one without directions leaves it, where a
    /// single frame would give it the largest σ of the others.
    #[test]
    fn contribution_classes_remember_earlier_frames() {
        let mut a = EmissionAllocation::new(4, EmissionPolicy::Contribution);
        let mut m = EmissionMoments::default();
        add(&mut m, EmissionClass::of_depth(0), 1.0, 10, 0, 0.0);
        a.merge(&m);
        a.end_frame();
        let (low, high) = (class(0, 5), class(0, 8));
        assert_eq!((a.class(0, 1.0), a.class(0, 8.0)), (low, high));
        let frame = |a: &mut EmissionAllocation, low_directions| {
            let mut m = EmissionMoments::default();
            add(&mut m, low, 1.0, 1000, low_directions, 1.0);
            add(&mut m, high, 8.0, 1000, 4, 4.0);
            a.merge(&m);
            a.end_frame();
            (a.per_class[low.class], a.per_class[high.class])
        };
        let first = frame(&mut a, 4);
        // The low class draws no directions: a single frame would give it σ = 4, the
        // largest, and K = K(high); with its history its σ stays 1.
        let second = frame(&mut a, 0);
        assert!(second.0 < second.1, "{second:?}");
        assert!((second.0 - first.0).abs() < 1e-2, "{first:?} {second:?}");
    }

    /// Statistics without contributions (a GPU tracer's): `Contribution` then spreads by
    /// depth exactly as `Adaptive`, and every class of a depth draws its K(d).
    #[test]
    fn contribution_without_contributions_is_adaptive() {
        let depths = moments(&[(100, 400, 400.0), (100, 400, 6400.0)]);
        let mut adaptive = EmissionAllocation::new(4, EmissionPolicy::Adaptive);
        let mut contribution = EmissionAllocation::new(4, EmissionPolicy::Contribution);
        for a in [&mut adaptive, &mut contribution] {
            a.merge(&depths);
            a.end_frame();
        }
        assert_eq!(adaptive.per_depth(), contribution.per_depth());
        assert_eq!(contribution.class(1, 5.0), EmissionClass::of_depth(1));
        for bin in 0..CLASSES_PER_DEPTH {
            assert_eq!(
                contribution.per_class[class(1, bin).class],
                adaptive.per_depth()[1]
            );
        }
    }
}
