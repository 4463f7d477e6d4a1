//! `#[repr(C)]` + `Pod` host twins of the WGSL structs that have no CPU-crate type of their
//! own (kernel inputs and outputs, table and level parameters). Sizes are asserted here and
//! field offsets checked against naga's layouter in the `wgsl` test.

use bytemuck::{Pod, Zeroable};
use glam::{Vec2, Vec3};
use mcg_hashgrid::{AdaptiveGrid, BucketHash, SlotIndexer};
use mcg_vmf::{MapPrior, PriorDecay, Vmf};

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
            prior_decay: match prior.decay {
                PriorDecay::SquaredCount => 0,
                PriorDecay::Count => 1,
            },
            _pad: 0.0,
        }
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
