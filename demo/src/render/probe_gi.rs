//! `adgi` and `ddgi` on the CPU: a grid of irradiance probes fitted to the scene, updated
//! every frame by probe rays traced in the scene's BVH, and read by the camera's first hit.
//!
//! # What is computed
//! - **Probe update.** Which rays the probes trace each frame, and how they land in the
//!   texels, is `mcg-probe-cache`'s [`ProbeUpdater`]: DDGI's uniform rays and blend for
//!   `ddgi`, ADGI's pilot rays → heuristics → dynamic chains → static chains within the same
//!   budget for `adgi`. This module traces the batches it asks for ([`ShadingProbes::trace_batch`]).
//! - **Probe rays.** A ray from a probe that hits a front face at `x` brings back the radiance
//!   *reflected* there toward the probe: `ρ/π · (E_direct + E_probes(x))`, with `E_direct`
//!   estimated by one light sample (as `nee`'s light sample, [`super::cpu`], without MIS
//!   weight since nothing else samples the lights) and `E_probes` the probes' irradiance at
//!   `x` as the previous frame left it — so every frame adds one bounce and the probes
//!   converge to all bounces (DDGI's multi-bounce, Majercik et al. 2019, sec. 4). The
//!   emission of the hit surface is **not** added: the camera's shading samples the lights
//!   itself, so the probes must hold only light that has scattered at least once (the
//!   indirect light), or direct light from area emitters would be counted twice. A ray that
//!   hits a back face brings back 0 at a fifth of its distance (after the RTXGI SDK, which
//!   shortens back-face hits so that Chebyshev visibility distrusts a probe that sits inside
//!   geometry or outside the scene's walls); a miss brings back 0 at infinity.
//! - **Camera.** The first hit `x` of each camera ray shows its emission (front faces), one
//!   light sample (no MIS: the lights are only light-sampled) and `ρ/π · E_probes(x)` read with
//!   DDGI's query (trilinear, wrap shading, Chebyshev visibility;
//!   [`ProbeTexels::irradiance_at`], [`QueryConfig::DDGI`]). `ρ = (1 − metallic)·base colour`
//!   is the diffuse albedo.
//!
//! # What is approximated
//! Indirect light is diffuse only: a conductor's (GGX) lobe receives direct light from the
//! light sample and nothing from the probes, so glossy indirect reflections are missing, and
//! the probes' irradiance is a low-frequency, leak-prone estimate (DDGI sec. 4.2) — this is a
//! real-time approximation, not a consistent estimator. Each frame is shown on its own (no
//! accumulation across frames).

use core::f32::consts::FRAC_1_PI;

use glam::{UVec3, Vec3};
use mcg_gpu_backend::sampling::{next_uniform, pcg_hash};
use mcg_probe_cache::{
    FrameRays, GridError, ProbeGrid, ProbeRayRequest, ProbeTexels, ProbeUpdater, QueryConfig,
    RaySample, TexelContent, UpdateConfig, UpdatePolicy,
};
use rayon::prelude::*;

use super::cpu::{Method, RenderSettings, Vertex, direct_light, front_face, offset, render_pixels};
use super::material::Material;
use super::scene::Scene;
use crate::Result;

/// Default probe spacing in metres (`--probe-spacing`): about two probes per metre, DDGI's
/// usual density for rooms.
pub const DEFAULT_PROBE_SPACING: f32 = 0.5;

/// Default rays per probe per frame of `ddgi` (`--probe-rays`; ADGI sec. 5 gives Q-DDGI 32);
/// `adgi` spends at most the same total.
pub const DEFAULT_PROBE_RAYS: u32 = 32;

/// A back-face hit of a probe ray is recorded at this fraction of its distance (after the
/// RTXGI SDK's probe tracing, which shortens back-face hits so that Chebyshev visibility
/// distrusts the probe).
pub const BACK_FACE_DISTANCE_SCALE: f32 = 0.2;

/// The probe grid for `scene`: probes at the centres of the cells of a division of the
/// scene's bounding box (the BVH root) into `round(extent / spacing)` cells per axis (at least
/// 2), so the probes stay half a cell off the bounding walls and the spacing differs from
/// `spacing` by the rounding only.
///
/// # Errors
/// [`GridError::SpacingNotPositive`] unless `spacing` is positive and finite.
pub fn fit_grid(scene: &Scene, spacing: f32) -> Result<ProbeGrid, GridError> {
    if !(spacing > 0.0) || !spacing.is_finite() {
        return Err(GridError::SpacingNotPositive {
            spacing: Vec3::splat(spacing),
        });
    }
    let root = scene.bvh.nodes[0];
    let (lo, hi) = (Vec3::from(root.min), Vec3::from(root.max));
    let extent = (hi - lo).max(Vec3::splat(spacing));
    let counts = (extent / spacing).round().max(Vec3::splat(2.0));
    let step = extent / counts;
    ProbeGrid::new(
        lo + 0.5 * step,
        step,
        counts.as_uvec3().max(UVec3::splat(2)),
    )
}

/// The diffuse albedo of a material: the Lambertian part `(1 − metallic)·base colour`.
fn diffuse_albedo(m: &Material) -> Vec3 {
    (1.0 - m.metallic) * Vec3::from(m.base_color)
}

/// Three uniforms from a 32-bit stream seed (the light sample's).
fn three_uniforms(mut rng: u32) -> [f32; 3] {
    [
        next_uniform(&mut rng),
        next_uniform(&mut rng),
        next_uniform(&mut rng),
    ]
}

/// The probes as the renderer reads them: a grid of texels filled with `E/π` (DDGI's content)
/// and the query that reads them.
#[derive(Debug)]
pub struct ShadingProbes {
    /// The texels.
    pub texels: ProbeTexels,
    /// The query ([`QueryConfig::DDGI`] unless a caller changes it).
    pub query: QueryConfig,
}

impl ShadingProbes {
    /// Light reflected toward `vertex.wo` at `vertex`: one light sample (uniforms `u`) plus
    /// `ρ/π ·` the probes' irradiance (module docs).
    #[must_use]
    pub fn reflected(&self, scene: &Scene, vertex: &Vertex, u: [f32; 3]) -> Vec3 {
        let origin = offset(vertex.position, vertex.normal);
        let direct = direct_light(scene, vertex, origin, u).map_or(Vec3::ZERO, |(e, _, _)| e);
        let albedo = diffuse_albedo(&vertex.material);
        if albedo == Vec3::ZERO {
            return direct;
        }
        let e = self
            .texels
            .irradiance_at(vertex.position, vertex.normal, vertex.wo, &self.query);
        direct + albedo * FRAC_1_PI * e
    }

    /// What a probe ray from `origin` along the unit `direction` brings back (module docs);
    /// `u` seeds the light sample at its hit.
    #[must_use]
    pub fn probe_ray(&self, scene: &Scene, origin: Vec3, direction: Vec3, u: u32) -> RaySample {
        let miss = RaySample {
            direction,
            radiance: Vec3::ZERO,
            distance: f32::INFINITY,
        };
        // Probes hold reflected light only: emission, the environment's included, is the
        // shading point's light sample's.
        let Some(hit) = scene.intersect(origin, direction, 0.0, f32::INFINITY) else {
            return miss;
        };
        let tri = scene.bvh.triangles[hit.triangle as usize];
        let (_, n_front, cos_front) = front_face(&tri, direction);
        if !(cos_front > 0.0) {
            return RaySample {
                distance: BACK_FACE_DISTANCE_SCALE * hit.t,
                ..miss
            };
        }
        let vertex = Vertex {
            position: origin + hit.t * direction,
            normal: n_front,
            wo: -direction,
            material: scene.material_at(&hit),
            depth: 1,
        };
        RaySample {
            direction,
            radiance: self.reflected(scene, &vertex, three_uniforms(u)),
            distance: hit.t,
        }
    }

    /// The radiance a camera ray along `d` sees (module docs); draws three uniforms from `rng`.
    #[must_use]
    pub fn camera_ray(&self, scene: &Scene, d: Vec3, rng: &mut u32) -> Vec3 {
        let u = [next_uniform(rng), next_uniform(rng), next_uniform(rng)];
        let o = scene.camera.position;
        let Some(hit) = scene.intersect(o, d, 0.0, f32::INFINITY) else {
            return scene.environment_radiance(d);
        };
        let tri = scene.bvh.triangles[hit.triangle as usize];
        let (_, n_front, cos_front) = front_face(&tri, d);
        let material = scene.material_at(&hit);
        let front = cos_front > 0.0;
        let vertex = Vertex {
            position: o + hit.t * d,
            normal: if front { n_front } else { -n_front },
            wo: -d,
            material,
            depth: 0,
        };
        let emitted = if front {
            material.emission()
        } else {
            Vec3::ZERO
        };
        emitted + self.reflected(scene, &vertex, u)
    }

    /// One frame of the camera: `settings.spp` jittered camera rays per pixel
    /// ([`render_pixels`]), each shaded by [`Self::camera_ray`].
    #[must_use]
    pub fn render_frame(&self, scene: &Scene, settings: &RenderSettings, frame: u32) -> Vec<Vec3> {
        render_pixels(
            scene,
            settings,
            frame,
            || (),
            |(), d, rng| self.camera_ray(scene, d, rng),
            || (),
        )
    }

    /// Traces a batch of probe rays on rayon into `out` (one [`RaySample`] each, in order):
    /// the trace callback of [`ProbeUpdater::frame`]. A request's two uniforms seed the
    /// three of the light sample at its hit.
    ///
    /// # Panics
    /// If `out` is shorter than `requests`.
    pub fn trace_batch(&self, scene: &Scene, requests: &[ProbeRayRequest], out: &mut [RaySample]) {
        out[..requests.len()]
            .par_iter_mut()
            .zip(requests.par_iter())
            .for_each(|(o, r)| {
                *o = self.probe_ray(scene, r.origin, r.direction, request_seed(r));
            });
    }
}

/// The 32-bit seed of the light sample at the hit of `request`, from its two uniforms (both
/// devices seed the same light sample from it).
#[must_use]
pub fn request_seed(request: &ProbeRayRequest) -> u32 {
    pcg_hash(request.u.x.to_bits() ^ pcg_hash(request.u.y.to_bits()))
}

/// The seed of the light sample of probe ray `ray` of probe `probe` in frame `frame` (a
/// stream apart from the camera's paths).
#[must_use]
pub fn probe_ray_seed(seed: u32, frame: u32, probe: u32, ray: u32) -> u32 {
    const PROBE_SALT: u32 = 0x7072_6f62;
    super::cpu::path_seed(seed ^ PROBE_SALT, frame, probe, ray) ^ pcg_hash(PROBE_SALT)
}

/// The probe GI of one render: mcg-probe-cache's per-frame probe update
/// ([`ProbeUpdater`], DDGI's or ADGI's policy) whose rays this module traces, the probes the
/// renderer reads (the texels as the last update left them, as `E/π`) and the frame's ray
/// count.
#[derive(Debug)]
pub struct ProbeGi {
    updater: ProbeUpdater,
    shading: ShadingProbes,
    seed: u32,
    last_frame: FrameRays,
}

impl ProbeGi {
    /// Probe GI of `method` (`adgi` or `ddgi`) on `grid`: `ddgi` traces `rays_per_probe` rays
    /// per probe per frame, `adgi` at most the same total ([`UpdateConfig::rays_per_probe`]);
    /// every random decision comes from the counter-based stream seeded by `seed`.
    ///
    /// # Errors
    /// When `method` is not a probe method, or the updater refuses the budget (`adgi` needs
    /// more than its 8 pilot rays per probe).
    pub fn new(method: Method, grid: ProbeGrid, rays_per_probe: u32, seed: u32) -> Result<Self> {
        let policy = match method {
            Method::Adgi => UpdatePolicy::Adgi,
            Method::AdgiRefill => UpdatePolicy::AdgiRefill,
            Method::AdgiBlend => UpdatePolicy::AdgiBlend,
            Method::Ddgi => UpdatePolicy::Ddgi,
            _ => return Err(format!("{} does not shade from probes", method.name()).into()),
        };
        let mut config = UpdateConfig::DEFAULT;
        config.rays_per_probe = rays_per_probe;
        config.pilot_seed = u64::from(seed);
        let mut rng = probe_ray_seed(seed, u32::MAX, u32::MAX, u32::MAX);
        let updater =
            ProbeUpdater::new(grid, policy, config, || next_uniform(&mut rng)).map_err(|e| {
                format!(
                    "--method {} --probe-rays {rays_per_probe}: {e:?}",
                    method.name()
                )
            })?;
        let texels = ProbeTexels::new(grid, config.texels);
        Ok(Self {
            updater,
            shading: ShadingProbes {
                texels,
                query: QueryConfig::DDGI,
            },
            seed,
            last_frame: FrameRays::default(),
        })
    }

    /// The probes the renderer reads (as the last update left them).
    #[must_use]
    pub fn shading(&self) -> &ShadingProbes {
        &self.shading
    }

    /// The per-frame update.
    #[must_use]
    pub fn updater(&self) -> &ProbeUpdater {
        &self.updater
    }

    /// Probe rays traced by the last [`Self::frame`].
    #[must_use]
    pub fn rays_last_frame(&self) -> u64 {
        self.last_frame.rays
    }

    /// What the last [`Self::frame`] traced, by phase.
    #[must_use]
    pub fn last_frame(&self) -> FrameRays {
        self.last_frame
    }

    /// One frame: updates the probes with this frame's rays (which read the probes of the
    /// previous frame), then renders the camera's image from the updated probes.
    ///
    /// # Errors
    /// When the updated texels cannot be copied (never for a grid of this object's layout).
    pub fn frame(
        &mut self,
        scene: &Scene,
        settings: &RenderSettings,
        frame: u32,
    ) -> Result<Vec<Vec3>> {
        self.update(
            scene.camera.position,
            frame,
            |shading, requests, samples| {
                shading.trace_batch(scene, requests, samples);
            },
        )?;
        Ok(self.shading.render_frame(scene, settings, frame))
    }

    /// The probe update of frame `frame` with the camera at `camera`: the updater's batches
    /// traced by `trace(probes, requests, samples)` (`probes` as the previous frame left
    /// them), then the probes the renderer reads refreshed from the texels. [`Self::frame`]
    /// traces on the CPU; the GPU renderer traces the same batches in WGSL.
    ///
    /// # Errors
    /// When the updated texels cannot be copied (never for a grid of this object's layout).
    pub fn update(
        &mut self,
        camera: Vec3,
        frame: u32,
        mut trace: impl FnMut(&ShadingProbes, &[ProbeRayRequest], &mut [RaySample]),
    ) -> Result<()> {
        let mut rng = probe_ray_seed(self.seed, frame, u32::MAX, u32::MAX);
        let shading = &self.shading;
        let rays = self.updater.frame(
            u64::from(frame),
            camera,
            || next_uniform(&mut rng),
            |requests, samples| trace(shading, requests, samples),
        );
        self.last_frame = rays;
        let texels = self.updater.texels();
        match self.updater.content() {
            TexelContent::Irradiance => self
                .shading
                .texels
                .load_words(&texels.irradiance_words(), &texels.visibility_words())?,
            TexelContent::Radiance => self.shading.texels = texels.convolved(),
        }
        Ok(())
    }

    /// The seed of every random decision of this probe GI.
    #[must_use]
    pub fn seed(&self) -> u32 {
        self.seed
    }
}
