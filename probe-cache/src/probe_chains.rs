//! ADGI's static and dynamic Metropolis chains over (position, direction) (sec. 3.3, Alg. 1;
//! sec. 4.8, 4.9; App. A, Alg. 5), built on `mcg-markov-guide`'s [`RandomWalk`].
//!
//! # State space (d = 3 + 2)
//! A chain's state is `x = (p_x, p_y, p_z, z, φ)`: a world position p and a direction written
//! as `z = cos θ ∈ [−1, 1]`, `φ ∈ [0, 2π)`, i.e. `ω = (√(1−z²) cos φ, √(1−z²) sin φ, z)`.
//!
//! Why (cos θ, φ): the map is **equal-area** (Archimedes: dω = dz dφ), so a chain whose
//! stationary density is h on (z, φ) has density h per steradian — what eq. 2 means — with no
//! Jacobian in the acceptance ratio. Its boundaries are handled without breaking the
//! proposal's symmetry: φ wraps modulo 2π and z reflects at ±1. Both are isometries of the
//! (z, φ) plane, and folding a symmetric Gaussian proposal by a group of isometries keeps it
//! symmetric (q(x → y) = Σ_g N(g·y − x) = Σ_g N(g⁻¹·x − y) = q(y → x)), so Alg. 5's plain ratio
//! min(1, h(x')/h(x)) stays exact. It also needs no texel map, so the chains work with either
//! of the crate's texel layouts. The price: near the poles a φ step moves less than its size
//! in radians; the target is piecewise constant per octant, so this only slows mixing there.
//!
//! Positions are not folded: a proposal outside the sampling domain (the box of the probes'
//! Voronoi cells, [`ProxyGrid::nearest_probe`]) has h = 0 and is rejected.
//!
//! # Step sizes
//! Static chains (sec. 4.8): σ = (spacing, √(π/256), √(π/256)) — position steps of one probe
//! spacing per axis ("proportional to the size of a voxel in the probe grid"), direction steps
//! of [`ADGI_DIRECTION_STEP`] in z and φ (radians at the equator). Dynamic chains (sec. 4.9):
//! 3× and 6× those. For an isotropic grid these are exactly
//! [`RandomWalk::adgi_static`] and [`RandomWalk::adgi_dynamic`].
//!
//! # Per frame (Alg. 1)
//! Each chain re-evaluates h at its persisted state (the target changes between frames), runs
//! M steps of the schedule and emits the states after the first K (burn-in), skipping states
//! with h = 0 (a chain that has not yet found the target's support). A chain whose state has
//! h = 0 at the start of a frame restarts at a uniform point of the domain (from one extra draw
//! of uniforms) — an independence move out of a region the stationary distribution never
//! visits, so it does not change what the chains converge to, and lets the dynamic chains find
//! a change that appears far from them.
//!
//! Dynamic chains emit each (proxy, octant) at most once per frame: ADGI traces a whole octant
//! of every probe in the proxy per sample, deterministically, so "the first invocation to update
//! the octant marks it updated" (sec. 4.9).
//!
//! # Using the samples
//! - **Static** ([`ProbeSample::cell`] = probe index): trace from the probe's position along
//!   [`ProbeSample::direction`] for irradiance and along its opposite for visibility, and
//!   update the texels those directions land in (sec. 4.8, Alg. 2). If the probe's f_d > 0,
//!   ADGI snaps the direction to the centre of its texel first, to keep sampling noise out of
//!   a changing texel (end of sec. 4.9).
//! - **Dynamic** ([`ProbeSample::cell`] = proxy index): for every probe of the proxy
//!   ([`ProxyGrid::probes_of`]) that the deferred shader uses (e.g. in V_in, see
//!   [`clip_volume`](crate::clip_volume)), trace the centres of the texels whose directions lie
//!   in [`ProbeSample::octant`] (sec. 4.9: deterministic rays through texel centres).
//! - Run the dynamic chains after the static ones (sec. 4.9).

use core::f32::consts::TAU;

use glam::{UVec3, Vec3};
use mcg_markov_guide::mcg_smis::finite_non_negative_or_zero;
use mcg_markov_guide::{
    ADGI_DIRECTION_STEP, FrameSchedule, MetropolisChain, RandomWalk, StepUniforms,
};

use crate::guiding_function::Guide;
use crate::heuristics::{OCTANTS, octant};
use crate::proxies::ProxyGrid;
use crate::{ChainError, ProbeGrid};

/// Dimension of a chain's state: 3 for the position, 2 for the direction (sec. 3.2: d = 5).
pub const CHAIN_DIMENSIONS: usize = 5;

/// The state of one probe chain, `(p_x, p_y, p_z, cos θ, φ)` and h there (ADGI Alg. 1's `S[j]`).
pub type ProbeChainState = MetropolisChain<CHAIN_DIMENSIONS>;

/// The uniforms of one step of a probe chain: five for the proposal, one for the acceptance.
pub type ProbeStepUniforms = StepUniforms<CHAIN_DIMENSIONS>;

/// The unit direction of chain coordinates `(z, φ) = (cos θ, φ)`: `(√(1−z²) cos φ,
/// √(1−z²) sin φ, z)`. `z` is clamped to [−1, 1].
#[inline]
#[must_use]
pub fn direction_from_chain(z: f32, phi: f32) -> Vec3 {
    let z = z.clamp(-1.0, 1.0);
    let r = (1.0 - z * z).max(0.0).sqrt();
    let (s, c) = phi.sin_cos();
    Vec3::new(r * c, r * s, z)
}

/// Chain coordinates `(cos θ, φ ∈ [0, 2π))` of a direction (normalised first; the zero vector
/// gives (1, 0)).
#[inline]
#[must_use]
pub fn chain_from_direction(direction: Vec3) -> [f32; 2] {
    let d = direction.normalize_or(Vec3::Z);
    let phi = d.y.atan2(d.x);
    [
        d.z.clamp(-1.0, 1.0),
        if phi < 0.0 { phi + TAU } else { phi },
    ]
}

/// Folds chain direction coordinates into the domain: z reflected into [−1, 1], φ wrapped
/// into [0, 2π). Non-finite coordinates become (1, 0).
#[inline]
#[must_use]
pub fn fold_direction(z: f32, phi: f32) -> [f32; 2] {
    if !(z.is_finite() && phi.is_finite()) {
        return [1.0, 0.0];
    }
    // Fast paths for the usual small excursion past one boundary.
    let z = if (-1.0..=1.0).contains(&z) {
        z
    } else if (1.0..=3.0).contains(&z) {
        2.0 - z
    } else if (-3.0..-1.0).contains(&z) {
        -2.0 - z
    } else {
        // Reflection at ±1 has period 4: t = (z + 1) mod 4 ∈ [0, 4), folded to [0, 2].
        let mut t = (z + 1.0).rem_euclid(4.0);
        if t > 2.0 {
            t = 4.0 - t;
        }
        t - 1.0
    };
    let mut phi = if (0.0..TAU).contains(&phi) {
        phi
    } else if (-TAU..0.0).contains(&phi) {
        phi + TAU
    } else if (TAU..2.0 * TAU).contains(&phi) {
        phi - TAU
    } else {
        phi.rem_euclid(TAU)
    };
    if phi >= TAU {
        phi = 0.0; // rounding can reach TAU for tiny negative inputs
    }
    [z, phi]
}

/// Static or dynamic chains (sec. 4.8, 4.9): their step sizes and whether emitted
/// (cell, octant) pairs are deduplicated per frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ChainKind {
    /// Sec. 4.8: per-probe target, steps of one spacing and √(π/256); every sample emitted.
    Static,
    /// Sec. 4.9: proxy target, steps 3× (position) and 6× (direction) larger; each
    /// (proxy, octant) emitted once per frame.
    Dynamic,
}

impl ChainKind {
    /// `(position, direction)` step multipliers relative to the static chain: (1, 1) and (3, 6).
    #[inline]
    #[must_use]
    pub const fn step_scale(self) -> (f32, f32) {
        match self {
            ChainKind::Static => (1.0, 1.0),
            ChainKind::Dynamic => (3.0, 6.0),
        }
    }

    /// The random walk of this kind of chain on `grid`: σ = k_p · spacing per axis for the
    /// position and k_ω · √(π/256) for both z and φ, with (k_p, k_ω) = [`Self::step_scale`].
    ///
    /// # Errors
    /// [`ChainError::ChainStep`] with the walk's [`WalkError`](mcg_markov_guide::WalkError)
    /// if a scaled spacing is not a valid step (it overflows, or exceeds
    /// [`RandomWalk::STEP_MAX`]).
    pub fn walk(self, grid: &ProbeGrid) -> Result<RandomWalk<CHAIN_DIMENSIONS>, ChainError> {
        let (kp, kd) = self.step_scale();
        let s = grid.spacing() * kp;
        let a = ADGI_DIRECTION_STEP * kd;
        RandomWalk::new([s.x, s.y, s.z, a, a]).map_err(ChainError::ChainStep)
    }
}

/// One emitted chain sample: which cell (probe for static chains, proxy for dynamic ones) and
/// which direction to update this frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ProbeSample {
    /// Linear index of the cell: the probe (static chains) or the proxy (dynamic chains).
    pub cell: u32,
    /// Coordinates of the probe nearest to the chain's position (inside `cell`).
    pub probe: UVec3,
    /// Octant of `direction` ([`octant`]).
    pub octant: u8,
    /// The chain's continuous position (inside the probe's Voronoi box).
    pub position: Vec3,
    /// The sampled unit direction ω. Trace from the probe along ω for irradiance and along −ω
    /// for visibility (sec. 4.8); map ω to a texel with the probe's texel map.
    pub direction: Vec3,
    /// The guiding function's value h(p, ω) (ADGI eq. 2) at the sample.
    pub guiding_value: f32,
}

/// Counters of the last [`ProbeChains::step_frame`] or [`ProbeChains::step_frame_parallel`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct FrameStats {
    /// Proposals made (chains × M).
    pub proposals: u32,
    /// Proposals accepted.
    pub accepted: u32,
    /// Chains restarted uniformly because h was 0 at their state.
    pub restarts: u32,
    /// Samples emitted.
    pub emitted: u32,
    /// Samples dropped because their (cell, octant) was already emitted this frame (dynamic
    /// chains) or h was 0.
    pub dropped: u32,
}

/// A set of persistent Metropolis chains over (position, direction) on a probe grid (ADGI
/// Alg. 1 with the random walk of Alg. 5; sec. 4.8 static, 4.9 dynamic).
///
/// # Example
/// ```
/// use mcg_probe_cache::{GuideParams, GuidingFunction, ProbeChains, ProbeGrid, ProbeStepUniforms,
///     ProxyGrid, glam::{UVec3, Vec3}};
///
/// let grid = ProbeGrid::new(Vec3::ZERO, Vec3::splat(0.5), UVec3::new(4, 4, 4))?;
/// // f_s per probe and octant (here: 1 for the probes with x index < 2, upward octants 0-3).
/// let mut f_s = vec![0.0f32; grid.probe_count() * 8];
/// for p in 0..grid.probe_count() {
///     if grid.probe_coords(p).x < 2 {
///         for o in 0..4 { f_s[p * 8 + o] = 1.0; }
///     }
/// }
/// let guide = GuidingFunction::new(ProxyGrid::probes(grid), &f_s, None, GuideParams::STATIC)?;
///
/// // A toy uniform stream; use a real generator.
/// let mut k = 0u32;
/// let mut u = move || { k += 1; (k as f32 * 0.618_034).fract() };
/// let mut chains = ProbeChains::new_static(grid, 64, || std::array::from_fn(|_| u()))?;
/// let mut v = 0u32;
/// let mut uniforms = move || { v += 1; let t = |i: u32| ((v * 7 + i) as f32 * 0.754_878).fract();
///     ProbeStepUniforms { proposal: [t(1), t(2), t(3), t(4), t(5)], accept: t(6) } };
/// for _frame in 0..4 {
///     for s in chains.step_frame(&guide, &mut uniforms) {
///         // Trace from grid.probe_position(s.probe) along s.direction, update its texel.
///         assert!(s.probe.x < 2 && s.direction.z >= 0.0 && s.guiding_value > 0.0);
///     }
/// }
/// # Ok::<(), mcg_probe_cache::ProbeError>(())
/// ```
#[derive(Clone, Debug)]
pub struct ProbeChains {
    cells: ProxyGrid,
    kind: ChainKind,
    walk: RandomWalk<CHAIN_DIMENSIONS>,
    schedule: FrameSchedule,
    lo: Vec3,
    extent: Vec3,
    chains: Vec<ProbeChainState>,
    samples: Vec<ProbeSample>,
    claimed: Vec<u64>,
    stats: FrameStats,
}

impl ProbeChains {
    /// `count` chains of `kind` over `cells`, each started at the point of the domain given by
    /// five uniforms from `init` (position uniform in the probes' Voronoi box, direction
    /// uniform on the sphere), running `schedule` per frame.
    ///
    /// # Errors
    /// [`ChainError::NoChains`] for `count = 0`; [`ChainError::ChainStep`] as
    /// [`ChainKind::walk`].
    pub fn new(
        cells: ProxyGrid,
        kind: ChainKind,
        count: usize,
        schedule: FrameSchedule,
        mut init: impl FnMut() -> [f32; CHAIN_DIMENSIONS],
    ) -> Result<Self, ChainError> {
        if count == 0 {
            return Err(ChainError::NoChains);
        }
        let grid = cells.grid();
        let walk = kind.walk(&grid)?;
        let lo = grid.origin() - 0.5 * grid.spacing();
        let extent = grid.counts().as_vec3() * grid.spacing();
        let mut this = Self {
            cells,
            kind,
            walk,
            schedule,
            lo,
            extent,
            chains: Vec::with_capacity(count),
            samples: Vec::new(),
            claimed: Vec::new(),
            stats: FrameStats::default(),
        };
        for _ in 0..count {
            let x = this.uniform_state(&init());
            this.chains.push(ProbeChainState::new(x));
        }
        if kind == ChainKind::Dynamic {
            this.claimed = vec![0; cells.table_len().div_ceil(64)];
        }
        Ok(this)
    }

    /// ADGI's static chains (sec. 4.8): one cell per probe, the default schedule.
    ///
    /// # Errors
    /// As [`ProbeChains::new`].
    pub fn new_static(
        grid: ProbeGrid,
        count: usize,
        init: impl FnMut() -> [f32; CHAIN_DIMENSIONS],
    ) -> Result<Self, ChainError> {
        Self::new(
            ProxyGrid::probes(grid),
            ChainKind::Static,
            count,
            FrameSchedule::DEFAULT,
            init,
        )
    }

    /// ADGI's dynamic chains (sec. 4.9): on the 3 × 3 × 3 proxies, the default schedule.
    ///
    /// # Errors
    /// As [`ProbeChains::new`].
    pub fn new_dynamic(
        grid: ProbeGrid,
        count: usize,
        init: impl FnMut() -> [f32; CHAIN_DIMENSIONS],
    ) -> Result<Self, ChainError> {
        Self::new(
            ProxyGrid::adgi(grid),
            ChainKind::Dynamic,
            count,
            FrameSchedule::DEFAULT,
            init,
        )
    }

    /// The point of the domain at uniforms `u`: position `lo + u[0..3] ⊙ extent`, direction
    /// `z = 2u₃ − 1`, `φ = 2π u₄` (uniform on the sphere, by the equal-area map).
    #[inline]
    #[must_use]
    pub fn uniform_state(&self, u: &[f32; CHAIN_DIMENSIONS]) -> [f32; CHAIN_DIMENSIONS] {
        uniform_state(self.lo, self.extent, u)
    }

    /// The cells (probes or proxies) the chains' samples name.
    #[inline]
    #[must_use]
    pub fn cells(&self) -> ProxyGrid {
        self.cells
    }

    /// Static or dynamic.
    #[inline]
    #[must_use]
    pub fn kind(&self) -> ChainKind {
        self.kind
    }

    /// The random walk (its step sizes).
    #[inline]
    #[must_use]
    pub fn walk(&self) -> RandomWalk<CHAIN_DIMENSIONS> {
        self.walk
    }

    /// Steps and burn-in per frame.
    #[inline]
    #[must_use]
    pub fn schedule(&self) -> FrameSchedule {
        self.schedule
    }

    /// Replaces the schedule (takes effect next frame).
    pub fn set_schedule(&mut self, schedule: FrameSchedule) {
        self.schedule = schedule;
    }

    /// The persisted chain states (upload these to run the chains on the GPU).
    #[inline]
    #[must_use]
    pub fn states(&self) -> &[ProbeChainState] {
        &self.chains
    }

    /// Mutable chain states, e.g. to restore them or re-seed some chains.
    #[inline]
    pub fn states_mut(&mut self) -> &mut [ProbeChainState] {
        &mut self.chains
    }

    /// The samples of the last frame.
    #[inline]
    #[must_use]
    pub fn samples(&self) -> &[ProbeSample] {
        &self.samples
    }

    /// Counters of the last frame.
    #[inline]
    #[must_use]
    pub fn stats(&self) -> FrameStats {
        self.stats
    }

    /// Where chain state `x` points: its position, nearest probe (if inside the domain), folded
    /// direction coordinates and unit direction.
    #[inline]
    fn locate(cells: &ProxyGrid, x: &[f32; CHAIN_DIMENSIONS]) -> Located {
        let position = Vec3::new(x[0], x[1], x[2]);
        let folded = fold_direction(x[3], x[4]);
        Located {
            position,
            probe: cells.nearest_probe(position),
            folded,
            direction: direction_from_chain(folded[0], folded[1]),
        }
    }

    /// h at a located state: the guide, 0 outside the domain or for a bad value.
    #[inline]
    fn target<G: Guide + ?Sized>(guide: &G, at: &Located) -> f32 {
        if at.probe.is_none() {
            return 0.0;
        }
        finite_non_negative_or_zero(guide.guiding_value(at.position, at.direction))
    }

    /// Runs one frame of every chain (Alg. 1) against `guide` and returns the emitted samples
    /// (also kept in [`Self::samples`] until the next frame), in chain order. `uniforms` is
    /// called once per step, plus once per restarted chain (before its steps).
    ///
    /// The guide must be a function over the same cells (for a
    /// [`GuidingFunction`](crate::GuidingFunction), built on [`Self::cells`]); its values that
    /// are NaN, infinite or negative count as 0.
    pub fn step_frame<G, U>(&mut self, guide: &G, mut uniforms: U) -> &[ProbeSample]
    where
        G: Guide + ?Sized,
        U: FnMut() -> ProbeStepUniforms,
    {
        self.begin_frame();
        let runner = self.runner();
        let mut stats = FrameStats::default();
        let mut candidates = core::mem::take(&mut self.samples);
        for chain in &mut self.chains {
            runner.run(chain, guide, &mut uniforms, &mut candidates, &mut stats);
        }
        self.finish_frame(candidates, stats)
    }

    /// [`Self::step_frame`] on `threads` threads (scoped; `threads ≤ 1` runs on the caller's
    /// thread). Chain `j` draws its `k`-th uniforms as `uniforms(j, k)` (k counts from 0 each
    /// frame, restart draw included), so the result does not depend on the thread count and
    /// equals a sequential run fed the same keyed uniforms.
    pub fn step_frame_parallel<G, U>(
        &mut self,
        guide: &G,
        uniforms: U,
        threads: usize,
    ) -> &[ProbeSample]
    where
        G: Guide + Sync + ?Sized,
        U: Fn(usize, u32) -> ProbeStepUniforms + Sync,
    {
        self.begin_frame();
        let runner = self.runner();
        let threads = threads.clamp(1, self.chains.len());
        let per = self.chains.len().div_ceil(threads);
        let run_slice = |first: usize, slice: &mut [ProbeChainState]| {
            let mut out = Vec::new();
            let mut stats = FrameStats::default();
            for (i, chain) in slice.iter_mut().enumerate() {
                let mut k = 0u32;
                let mut u = || {
                    k += 1;
                    uniforms(first + i, k - 1)
                };
                runner.run(chain, guide, &mut u, &mut out, &mut stats);
            }
            (out, stats)
        };
        let parts: Vec<(Vec<ProbeSample>, FrameStats)> = if threads == 1 {
            vec![run_slice(0, &mut self.chains)]
        } else {
            std::thread::scope(|scope| {
                let handles: Vec<_> = self
                    .chains
                    .chunks_mut(per)
                    .enumerate()
                    .map(|(t, slice)| {
                        let run_slice = &run_slice;
                        scope.spawn(move || run_slice(t * per, slice))
                    })
                    .collect();
                handles
                    .into_iter()
                    .map(|h| h.join().expect("chain thread panicked"))
                    .collect()
            })
        };
        let mut candidates = core::mem::take(&mut self.samples);
        let mut stats = FrameStats::default();
        for (out, st) in parts {
            candidates.extend(out);
            stats.proposals += st.proposals;
            stats.accepted += st.accepted;
            stats.restarts += st.restarts;
            stats.emitted += st.emitted;
            stats.dropped += st.dropped;
        }
        self.finish_frame(candidates, stats)
    }

    /// Clears the last frame's samples and claimed (proxy, octant) bits.
    fn begin_frame(&mut self) {
        if self.kind == ChainKind::Dynamic {
            // Clear only the bits the last frame set (the table may be large).
            for s in &self.samples {
                let bit = s.cell as usize * OCTANTS + s.octant as usize;
                self.claimed[bit / 64] = 0;
            }
        }
        self.samples.clear();
    }

    /// Deduplicates (dynamic chains: first in chain order wins) and stores the samples.
    fn finish_frame(
        &mut self,
        mut candidates: Vec<ProbeSample>,
        mut stats: FrameStats,
    ) -> &[ProbeSample] {
        if self.kind == ChainKind::Dynamic {
            let claimed = &mut self.claimed;
            candidates.retain(|s| {
                let bit = s.cell as usize * OCTANTS + s.octant as usize;
                let (word, mask) = (bit / 64, 1u64 << (bit % 64));
                let fresh = claimed[word] & mask == 0;
                claimed[word] |= mask;
                fresh
            });
            let duplicates = stats.emitted - candidates.len() as u32;
            stats.emitted -= duplicates;
            stats.dropped += duplicates;
        }
        self.samples = candidates;
        self.stats = stats;
        &self.samples
    }

    fn runner(&self) -> ChainRunner {
        ChainRunner {
            cells: self.cells,
            walk: self.walk,
            schedule: self.schedule,
            lo: self.lo,
            extent: self.extent,
        }
    }
}

/// What one chain's frame needs, copied out of [`ProbeChains`] so chains can run on threads.
#[derive(Clone, Copy)]
struct ChainRunner {
    cells: ProxyGrid,
    walk: RandomWalk<CHAIN_DIMENSIONS>,
    schedule: FrameSchedule,
    lo: Vec3,
    extent: Vec3,
}

impl ChainRunner {
    /// One frame of one chain (Alg. 1): re-evaluate, restart if h = 0, M steps, emit after K.
    fn run<G, U>(
        &self,
        chain: &mut ProbeChainState,
        guide: &G,
        uniforms: &mut U,
        out: &mut Vec<ProbeSample>,
        stats: &mut FrameStats,
    ) where
        G: Guide + ?Sized,
        U: FnMut() -> ProbeStepUniforms,
    {
        let cells = self.cells;
        let mut current = ProbeChains::locate(&cells, &chain.x);
        chain.target = ProbeChains::target(guide, &current);
        if chain.target == 0.0 {
            // Independence restart of a chain outside the support.
            let u = uniforms();
            chain.x = uniform_state(self.lo, self.extent, &u.proposal);
            current = ProbeChains::locate(&cells, &chain.x);
            chain.target = ProbeChains::target(guide, &current);
            stats.restarts += 1;
        }
        for i in 0..self.schedule.iterations() {
            let u = uniforms();
            let mut proposed = current;
            let accepted = self.walk.step(
                chain,
                |x| {
                    proposed = ProbeChains::locate(&cells, x);
                    ProbeChains::target(guide, &proposed)
                },
                &u,
            );
            stats.proposals += 1;
            if accepted {
                stats.accepted += 1;
                chain.x[3] = proposed.folded[0];
                chain.x[4] = proposed.folded[1];
                current = proposed;
            }
            if i < self.schedule.burn_in() {
                continue;
            }
            let (Some(probe), true) = (current.probe, chain.target > 0.0) else {
                stats.dropped += 1;
                continue;
            };
            out.push(ProbeSample {
                cell: cells.proxy_of_probe(probe) as u32,
                probe,
                octant: octant(current.direction) as u8,
                position: current.position,
                direction: current.direction,
                guiding_value: chain.target,
            });
            stats.emitted += 1;
        }
    }
}

/// The point of the domain `lo + [0, 1]³ ⊙ extent` × sphere at uniforms `u`.
#[inline]
fn uniform_state(lo: Vec3, extent: Vec3, u: &[f32; CHAIN_DIMENSIONS]) -> [f32; CHAIN_DIMENSIONS] {
    let c = |x: f32| if x >= 0.0 { x.min(1.0) } else { 0.0 };
    let p = lo + Vec3::new(c(u[0]), c(u[1]), c(u[2])) * extent;
    let [z, phi] = fold_direction(2.0 * c(u[3]) - 1.0, TAU * c(u[4]));
    [p.x, p.y, p.z, z, phi]
}

/// A chain state resolved into what the guide and the samples need.
#[derive(Clone, Copy)]
struct Located {
    position: Vec3,
    probe: Option<UVec3>,
    folded: [f32; 2],
    direction: Vec3,
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{GuideParams, GuidingFunction};

    #[test]
    fn rejected_steps_keep_the_walks_cause() {
        use core::error::Error;
        use mcg_markov_guide::WalkError;
        let grid = |s: f32| ProbeGrid::new(Vec3::ZERO, Vec3::splat(s), UVec3::splat(2)).unwrap();
        // 3 · 10³⁰ is above the walk's maximum step; 3 · f32::MAX overflows.
        let err = ChainKind::Dynamic.walk(&grid(1e30)).unwrap_err();
        assert!(matches!(
            err,
            ChainError::ChainStep(WalkError::StepAboveMax {
                dimension: 0,
                step,
                maximum: 1e30
            }) if step > 1e30
        ));
        assert!(
            err.source()
                .is_some_and(|c| c.to_string().contains("above"))
        );
        let err = ChainKind::Dynamic.walk(&grid(f32::MAX)).unwrap_err();
        assert_eq!(
            err,
            ChainError::ChainStep(WalkError::StepNotFinite {
                dimension: 0,
                step: f32::INFINITY
            })
        );
        assert!(ChainKind::Static.walk(&grid(1.0)).is_ok());
    }

    fn lcg(seed: u32) -> impl FnMut() -> f32 {
        let mut s = seed;
        move || {
            s = s.wrapping_mul(747_796_405).wrapping_add(2_891_336_453);
            let w = ((s >> ((s >> 28) + 4)) ^ s).wrapping_mul(277_803_737);
            ((w >> 22) ^ w) as f32 * (1.0 / 4_294_967_296.0)
        }
    }

    fn step_uniforms(mut u: impl FnMut() -> f32) -> impl FnMut() -> ProbeStepUniforms {
        move || ProbeStepUniforms {
            proposal: [u(), u(), u(), u(), u()],
            accept: u(),
        }
    }

    #[test]
    fn direction_coordinates_round_trip_and_fold() {
        for &(z, phi) in &[(0.3f32, 1.0f32), (-0.9, 5.5), (1.0, 0.0), (0.0, 3.0)] {
            let d = direction_from_chain(z, phi);
            mcg_test_support::assert_close!(d.length(), 1.0, 1e-6);
            let [z2, phi2] = chain_from_direction(d);
            assert!(
                (z2 - z).abs() < 1e-6 && (z == 1.0 || (phi2 - phi).abs() < 1e-5),
                "{z} {phi}"
            );
        }
        // Reflection at +1: 1.25 → 0.75; at −1: −1.5 → −0.5; period 4.
        assert_eq!(fold_direction(1.25, 0.0), [0.75, 0.0]);
        assert_eq!(fold_direction(-1.5, 0.0), [-0.5, 0.0]);
        assert_eq!(fold_direction(4.5, 0.0), [0.5, 0.0]);
        let [_, p] = fold_direction(0.0, -0.5);
        mcg_test_support::assert_close!(p, (TAU - 0.5), 1e-6);
        assert_eq!(fold_direction(0.0, -1e-9)[1], 0.0);
        assert_eq!(fold_direction(f32::NAN, 1.0), [1.0, 0.0]);
        assert_eq!(chain_from_direction(Vec3::ZERO), [1.0, 0.0]);
        // Reflection preserves the direction's z and φ wraps: the same ω.
        let a = direction_from_chain(0.2, 7.0);
        let [z, p] = fold_direction(0.2, 7.0);
        assert!((direction_from_chain(z, p) - a).length() < 1e-6);
    }

    #[test]
    fn step_sizes_match_markov_guide_presets() {
        let grid = ProbeGrid::new(Vec3::ZERO, Vec3::splat(0.5), UVec3::splat(4)).unwrap();
        assert_eq!(
            ChainKind::Static.walk(&grid).unwrap(),
            RandomWalk::adgi_static(0.5).unwrap()
        );
        let d = ChainKind::Dynamic.walk(&grid).unwrap().step_sizes();
        let want = RandomWalk::adgi_dynamic(0.5).unwrap().step_sizes();
        for i in 0..5 {
            mcg_test_support::assert_close!(d[i], want[i], 1e-6);
        }
        let aniso = ProbeGrid::new(Vec3::ZERO, Vec3::new(1.0, 2.0, 0.25), UVec3::splat(2)).unwrap();
        let s = ChainKind::Static.walk(&aniso).unwrap().step_sizes();
        assert_eq!(&s[..3], &[1.0, 2.0, 0.25]);
    }

    #[test]
    fn rejects_zero_chains() {
        let grid = ProbeGrid::new(Vec3::ZERO, Vec3::ONE, UVec3::splat(2)).unwrap();
        assert_eq!(
            ProbeChains::new_static(grid, 0, || [0.5; 5]).err(),
            Some(ChainError::NoChains)
        );
    }

    #[test]
    fn chains_stay_in_support_and_restart() {
        let grid = ProbeGrid::new(Vec3::ZERO, Vec3::ONE, UVec3::new(4, 2, 2)).unwrap();
        let cells = ProxyGrid::probes(grid);
        // Only probe (3, 1, 1), octant 6 (−y, −z) is non-zero.
        let mut f = vec![0.0; cells.table_len()];
        let hot = grid.probe_index(UVec3::new(3, 1, 1));
        f[hot * 8 + 6] = 0.7;
        let guide = GuidingFunction::new(cells, &f, None, GuideParams::STATIC).unwrap();
        let mut u = lcg(7);
        let mut chains = ProbeChains::new_static(grid, 32, || [u(), u(), u(), u(), u()]).unwrap();
        let mut su = step_uniforms(lcg(11));
        let mut total = 0;
        for _ in 0..400 {
            for s in chains.step_frame(&guide, &mut su) {
                assert_eq!(s.cell as usize, hot);
                assert_eq!(s.octant, 6);
                assert_eq!(s.guiding_value, 0.7);
                assert!(s.direction.y < 0.0 && s.direction.z < 0.0);
                total += 1;
            }
            let st = chains.stats();
            assert_eq!(st.proposals, 32 * 8);
            assert_eq!(st.emitted + st.dropped, 32 * 6);
        }
        // The hot cell is 1/16 of the positions and 1/8 of the directions: restarts find it.
        assert!(total > 1000, "{total}");
        assert!(
            chains
                .states()
                .iter()
                .all(|c| c.target == 0.0 || c.target == 0.7)
        );
    }

    #[test]
    fn dynamic_chains_emit_each_proxy_octant_once() {
        let grid = ProbeGrid::new(Vec3::ZERO, Vec3::ONE, UVec3::new(6, 3, 3)).unwrap();
        let mut chains = ProbeChains::new_dynamic(grid, 256, {
            let mut u = lcg(3);
            move || [u(), u(), u(), u(), u()]
        })
        .unwrap();
        assert_eq!(chains.cells().proxy_count(), 2);
        assert_eq!(chains.kind(), ChainKind::Dynamic);
        let guide = |_: Vec3, _: Vec3| 1.0;
        let mut su = step_uniforms(lcg(5));
        let samples = chains.step_frame(&guide, &mut su).to_vec();
        // 2 proxies × 8 octants, each at most once; 256 chains × 6 samples find all 16.
        assert_eq!(samples.len(), 16);
        let mut seen: Vec<(u32, u8)> = samples.iter().map(|s| (s.cell, s.octant)).collect();
        seen.sort_unstable();
        seen.dedup();
        assert_eq!(seen.len(), 16);
        assert_eq!(chains.stats().emitted + chains.stats().dropped, 256 * 6);
    }

    #[test]
    fn parallel_frames_do_not_depend_on_thread_count() {
        let grid = ProbeGrid::new(Vec3::ZERO, Vec3::ONE, UVec3::new(7, 3, 4)).unwrap();
        let keyed = |j: usize, k: u32| {
            let mut u = lcg((j as u32).wrapping_mul(7919) ^ k.wrapping_mul(104_729) ^ 0x5bd1);
            ProbeStepUniforms {
                proposal: [u(), u(), u(), u(), u()],
                accept: u(),
            }
        };
        let guide = |p: Vec3, d: Vec3| {
            if p.x < 2.0 {
                0.0
            } else {
                1.0 + d.z.max(0.0) + p.y
            }
        };
        for kind in [ChainKind::Static, ChainKind::Dynamic] {
            let cells = if kind == ChainKind::Static {
                ProxyGrid::probes(grid)
            } else {
                ProxyGrid::adgi(grid)
            };
            let run = |threads: usize| {
                let mut u = lcg(9);
                let mut chains = ProbeChains::new(cells, kind, 37, FrameSchedule::DEFAULT, || {
                    [u(), u(), u(), u(), u()]
                })
                .unwrap();
                let mut all = Vec::new();
                for _ in 0..5 {
                    all.extend_from_slice(chains.step_frame_parallel(&guide, keyed, threads));
                }
                (all, chains.states().to_vec(), chains.stats())
            };
            let one = run(1);
            assert!(!one.0.is_empty());
            assert_eq!(one, run(3), "{kind:?}");
            assert_eq!(one, run(64), "{kind:?}");
            let st = one.2;
            assert_eq!(st.proposals, 37 * 8);
            assert_eq!(st.emitted + st.dropped, 37 * 6);
        }
    }

    #[test]
    fn bad_guide_values_never_stick() {
        let grid = ProbeGrid::new(Vec3::ZERO, Vec3::ONE, UVec3::splat(2)).unwrap();
        let mut u = lcg(1);
        let mut chains = ProbeChains::new_static(grid, 8, || [u(), u(), u(), u(), u()]).unwrap();
        let bad = |p: Vec3, _: Vec3| if p.x < 0.5 { f32::NAN } else { f32::INFINITY };
        let s = chains.step_frame(&bad, step_uniforms(lcg(2)));
        assert!(s.is_empty());
        assert!(chains.states().iter().all(|c| c.target == 0.0));
    }

    #[test]
    fn value_stability() {
        let grid =
            ProbeGrid::new(Vec3::new(-1.0, 0.0, 0.0), Vec3::ONE, UVec3::new(3, 2, 2)).unwrap();
        let mut u = lcg(42);
        let mut chains = ProbeChains::new_static(grid, 2, || [u(), u(), u(), u(), u()]).unwrap();
        let guide = |p: Vec3, d: Vec3| 1.0 + p.x.abs() + d.z.max(0.0);
        let s = chains.step_frame(&guide, step_uniforms(lcg(43)));
        let got: Vec<(u32, u8)> = s.iter().map(|s| (s.cell, s.octant)).collect();
        assert_eq!(
            got,
            vec![
                (0, 5),
                (7, 5),
                (7, 5),
                (2, 5),
                (2, 5),
                (2, 5),
                (1, 1),
                (1, 1),
                (1, 5),
                (1, 5),
                (4, 5),
                (3, 5)
            ],
            "{got:?}"
        );
        let x = chains.states()[0].x;
        assert_eq!(
            x.map(f32::to_bits),
            [
                0x3f93_b442,
                0x3e5b_48e4,
                0x3ef6_ba1b,
                0xbeb1_faa3,
                0x403b_8115
            ],
            "{x:?}"
        );
    }
}
