//! How many emission-only directions `mcpg` spends at each depth of a path (mcg's extension
//! of its emission-only directions, [`super::guided::EMISSION_SAMPLES`]).
//!
//! A direction that only gathers the emission it meets is worth its cost where it meets
//! emission: at the vertices that see a light. Which depths those are depends on the scene —
//! in the room lit from behind a panel the camera's hits see almost none of the light and the
//! ceiling above the tray sees it whole; in a room with visible lights it is the other way
//! round. [`Allocation::Adaptive`] measures it: each frame it collects, per depth d, the
//! standard deviation σ(d) of one direction's estimate (its luminance times the path's
//! throughput: what it adds to the pixel), and the next frame spends
//!
//! K(d) = (K̄ + 1) · Σ_d N_d / Σ_d N_d σ(d) · σ(d) − 1
//!
//! directions on average at a vertex of depth d, N_d the vertices at that depth, K̄ the mean
//! ([`EmissionAllocation::new`]). A vertex's K + 1 directions (the path's own among them, all
//! from the same mixture) leave the variance σ(d)²/(K + 1), and this allocation minimises
//! Σ_d N_d σ(d)²/(K(d) + 1) for the same number of directions in all (a Lagrange multiplier,
//! as for the sample counts of stratified sampling). K(d) is kept in
//! [[`MIN_PER_VERTEX`], 4·K̄] (so every depth keeps being measured), and a vertex draws
//! ⌊K(d)⌋ or ⌈K(d)⌉ directions with the probabilities that make their mean K(d). The number is
//! decided before any of them is traced, and the emission along each of the K + 1 directions
//! of the vertex counts 1/(K + 1), so the estimate stays unbiased whatever the allocation.
//!
//! The CPU tracer's samplers gather [`EmissionMoments`] from every vertex. The WGSL tracer
//! gathers the same sums in about [`gpu::MOMENT_PIXELS`](super::gpu::MOMENT_PIXELS) evenly
//! spaced pixels, written after the pixels in its image buffer
//! ([`gpu::moment_entries`](super::gpu::moment_entries)), and the host turns them into the next
//! frame's K(d) with the same [`allocate`]; there the count is drawn once per depth and frame
//! ([`gpu::frame_counts`](super::gpu::frame_counts)) rather than per vertex, so that a SIMD group
//! runs one loop length.

use std::sync::Mutex;

use glam::Vec3;

use super::cpu::MAX_RECORDED;
use super::scene::luminance;

/// The smallest mean number of directions [`Allocation::Adaptive`] gives a depth: one
/// direction at every fourth vertex, so that its second moment stays measured.
pub const MIN_PER_VERTEX: f32 = 0.25;

/// How [`EmissionAllocation`] spreads the directions over the depths.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Allocation {
    /// K̄ at every vertex.
    Uniform,
    /// K(d) + 1 ∝ σ(d) from the previous frame (the module docs) — the default.
    #[value(help = "K(d) + 1 in proportion to depth d's spread in the frame before, the same mean")]
    #[default]
    Adaptive,
}

/// One frame's statistics of the emission-only directions, per depth (up to
/// the tracer's 16 recorded depths; deeper vertices count as the deepest).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EmissionMoments {
    /// Vertices that drew their number of directions.
    pub vertices: [u64; MAX_RECORDED],
    /// Directions drawn.
    pub directions: [u64; MAX_RECORDED],
    /// Σ of the luminance of the directions' estimates.
    pub first: [f64; MAX_RECORDED],
    /// Σ of the squared luminance of the directions' estimates.
    pub second: [f64; MAX_RECORDED],
}

impl Default for EmissionMoments {
    fn default() -> Self {
        Self {
            vertices: [0; MAX_RECORDED],
            directions: [0; MAX_RECORDED],
            first: [0.0; MAX_RECORDED],
            second: [0.0; MAX_RECORDED],
        }
    }
}

impl EmissionMoments {
    fn slot(depth: u32) -> usize {
        (depth as usize).min(MAX_RECORDED - 1)
    }

    /// A vertex at `depth`.
    pub fn add_vertex(&mut self, depth: u32) {
        self.vertices[Self::slot(depth)] += 1;
    }

    /// A direction at `depth` whose estimate (throughput included) is `value`; a non-finite
    /// value counts as 0.
    pub fn add_direction(&mut self, depth: u32, value: Vec3) {
        let d = Self::slot(depth);
        let l = f64::from(luminance(value));
        self.directions[d] += 1;
        if l.is_finite() {
            self.first[d] += l;
            self.second[d] += l * l;
        }
    }

    /// Adds `other`'s counts and sums.
    pub fn merge(&mut self, other: &Self) {
        for d in 0..MAX_RECORDED {
            self.vertices[d] += other.vertices[d];
            self.directions[d] += other.directions[d];
            self.first[d] += other.first[d];
            self.second[d] += other.second[d];
        }
    }
}

/// K(d) for every depth from one frame's `moments` with the mean `mean` (the module docs): K̄
/// everywhere when no direction met emission; a depth without directions gets the largest
/// σ of the others (so it is measured next time).
#[must_use]
pub fn allocate(mean: f32, moments: &EmissionMoments) -> [f32; MAX_RECORDED] {
    let mut out = [mean; MAX_RECORDED];
    let root = |d: usize| {
        (moments.directions[d] > 0).then(|| {
            let n = moments.directions[d] as f64;
            let mean = moments.first[d] / n;
            (moments.second[d] / n - mean * mean).max(0.0).sqrt()
        })
    };
    let largest = (0..MAX_RECORDED).filter_map(root).fold(0.0_f64, f64::max);
    if !(largest > 0.0) || !(mean > 0.0) {
        return out;
    }
    let (mut vertices, mut weighted) = (0.0_f64, 0.0_f64);
    for d in 0..MAX_RECORDED {
        let n = moments.vertices[d] as f64;
        vertices += n;
        weighted += n * root(d).unwrap_or(largest);
    }
    if !(weighted > 0.0) {
        return out;
    }
    let scale = (f64::from(mean) + 1.0) * vertices / weighted;
    for (d, k) in out.iter_mut().enumerate() {
        if moments.vertices[d] > 0 {
            let s = root(d).unwrap_or(largest);
            *k = ((scale * s - 1.0) as f32).clamp(MIN_PER_VERTEX, 4.0 * mean);
        }
    }
    out
}

/// ⌊k⌋, plus one when `u < k − ⌊k⌋` (`u` uniform in [0, 1)), so that the mean is `k` (≥ 0).
#[must_use]
pub fn round_stochastically(k: f32, u: f32) -> u32 {
    let whole = k.floor();
    whole as u32 + u32::from(u < k - whole)
}

/// The directions per vertex of one render: the mean K̄, the policy, this frame's K(d) and the
/// statistics being gathered for the next (from every rayon task's sampler at once, or from
/// the GPU tracer's recording pixels).
#[derive(Debug)]
pub struct EmissionAllocation {
    mean: f32,
    policy: Allocation,
    per_depth: [f32; MAX_RECORDED],
    gathered: Mutex<EmissionMoments>,
}

impl EmissionAllocation {
    /// `mean` directions per vertex on average, spread by `policy`; the first frame spends
    /// `mean` at every depth.
    #[must_use]
    pub fn new(mean: u32, policy: Allocation) -> Self {
        Self {
            mean: mean as f32,
            policy,
            per_depth: [mean as f32; MAX_RECORDED],
            gathered: Mutex::new(EmissionMoments::default()),
        }
    }

    /// K̄, the mean number of directions per vertex.
    #[must_use]
    pub fn mean(&self) -> u32 {
        self.mean as u32
    }

    /// How the directions are spread over the depths.
    #[must_use]
    pub fn policy(&self) -> Allocation {
        self.policy
    }

    /// K(d) of this frame, per depth.
    #[must_use]
    pub fn per_depth(&self) -> &[f32; MAX_RECORDED] {
        &self.per_depth
    }

    /// The number of directions for a vertex at `depth`: [`round_stochastically`] of K(d).
    #[must_use]
    pub fn samples_at(&self, depth: u32, u: f32) -> u32 {
        round_stochastically(self.per_depth[EmissionMoments::slot(depth)], u)
    }

    /// Adds one sampler's statistics of this frame.
    pub fn merge(&self, moments: &EmissionMoments) {
        self.gathered
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner)
            .merge(moments);
    }

    /// After a frame: K(d) of the next one from this frame's statistics ([`allocate`]; K̄ for
    /// [`Allocation::Uniform`]), and empty statistics.
    pub fn end_frame(&mut self) {
        let moments = std::mem::take(
            self.gathered
                .get_mut()
                .unwrap_or_else(std::sync::PoisonError::into_inner),
        );
        if self.policy == Allocation::Adaptive {
            self.per_depth = allocate(self.mean, &moments);
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
            m.vertices[d] = v;
            m.directions[d] = n;
            m.second[d] = second;
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
        constant.first[1] = 1600.0;
        let k = allocate(4.0, &constant);
        assert_eq!(k[1], MIN_PER_VERTEX, "σ(1) = 0: {k:?}");
        let k = allocate(4.0, &moments(&[(100, 400, 0.0), (100, 400, 6400.0)]));
        assert_eq!((k[0], k[1]), (MIN_PER_VERTEX, 9.0), "floor");
        let k = allocate(1.0, &moments(&[(900, 900, 0.0), (100, 400, 6400.0)]));
        assert_eq!((k[0], k[1]), (MIN_PER_VERTEX, 4.0), "cap");
        assert_eq!(
            allocate(4.0, &EmissionMoments::default()),
            [4.0; MAX_RECORDED]
        );
        assert_eq!(
            allocate(4.0, &moments(&[(100, 400, 0.0), (100, 400, 0.0)])),
            [4.0; MAX_RECORDED]
        );
        // A depth with vertices but no directions is treated as the best measured one.
        let k = allocate(2.0, &moments(&[(100, 0, 0.0), (100, 200, 200.0)]));
        assert_eq!((k[0], k[1]), (2.0, 2.0));
    }

    /// A vertex draws ⌊K⌋ or ⌈K⌉ directions with mean K (1.5 here); the adaptive policy takes
    /// effect at `end_frame`, the uniform one never.
    #[test]
    fn vertices_draw_the_mean_and_frames_update_it() {
        let mut a = EmissionAllocation::new(4, Allocation::Adaptive);
        assert_eq!(a.samples_at(0, 0.9), 4);
        a.merge(&moments(&[(100, 400, 400.0), (100, 400, 3600.0)]));
        a.end_frame();
        assert!((a.per_depth()[0] - 1.5).abs() < 1e-5, "{:?}", a.per_depth());
        let mean: f32 = (0..1000)
            .map(|i| a.samples_at(0, (i as f32 + 0.5) / 1000.0) as f32)
            .sum::<f32>()
            / 1000.0;
        assert!((mean - 1.5).abs() < 1e-3, "{mean}");
        let mut u = EmissionAllocation::new(4, Allocation::Uniform);
        u.merge(&moments(&[(100, 400, 400.0), (100, 400, 6400.0)]));
        u.end_frame();
        assert_eq!(u.per_depth(), &[4.0; MAX_RECORDED]);
    }
}
