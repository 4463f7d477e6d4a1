//! The whole renderer loop of ADGI on the CPU: scene → pilot rays → change detection → guided
//! Metropolis chains → traced rays → per-sample texel updates → irradiance queries.
//!
//! The scene is the crate's two-room test scene (`mcg_probe_cache::scene`): a lit room and a
//! dark closet behind a door that slides open at frame 12. The loop prints, per frame, how many
//! rays the dynamic chains spent, how many of all rays started in the closet, and the
//! irradiance the probes give at a floor point inside the closet next to the reference.
//!
//! Run with `cargo run --release -p mcg-probe-cache --example probe_loop`.

use mcg_probe_cache::glam::{Vec2, Vec3};
use mcg_probe_cache::guiding_function::decode_field;
use mcg_probe_cache::heuristics::{self, OCTANTS};
use mcg_probe_cache::mcg_color_codec::{HeuristicsWord, MovingAverage};
use mcg_probe_cache::pilot_rays::{PilotHit, octant_heuristics, pilot_rays};
use mcg_probe_cache::scene::Scene;
use mcg_probe_cache::temporal_gradient::{ChangeDetector, SmoothingKernel, TemporalTrigger};
use mcg_probe_cache::{
    DynamicScene, GuideParams, GuidingFunction, HeuristicField, HeuristicParams, PilotFrame,
    PilotSchedule, ProbeChains, ProbeStepUniforms, ProbeTexels, ProxyGrid, QueryConfig, RaySample,
    TexelConfig, reference_irradiance,
};
use rand::{RngExt, SeedableRng};
use rand_pcg::Pcg64Mcg;

/// Rays per frame: 16 per probe, the budget a DDGI renderer would spend.
const RAYS_PER_PROBE: usize = 16;

/// ADGI's storage and the pieces of its guide.
struct Adgi {
    texels: ProbeTexels,
    params: HeuristicParams,
    detector: ChangeDetector,
    static_chains: ProbeChains,
    dynamic_chains: ProbeChains,
    f_v: Vec<f32>,
    f_r: Vec<f32>,
    words: Vec<HeuristicsWord>,
    f_s: Vec<f32>,
    f_d: Vec<f32>,
    proxy_f_d: Vec<f32>,
    /// ĝ = 0: h = f_s (a renderer reads a mip of its cache here).
    feedback: Vec<f32>,
}

/// Rays traced in a frame: all of them, those started in the closet, the dynamic chains'.
#[derive(Default)]
struct Rays {
    all: usize,
    closet: usize,
    dynamic: usize,
}

fn main() -> Result<(), mcg_probe_cache::ProbeError> {
    let scene = DynamicScene::door_opens(12, 2);
    let mut rng = Pcg64Mcg::seed_from_u64(7);
    let mut adgi = Adgi::new(&scene, &mut rng)?;

    // A floor point in the closet, and its reference irradiance with the door open.
    let (point, normal) = (Vec3::new(8.55, 0.0, 2.0), Vec3::Y);
    let truth = reference_irradiance(&scene.after, point + 1e-3 * normal, &[normal], 32, 1)[0];
    println!(
        "frame  dynamic rays  rays in the closet  E at the closet floor (reference {truth:.3})"
    );
    for frame in 0..32u32 {
        let rays = adgi.frame(&scene, frame, &mut rng)?;
        // 5. Query: the irradiance a renderer would shade the closet floor with.
        let e = adgi
            .texels
            .irradiance_at(point, normal, Vec3::Y, &QueryConfig::ADGI_RADIANCE);
        println!(
            "{frame:>5}  {:>12}  {:>18}  {e:.3}",
            rays.dynamic, rays.closet
        );
    }
    Ok(())
}

impl Adgi {
    /// Empty texels, f_c = 1 everywhere, chains with random starts.
    fn new(scene: &DynamicScene, rng: &mut Pcg64Mcg) -> Result<Self, mcg_probe_cache::ProbeError> {
        let grid = scene.grid;
        let n = grid.probe_count() * OCTANTS;
        let detector = ChangeDetector::new(
            grid,
            TemporalTrigger::new(0.5)?,
            SmoothingKernel {
                spatial_radius: 1,
                directional: true,
            },
        );
        let params = HeuristicParams::new(1.0e3, grid.cell_diagonal())?;
        let mut init = || std::array::from_fn(|_| rng.random::<f32>());
        let budget = RAYS_PER_PROBE * grid.probe_count();
        let static_chains = ProbeChains::new_static(grid, budget / 8, &mut init)?;
        let dynamic_chains = ProbeChains::new_dynamic(grid, 32, &mut init)?;
        let proxies = dynamic_chains.cells().table_len();
        Ok(Self {
            texels: ProbeTexels::new(grid, TexelConfig::ADGI),
            params,
            detector,
            static_chains,
            dynamic_chains,
            f_v: vec![0.0; n],
            f_r: vec![0.0; n],
            words: vec![HeuristicsWord(0); n],
            f_s: vec![0.0; n],
            f_d: vec![0.0; n],
            proxy_f_d: vec![0.0; proxies],
            feedback: vec![0.0; n],
        })
    }

    /// Steps 1-4 of a frame of `scene`.
    fn frame(
        &mut self,
        scene: &DynamicScene,
        frame: u32,
        rng: &mut Pcg64Mcg,
    ) -> Result<Rays, mcg_probe_cache::ProbeError> {
        let now = scene.at_frame(frame);
        let in_closet = |probe: usize| {
            let grid = scene.grid;
            scene
                .event_region
                .contains(grid.probe_position(grid.probe_coords(probe)))
        };
        let mut rays = Rays::default();
        let mut count = |rays: &mut Rays, probe: usize, k: usize| {
            rays.all += k;
            if in_closet(probe) {
                rays.closet += k;
            }
        };
        let pilot = self.pilot_rays(&now, frame, rng, |p| count(&mut rays, p, 1));
        self.compose_heuristics(pilot)?;
        self.dynamic_chains_step(&now, rng, &mut rays, &mut count)?;
        self.static_chains_step(&now, rng, &mut rays, &mut count)?;
        Ok(rays)
    }

    /// 1. Pilot rays: one per probe octant, the same on both frames of a pair (uniforms hashed
    ///    from the pattern), so a difference between the two frames is a change.
    fn pilot_rays(
        &mut self,
        now: &Scene,
        frame: u32,
        rng: &mut Pcg64Mcg,
        mut count: impl FnMut(usize),
    ) -> PilotFrame {
        let grid = *self.texels.grid();
        let pilot = PilotSchedule::ADGI.frame(u64::from(frame));
        let hash = |pattern: u64, probe: usize, o: usize| {
            let c = (pattern << 32) ^ ((probe * OCTANTS + o) as u64) << 2;
            let h = mcg_probe_cache::reference::hash_uniform;
            (Vec2::new(h(c), h(c + 1)), Vec2::new(h(c + 2), h(c + 3)))
        };
        let mut hits = [PilotHit {
            distance: 0.0,
            luminance: 0.0,
        }; OCTANTS];
        let mut pilots = Vec::with_capacity(grid.probe_count() * OCTANTS);
        pilot_rays(
            &grid,
            pilot,
            |_| true,
            |pat, p, o| hash(pat, p, o).0,
            |r| pilots.push(r),
        );
        for ray in pilots {
            let (p, o) = (ray.probe as usize, usize::from(ray.octant));
            let hit = now.trace_probe_ray(ray.origin, ray.direction, hash(pilot.pattern, p, o).1);
            hits[o] = PilotHit {
                distance: hit.distance,
                luminance: hit.radiance.dot(Vec3::new(0.2126, 0.7152, 0.0722)),
            };
            if pilot.updates_caches() {
                self.texels.update_sample(
                    p,
                    &RaySample {
                        direction: ray.direction,
                        radiance: hit.radiance,
                        distance: hit.distance,
                    },
                    rng.random(),
                );
            }
            count(p);
            if o == OCTANTS - 1 {
                let (v, r) = octant_heuristics(&hits, &self.params);
                self.f_v[p * OCTANTS..][..OCTANTS].copy_from_slice(&v);
                self.f_r[p * OCTANTS..][..OCTANTS].copy_from_slice(&r);
            }
        }
        pilot
    }

    /// 2. Change detection (eq. 13-18) and the heuristics words (eq. 19-20, sec. 4.3).
    fn compose_heuristics(&mut self, pilot: PilotFrame) -> Result<(), mcg_probe_cache::ProbeError> {
        let grid = *self.texels.grid();
        if pilot.measures_gradient() {
            self.detector.detect(&self.f_v, &self.f_r)?;
        } else {
            self.detector.set_reference(&self.f_v, &self.f_r)?;
        }
        heuristics::compose_grid(
            &grid,
            &self.params,
            grid.origin(),
            &self.f_v,
            self.detector.delta_visibility(),
            self.detector.delta_radiance(),
            &mut self.words,
        )?;
        decode_field(&self.words, HeuristicField::Static, &mut self.f_s)?;
        decode_field(&self.words, HeuristicField::Dynamic, &mut self.f_d)?;
        Ok(())
    }

    /// 3. Dynamic chains on the 3×3×3 proxies, where something changed (sec. 4.9): each
    ///    sample = 64 rays into one octant of every probe of the proxy, N_max = 10, with up
    ///    to three quarters of the rays the pilots left.
    fn dynamic_chains_step(
        &mut self,
        now: &Scene,
        rng: &mut Pcg64Mcg,
        rays: &mut Rays,
        count: &mut impl FnMut(&mut Rays, usize, usize),
    ) -> Result<(), mcg_probe_cache::ProbeError> {
        let grid = *self.texels.grid();
        let budget = RAYS_PER_PROBE * grid.probe_count();
        let proxies = self.dynamic_chains.cells();
        proxies.max_pool(&self.f_d, &mut self.proxy_f_d)?;
        let dynamic_budget = rays.all + (budget - rays.all) * 3 / 4;
        if !self.proxy_f_d.iter().any(|&v| v > 0.0) {
            return Ok(());
        }
        let guide = GuidingFunction::new(proxies, &self.proxy_f_d, None, GuideParams::DYNAMIC)?;
        let samples = self
            .dynamic_chains
            .step_frame(&guide, || uniforms(rng))
            .to_vec();
        'samples: for s in samples {
            for coords in proxies.probes_of(s.cell as usize) {
                if rays.all + 64 > dynamic_budget {
                    break 'samples;
                }
                let p = grid.probe_index(coords);
                let signs = mcg_probe_cache::heuristics::octant_signs(usize::from(s.octant));
                for _ in 0..64 {
                    let u = Vec2::new(rng.random(), rng.random());
                    let d = mcg_probe_cache::pilot_rays::pilot_direction(0, u) * signs;
                    self.trace(now, p, d, rng, MovingAverage::DYNAMIC);
                }
                count(rays, p, 64);
                rays.dynamic += 64;
            }
        }
        Ok(())
    }

    /// 4. Static chains with the rest of the budget (sec. 4.8): h = exp(min(ĝ/f_s, 1)) f_s.
    fn static_chains_step(
        &mut self,
        now: &Scene,
        rng: &mut Pcg64Mcg,
        rays: &mut Rays,
        count: &mut impl FnMut(&mut Rays, usize, usize),
    ) -> Result<(), mcg_probe_cache::ProbeError> {
        let grid = *self.texels.grid();
        let budget = RAYS_PER_PROBE * grid.probe_count();
        let guide = GuidingFunction::new(
            ProxyGrid::probes(grid),
            &self.f_s,
            Some(&self.feedback),
            GuideParams::STATIC,
        )?;
        let left = budget.saturating_sub(rays.all);
        let samples = self
            .static_chains
            .step_frame(&guide, || uniforms(rng))
            .to_vec();
        for s in samples.iter().take(left) {
            let p = grid.probe_index(s.probe);
            self.trace(now, p, s.direction, rng, MovingAverage::STATIC);
            count(rays, p, 1);
        }
        Ok(())
    }

    /// Traces from a probe and updates the texel the ray lands in with N_max `average`.
    fn trace(
        &self,
        now: &Scene,
        probe: usize,
        d: Vec3,
        rng: &mut Pcg64Mcg,
        average: MovingAverage,
    ) {
        let grid = self.texels.grid();
        let origin = grid.probe_position(grid.probe_coords(probe));
        let hit = now.trace_probe_ray(origin, d, Vec2::new(rng.random(), rng.random()));
        let sample = RaySample {
            direction: d,
            radiance: hit.radiance,
            distance: hit.distance,
        };
        self.texels
            .update_sample_with(probe, &sample, rng.random(), average);
    }
}

fn uniforms(rng: &mut Pcg64Mcg) -> ProbeStepUniforms {
    ProbeStepUniforms {
        proposal: std::array::from_fn(|_| rng.random()),
        accept: rng.random(),
    }
}
