//! `#[repr(C)]` + `Pod` host twins of the WGSL structs that have no CPU-crate type of their
//! own (kernel inputs and outputs, table and level parameters). Sizes are asserted here and
//! field offsets checked against naga's layouter in the `wgsl` test.

use bytemuck::{Pod, Zeroable};
use glam::{Vec2, Vec3};
use mcg_hashgrid::{AdaptiveGrid, BucketHash, SlotIndexer};
use mcg_vmf::{MapPrior, PriorDecay, Vmf, VmfMixture};

/// Input of the `vmf_pdf_and_sample` kernel: a direction to evaluate the pdf at and two
/// uniforms to sample with. WGSL `VmfQuery` (32 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct VmfQuery {
    /// Unit direction ω for `vmf_pdf`.
    pub direction: Vec3,
    /// Padding (WGSL aligns the following `vec2<f32>` to 8 bytes, after `vec3`'s 12).
    pub _pad0: f32,
    /// Uniforms in [0, 1)² for `vmf_sample_with_pdf`.
    pub uniforms: Vec2,
    /// Padding to the struct's 16-byte alignment.
    pub _pad1: [f32; 2],
}
const _: () = assert!(size_of::<VmfQuery>() == 32);

impl VmfQuery {
    /// A query for direction `direction` and uniforms `uniforms`.
    #[must_use]
    pub fn new(direction: Vec3, uniforms: Vec2) -> Self {
        Self {
            direction,
            uniforms,
            ..Self::default()
        }
    }
}

/// Output of `vmf_sample_with_pdf`: WGSL `VmfSample` (16 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct VmfSample {
    /// The sampled unit direction.
    pub direction: Vec3,
    /// Its density in sr⁻¹.
    pub pdf: f32,
}
const _: () = assert!(size_of::<VmfSample>() == 16);

/// Input of the `vmf_stats` kernel: WGSL `VmfStatsQuery` (48 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct VmfStatsQuery {
    /// Shading point x of the reconstruction.
    pub shading_point: Vec3,
    /// A concentration for the mean-cosine round trip.
    pub kappa: f32,
    /// Lobe multiplied with the reconstructed one.
    pub other: Vmf,
    /// r_p of the MAP prior.
    pub prior_mean_cosine: f32,
    /// N_p of the MAP prior.
    pub prior_weight: f32,
    /// 0 for [`PriorDecay::SquaredCount`], 1 for [`PriorDecay::Count`].
    pub prior_decay: u32,
    /// Padding to 16-byte alignment.
    pub _pad: f32,
}
const _: () = assert!(size_of::<VmfStatsQuery>() == 48);

impl VmfStatsQuery {
    /// A query with a prior given as the CPU's [`MapPrior`].
    #[must_use]
    pub fn new(shading_point: Vec3, prior: MapPrior, other: Vmf, kappa: f32) -> Self {
        Self {
            shading_point,
            kappa,
            other,
            prior_mean_cosine: prior.mean_cosine,
            prior_weight: prior.weight,
            prior_decay: prior_decay_code(prior.decay),
            _pad: 0.0,
        }
    }
}

/// The WGSL code of a prior decay (`VMF_PRIOR_DECAY_*`): 0 squared count, 1 count.
fn prior_decay_code(decay: PriorDecay) -> u32 {
    match decay {
        PriorDecay::SquaredCount => 0,
        PriorDecay::Count => 1,
    }
}

/// Output of the `vmf_stats` kernel: WGSL `VmfStatsResult` (48 bytes). Lobes are raw
/// `[μ, κ]` because the GPU marks "no lobe" with κ = −1, which [`Vmf`] does not allow.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct VmfStatsResult {
    /// `to_vmf` (μ, κ), κ = −1 for `None`.
    pub reconstructed: [f32; 4],
    /// The product lobe (μ, κ) with the query's `other` (zero when there is no lobe).
    pub product: [f32; 4],
    /// Scale of the product.
    pub product_scale: f32,
    /// A₃(κ) of the query's κ.
    pub mean_cosine: f32,
    /// Banerjee's κ of that mean cosine.
    pub kappa_back: f32,
    /// Padding.
    pub _pad: f32,
}
const _: () = assert!(size_of::<VmfStatsResult>() == 48);

/// A hash table's shape for the WGSL table functions: WGSL `HashgridTable` (32 bytes),
/// bound as a uniform.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Pod, Zeroable)]
pub struct HashgridTableParams {
    /// Number of slots.
    pub capacity: u32,
    /// `capacity − 1` for a power-of-two capacity, else 0.
    pub mask: u32,
    /// 1 when the slot index is `h & mask`, 0 when it is `h % capacity`.
    pub is_mask: u32,
    /// Probe bound.
    pub max_probes: u32,
    /// 0 xor-primes, 1 mix, 2 mix-coherent.
    pub bucket_hash: u32,
    /// Padding to the uniform address space's 16-byte alignment.
    pub _pad: [u32; 3],
}
const _: () = assert!(size_of::<HashgridTableParams>() == 32);

impl HashgridTableParams {
    /// The parameters of a table with `capacity` slots, `max_probes` and `hash`, as
    /// `HashTable::new(capacity, max_probes, hash)` / `ConcurrentTable::new` build it.
    /// `None` for a zero capacity.
    #[must_use]
    pub fn new(capacity: u32, max_probes: u32, hash: BucketHash) -> Option<Self> {
        let indexer = SlotIndexer::new(capacity)?;
        Some(Self {
            capacity,
            mask: if indexer.is_mask() { capacity - 1 } else { 0 },
            is_mask: u32::from(indexer.is_mask()),
            max_probes,
            bucket_hash: match hash {
                BucketHash::XorPrimes => 0,
                BucketHash::Mix => 1,
                BucketHash::MixCoherent => 2,
                BucketHash::Fold => 3,
            },
            _pad: [0; 3],
        })
    }
}

/// An [`AdaptiveGrid`]'s parameters for `hashgrid_level` and `hashgrid_vertex_key`: WGSL
/// `HashgridLevels` (32 bytes), bound as a uniform.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct HashgridLevelParams {
    /// tan(θ/2) of the target footprint angle.
    pub tan_half_angle: f32,
    /// Width of level 0.
    pub min_width: f32,
    /// steps / ln(power).
    pub levels_per_ln: f32,
    /// ln(power) / steps.
    pub ln_per_level: f32,
    /// Highest level.
    pub max_level: u32,
    /// Padding.
    pub _pad: [u32; 3],
}
const _: () = assert!(size_of::<HashgridLevelParams>() == 32);

impl From<&AdaptiveGrid> for HashgridLevelParams {
    /// The grid's parameters, with `levels_per_ln` and `ln_per_level` computed as
    /// `AdaptiveGrid::new` computes them (std's `ln`).
    fn from(grid: &AdaptiveGrid) -> Self {
        let p = grid.params();
        let ln_power = p.power.ln();
        Self {
            tan_half_angle: p.tan_half_angle,
            min_width: p.min_width,
            levels_per_ln: p.steps as f32 / ln_power,
            ln_per_level: ln_power / p.steps as f32,
            max_level: p.max_level,
            _pad: [0; 3],
        }
    }
}

/// Input of the vertex-key part of `hashgrid_hashes`: WGSL `HashgridVertexQuery` (48 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct HashgridVertexQuery {
    /// Shading point.
    pub position: Vec3,
    /// Uniform of the level jitter.
    pub xi_level: f32,
    /// Surface normal (selects the normal class).
    pub normal: Vec3,
    /// Uniform of the stochastic trilinear corner.
    pub u_corner: f32,
    /// Camera position (sets the level by distance).
    pub camera: Vec3,
    /// Padding.
    pub _pad: f32,
}
const _: () = assert!(size_of::<HashgridVertexQuery>() == 48);

/// Size in `f32`s of one WGSL `VmfMixture` with `k` lobes (`shaders::VMF_MIXTURE`): 4k floats
/// of lobes (μ, κ), k weights, padded to WGSL's 16-byte struct alignment.
#[must_use]
pub const fn mixture_stride_floats(k: usize) -> usize {
    (5 * k).next_multiple_of(4)
}

/// The mixtures in the memory layout of `array<VmfMixture>` with `VMF_MIXTURE_K = K`: per
/// mixture the K lobes, then the K normalised weights, then zero padding to
/// [`mixture_stride_floats`]`(K)` floats. Upload with `GpuContext::storage_buffer`.
///
/// (`VmfMixture<K>` itself has no guaranteed layout, and a `Pod` impl generic over K would
/// need `unsafe`; this copy is what crosses the bus.)
#[must_use]
pub fn pack_mixtures<const K: usize>(mixtures: &[VmfMixture<K>]) -> Vec<f32> {
    let stride = mixture_stride_floats(K);
    let mut out = vec![0.0; stride * mixtures.len()];
    for (m, chunk) in mixtures.iter().zip(out.chunks_exact_mut(stride)) {
        for (i, lobe) in m.lobes().iter().enumerate() {
            chunk[4 * i..4 * i + 3].copy_from_slice(&lobe.mu().to_array());
            chunk[4 * i + 3] = lobe.kappa();
        }
        chunk[4 * K..5 * K].copy_from_slice(m.weights());
    }
    out
}

/// One sample for the `vmf_update` kernel: target point y seen from shading point x with
/// weight f. WGSL `VmfUpdate` (32 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct VmfUpdate {
    /// Shading point x.
    pub x: Vec3,
    /// Weight f of the sample.
    pub weight: f32,
    /// Target point y.
    pub y: Vec3,
    /// Padding to 16-byte alignment.
    pub _pad: f32,
}
const _: () = assert!(size_of::<VmfUpdate>() == 32);

/// `mcg_vmf::FitParams` for WGSL (`VmfFitParams`, bound as a uniform, 16 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct VmfFitParamsGpu {
    /// N_max.
    pub max_count: u32,
    /// α_min.
    pub alpha_min: f32,
    /// 0 for `MeanCosineUpdate::Resultant`, 1 for `Projected`.
    pub mean_cosine_update: u32,
    /// Padding to the uniform address space's 16-byte alignment.
    pub _pad: u32,
}
const _: () = assert!(size_of::<VmfFitParamsGpu>() == 16);

impl From<&mcg_vmf::FitParams> for VmfFitParamsGpu {
    fn from(p: &mcg_vmf::FitParams) -> Self {
        Self {
            max_count: p.max_count,
            alpha_min: p.alpha_min,
            mean_cosine_update: match p.mean_cosine_update {
                mcg_vmf::MeanCosineUpdate::Resultant => 0,
                mcg_vmf::MeanCosineUpdate::Projected => 1,
            },
            _pad: 0,
        }
    }
}

/// One moving-average update of a packed texel for the `codec_texel_updates` kernel: WGSL
/// `TexelUpdate` (16 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct TexelUpdate {
    /// The sample (irradiance RGB, or the visibility moments in xy).
    pub sample: Vec3,
    /// Index of the texel word it folds into.
    pub texel: u32,
}
const _: () = assert!(size_of::<TexelUpdate>() == 16);

/// Parameters of the `codec_texel_updates` kernel: WGSL `TexelParams` (uniform, 16 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct TexelParams {
    /// N_max of the moving average.
    pub max_count: u32,
    /// 0 round down, 1 nearest, 2 stochastic (`CODEC_ROUND_*`).
    pub rounding_mode: u32,
    /// The uniform of stochastic rounding.
    pub rounding_u: f32,
    /// 0 irradiance words, 1 visibility words.
    pub word_layout: u32,
}
const _: () = assert!(size_of::<TexelParams>() == 16);

/// The frame and the eviction age of the age-counter kernels: WGSL `HashgridAgeParams`
/// (uniform, 16 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Pod, Zeroable)]
pub struct HashgridAgeParams {
    /// The current frame (`HashTable::frame`).
    pub frame: u32,
    /// Slots with frame − age > `max_age` (wrapping) are evicted.
    pub max_age: u32,
    /// Padding to the uniform address space's 16-byte alignment.
    pub _pad: [u32; 2],
}
const _: () = assert!(size_of::<HashgridAgeParams>() == 16);

impl HashgridAgeParams {
    /// The parameters for `frame` and `max_age`.
    #[must_use]
    pub fn new(frame: u32, max_age: u32) -> Self {
        Self {
            frame,
            max_age,
            _pad: [0; 2],
        }
    }
}

/// Input of the `hashgrid_vertices` kernel: a position with the uniforms of both vertex
/// choices and a static grid's cell width. WGSL `HashgridJitterQuery` (32 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct HashgridJitterQuery {
    /// The position, in world units.
    pub position: Vec3,
    /// Uniform of the stochastic trilinear corner (`StaticGrid::vertex_key`).
    pub u_corner: f32,
    /// Uniforms of `jittered_vertex` (the position read as grid coordinates).
    pub u_jitter: Vec3,
    /// Cell width of the `StaticGrid`.
    pub width: f32,
}
const _: () = assert!(size_of::<HashgridJitterQuery>() == 32);

/// The shading point and the fixed MAP prior of the `markov_pixel_states` kernel: WGSL
/// `PixelQuery` (uniform, 32 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct MarkovPixelQuery {
    /// Shading point x of `PixelState::lobe`.
    pub x: Vec3,
    /// r̄_p of the MAP prior.
    pub prior_mean_cosine: f32,
    /// N_p of the MAP prior.
    pub prior_weight: f32,
    /// 0 for [`PriorDecay::SquaredCount`], 1 for [`PriorDecay::Count`].
    pub prior_decay: u32,
    /// Padding to the uniform address space's 16-byte alignment.
    pub _pad: [u32; 2],
}
const _: () = assert!(size_of::<MarkovPixelQuery>() == 32);

impl MarkovPixelQuery {
    /// The query for shading point `x` with the CPU's `prior`.
    #[must_use]
    pub fn new(x: Vec3, prior: MapPrior) -> Self {
        Self {
            x,
            prior_mean_cosine: prior.mean_cosine,
            prior_weight: prior.weight,
            prior_decay: prior_decay_code(prior.decay),
            _pad: [0; 2],
        }
    }
}
