//! The MCPG guide a renderer calls per path vertex: `begin`, `sample`, `pdf`, `finish`, and
//! `end_frame` per frame (MCPG Alg. 1-3, sec. 4-5).

use mcg_hashgrid::{
    AdaptiveGrid, CellKey, LevelParams, Located, StaticGrid, cell_and_fraction, geometric_jitter,
    normal_class, stochastic_corner, stochastic_trilinear,
};
use mcg_vmf::glam::{IVec3, Vec2, Vec3};
use mcg_vmf::{LobeInputs, Vmf, VmfLanes};

use super::resampling::prepare_in_place;
use super::single_scattering::jittered_view_direction;
use super::{
    CacheConfig, CandidateSet, GridKind, GridState, GridUniforms, IrradianceCache, McpgParams,
    Observation, SharedGrid, should_discard, update,
};
use crate::error::GuideError;
use crate::{cosine_hemisphere, cosine_hemisphere_pdf};

/// The most candidates a vertex loads; [`McpgParams::candidates`] is clamped to it.
pub const MAX_CANDIDATES: usize = 8;

/// The extent, in Quake units, that [`GuideConfig::for_scene`] takes the paper's scenes to
/// span (a room of a Quake map, where the player is 56 units tall). Our choice, not the
/// paper's: it only anchors how the paper's lengths are carried over to other scenes.
pub const PAPER_SCENE_EXTENT: f32 = 1000.0;

/// Rec. 709 / sRGB luminance of linear RGB, MCPG's `lum` (Alg. 3 line 1).
#[inline]
#[must_use]
pub fn luminance(rgb: Vec3) -> f32 {
    rgb.dot(Vec3::new(0.2126, 0.7152, 0.0722))
}

/// The scattering function at a vertex: the BSDF (times |cos|) density a renderer samples
/// when the guide falls back (MCPG Alg. 2 line 3), or the phase function at a volume vertex
/// (sec. 4, "Extension to Single Scattering").
pub trait Scatter {
    /// A direction from two uniforms in [0, 1)².
    fn sample(&self, u: Vec2) -> Vec3;
    /// The density (per steradian) of [`sample`](Self::sample) at unit `w`.
    fn pdf(&self, w: Vec3) -> f32;
}

/// Lambertian scattering sampled by the cosine hemisphere around `normal` (density
/// max(0, n·ω)/π): pass the normal on the side the path arrives from.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lambertian {
    /// The unit normal of the hemisphere.
    pub normal: Vec3,
}

impl Scatter for Lambertian {
    #[inline]
    fn sample(&self, u: Vec2) -> Vec3 {
        cosine_hemisphere(self.normal, u).0
    }
    #[inline]
    fn pdf(&self, w: Vec3) -> f32 {
        cosine_hemisphere_pdf(self.normal, w)
    }
}

/// The isotropic phase function, density 1/(4π) over the sphere.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct IsotropicPhase;

impl Scatter for IsotropicPhase {
    #[inline]
    fn sample(&self, u: Vec2) -> Vec3 {
        Vmf::uniform().sample(u)
    }
    #[inline]
    fn pdf(&self, _w: Vec3) -> f32 {
        Vmf::uniform().pdf(Vec3::Z)
    }
}

/// How guided directions relate to the surface's hemisphere.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Hemisphere {
    /// The paper's lobes over the whole sphere: directions below the surface are sampled and
    /// wasted (their contribution is 0 for an opaque surface).
    Sphere,
    /// Every lobe multiplied by the vMF approximation of the clamped cosine around the normal
    /// (κ = [`mcg_vmf::CLAMPED_COSINE_KAPPA`], as Open PGL's cosine product): each lobe leans
    /// towards the normal and narrows, so fewer directions go below the surface. The lobes are
    /// still normalised vMFs and [`GuidedVertex::pdf`] is their exact mixture.
    #[default]
    CosineProduct,
}

/// Everything a [`Guide`] is built from.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GuideConfig {
    /// MCPG's constants.
    pub params: McpgParams,
    /// The adaptive grid's levels (cell size from the camera distance).
    pub adaptive: LevelParams,
    /// The static grid's cell width.
    pub static_width: f32,
    /// Slots of the adaptive grid's table.
    pub adaptive_capacity: u32,
    /// Slots of the static grid's table.
    pub static_capacity: u32,
    /// The irradiance cache, `None` to train on the radiance the renderer reports only.
    pub cache: Option<CacheConfig>,
    /// Whether lobes respect the surface's hemisphere.
    pub hemisphere: Hemisphere,
    /// How far the virtual target of an escaped ray lies (MCPG sec. 4: "virtual points
    /// displaced in the direction of the light source").
    pub environment_distance: f32,
    /// States of grid vertices not looked up or stored for more frames than this are freed by
    /// [`Guide::end_frame`]. The tables probe for a free slot (the GPU's overwrite on a hash
    /// collision has no CPU twin), so without eviction a guide whose camera keeps moving fills
    /// its tables and stops storing. `None` never evicts (and saves one age store per access).
    pub max_state_age: Option<u32>,
}

impl GuideConfig {
    /// The paper's setting, in Quake units: [`McpgParams::PAPER`], [`LevelParams::MCPG`]
    /// (0.6°, finest cell 0.01), static cells 25 wide, 2²⁰ adaptive and 2¹⁶ static slots, the
    /// cache with [`CacheConfig::DEFAULT`], whole-sphere lobes, escaped rays' targets 10⁵ away,
    /// states idle for 64 frames evicted.
    pub const PAPER: Self = Self {
        params: McpgParams::PAPER,
        adaptive: LevelParams::MCPG,
        static_width: mcg_hashgrid::constants::DEFAULT_STATIC_WIDTH,
        adaptive_capacity: 1 << 20,
        static_capacity: 1 << 16,
        cache: Some(CacheConfig::DEFAULT),
        hemisphere: Hemisphere::Sphere,
        environment_distance: 1.0e5,
        max_state_age: Some(64),
    };

    /// The paper's setting carried over to a scene whose bounds are `min`..`max`, with the
    /// cosine product on. With e = |max − min| and s = e / [`PAPER_SCENE_EXTENT`] scene units
    /// per Quake unit:
    ///
    /// | parameter | value | why |
    /// |---|---|---|
    /// | static cell width | 25·s | a length |
    /// | finest adaptive cell `min_width` | 0.01·s | a length |
    /// | angular resolution `tan_half_angle` | tan 0.3° | an angle seen from the camera |
    /// | prior scale (N_p = scale/d²) | (e/10)² | see below |
    /// | prior floor, p_bsdf, p_adaptive, N_mc, fit | as the paper | dimensionless |
    /// | escaped rays' target distance | 10⁵·s | a length |
    ///
    /// The prior: N_p = scale/d² equals one sample's weight (N² = 1) at d = √scale. The paper's
    /// scale 1 carried over as a length² ([`McpgParams::scaled`], s²) puts N_p at its floor
    /// 10⁻⁴ for every target farther than 100 Quake units, and a single accepted sample then
    /// makes a lobe with 1 − r ≈ 10⁻⁴ (κ ≈ 10⁴, half a degree) that later samples from it can
    /// hardly widen: on a light of radius 0.6 at distance 3 we measured a guided variance 10×
    /// that of cosine sampling. With √scale a tenth of the scene the first lobes are a few
    /// degrees wide and the same case has 1/30 of cosine's variance (the `guide` tests); any
    /// scale from 0.01 to 3 in that 10-unit scene gave the same within 30 %.
    ///
    /// Bounds that are not finite or have zero extent fall back to e = 1.
    #[must_use]
    pub fn for_scene(min: Vec3, max: Vec3) -> Self {
        let extent = (max - min).length();
        let extent = if extent > 0.0 && extent.is_finite() {
            extent
        } else {
            1.0
        };
        let s = extent / PAPER_SCENE_EXTENT;
        let mut c = Self::PAPER;
        c.params.prior_scale = (0.1 * extent) * (0.1 * extent);
        c.adaptive.min_width *= s;
        c.static_width *= s;
        c.environment_distance *= s;
        c.hemisphere = Hemisphere::CosineProduct;
        c
    }
}

impl GuideConfig {
    /// The same configuration with the adaptive grid's angular resolution set so that a cell
    /// spans about 8 pixels of an image `height_pixels` high with vertical field of view
    /// `fov_y` (radians). The paper's 0.6° is about 8 pixels of a 1080-pixel-high image with a
    /// 60° field of view; at lower resolutions the same 0.6° gives cells smaller than a pixel,
    /// many more states than pixels, and a slower, colder grid. Invalid input leaves the
    /// configuration unchanged.
    #[must_use]
    pub fn for_camera(mut self, fov_y: f32, height_pixels: u32) -> Self {
        let cell = 8.0 * fov_y / height_pixels as f32;
        if cell > 0.0 && cell < core::f32::consts::PI {
            self.adaptive.tan_half_angle = (0.5 * cell).tan();
        }
        self
    }

    /// The adaptive table's slots for an image of `pixels`: [`SLOTS_PER_PIXEL`] per pixel,
    /// rounded up to a power of two, at least 2¹² and at most [`MAX_ADAPTIVE_CAPACITY`]
    /// (2²² at 1920 × 1080).
    #[must_use]
    pub fn adaptive_capacity_for(pixels: u64) -> u32 {
        let slots = pixels.saturating_mul(u64::from(SLOTS_PER_PIXEL));
        let max = u64::from(MAX_ADAPTIVE_CAPACITY);
        slots.clamp(1 << 12, max).next_power_of_two() as u32
    }

    /// The same configuration with the adaptive table sized for an image of `pixels`
    /// ([`adaptive_capacity_for`](Self::adaptive_capacity_for)).
    ///
    /// With [`for_camera`](Self::for_camera)'s cells the adaptive grid holds about 1.5-1.7
    /// states per pixel (3 bounces in a closed room, `mcg-demo`'s hidden-light room at 128²
    /// and 256²), so 8 slots per pixel keep the table at load ≈ 0.2, where linear probing
    /// seldom leaves the home slot. A table much larger than that costs time, not only
    /// memory: its few occupied slots spread over many more pages and cache lines, and a
    /// guided vertex waits on its candidates' loads. At 128 × 128 pixels 2¹⁷ slots instead of
    /// 2²⁰ made a guided CPU frame of that room about 10 % cheaper with the same error
    /// (`benches/README.md`); 2¹⁶ (load ≈ 0.4) was slower again.
    #[must_use]
    pub fn for_pixels(mut self, pixels: u64) -> Self {
        self.adaptive_capacity = Self::adaptive_capacity_for(pixels);
        self
    }
}

/// Adaptive-table slots per pixel of [`GuideConfig::for_pixels`].
pub const SLOTS_PER_PIXEL: u32 = 8;

/// The most adaptive-table slots [`GuideConfig::for_pixels`] gives: 2²², [`SLOTS_PER_PIXEL`]
/// per pixel up to 724 × 724 pixels and 2 per pixel at 1920 × 1080 (the paper's engine ships
/// 32,777,259 slots). Memory per slot: 64 bytes in the CPU guide (a state, its checksum and age
/// in one cache line; 256 MiB at 2²²), 44 bytes in `mcg-gpu-backend`'s
/// `GpuMcpgGuide` (176 MiB).
///
/// It used to be [`GuideConfig::PAPER`]'s 2²⁰, which 1920 × 1080 fills: `mcg-demo`'s
/// hidden-light room (CPU, 1 spp, 3 bounces) holds 1.46 million states after 96 frames in a
/// larger table, still growing, and a full table stops storing new chains (at 128 × 128 a
/// table 3.5 times too small raised the 64-frame error 1.41-fold). At 1920 × 1080 over 96
/// frames, 2²² slots against 2²⁰: the late frames' error −9 %, the frame +3 %; 2²⁴ slots
/// gave −7 % for +13 % (more cache misses), so the cap is 2²² (`benches/README.md`).
pub const MAX_ADAPTIVE_CAPACITY: u32 = 1 << 22;

impl Default for GuideConfig {
    /// [`GuideConfig::PAPER`].
    fn default() -> Self {
        Self::PAPER
    }
}

/// The uniforms of one candidate of Alg. 1: which grid, the level jitter, the corner, and the
/// reservoir's ξ (line 9).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct CandidateUniforms {
    /// Chooses the adaptive grid when below p_adaptive.
    pub grid: f32,
    /// ξ of the geometric jitter to coarser levels.
    pub level: f32,
    /// The stochastic trilinear corner.
    pub corner: f32,
    /// The reservoir's ξ.
    pub reservoir: f32,
}

/// The uniforms of [`Guide::begin`]: one [`CandidateUniforms`] per candidate (the first
/// N_mc are used).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct BeginUniforms {
    /// Per candidate.
    pub candidates: [CandidateUniforms; MAX_CANDIDATES],
}

impl BeginUniforms {
    /// The first `count` candidates' uniforms from `next` (grid, level, corner, reservoir for
    /// each in turn), the rest 0.
    #[inline]
    #[must_use]
    pub fn from_fn(count: usize, mut next: impl FnMut() -> f32) -> Self {
        let mut u = Self::default();
        for c in u.candidates.iter_mut().take(count) {
            *c = CandidateUniforms {
                grid: next(),
                level: next(),
                corner: next(),
                reservoir: next(),
            };
        }
        u
    }
}

/// The uniforms of [`GuidedVertex::sample`]: Alg. 2's ξ against p_bsdf and the two of the
/// direction.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SampleUniforms {
    /// Alg. 2 line 1.
    pub choice: f32,
    /// The direction's (lobe's or BSDF's).
    pub direction: Vec2,
}

impl SampleUniforms {
    /// Three uniforms from `next`: choice, then the direction's two.
    #[inline]
    #[must_use]
    pub fn from_fn(mut next: impl FnMut() -> f32) -> Self {
        let choice = next();
        let x = next();
        Self {
            choice,
            direction: Vec2::new(x, next()),
        }
    }
}

/// The uniforms of [`GuidedVertex::finish`]: acceptance, the fresh store vertex, the cache's
/// corners.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FinishUniforms {
    /// Alg. 3 line 2.
    pub accept: f32,
    /// The vertex the transitioned state is stored at (Alg. 3 line 12).
    pub store: GridUniforms,
    /// The corner of the cache cell read at hit_next and written at x.
    pub cache: f32,
}

impl FinishUniforms {
    /// Five uniforms from `next`: accept, store grid, level, corner, cache corner.
    #[inline]
    #[must_use]
    pub fn from_fn(mut next: impl FnMut() -> f32) -> Self {
        let accept = next();
        let store = GridUniforms {
            grid: next(),
            level: next(),
            corner: next(),
        };
        Self {
            accept,
            store,
            cache: next(),
        }
    }
}

/// Where a guided vertex is.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Vertex {
    /// hit.x.
    pub position: Vec3,
    /// The direction whose cube-map class goes into the adaptive key: the surface normal, or
    /// the jittered reverse view direction in a volume.
    pub key_direction: Vec3,
    /// The surface normal (facing the side the path is on); `None` in a volume.
    pub normal: Option<Vec3>,
}

impl Vertex {
    /// A surface vertex at `position` with unit `normal` on the side the path arrives from.
    #[inline]
    #[must_use]
    pub const fn surface(position: Vec3, normal: Vec3) -> Self {
        Self {
            position,
            key_direction: normal,
            normal: Some(normal),
        }
    }

    /// A volume vertex at `position` seen along unit `view` (camera towards the vertex), the
    /// key direction jittered by a cosine lobe from `jitter` (MCPG sec. 4, single scattering;
    /// [`jittered_view_direction`]).
    #[inline]
    #[must_use]
    pub fn volume(position: Vec3, view: Vec3, jitter: Vec2) -> Self {
        Self {
            position,
            key_direction: jittered_view_direction(view, jitter),
            normal: None,
        }
    }
}

/// What the renderer found along the guided direction.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Traced {
    /// The ray hit a surface.
    Hit {
        /// hit_next.x.
        position: Vec3,
        /// Its normal, facing the ray's origin (the cache key's side).
        normal: Vec3,
        /// L_e(hit_next, −ω), linear RGB.
        emitted: Vec3,
        /// hit_next.x_prev for moving geometry (MCPG eq. 9); `None` for static geometry.
        previous_position: Option<Vec3>,
    },
    /// The ray left the scene; `radiance` is the environment's along ω (0 for none).
    Escaped {
        /// L_env(ω), linear RGB.
        radiance: Vec3,
    },
}

/// The inputs of [`GuidedVertex::finish`] (MCPG Alg. 3).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VertexObservation {
    /// What the ray found.
    pub traced: Traced,
    /// f·|cos θ|/p for the sampled direction, linear RGB: the factor a forward tracer multiplies
    /// its throughput by at this vertex (p the [`GuidedSample::pdf`]).
    pub weight: Vec3,
    /// L_r(hit_next, −ω), the reflected radiance at hit_next, when the renderer knows it (it
    /// finished the path and carries radiance back); `None` reads the irradiance cache (0
    /// without a cache).
    pub reflected: Option<Vec3>,
    /// w_e, the MIS weight the renderer's estimator gave the emission found along ω (`emitted`
    /// of a hit, or the environment's `radiance`), for a renderer that also samples its lights
    /// at this vertex (next-event estimation) and combines the two by MIS: 1 (what the
    /// constructors set, MCPG's rule) for a renderer without light sampling.
    ///
    /// The chain learns from f_mc = lum(weight·(w_e·L_e + L_r)), the part of the incident
    /// radiance that the guided direction carries in the renderer's estimate, so that its
    /// lobes leave to light sampling the lights it already finds and go to the light it does
    /// not (reflected light, MCPG's case); the irradiance cache still receives
    /// weight·(L_e + L_r), the whole radiance, since it stands in for L_r at the vertex before.
    /// mcg's extension (the paper samples no lights). Measured in mcg-demo's `mcpg-nee` on the
    /// room lit from behind a panel, after 64 frames: 8 % lower relative MSE than with w_e = 1
    /// on the CPU (L_r from the path), 2 % on the GPU tracer (L_r from the cache, which is
    /// empty in the first frames; those came out worse) (`benches/README.md`). Values outside
    /// [0, 1] are clamped; NaN counts as 1.
    pub emission_weight: f32,
}

impl VertexObservation {
    /// A hit of static geometry with emitted radiance `emitted`, the reflected radiance from
    /// the cache.
    #[inline]
    #[must_use]
    pub const fn hit(position: Vec3, normal: Vec3, emitted: Vec3, weight: Vec3) -> Self {
        Self {
            traced: Traced::Hit {
                position,
                normal,
                emitted,
                previous_position: None,
            },
            weight,
            reflected: None,
            emission_weight: 1.0,
        }
    }

    /// A ray that left the scene, seeing `radiance`.
    #[inline]
    #[must_use]
    pub const fn escaped(radiance: Vec3, weight: Vec3) -> Self {
        Self {
            traced: Traced::Escaped { radiance },
            weight,
            reflected: None,
            emission_weight: 1.0,
        }
    }
}

/// A direction from [`GuidedVertex::sample`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GuidedSample {
    /// ω, unit.
    pub direction: Vec3,
    /// The density the estimator divides by: [`GuidedVertex::pdf`] of `direction` (the
    /// mixture over all candidates, MCPG eq. 6-7).
    pub pdf: f32,
    /// The candidate whose lobe was sampled; `None` for the BSDF technique.
    pub lobe: Option<u8>,
}

/// What [`GuidedVertex::finish`] did with the chain (MCPG Alg. 3, sec. 5).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Transition {
    /// Accepted and stored at a fresh vertex.
    Stored,
    /// Accepted, but the store found no free slot or lost a race; the state was dropped.
    Dropped,
    /// Rejected (the chain stays).
    Rejected,
    /// Rejected, and the discard heuristic zeroed the state the lobe came from.
    Discarded,
}

/// MCPG (Alber et al. 2025) as one object: the adaptive and static grids of chain states, the
/// irradiance cache and the constants. Every per-vertex call takes `&self` and may run on many
/// threads at once; [`end_frame`](Self::end_frame) and [`set_camera`](Self::set_camera) take
/// `&mut self` between frames.
///
/// A path tracer's vertex loop, with `next()` any uniform source:
///
/// ```text
/// let v = guide.begin(Vertex::surface(x, n), Lambertian { normal: n }, &BeginUniforms::from_fn(5, next));
/// let s = v.sample(&SampleUniforms::from_fn(next));          // ω and its pdf
/// let weight = albedo * n.dot(s.direction).max(0.0) / PI / s.pdf;  // f·cos/p
/// let hit = trace(x, s.direction);
/// v.finish(&s, &VertexObservation::hit(hit.x, hit.n, hit.emitted, weight), &FinishUniforms::from_fn(next));
/// throughput *= weight;
/// ```
///
/// Time is counted in frames: [`end_frame`](Self::end_frame) advances it by one.
#[derive(Debug)]
pub struct Guide {
    config: GuideConfig,
    adaptive: AdaptiveGrid,
    static_grid: StaticGrid,
    adaptive_states: SharedGrid,
    static_states: SharedGrid,
    cache: Option<IrradianceCache>,
    camera: Vec3,
    frame: u32,
}

impl Guide {
    /// An empty guide.
    ///
    /// # Errors
    /// [`GuideError::Params`] for invalid constants, [`GuideError::Grid`] for invalid grid
    /// geometry, [`GuideError::Table`] for a capacity below 8,
    /// [`GuideError::EnvironmentDistanceNotPositive`].
    pub fn new(config: GuideConfig) -> Result<Self, GuideError> {
        config.params.validate().map_err(GuideError::Params)?;
        if !(config.environment_distance > 0.0 && config.environment_distance.is_finite()) {
            return Err(GuideError::EnvironmentDistanceNotPositive {
                distance: config.environment_distance,
            });
        }
        let adaptive = AdaptiveGrid::new(config.adaptive).map_err(GuideError::Grid)?;
        let static_grid = StaticGrid::new(config.static_width).map_err(GuideError::Grid)?;
        let aged = |g: SharedGrid| {
            if config.max_state_age.is_some() {
                g.with_age_tracking()
            } else {
                g
            }
        };
        let cache = match config.cache {
            Some(c) => Some(IrradianceCache::new(adaptive, c)?),
            None => None,
        };
        Ok(Self {
            config,
            adaptive,
            static_grid,
            adaptive_states: aged(
                SharedGrid::new(config.adaptive_capacity).map_err(GuideError::Table)?,
            ),
            static_states: aged(
                SharedGrid::new(config.static_capacity).map_err(GuideError::Table)?,
            ),
            cache,
            camera: Vec3::ZERO,
            frame: 0,
        })
    }

    /// The configuration.
    #[must_use]
    pub const fn config(&self) -> &GuideConfig {
        &self.config
    }

    /// The constants.
    #[must_use]
    pub const fn params(&self) -> &McpgParams {
        &self.config.params
    }

    /// Sets the camera position the adaptive grids' levels follow (once per frame).
    pub fn set_camera(&mut self, camera: Vec3) {
        self.camera = camera;
    }

    /// The current frame, the time T of the states (MCPG sec. 5).
    #[must_use]
    pub const fn frame(&self) -> u32 {
        self.frame
    }

    /// The irradiance cache, if any.
    #[must_use]
    pub const fn cache(&self) -> Option<&IrradianceCache> {
        self.cache.as_ref()
    }

    /// The adaptive and static grids (slot index and states).
    #[must_use]
    pub const fn grids(&self) -> (&SharedGrid, &SharedGrid) {
        (&self.adaptive_states, &self.static_states)
    }

    /// The adaptive and static grids, mutably (for upload snapshots or clearing).
    pub fn grids_mut(&mut self) -> (&mut SharedGrid, &mut SharedGrid) {
        (&mut self.adaptive_states, &mut self.static_states)
    }

    /// Ends the frame: folds the frame's samples into the irradiance cache and evicts its
    /// idle cells, evicts idle states ([`GuideConfig::max_state_age`]), then advances the time
    /// by one frame.
    pub fn end_frame(&mut self) {
        if let Some(cache) = &mut self.cache {
            cache.end_frame();
        }
        if let Some(max_age) = self.config.max_state_age {
            self.adaptive_states.evict_older_than(max_age);
            self.static_states.evict_older_than(max_age);
        }
        self.frame = self.frame.wrapping_add(1);
    }

    /// The adaptive key at `level` for the given position, class and corner.
    #[inline]
    fn adaptive_key(&self, position: Vec3, class: u8, level: u32, corner: f32) -> CellKey {
        let vertex = stochastic_trilinear(position / self.adaptive.width(level), corner);
        CellKey::new(vertex, level as u8, class)
    }

    /// The grid and key of `grid.load`/`grid.store` (MCPG sec. 4, step 3): adaptive with
    /// probability p_adaptive at the target level plus the geometric jitter, else static.
    #[inline]
    fn key(
        &self,
        position: Vec3,
        class: u8,
        target_level: u32,
        u: &GridUniforms,
    ) -> (GridKind, CellKey) {
        if u.grid < self.config.params.adaptive_probability {
            let level =
                (target_level + geometric_jitter(u.level)).min(self.adaptive.params().max_level);
            (
                GridKind::Adaptive,
                self.adaptive_key(position, class, level, u.corner),
            )
        } else {
            (
                GridKind::Static,
                self.static_grid.vertex_key(position, u.corner),
            )
        }
    }

    /// The candidates' keys of [`begin`](Self::begin): [`key`](Self::key) for each, with the
    /// cell of `position` (`⌊q⌋` and the fraction, [`cell_and_fraction`]) computed once per
    /// grid and level instead of once per candidate (most candidates share the static grid's
    /// cell or the target level's). The same keys as [`key`](Self::key) bit for bit:
    /// [`stochastic_trilinear`] is the lower corner plus the [`stochastic_corner`] offset.
    /// Hands the first `count` candidates' grids and keys to `emit`, in order (`begin` looks
    /// each up as it comes: an array of keys in between cost its initialisation and copies).
    #[inline(always)]
    fn candidate_keys(
        &self,
        position: Vec3,
        class: u8,
        target_level: u32,
        u: &BeginUniforms,
        count: usize,
        mut emit: impl FnMut(usize, GridKind, &CellKey),
    ) {
        let params = &self.config.params;
        let max_level = self.adaptive.params().max_level;
        // The cells met so far, direct-mapped: entry 0 the static grid's, entry 1 + j the
        // adaptive level target_level + j (j < 7; the geometric jitter rarely goes further),
        // `filled` their bits.
        let mut memo = [(IVec3::ZERO, Vec3::ZERO); MAX_CANDIDATES];
        let mut filled = 0_u32;
        for (k, c) in u.candidates.iter().enumerate().take(count) {
            let (kind, level, width, entry) = if c.grid < params.adaptive_probability {
                let level = (target_level + geometric_jitter(c.level)).min(max_level);
                let j = level.wrapping_sub(target_level) as usize;
                let entry = if j < MAX_CANDIDATES - 1 {
                    j + 1
                } else {
                    usize::MAX
                };
                (GridKind::Adaptive, level, self.adaptive.width(level), entry)
            } else {
                (GridKind::Static, 0, self.static_grid.width(), 0)
            };
            let (base, f) = match memo.get_mut(entry) {
                Some(m) if filled & (1 << entry) != 0 => *m,
                m => {
                    let cell = cell_and_fraction(position / width);
                    if let Some(m) = m {
                        *m = cell;
                        filled |= 1 << entry;
                    }
                    cell
                }
            };
            let corner = stochastic_corner(f, c.corner) as i32;
            let vertex = base + IVec3::new(corner & 1, (corner >> 1) & 1, corner >> 2);
            let key = match kind {
                GridKind::Adaptive => CellKey::new(vertex, level as u8, class),
                GridKind::Static => CellKey::unclassed(vertex),
            };
            emit(k, kind, &key);
        }
    }

    #[inline]
    fn grid(&self, kind: GridKind) -> &SharedGrid {
        match kind {
            GridKind::Adaptive => &self.adaptive_states,
            GridKind::Static => &self.static_states,
        }
    }

    /// MCPG Alg. 1 at `vertex`: loads N_mc candidates (all keys first, then the lookups),
    /// predicts them to the current frame (eq. 10), rejects collisions and, in the static grid,
    /// lobes below the surface; chooses one by reservoir sampling on w̄; builds every
    /// candidate's lobe once (with the cosine product if configured). `scatter` is the
    /// fallback technique (Alg. 2 line 3). A non-finite position loads nothing (the vertex
    /// samples `scatter` only). [`begin_in`](Self::begin_in) does the same in a vertex the
    /// caller keeps.
    pub fn begin<S: Scatter>(
        &self,
        vertex: Vertex,
        scatter: S,
        u: &BeginUniforms,
    ) -> GuidedVertex<'_, S> {
        let mut v = GuidedVertex {
            guide: self,
            vertex,
            scatter,
            set: CandidateSet::new(),
            slots: [None; MAX_CANDIDATES],
            lobes: VmfLanes::EMPTY,
            scatter_share: 0.0,
            class: 0,
            target_level: 0,
        };
        self.load_candidates(&mut v, u);
        v
    }

    /// [`begin`](Self::begin) written over `v`, a vertex begun earlier (by this guide or
    /// another): every part of it is replaced, and it then answers exactly as the vertex
    /// `begin(vertex, scatter, u)` returns would (the same candidates, choice, lobes, samples
    /// and densities, bit for bit). For a renderer that keeps its open vertices in place: the
    /// vertex (some 600 bytes with eight candidates) is built where it lives instead of being
    /// returned and moved there.
    pub fn begin_in<'g, S: Scatter>(
        &'g self,
        v: &mut GuidedVertex<'g, S>,
        vertex: Vertex,
        scatter: S,
        u: &BeginUniforms,
    ) {
        v.guide = self;
        v.vertex = vertex;
        v.scatter = scatter;
        self.load_candidates(v, u);
    }

    /// Alg. 1 into `v`, whose guide (`self`), vertex and scatter are set: writes every other
    /// field, whatever it held.
    #[inline(always)]
    fn load_candidates<S: Scatter>(&self, v: &mut GuidedVertex<'_, S>, u: &BeginUniforms) {
        let params = &self.config.params;
        let vertex = v.vertex;
        let x = vertex.position;
        let count = (params.candidates as usize).min(MAX_CANDIDATES);
        v.class = normal_class(vertex.key_direction);
        v.target_level = self.adaptive.target_level(self.camera.distance(x));
        v.slots = [None; MAX_CANDIDATES];
        v.scatter_share = 0.0;
        if !crate::math::all_finite(x) {
            *v.set.restart() = [GridState::EMPTY; MAX_CANDIDATES];
            v.lobes.clear();
            return;
        }
        // One batch: every key located (hashed, its lines asked for), then every lookup, then
        // every state, so that the candidates' cache misses overlap instead of waiting on
        // each other.
        let mut kinds = [GridKind::Static; MAX_CANDIDATES];
        let mut located = [Located::default(); MAX_CANDIDATES];
        self.candidate_keys(x, v.class, v.target_level, u, count, |k, kind, key| {
            kinds[k] = kind;
            located[k] = self.grid(kind).locate(key);
        });
        for k in 0..count {
            v.slots[k] = self
                .grid(kinds[k])
                .find_located(located[k])
                .map(|s| (kinds[k], s));
        }
        // The states go straight into the candidate set's storage: the loaded state, or
        // `EMPTY` for a slot without a state, a hash collision, a torn read (which leaves its
        // entry as it was) and the entries past N_mc. Then they are prepared there and
        // offered in load order.
        let states = v.set.restart();
        for (state, slot) in states.iter_mut().zip(&mut v.slots) {
            match *slot {
                Some((kind, s)) if self.grid(kind).load_into(s, state) => {}
                _ => {
                    *slot = None;
                    *state = GridState::EMPTY;
                }
            }
        }
        let now = self.frame as f32;
        for k in 0..count {
            // An `EMPTY` state is invalid: prepared to w̄ = 0 like a collision (Alg. 1 line 6).
            prepare_in_place(
                &mut states[k],
                false,
                kinds[k],
                x,
                vertex.normal,
                now,
                params,
            );
        }
        for c in &u.candidates[..count] {
            v.set.offer_stored(c.reservoir);
        }
        v.build_lobes();
    }
}

/// One vertex between [`Guide::begin`] and [`GuidedVertex::finish`]: the accessed states,
/// their lobes (built once) and the chosen one.
#[derive(Clone, Debug)]
pub struct GuidedVertex<'g, S> {
    guide: &'g Guide,
    vertex: Vertex,
    scatter: S,
    set: CandidateSet<MAX_CANDIDATES>,
    slots: [Option<(GridKind, u32)>; MAX_CANDIDATES],
    /// The lobe of each candidate with a lobe at x, weighted by its share w̄_k / Σw̄; the
    /// other lanes empty.
    lobes: VmfLanes<MAX_CANDIDATES>,
    /// The shares of valid candidates whose lobe cannot be built at x: Alg. 2 answers them
    /// with the scatter technique.
    scatter_share: f32,
    /// The cube-map class of the key direction.
    class: u8,
    /// The adaptive grid's target level at x.
    target_level: u32,
}

impl<'g, S: Scatter> GuidedVertex<'g, S> {
    /// Writes `lobes` and `scatter_share` (0 before) from the offered candidates.
    #[inline(always)]
    fn build_lobes(&mut self) {
        let total = self.set.weight_sum();
        if !(total > 0.0) {
            self.lobes.clear();
            return;
        }
        let params = &self.guide.config.params;
        let x = self.vertex.position;
        let cosine = match (self.guide.config.hemisphere, self.vertex.normal) {
            (Hemisphere::CosineProduct, Some(n)) => Vmf::clamped_cosine(n).ok(),
            _ => None,
        };
        let states = self.set.states();
        // The states' fields lane by lane (the states are stored whole), then every lane's
        // inputs in passes over all lanes, which the compiler runs four lanes wide: the
        // distance prior (`distance_prior`), the posterior's parts
        // (`SufficientStats::posterior_parts` with r_p = 0 and the N² decay) and the share,
        // with the same operations as those functions, so the lobes are the same bits.
        let mut target = [[0.0_f32; MAX_CANDIDATES]; 3];
        let mut weight_sum = [0.0_f32; MAX_CANDIDATES];
        let mut count = [0.0_f32; MAX_CANDIDATES];
        let mut inputs = LobeInputs::<MAX_CANDIDATES>::EMPTY;
        for (k, s) in states.iter().enumerate() {
            target[0][k] = s.mean_target.x;
            target[1][k] = s.mean_target.y;
            target[2][k] = s.mean_target.z;
            weight_sum[k] = s.weight_sum;
            count[k] = s.sample_count() as f32;
            inputs.one_minus_mean_cosine[k] = s.one_minus_mean_cosine;
        }
        // A young state lends the part y_k = `young_share` of its share to the scatter
        // technique: computed once here for the lobes' weights and the scatter share. The
        // parameters are read before the loop and every quotient is formed in every lane and
        // then selected: a load or a division under a branch keeps the loop from vectorising.
        let confident = params.confidence_samples > 0.0;
        let per_sample = 1.0 / params.confidence_samples;
        let (scale, min_weight) = (params.prior_scale, params.prior_min_weight);
        let mut young = [0.0_f32; MAX_CANDIDATES];
        for k in 0..MAX_CANDIDATES {
            let y = (1.0 - count[k] * per_sample).max(0.0);
            young[k] = if confident & (count[k] != 0.0) {
                y
            } else {
                0.0
            };
            let (dx, dy, dz) = (target[0][k] - x.x, target[1][k] - x.y, target[2][k] - x.z);
            let d2 = dx * dx + dy * dy + dz * dz;
            let prior = (scale / d2).max(min_weight);
            let prior = if d2 > 0.0 { prior } else { f32::INFINITY };
            // `prior != prior`: NaN (a float compare, no class test).
            #[allow(clippy::eq_op)]
            let prior = if prior != prior { min_weight } else { prior };
            inputs.offset_x[k] = dx;
            inputs.offset_y[k] = dy;
            inputs.offset_z[k] = dz;
            inputs.n_eff[k] = count[k] * count[k];
            inputs.prior_weight[k] = prior.max(0.0);
            // `prepare_in_place` zeroed w̄ of every invalid state: w̄ > 0 is valid here; lanes
            // past the offered states hold w̄ = 0 and N = 0.
            let has = (weight_sum[k] > 0.0) & (count[k] != 0.0);
            let share = (weight_sum[k] / total) * (1.0 - young[k]);
            inputs.weight[k] = if has { share } else { 0.0 };
        }
        // Every lobe at once (Alg. 2 lines 6-8; with the cosine product's lobe only,
        // μ' ∝ κμ + κ_c n, κ' = |κμ + κ_c n|), lane-wise, bit-identical to building each.
        self.lobes.set_from_inputs(&inputs, cosine.as_ref());
        for ((k, s), y) in states.iter().enumerate().zip(young) {
            if !(s.weight_sum > 0.0) {
                continue;
            }
            let share = s.weight_sum / total;
            if self.lobes.is_set(k) {
                self.scatter_share += share * y;
            } else {
                self.scatter_share += share;
            }
        }
    }

    /// The accessed states (after prediction and rejection), in load order.
    #[must_use]
    pub fn candidates(&self) -> &[GridState] {
        self.set.states()
    }

    /// sum_mc = Σ w̄ over the accessed states (MCPG Alg. 1), 0 when none is valid. Each w̄ is
    /// its chain's moving average of the target f_mc = lum(f·cos/p · L) (eq. 7), so sum_mc is
    /// N_mc times the guide's estimate of the luminance of the radiance reflected at the
    /// vertex: known before anything is traced from it, for a renderer that spends more
    /// samples where a vertex carries more light (mcg-demo's emission-only directions).
    #[inline]
    #[must_use]
    pub fn weight_sum(&self) -> f32 {
        self.set.weight_sum()
    }

    /// The index of the state Alg. 1 chose, `None` when every candidate had w̄ = 0.
    #[must_use]
    pub fn selected(&self) -> Option<usize> {
        self.set.selected_index()
    }

    /// MCPG Alg. 2: the scatter technique when no state was chosen or with probability p_bsdf
    /// (`u.choice < p_bsdf`), else the chosen state's lobe. Returns ω with
    /// [`pdf`](Self::pdf)(ω), the density to divide by.
    ///
    /// p_bsdf is also the rate at which chains restart: a scatter sample continues from the
    /// empty state (Alg. 2 line 4), so an accepted one stores a fresh single-sample state.
    ///
    /// With [`McpgParams::confidence_samples`] (mcg's extension) a chosen state with N < N_c
    /// samples gives its lobe only the part 1 − y of the remaining choices, y =
    /// [`McpgParams::young_share`] (`u.choice − p_bsdf < y·(1 − p_bsdf)` takes the scatter
    /// technique), and [`finish`](Self::finish) continues that young chain after any scatter
    /// sample rather than restarting it.
    #[inline]
    #[must_use]
    pub fn sample(&self, u: &SampleUniforms) -> GuidedSample {
        let lobe = self.lobe_choice(u.choice);
        let direction = self.direction_of(lobe, u);
        GuidedSample {
            direction,
            pdf: self.pdf(direction),
            lobe: lobe.map(|k| k as u8),
        }
    }

    /// A direction from the whole mixture that [`pdf`](Self::pdf) describes, chosen afresh by
    /// `u.choice` — the scatter technique with probability p_bsdf, else lobe k with its share
    /// (w̄_k/Σw̄)·(1 − y_k), else the scatter technique — rather than from the state Alg. 1
    /// chose for the vertex. Its density, given the vertex, is exactly [`pdf`](Self::pdf), as
    /// [`sample`](Self::sample)'s is only on average over Alg. 1's choice: several such
    /// directions at one vertex spread over every candidate's lobe where `sample`'s keep to
    /// one. Only the direction is returned, as its density is needed only where it
    /// contributes ([`pdf`](Self::pdf) of it), and it trains nothing: for directions that only
    /// gather what they meet (mcg's extension; mcg-demo's emission-only directions).
    #[inline]
    #[must_use]
    pub fn sample_mixture(&self, u: &SampleUniforms) -> Vec3 {
        self.direction_of(self.mixture_choice(u.choice), u)
    }

    /// [`sample_mixture`](Self::sample_mixture)'s lobe (`None`: the scatter technique), the
    /// twin of the WGSL `mcpg_choose_mixture`.
    #[inline]
    fn mixture_choice(&self, choice: f32) -> Option<usize> {
        let p = self.guide.config.params.bsdf_probability;
        if !(self.set.weight_sum() > 0.0) || choice < p {
            return None;
        }
        let mut rest = (choice - p) / (1.0 - p);
        for k in 0..MAX_CANDIDATES {
            let share = self.lobes.weight(k);
            if rest < share {
                return Some(k);
            }
            rest -= share;
        }
        None
    }

    /// The chosen lobe's sample, or the scatter technique's without one.
    #[inline(always)]
    fn direction_of(&self, lobe: Option<usize>, u: &SampleUniforms) -> Vec3 {
        match lobe {
            Some(k) => self.lobes.lobe(k).sample(u.direction),
            None => self.scatter.sample(u.direction),
        }
    }

    #[inline]
    fn lobe_choice(&self, choice: f32) -> Option<usize> {
        let k = self.set.selected_index()?;
        let params = &self.guide.config.params;
        let p = params.bsdf_probability;
        if choice < p || !self.lobes.is_set(k) {
            return None;
        }
        let young = params.young_share(self.set.states()[k].sample_count());
        if choice - p < young * (1.0 - p) {
            return None;
        }
        Some(k)
    }

    /// The chosen state when it is young ([`McpgParams::young_share`] > 0) and has a lobe
    /// at x: the chain a scatter sample continues.
    fn young_chain(&self) -> Option<&GridState> {
        let k = self.set.selected_index()?;
        let state = &self.set.states()[k];
        let young = self.guide.config.params.young_share(state.sample_count());
        (young > 0.0 && self.lobes.is_set(k)).then_some(state)
    }

    /// The density of ω given the accessed states (MCPG eq. 6-7 with the exact mixture of
    /// [`CandidateSet::pdf`]): p_bsdf·p_s(ω) + (1 − p_bsdf)·Σ_k (w̄_k/Σw̄)·V_k(ω), the share of
    /// a state without a lobe at x going to p_s; p_s(ω) alone when Σw̄ = 0. With the cosine
    /// product, V_k is the product lobe. With [`McpgParams::confidence_samples`], state k's
    /// term is (w̄_k/Σw̄)·((1 − y_k)·V_k(ω) + y_k·p_s(ω)), y_k = [`McpgParams::young_share`]
    /// of its N: the density [`sample`](Self::sample) draws from, exactly.
    #[inline]
    #[must_use]
    pub fn pdf(&self, w: Vec3) -> f32 {
        let scatter = self.scatter.pdf(w);
        if !(self.set.weight_sum() > 0.0) {
            return scatter;
        }
        // Every lobe's share·V_k(ω) in one lane-wise pass (normalisations computed in `begin`).
        let lobes = self.scatter_share * scatter + self.lobes.pdf(w);
        let p = self.guide.config.params.bsdf_probability;
        p * scatter + (1.0 - p) * lobes
    }

    /// MCPG Alg. 3 and the cache update, after the renderer traced `sample`:
    ///
    /// 1. L(hit_next, −ω) = L_e + L_r, L_r from the observation or the irradiance cache at
    ///    hit_next (sec. 4, "Irradiance Caching"); f_mc = lum(weight · L) (eq. 7, Alg. 3 line 1).
    /// 2. At a surface vertex, weight · L goes into the cache at x: one sample of the radiance
    ///    reflected there (exact for Lambertian surfaces, whose reflected radiance does not
    ///    depend on the outgoing direction).
    /// 3. Acceptance against the mean candidate score (eq. 8); the MLE update of the chosen
    ///    state (or the empty state after a scatter sample, unless the chosen state is young:
    ///    [`McpgParams::confidence_samples`]), T ← now and v from the hit's
    ///    previous position (eq. 9); the new state stored at a freshly chosen vertex
    ///    (line 12).
    /// 4. A rejected lobe sample may discard the state it came from (sec. 5).
    ///
    /// NaN, infinite or negative radiance or weights count as 0 and never reach a state.
    #[inline]
    pub fn finish(
        &self,
        sample: &GuidedSample,
        observation: &VertexObservation,
        u: &FinishUniforms,
    ) -> Transition {
        self.pending(sample).finish(observation, u)
    }

    /// What [`finish`](Self::finish) needs of this vertex once `sample` is drawn, apart from
    /// the lobes: a renderer that finishes its vertices only when the whole path is known
    /// (to train on the path's own estimate of L_r, [`VertexObservation::reflected`]) keeps
    /// one [`PendingFinish`] per vertex, about a sixth of a `GuidedVertex`, and may begin the
    /// next vertex over this one. `self.finish(s, o, u)` is `self.pending(s).finish(o, u)`.
    #[inline]
    #[must_use]
    pub fn pending(&self, sample: &GuidedSample) -> PendingFinish<'g> {
        let chosen = match sample.lobe {
            Some(k) => self.set.states()[k as usize],
            None => self.young_chain().copied().unwrap_or(GridState::EMPTY),
        };
        PendingFinish {
            guide: self.guide,
            position: self.vertex.position,
            normal: self.vertex.normal,
            direction: sample.direction,
            chosen,
            mean_weight: self.set.mean_weight(),
            lobe_slot: sample.lobe.and_then(|k| self.slots[k as usize]),
            class: self.class,
            target_level: self.target_level,
        }
    }
}

/// A guided vertex whose sample is drawn and whose finish (MCPG Alg. 3) waits for the
/// observation: [`GuidedVertex::pending`]. Holds the continued chain's state, the candidates'
/// mean score, the slot of the sampled lobe's state (for the discard), and where the vertex
/// is; the WGSL twin is `McpgPending` of `mcg::mcpg`.
///
/// A path tracer that trains every vertex but the last on the path's own L_r (what the path
/// gathered from the next hit on) keeps these until the path ends:
///
/// ```
/// use mcg_markov_guide::glam::Vec3;
/// use mcg_markov_guide::mcpg::{
///     BeginUniforms, FinishUniforms, Guide, GuideConfig, Lambertian, SampleUniforms, Vertex,
///     VertexObservation,
/// };
///
/// let guide = Guide::new(GuideConfig::for_scene(Vec3::ZERO, Vec3::ONE)).unwrap();
/// let mut u = 0.0_f32;
/// let mut next = move || {
///     u = (u + 0.618_034) % 1.0;
///     u
/// };
/// // A path from the floor of a unit room to its glowing ceiling and back down.
/// let (floor, ceiling) = (Vec3::new(0.5, 0.5, 0.0), Vec3::new(0.5, 0.5, 1.0));
/// let mut pending = Vec::new();
/// for (x, n) in [(floor, Vec3::Z), (ceiling, -Vec3::Z)] {
///     let u = BeginUniforms::from_fn(5, &mut next);
///     let v = guide.begin(Vertex::surface(x, n), Lambertian { normal: n }, &u);
///     let s = v.sample(&SampleUniforms::from_fn(&mut next));
///     let cos = n.dot(s.direction).max(0.0);
///     let weight = Vec3::splat(0.5 * cos / (core::f32::consts::PI * s.pdf)); // albedo 0.5
///     pending.push((v.pending(&s), weight)); // `v` may go now
/// }
/// // The path is done: the floor's vertex learns the ceiling's emission plus what the path
/// // gathered after it; the last vertex, whose hit did not scatter, reads the cache.
/// let hits = [(ceiling, -Vec3::Z, Vec3::splat(4.0)), (floor, Vec3::Z, Vec3::ZERO)];
/// let reflected = [Some(Vec3::splat(1.5)), None];
/// for (((p, weight), (y, n_y, emitted)), r) in pending.iter().zip(hits).zip(reflected) {
///     let mut seen = VertexObservation::hit(y, n_y, emitted, *weight);
///     seen.reflected = r;
///     p.finish(&seen, &FinishUniforms::from_fn(&mut next));
/// }
/// ```
#[derive(Clone, Copy, Debug)]
pub struct PendingFinish<'g> {
    guide: &'g Guide,
    position: Vec3,
    normal: Option<Vec3>,
    direction: Vec3,
    /// The chain the transition continues: the sampled lobe's state, a young chosen state's
    /// after a scatter sample, else the empty state (Alg. 2 line 4).
    chosen: GridState,
    /// Σw̄ / N over the accessed states (eq. 8's denominator).
    mean_weight: f32,
    /// The grid and slot the sampled lobe's state was read from; `None` after a scatter
    /// sample or for a state that was not found.
    lobe_slot: Option<(GridKind, u32)>,
    class: u8,
    target_level: u32,
}

impl PendingFinish<'_> {
    /// [`GuidedVertex::finish`] of the vertex this was taken from, with the same result and
    /// effects on the guide.
    #[inline]
    pub fn finish(&self, observation: &VertexObservation, u: &FinishUniforms) -> Transition {
        let guide = self.guide;
        let params = &guide.config.params;
        let x = self.position;
        let w = self.direction;
        let w_e = observation.emission_weight;
        let w_e = if w_e.is_nan() {
            1.0
        } else {
            w_e.clamp(0.0, 1.0)
        };
        let (next, next_previous, incident, learned) = match observation.traced {
            Traced::Hit {
                position,
                normal,
                emitted,
                previous_position,
            } => {
                let reflected = observation.reflected.unwrap_or_else(|| match &guide.cache {
                    Some(cache) => cache.query(
                        position,
                        normal,
                        guide.adaptive.target_level(guide.camera.distance(position)),
                        u.cache,
                    ),
                    None => Vec3::ZERO,
                });
                (
                    position,
                    previous_position.unwrap_or(position),
                    emitted + reflected,
                    emitted * w_e + reflected,
                )
            }
            Traced::Escaped { radiance } => {
                let target = x + w * guide.config.environment_distance;
                (target, target, radiance, radiance * w_e)
            }
        };
        let carried = crate::math::finite_radiance(observation.weight * incident);
        if let (Some(cache), Some(n)) = (&guide.cache, self.normal)
            && let Some(corner) = cache.config().add_uniform(u.cache)
        {
            cache.add(x, n, self.target_level, corner, carried);
        }
        let estimate = luminance(crate::math::finite_radiance(observation.weight * learned));
        let now = guide.frame as f32;
        let chosen = self.chosen;
        let obs = Observation {
            x,
            next,
            next_previous,
            estimate,
            now,
            frame_time: 1.0,
        };
        match update(&chosen, self.mean_weight, &obs, u.accept, params) {
            Some(new) => {
                let (kind, key) = guide.key(x, self.class, self.target_level, &u.store);
                if guide.grid(kind).store(&key, &new) {
                    Transition::Stored
                } else {
                    Transition::Dropped
                }
            }
            None => {
                if let Some((kind, slot)) = self.lobe_slot
                    && should_discard(&chosen, x, w, estimate, now, params)
                {
                    guide.grid(kind).discard(slot);
                    return Transition::Discarded;
                }
                Transition::Rejected
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mcpg::distance_prior;
    use mcg_vmf::{MapPrior, SufficientStats};

    #[test]
    fn adaptive_capacity_follows_the_pixels_within_bounds() {
        assert_eq!(GuideConfig::adaptive_capacity_for(0), 1 << 12);
        assert_eq!(GuideConfig::adaptive_capacity_for(16 * 16), 1 << 12);
        assert_eq!(GuideConfig::adaptive_capacity_for(128 * 128), 1 << 17);
        assert_eq!(GuideConfig::adaptive_capacity_for(100 * 100), 1 << 17);
        assert_eq!(GuideConfig::adaptive_capacity_for(1920 * 1080), 1 << 22);
        assert_eq!(GuideConfig::adaptive_capacity_for(512 * 512), 1 << 21);
        assert_eq!(
            GuideConfig::adaptive_capacity_for(u64::MAX),
            MAX_ADAPTIVE_CAPACITY
        );
        let c = GuideConfig::PAPER.for_pixels(64 * 64);
        assert_eq!(c.adaptive_capacity, 1 << 15);
        assert_eq!(c.static_capacity, GuideConfig::PAPER.static_capacity);
        assert!(Guide::new(c).is_ok());
    }

    /// `candidate_keys` memoises cells per grid and level; it must give [`Guide::key`]'s
    /// keys bit for bit, for every grid choice, level jitter and corner (here a 4096-vertex
    /// sweep over points, camera distances and uniforms, uniforms at 0, near 1 and beyond).
    #[test]
    fn candidate_keys_equal_the_single_keys() {
        let mut config = GuideConfig::for_scene(Vec3::ZERO, Vec3::splat(10.0));
        config.cache = None;
        let mut guide = Guide::new(config).unwrap();
        guide.set_camera(Vec3::new(5.0, 5.0, 20.0));
        let mut state = 0x1234_5678_u32;
        let mut next = || {
            state = state.wrapping_mul(747_796_405).wrapping_add(2_891_336_453);
            (state >> 8) as f32 / (1u32 << 24) as f32
        };
        let edge = [0.0, 0.999_999_94, 1.0, 0.5];
        for i in 0..4096 {
            let x = Vec3::new(
                10.0 * next(),
                10.0 * next(),
                10.0 * next() - 0.05 * i as f32,
            );
            let u = if i % 64 == 0 {
                BeginUniforms::from_fn(MAX_CANDIDATES, {
                    let mut k = 0;
                    move || {
                        k += 1;
                        edge[k % 4]
                    }
                })
            } else {
                BeginUniforms::from_fn(MAX_CANDIDATES, &mut next)
            };
            let class = normal_class(Vec3::Y);
            let target = guide.adaptive.target_level(guide.camera.distance(x));
            let mut keys = [(GridKind::Adaptive, CellKey::unclassed(IVec3::ONE)); MAX_CANDIDATES];
            guide.candidate_keys(x, class, target, &u, MAX_CANDIDATES, |k, kind, key| {
                keys[k] = (kind, *key);
            });
            for (k, c) in u.candidates.iter().enumerate() {
                let g = GridUniforms {
                    grid: c.grid,
                    level: c.level,
                    corner: c.corner,
                };
                assert_eq!(keys[k], guide.key(x, class, target, &g), "vertex {i}, {k}");
            }
        }
    }

    /// `build_lobes` forms the distance prior, the posterior's parts and the shares in passes
    /// over whole lanes; its lobes, weights and scatter share must be those of the per-state
    /// path (`distance_prior`, `young_share` and `VmfLanes::from_stats`, which gives
    /// `SufficientStats::to_vmf`'s lobes) bit for bit: 2048 random candidate sets of one to
    /// eight states per configuration (both hemisphere modes, N_c off and on), with the edge
    /// cases ȳ at x, ȳ − x underflowing and overflowing in |ȳ − x|², N = 0 and w̄ = 0.
    #[test]
    fn build_lobes_equals_the_per_state_lobes() {
        let mut seed = 0x2545_f491_u32;
        let mut next = || {
            seed = seed.wrapping_mul(747_796_405).wrapping_add(2_891_336_453);
            (seed >> 8) as f32 / (1u32 << 24) as f32
        };
        let mut lobes = 0;
        for (hemisphere, confidence) in [
            (Hemisphere::Sphere, 0.0),
            (Hemisphere::CosineProduct, 0.0),
            (Hemisphere::CosineProduct, 16.0),
        ] {
            let mut config = GuideConfig::for_scene(Vec3::ZERO, Vec3::splat(10.0));
            config.cache = None;
            config.hemisphere = hemisphere;
            config.params.confidence_samples = confidence;
            let guide = Guide::new(config).unwrap();
            let params = &guide.config.params;
            for round in 0..2048_usize {
                let x = Vec3::new(next(), next(), next()) * 10.0;
                let n = Vec3::new(next() - 0.5, next() - 0.5, next() - 0.5).normalize();
                let u = BeginUniforms::from_fn(MAX_CANDIDATES, &mut next);
                let mut v = guide.begin(Vertex::surface(x, n), Lambertian { normal: n }, &u);
                let count = 1 + round % MAX_CANDIDATES;
                let states = v.set.restart();
                for (k, state) in states.iter_mut().enumerate() {
                    let target = Vec3::new(next(), next(), next()) * 10.0;
                    let stats = SufficientStats {
                        mean_target: match (round + k) % 23 {
                            0 => x,
                            1 => x + Vec3::new(1e-24, 0.0, 0.0),
                            2 => Vec3::new(3e19, -1e19, 2e19),
                            _ => target,
                        },
                        weight_sum: if (round + k) % 17 == 3 {
                            0.0
                        } else {
                            5.0 * next()
                        },
                        one_minus_mean_cosine: next().powi(3) * 1.5,
                        sample_count: if (round + k) % 19 == 4 {
                            0
                        } else {
                            1 + (next() * 40.0) as u32
                        },
                    };
                    *state = if k < count {
                        GridState::from_stats(&stats, 0.0, Vec3::ZERO)
                    } else {
                        GridState::EMPTY
                    };
                }
                for _ in 0..count {
                    v.set.offer_stored(next());
                }
                // Stale lanes and share from the begun vertex: build_lobes writes over them.
                v.scatter_share = 0.0;
                v.build_lobes();

                let total = v.set.weight_sum();
                let states = v.set.states();
                let cosine = match hemisphere {
                    Hemisphere::CosineProduct => Vmf::clamped_cosine(n).ok(),
                    Hemisphere::Sphere => None,
                };
                let young: [f32; MAX_CANDIDATES] = core::array::from_fn(|k| {
                    states
                        .get(k)
                        .map_or(0.0, |s| params.young_share(s.sample_count()))
                });
                let want = if total > 0.0 {
                    VmfLanes::<MAX_CANDIDATES>::from_stats(x, cosine.as_ref(), |k| {
                        match states.get(k) {
                            Some(s) if s.weight_sum > 0.0 => (
                                s.stats(),
                                distance_prior(s, x, params),
                                (s.weight_sum / total) * (1.0 - young[k]),
                            ),
                            _ => (SufficientStats::EMPTY, MapPrior::NONE, 0.0),
                        }
                    })
                } else {
                    VmfLanes::EMPTY
                };
                let mut scatter_share = 0.0_f32;
                for (k, s) in states.iter().enumerate() {
                    if s.weight_sum > 0.0 && total > 0.0 {
                        let share = s.weight_sum / total;
                        scatter_share += if want.is_set(k) {
                            share * young[k]
                        } else {
                            share
                        };
                    }
                }
                for k in 0..MAX_CANDIDATES {
                    assert_eq!(v.lobes.is_set(k), want.is_set(k), "round {round} lane {k}");
                    if want.is_set(k) {
                        lobes += 1;
                        assert_eq!(v.lobes.lobe(k), want.lobe(k), "round {round} lane {k}");
                        assert_eq!(
                            v.lobes.weight(k).to_bits(),
                            want.weight(k).to_bits(),
                            "round {round} lane {k}"
                        );
                    }
                }
                let w = Vec3::new(next() - 0.5, next() - 0.5, next() - 0.5).normalize();
                assert_eq!(
                    v.lobes.pdf(w).to_bits(),
                    want.pdf(w).to_bits(),
                    "round {round}"
                );
                assert_eq!(
                    v.scatter_share.to_bits(),
                    scatter_share.to_bits(),
                    "round {round}"
                );
            }
        }
        assert!(lobes > 10_000, "{lobes}");
    }
}
