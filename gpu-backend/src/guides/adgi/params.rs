//! The parameters `mcg::adgi` reads (`AdgiParams` in WGSL), the structs the steps exchange,
//! and the checks that a CPU configuration has a GPU twin, all derived from the CPU crate's
//! [`ProbeGrid`], [`TexelConfig`], [`QueryConfig`] and [`BlendWeights`].

use core::fmt;

use bytemuck::{Pod, Zeroable};
use glam::{UVec3, Vec3, Vec4};
use mcg_color_codec::{IrradianceLayout, VisibilityLayout};
use mcg_probe_cache::clip_volume::{ClipVolume, SHELL_COUNT};
use mcg_probe_cache::probe_chains::{ChainKind, ProbeChainState, ProbeSample, ProbeStepUniforms};
use mcg_probe_cache::{
    BlendWeights, ClipVolumes, GuideParams, HeuristicField, HeuristicParams, MapKind, PilotPhase,
    ProbeChains, ProbeGrid, ProbeTexels, QueryConfig, RaySample, RoundingMode, SmoothingKernel,
    TemporalTrigger, TexelConfig, TexelContent,
};

use crate::codes;

/// Why a CPU probe-cache configuration has no GPU twin, or why a step's input is unusable.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum AdgiConfigError {
    /// The irradiance or visibility map is not octahedral (`mcg::adgi` implements DDGI's
    /// octahedral map only; [`MapKind::EqualArea`] is CPU-only).
    MapNotOctahedral,
    /// The irradiance words do not use [`IrradianceLayout::ADGI`] (the only layout
    /// `mcg::color_codec` decodes).
    IrradianceLayoutNotAdgi,
    /// The visibility words do not use [`VisibilityLayout::ADGI`].
    VisibilityLayoutNotAdgi,
    /// A blend exponent is NaN, infinite or not positive.
    BlendPowerNotPositive,
    /// A query constant is NaN or infinite, or a floor, threshold or weight is negative.
    QueryConstantInvalid,
    /// `rays_per_probe` is 0.
    RaysPerProbeZero,
    /// The texel words need more than `u32::MAX` words or more bytes than the device binds.
    TooManyWords {
        /// Words the configuration needs.
        words: u64,
    },
    /// The chains' samples of one frame (chains × emitted steps) exceed `u32::MAX` or the
    /// device's binding size.
    TooManyChainSamples {
        /// Samples one frame can emit.
        samples: u64,
    },
}

impl fmt::Display for AdgiConfigError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::MapNotOctahedral => f.write_str("the GPU probe cache needs octahedral maps"),
            Self::IrradianceLayoutNotAdgi => {
                f.write_str("the GPU probe cache needs IrradianceLayout::ADGI")
            }
            Self::VisibilityLayoutNotAdgi => {
                f.write_str("the GPU probe cache needs VisibilityLayout::ADGI")
            }
            Self::BlendPowerNotPositive => f.write_str("a blend exponent is not positive"),
            Self::QueryConstantInvalid => f.write_str("a query constant is invalid"),
            Self::RaysPerProbeZero => f.write_str("rays_per_probe is 0"),
            Self::TooManyWords { words } => write!(f, "{words} texel words are too many"),
            Self::TooManyChainSamples { samples } => {
                write!(f, "{samples} chain samples per frame are too many")
            }
        }
    }
}

impl std::error::Error for AdgiConfigError {}

/// Everything `mcg::adgi` reads, WGSL `AdgiParams` (uniform, 144 bytes): the grid, the two
/// maps, where the visibility words start, the moving average and rounding, the codec's range,
/// DDGI's blend exponents and the query's constants. Built by [`AdgiGpuParams::new`] from the
/// CPU crate's types.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct AdgiGpuParams {
    /// [`ProbeGrid::origin`].
    pub origin: Vec3,
    /// [`ProbeGrid::cell_diagonal`], the unit of the visibility texels.
    pub cell_diagonal: f32,
    /// [`ProbeGrid::spacing`].
    pub spacing: Vec3,
    /// The smallest spacing, the unit of the query's biases.
    pub min_spacing: f32,
    /// [`ProbeGrid::counts`].
    pub counts: UVec3,
    /// [`ProbeGrid::probe_count`].
    pub probe_count: u32,
    /// Stored side of the irradiance map.
    pub irradiance_side: u32,
    /// Interior side of the irradiance map.
    pub irradiance_interior: u32,
    /// Stored side of the visibility map.
    pub visibility_side: u32,
    /// Interior side of the visibility map.
    pub visibility_interior: u32,
    /// Word index of the first visibility word (after every irradiance word).
    pub visibility_offset: u32,
    /// N_max of the moving average (`TexelConfig::moving_average`).
    pub max_count: u32,
    /// `codes::ROUND_*` of `TexelConfig::rounding`.
    pub rounding: u32,
    /// Rays per probe of DDGI's blend (the rays buffer holds `probe_count · rays_per_probe`).
    pub rays_per_probe: u32,
    /// [`ProbeTexels::max_distance`].
    pub max_distance: f32,
    /// The irradiance codec's largest value (DDGI's blend clamps radiance to it).
    pub irradiance_max_value: f32,
    /// [`BlendWeights::irradiance_power`].
    pub irradiance_power: f32,
    /// [`BlendWeights::distance_power`].
    pub distance_power: f32,
    /// 1 for [`TexelContent::Radiance`], 0 for [`TexelContent::Irradiance`].
    pub radiance_content: u32,
    /// [`QueryConfig::normal_bias`].
    pub normal_bias: f32,
    /// [`QueryConfig::view_bias`].
    pub view_bias: f32,
    /// [`QueryConfig::wrap_shading`] as 0 / 1.
    pub wrap_shading: u32,
    /// [`QueryConfig::visibility`] as 0 / 1.
    pub visibility: u32,
    /// [`QueryConfig::chebyshev_floor`].
    pub chebyshev_floor: f32,
    /// [`QueryConfig::crush_threshold`].
    pub crush_threshold: f32,
    /// [`QueryConfig::min_weight`].
    pub min_weight: f32,
    /// [`QueryConfig::min_trilinear`].
    pub min_trilinear: f32,
    /// [`QueryConfig::sqrt_blend`] as 0 / 1.
    pub sqrt_blend: u32,
    /// The clip-volume reset's count ([`SHELL_COUNT`], ADGI sec. 4.8).
    pub shell_count: u32,
    /// Padding to 16 bytes.
    pub pad_a: u32,
}
const _: () = assert!(size_of::<AdgiGpuParams>() == 144);

/// The configuration of a GPU probe cache: the same types as the CPU crate's.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ProbeCacheConfig {
    /// The probe lattice.
    pub grid: ProbeGrid,
    /// Maps, word layouts, moving average and rounding (GPU: octahedral maps, ADGI layouts).
    pub texels: TexelConfig,
    /// The irradiance query's constants.
    pub query: QueryConfig,
    /// DDGI's blend exponents.
    pub blend: BlendWeights,
    /// Rays per probe and frame of DDGI's blend (the size of the cache's rays buffer).
    pub rays_per_probe: u32,
}

impl ProbeCacheConfig {
    /// ADGI's texels ([`TexelConfig::ADGI`]) on `grid`, queried with DDGI's constants
    /// ([`QueryConfig::DDGI`]) and blended with DDGI's exponents ([`BlendWeights::DDGI`]),
    /// with room for `rays_per_probe` blend rays per probe.
    #[must_use]
    pub fn adgi(grid: ProbeGrid, rays_per_probe: u32) -> Self {
        Self {
            grid,
            texels: TexelConfig::ADGI,
            query: QueryConfig::DDGI,
            blend: BlendWeights::DDGI,
            rays_per_probe,
        }
    }
}

impl AdgiGpuParams {
    /// The parameters of `config`, validated, and the number of texel words (irradiance, then
    /// visibility).
    ///
    /// # Errors
    /// An [`AdgiConfigError`] naming what has no GPU twin or is invalid.
    pub fn new(config: &ProbeCacheConfig) -> Result<(Self, u64), AdgiConfigError> {
        validate(config)?;
        let t = &config.texels;
        let probes = config.grid.probe_count() as u64;
        let irradiance_words = probes * t.irradiance_map.texel_count() as u64;
        let words = irradiance_words + probes * t.visibility_map.texel_count() as u64;
        let rays = probes * u64::from(config.rays_per_probe);
        if words > u64::from(u32::MAX) || rays > u64::from(u32::MAX) {
            return Err(AdgiConfigError::TooManyWords { words });
        }
        let params = Self::derive(config, probes, irradiance_words);
        Ok((params, words))
    }

    /// The parameters of a validated `config` with `probes` probes, the visibility words
    /// starting at `irradiance_words`.
    fn derive(config: &ProbeCacheConfig, probes: u64, irradiance_words: u64) -> Self {
        let (grid, t, b, q) = (&config.grid, &config.texels, &config.blend, &config.query);
        // The CPU texels own the derived constants (max distance); build a one-probe twin.
        let one = ProbeGrid::new(grid.origin(), grid.spacing(), UVec3::ONE)
            .expect("a valid grid's origin and spacing");
        let max_distance = ProbeTexels::new(one, *t).max_distance();
        Self {
            origin: grid.origin(),
            cell_diagonal: grid.cell_diagonal(),
            spacing: grid.spacing(),
            min_spacing: grid.spacing().min_element(),
            counts: grid.counts(),
            probe_count: probes as u32,
            irradiance_side: t.irradiance_map.side(),
            irradiance_interior: t.irradiance_map.interior(),
            visibility_side: t.visibility_map.side(),
            visibility_interior: t.visibility_map.interior(),
            visibility_offset: irradiance_words as u32,
            max_count: t.moving_average.max_count(),
            rounding: rounding_code(t.rounding),
            rays_per_probe: config.rays_per_probe,
            max_distance,
            irradiance_max_value: t.irradiance_layout.codec().max_value(),
            irradiance_power: b.irradiance_power,
            distance_power: b.distance_power,
            radiance_content: u32::from(q.content == TexelContent::Radiance),
            normal_bias: q.normal_bias,
            view_bias: q.view_bias,
            wrap_shading: u32::from(q.wrap_shading),
            visibility: u32::from(q.visibility),
            chebyshev_floor: q.chebyshev_floor,
            crush_threshold: q.crush_threshold,
            min_weight: q.min_weight,
            min_trilinear: q.min_trilinear,
            sqrt_blend: u32::from(q.sqrt_blend),
            shell_count: SHELL_COUNT,
            pad_a: 0,
        }
    }
}

/// Checks that `config` has a GPU twin: octahedral maps, ADGI layouts, positive blend powers,
/// finite non-negative query constants and some rays per probe.
fn validate(config: &ProbeCacheConfig) -> Result<(), AdgiConfigError> {
    let t = &config.texels;
    if t.irradiance_map.kind() != MapKind::Octahedral
        || t.visibility_map.kind() != MapKind::Octahedral
    {
        return Err(AdgiConfigError::MapNotOctahedral);
    }
    if t.irradiance_layout != IrradianceLayout::ADGI {
        return Err(AdgiConfigError::IrradianceLayoutNotAdgi);
    }
    if t.visibility_layout != VisibilityLayout::ADGI {
        return Err(AdgiConfigError::VisibilityLayoutNotAdgi);
    }
    let b = &config.blend;
    let positive = |x: f32| x > 0.0 && x.is_finite();
    if !positive(b.irradiance_power) || !positive(b.distance_power) {
        return Err(AdgiConfigError::BlendPowerNotPositive);
    }
    let q = &config.query;
    let non_negative = |x: f32| x >= 0.0 && x.is_finite();
    if ![
        q.normal_bias.abs(),
        q.view_bias.abs(),
        q.chebyshev_floor,
        q.crush_threshold,
        q.min_weight,
        q.min_trilinear,
    ]
    .into_iter()
    .all(non_negative)
    {
        return Err(AdgiConfigError::QueryConstantInvalid);
    }
    if config.rays_per_probe == 0 {
        return Err(AdgiConfigError::RaysPerProbeZero);
    }
    Ok(())
}

/// The `codes::ROUND_*` of a [`RoundingMode`].
#[must_use]
pub const fn rounding_code(mode: RoundingMode) -> u32 {
    match mode {
        RoundingMode::Stochastic => codes::ROUND_STOCHASTIC,
        RoundingMode::Down => codes::ROUND_DOWN,
        RoundingMode::Nearest => codes::ROUND_NEAREST,
    }
}

/// One ray a renderer traced from a probe, WGSL `AdgiRaySample` (32 bytes): a
/// [`RaySample`] and the probe's linear index. Rays of DDGI's blend are stored probe-major
/// (`probe` is then ignored); samples of ADGI's per-sample update name their probe.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuRaySample {
    /// [`RaySample::direction`].
    pub direction: Vec3,
    /// [`RaySample::distance`] (world units, `f32::INFINITY` for a miss, NaN ignored).
    pub distance: f32,
    /// [`RaySample::radiance`].
    pub radiance: Vec3,
    /// The probe's linear index ([`ProbeGrid::probe_index`]).
    pub probe: u32,
}
const _: () = assert!(size_of::<GpuRaySample>() == 32);

impl GpuRaySample {
    /// `sample` at probe `probe`.
    #[must_use]
    pub const fn new(probe: u32, sample: &RaySample) -> Self {
        Self {
            direction: sample.direction,
            distance: sample.distance,
            radiance: sample.radiance,
            probe,
        }
    }
}

/// One irradiance query, WGSL `AdgiQuery` (48 bytes): point, normal and direction to the
/// viewer of `ProbeTexels::irradiance_at`, each in the `xyz` of a `Vec4`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuIrradianceQuery {
    /// The shading point (`w` unused).
    pub position: Vec4,
    /// The surface normal (`w` unused).
    pub normal: Vec4,
    /// The unit direction toward the viewer, zero for no view bias (`w` unused).
    pub to_viewer: Vec4,
}
const _: () = assert!(size_of::<GpuIrradianceQuery>() == 48);

impl GpuIrradianceQuery {
    /// The query at `position` with `normal`, seen from `to_viewer`.
    #[must_use]
    pub fn new(position: Vec3, normal: Vec3, to_viewer: Vec3) -> Self {
        Self {
            position: position.extend(0.0),
            normal: normal.extend(0.0),
            to_viewer: to_viewer.extend(0.0),
        }
    }
}

/// The sizes of one step, WGSL `AdgiStep` (uniform, 16 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Pod, Zeroable)]
pub struct GpuStepParams {
    /// Samples or queries of the step.
    pub count: u32,
    /// N_max of the per-sample update.
    pub max_count: u32,
    /// The clip-volume reset's count cap.
    pub cap: u32,
    /// Padding.
    pub pad_a: u32,
}
const _: () = assert!(size_of::<GpuStepParams>() == 16);

/// One clip volume, WGSL `AdgiClipVolume` (128 bytes): the six normalised planes of its frustum
/// and its box (`xyz` of `min_corner` / `max_corner`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuClipVolume {
    /// `Frustum::planes`.
    pub planes: [Vec4; 6],
    /// The box's lower corner (`w` unused).
    pub min_corner: Vec4,
    /// The box's upper corner (`w` unused).
    pub max_corner: Vec4,
}

/// V_in and V_out, WGSL `AdgiClipVolumes` (uniform, 256 bytes), from [`ClipVolumes`].
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuClipVolumes {
    /// V_in.
    pub inner: GpuClipVolume,
    /// V_out.
    pub outer: GpuClipVolume,
}
const _: () = assert!(size_of::<GpuClipVolumes>() == 256);

impl From<&ClipVolume> for GpuClipVolume {
    fn from(v: &ClipVolume) -> Self {
        let (lo, hi) = v.bounds();
        Self {
            planes: *v.frustum().planes(),
            min_corner: lo.extend(0.0),
            max_corner: hi.extend(0.0),
        }
    }
}

impl From<&ClipVolumes> for GpuClipVolumes {
    fn from(v: &ClipVolumes) -> Self {
        Self {
            inner: v.inner().into(),
            outer: v.outer().into(),
        }
    }
}

/// The constants of a pilot step, WGSL `AdgiPilotStep` (uniform, 16 bytes), from the CPU
/// crate's `HeuristicParams` and `TemporalTrigger`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuPilotStep {
    /// `HeuristicParams::voxel_diagonal` (eq. 11's s).
    pub voxel_diagonal: f32,
    /// `HeuristicParams::radiance_range` (eq. 12's β).
    pub radiance_range: f32,
    /// `TemporalTrigger::decay` (θ).
    pub decay: f32,
    /// 1 on a detection frame (`PilotPhase::Detect`), 0 on a reference frame.
    pub detect: u32,
}
const _: () = assert!(size_of::<GpuPilotStep>() == 16);

impl GpuPilotStep {
    /// The step of `phase` with `heuristics`' ranges and `trigger`'s decay.
    #[must_use]
    pub fn new(heuristics: &HeuristicParams, trigger: TemporalTrigger, phase: PilotPhase) -> Self {
        Self {
            voxel_diagonal: heuristics.voxel_diagonal(),
            radiance_range: heuristics.radiance_range(),
            decay: trigger.decay(),
            detect: u32::from(phase == PilotPhase::Detect),
        }
    }
}

/// One probe chain, WGSL `AdgiChainState` (32 bytes): the CPU's [`ProbeChainState`]
/// (position, z = cos θ, φ and h) and what its last GPU frame did.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuChainState {
    /// The chain's position `x[0..3]`.
    pub position: Vec3,
    /// `x[3]`, cos θ of the direction.
    pub z: f32,
    /// `x[4]`, φ of the direction.
    pub phi: f32,
    /// h at the state when it was last evaluated (`MetropolisChain::target`).
    pub target_value: f32,
    /// Bit i set when step i (< 32) of the last frame was accepted.
    pub accepted: u32,
    /// 1 when the chain restarted uniformly at the start of the last frame (its h was 0).
    pub restarted: u32,
}
const _: () = assert!(size_of::<GpuChainState>() == 32);

impl From<&ProbeChainState> for GpuChainState {
    fn from(c: &ProbeChainState) -> Self {
        Self {
            position: Vec3::new(c.x[0], c.x[1], c.x[2]),
            z: c.x[3],
            phi: c.x[4],
            target_value: c.target,
            accepted: 0,
            restarted: 0,
        }
    }
}

impl From<&GpuChainState> for ProbeChainState {
    fn from(c: &GpuChainState) -> Self {
        let mut s = ProbeChainState::new([c.position.x, c.position.y, c.position.z, c.z, c.phi]);
        s.target = c.target_value;
        s
    }
}

/// One emitted chain sample, WGSL `AdgiProbeSample` (48 bytes): the CPU's [`ProbeSample`]
/// (the probe as its linear index) and which chain emitted it at which step of the frame.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuProbeSample {
    /// [`ProbeSample::position`].
    pub position: Vec3,
    /// [`ProbeSample::cell`]: the probe (static chains) or proxy (dynamic chains).
    pub cell: u32,
    /// [`ProbeSample::direction`].
    pub direction: Vec3,
    /// [`ProbeSample::guiding_value`].
    pub guiding_value: f32,
    /// The linear index of [`ProbeSample::probe`] ([`ProbeGrid::probe_index`]).
    pub probe: u32,
    /// [`ProbeSample::octant`].
    pub octant: u32,
    /// The chain that emitted it.
    pub chain: u32,
    /// The step of the frame (K ≤ step < M).
    pub step: u32,
}
const _: () = assert!(size_of::<GpuProbeSample>() == 48);

impl GpuProbeSample {
    /// The CPU's [`ProbeSample`] on `grid`.
    #[must_use]
    pub fn to_cpu(&self, grid: &ProbeGrid) -> ProbeSample {
        ProbeSample {
            cell: self.cell,
            probe: grid.probe_coords(self.probe as usize),
            octant: self.octant as u8,
            position: self.position,
            direction: self.direction,
            guiding_value: self.guiding_value,
        }
    }
}

/// A point and direction at which to evaluate the guiding function, WGSL `AdgiGuideQuery`
/// (32 bytes; `w` unused).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuGuideQuery {
    /// The world position p.
    pub position: Vec4,
    /// The direction ω (any length).
    pub direction: Vec4,
}
const _: () = assert!(size_of::<GpuGuideQuery>() == 32);

impl GpuGuideQuery {
    /// The query h(`position`, `direction`).
    #[must_use]
    pub fn new(position: Vec3, direction: Vec3) -> Self {
        Self {
            position: position.extend(0.0),
            direction: direction.extend(0.0),
        }
    }
}

/// The chains' constants, WGSL `AdgiChainParams` (uniform, 160 bytes), derived from a CPU
/// [`ProbeChains`] and its [`GuideParams`] by [`GpuChainParams::new`].
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuChainParams {
    /// [`ProbeGrid::origin`].
    pub origin: Vec3,
    /// [`ProbeGrid::probe_count`].
    pub probe_count: u32,
    /// [`ProbeGrid::spacing`].
    pub spacing: Vec3,
    /// Padding.
    pub pad_d: u32,
    /// [`ProbeGrid::counts`].
    pub counts: UVec3,
    /// Padding.
    pub pad_e: u32,
    /// The lower corner of the sampling domain (the probes' Voronoi box).
    pub lo: Vec3,
    /// Probes per cell edge: 1 (static chains) or the proxy block (dynamic chains).
    pub block: u32,
    /// The domain's extent.
    pub extent: Vec3,
    /// Number of chains.
    pub chain_count: u32,
    /// The walk's position steps σ_p.
    pub position_step: Vec3,
    /// The walk's direction step σ_ω (z and φ).
    pub direction_step: f32,
    /// Cells per axis ([`ProxyGrid::counts`](mcg_probe_cache::ProxyGrid::counts)).
    pub cell_counts: UVec3,
    /// 1 when each (cell, octant) is emitted at most once per frame (dynamic chains).
    pub dedup: u32,
    /// M, steps per frame.
    pub iterations: u32,
    /// K, the discarded steps.
    pub burn_in: u32,
    /// The frame's key of [`chain_step_uniforms`].
    pub seed: u32,
    /// Slots of the sample buffer (chains × (M − K)).
    pub capacity: u32,
    /// α of eq. 2.
    pub alpha: f32,
    /// The cap of the exponent α ĝ / f.
    pub exponent_cap: f32,
    /// 1 when the feedback ĝ table is read, 0 for ĝ = 0.
    pub has_feedback: u32,
    /// The decoded heuristic: 0 f_v, 1 f_s, 2 f_d ([`HeuristicField`]).
    pub field: u32,
    /// Queries of a guide-value step.
    pub count: u32,
    /// Padding.
    pub pad_a: u32,
    /// Padding.
    pub pad_b: u32,
    /// Padding.
    pub pad_c: u32,
}
const _: () = assert!(size_of::<GpuChainParams>() == 160);

impl GpuChainParams {
    /// The constants of `chains` (grid, walk, schedule, kind) with the guide `guide` (eq. 2's
    /// α and cap; `feedback`: whether ĝ is read) sampling heuristic `field`. Static chains
    /// emit every sample, dynamic ones deduplicate (cell, octant) per frame.
    #[must_use]
    pub fn new(
        chains: &ProbeChains,
        guide: GuideParams,
        field: HeuristicField,
        feedback: bool,
    ) -> Self {
        let cells = chains.cells();
        let grid = cells.grid();
        let steps = chains.walk().step_sizes();
        let schedule = chains.schedule();
        let count = chains.states().len() as u32;
        Self {
            origin: grid.origin(),
            probe_count: grid.probe_count() as u32,
            spacing: grid.spacing(),
            pad_d: 0,
            counts: grid.counts(),
            pad_e: 0,
            // The expressions of `ProbeChains::new`, so the box is the CPU's bit for bit.
            lo: grid.origin() - 0.5 * grid.spacing(),
            block: cells.block(),
            extent: grid.counts().as_vec3() * grid.spacing(),
            chain_count: count,
            position_step: Vec3::new(steps[0], steps[1], steps[2]),
            direction_step: steps[3],
            cell_counts: cells.counts(),
            dedup: u32::from(chains.kind() == ChainKind::Dynamic),
            iterations: schedule.iterations(),
            burn_in: schedule.burn_in(),
            seed: 0,
            capacity: count.saturating_mul(schedule.iterations() - schedule.burn_in()),
            alpha: guide.alpha(),
            exponent_cap: guide.exponent_cap(),
            has_feedback: u32::from(feedback),
            field: match field {
                HeuristicField::Visibility => 0,
                HeuristicField::Static => 1,
                HeuristicField::Dynamic => 2,
            },
            count: 0,
            pad_a: 0,
            pad_b: 0,
            pad_c: 0,
        }
    }
}

/// The uniforms of draw `draw` (counted from 0 each frame, the restart draw included) of chain
/// `chain` in the frame keyed `seed`: six uniforms of the `mcg::sampling` stream seeded with
/// `pcg(pcg(pcg(seed) ^ chain) ^ draw)` — what `adgi_chain_uniforms` draws on the GPU. Pass
/// `|j, k| chain_step_uniforms(seed, j as u32, k)` to `ProbeChains::step_frame_parallel` to run
/// the CPU chains on the GPU's uniforms.
///
/// # Example
/// ```
/// use mcg_gpu_backend::guides::adgi::chain_step_uniforms;
/// let u = chain_step_uniforms(7, 3, 0);
/// assert!(u.proposal.iter().chain([&u.accept]).all(|x| (0.0..1.0).contains(x)));
/// assert_ne!(u, chain_step_uniforms(7, 3, 1));
/// ```
#[must_use]
pub fn chain_step_uniforms(seed: u32, chain: u32, draw: u32) -> ProbeStepUniforms {
    use crate::sampling::{next_uniform, pcg_hash};
    let mut state = pcg_hash(pcg_hash(pcg_hash(seed) ^ chain) ^ draw);
    let proposal = core::array::from_fn(|_| next_uniform(&mut state));
    ProbeStepUniforms {
        proposal,
        accept: next_uniform(&mut state),
    }
}

/// One pass of the triggers' smoothing, WGSL `AdgiSmoothingPass` (uniform, 16 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Pod, Zeroable)]
pub struct GpuSmoothingPass {
    /// 0, 1, 2: the x, y, z pass.
    pub axis: u32,
    /// [`SmoothingKernel::spatial_radius`].
    pub radius: u32,
    /// [`SmoothingKernel::directional`] as 0 / 1 (read by the x pass).
    pub directional: u32,
    /// Padding.
    pub pad_a: u32,
}
const _: () = assert!(size_of::<GpuSmoothingPass>() == 16);

impl GpuSmoothingPass {
    /// The three passes (x, y, z) of `kernel`.
    #[must_use]
    pub fn passes(kernel: SmoothingKernel) -> [Self; 3] {
        core::array::from_fn(|axis| Self {
            axis: axis as u32,
            radius: kernel.spatial_radius,
            directional: u32::from(kernel.directional),
            pad_a: 0,
        })
    }
}

/// The constants of the heuristics' composition, WGSL `AdgiCompose` (uniform, 32 bytes): the
/// camera and [`HeuristicParams`]' threshold k (eq. 10) and lighting weight μ (eq. 20).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuComposeParams {
    /// The camera position c of eq. 10.
    pub camera: Vec3,
    /// [`HeuristicParams::camera_threshold`] (k).
    pub camera_threshold: f32,
    /// [`HeuristicParams::lighting_weight`] (μ).
    pub lighting_weight: f32,
    /// Padding.
    pub pad_a: u32,
    /// Padding.
    pub pad_b: u32,
    /// Padding.
    pub pad_c: u32,
}
const _: () = assert!(size_of::<GpuComposeParams>() == 32);

impl GpuComposeParams {
    /// The composition of `heuristics` seen from `camera`.
    #[must_use]
    pub fn new(heuristics: &HeuristicParams, camera: Vec3) -> Self {
        Self {
            camera,
            camera_threshold: heuristics.camera_threshold(),
            lighting_weight: heuristics.lighting_weight(),
            pad_a: 0,
            pad_b: 0,
            pad_c: 0,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use mcg_probe_cache::TexelMap;

    fn config() -> ProbeCacheConfig {
        ProbeCacheConfig::adgi(
            ProbeGrid::new(Vec3::ZERO, Vec3::ONE, UVec3::new(4, 3, 2)).unwrap(),
            64,
        )
    }

    /// ADGI's texels: 24 probes × (64 + 256) words, visibility after 24 × 64.
    #[test]
    fn adgi_configuration_sizes() {
        let (p, words) = AdgiGpuParams::new(&config()).unwrap();
        assert_eq!(words, 24 * (64 + 256));
        assert_eq!(p.visibility_offset, 24 * 64);
        assert_eq!((p.irradiance_interior, p.visibility_interior), (6, 14));
        assert_eq!(p.max_count, 63);
        assert_eq!(p.rounding, codes::ROUND_STOCHASTIC);
    }

    #[test]
    fn configurations_without_a_gpu_twin_are_rejected() {
        let mut c = config();
        c.texels.irradiance_map = TexelMap::new(MapKind::EqualArea, 8, true).unwrap();
        assert_eq!(
            AdgiGpuParams::new(&c).unwrap_err(),
            AdgiConfigError::MapNotOctahedral
        );
        let mut c = config();
        c.blend.distance_power = f32::NAN;
        assert_eq!(
            AdgiGpuParams::new(&c).unwrap_err(),
            AdgiConfigError::BlendPowerNotPositive
        );
        let mut c = config();
        c.query.chebyshev_floor = -1.0;
        assert_eq!(
            AdgiGpuParams::new(&c).unwrap_err(),
            AdgiConfigError::QueryConstantInvalid
        );
        let mut c = config();
        c.rays_per_probe = 0;
        assert_eq!(
            AdgiGpuParams::new(&c).unwrap_err(),
            AdgiConfigError::RaysPerProbeZero
        );
    }
}
