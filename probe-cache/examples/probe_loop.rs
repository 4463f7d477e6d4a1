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
use mcg_probe_cache::temporal_gradient::{ChangeDetector, SmoothingKernel, TemporalTrigger};
use mcg_probe_cache::{
    DynamicScene, GuideParams, GuidingFunction, HeuristicField, HeuristicParams, PilotSchedule,
    ProbeChains, ProbeStepUniforms, ProbeTexels, ProxyGrid, QueryConfig, RaySample, TexelConfig,
    reference_irradiance,
};
use rand::{RngExt, SeedableRng};
use rand_pcg::Pcg64Mcg;

/// Rays per frame: 16 per probe, the budget a DDGI renderer would spend.
const RAYS_PER_PROBE: usize = 16;

fn main() -> Result<(), mcg_probe_cache::ProbeError> {
    let scene = DynamicScene::door_opens(12, 2);
    let grid = scene.grid;
    let probes = grid.probe_count();
    let budget = RAYS_PER_PROBE * probes;
    let mut rng = Pcg64Mcg::seed_from_u64(7);

    // Storage: ADGI's texel words, and the pieces of its guide.
    let texels = ProbeTexels::new(grid, TexelConfig::ADGI);
    let params = HeuristicParams::new(1.0e3, grid.cell_diagonal())?; // f_c = 1 everywhere
    let mut detector = ChangeDetector::new(
        grid,
        TemporalTrigger::new(0.5)?,
        SmoothingKernel {
            spatial_radius: 1,
            directional: true,
        },
    );
    let mut init = || std::array::from_fn(|_| rng.random::<f32>());
    let mut static_chains = ProbeChains::new_static(grid, budget / 8, &mut init)?;
    let mut dynamic_chains = ProbeChains::new_dynamic(grid, 32, &mut init)?;
    let proxies = dynamic_chains.cells();
    let n = probes * OCTANTS;
    let (mut f_v, mut f_r) = (vec![0.0; n], vec![0.0; n]);
    let mut words = vec![HeuristicsWord(0); n];
    let (mut f_s, mut f_d) = (vec![0.0; n], vec![0.0; n]);
    let mut proxy_f_d = vec![0.0; proxies.table_len()];
    let feedback = vec![0.0; n]; // ĝ = 0: h = f_s (a renderer reads a mip of its cache here)

    // A floor point in the closet, and its reference irradiance with the door open.
    let (point, normal) = (Vec3::new(8.55, 0.0, 2.0), Vec3::Y);
    let truth = reference_irradiance(&scene.after, point + 1e-3 * normal, &[normal], 32, 1)[0];
    println!(
        "frame  dynamic rays  rays in the closet  E at the closet floor (reference {truth:.3})"
    );

    for frame in 0..32u32 {
        let now = scene.at_frame(frame);
        // Trace from a probe and update the texel the ray lands in with N_max `average`.
        let trace = |probe: usize, d: Vec3, rng: &mut Pcg64Mcg, average: MovingAverage| {
            let origin = grid.probe_position(grid.probe_coords(probe));
            let hit = now.trace_probe_ray(origin, d, Vec2::new(rng.random(), rng.random()));
            let sample = RaySample {
                direction: d,
                radiance: hit.radiance,
                distance: hit.distance,
            };
            texels.update_sample_with(probe, &sample, rng.random(), average);
        };
        let (mut rays, mut closet) = (0, 0);
        let in_closet = |probe: usize| {
            scene
                .event_region
                .contains(grid.probe_position(grid.probe_coords(probe)))
        };
        let count = |rays: &mut usize, closet: &mut usize, probe: usize, k: usize| {
            *rays += k;
            if in_closet(probe) {
                *closet += k;
            }
        };

        // 1. Pilot rays: one per probe octant, the same on both frames of a pair (uniforms
        //    hashed from the pattern), so a difference between the two frames is a change.
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
        let mut pilots = Vec::with_capacity(n);
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
                texels.update_sample(
                    p,
                    &RaySample {
                        direction: ray.direction,
                        radiance: hit.radiance,
                        distance: hit.distance,
                    },
                    rng.random(),
                );
            }
            count(&mut rays, &mut closet, p, 1);
            if o == OCTANTS - 1 {
                let (v, r) = octant_heuristics(&hits, &params);
                f_v[p * OCTANTS..][..OCTANTS].copy_from_slice(&v);
                f_r[p * OCTANTS..][..OCTANTS].copy_from_slice(&r);
            }
        }

        // 2. Change detection (eq. 13-18) and the heuristics words (eq. 19-20, sec. 4.3).
        if pilot.measures_gradient() {
            detector.detect(&f_v, &f_r)?;
        } else {
            detector.set_reference(&f_v, &f_r)?;
        }
        heuristics::compose_grid(
            &grid,
            &params,
            grid.origin(),
            &f_v,
            detector.delta_visibility(),
            detector.delta_radiance(),
            &mut words,
        )?;
        decode_field(&words, HeuristicField::Static, &mut f_s)?;
        decode_field(&words, HeuristicField::Dynamic, &mut f_d)?;

        // 3. Dynamic chains on the 3×3×3 proxies, where something changed (sec. 4.9): each
        //    sample = 64 rays into one octant of every probe of the proxy, N_max = 10, with up
        //    to three quarters of the rays the pilots left.
        proxies.max_pool(&f_d, &mut proxy_f_d)?;
        let mut dynamic = 0;
        let dynamic_budget = rays + (budget - rays) * 3 / 4;
        if proxy_f_d.iter().any(|&v| v > 0.0) {
            let guide = GuidingFunction::new(proxies, &proxy_f_d, None, GuideParams::DYNAMIC)?;
            let samples = dynamic_chains
                .step_frame(&guide, || uniforms(&mut rng))
                .to_vec();
            'samples: for s in samples {
                for coords in proxies.probes_of(s.cell as usize) {
                    if rays + 64 > dynamic_budget {
                        break 'samples;
                    }
                    let p = grid.probe_index(coords);
                    let signs = mcg_probe_cache::heuristics::octant_signs(usize::from(s.octant));
                    for _ in 0..64 {
                        let u = Vec2::new(rng.random(), rng.random());
                        let d = mcg_probe_cache::pilot_rays::pilot_direction(0, u) * signs;
                        trace(p, d, &mut rng, MovingAverage::DYNAMIC);
                    }
                    count(&mut rays, &mut closet, p, 64);
                    dynamic += 64;
                }
            }
        }

        // 4. Static chains with the rest of the budget (sec. 4.8): h = exp(min(ĝ/f_s, 1)) f_s.
        let guide = GuidingFunction::new(
            ProxyGrid::probes(grid),
            &f_s,
            Some(&feedback),
            GuideParams::STATIC,
        )?;
        let left = budget.saturating_sub(rays);
        let samples = static_chains
            .step_frame(&guide, || uniforms(&mut rng))
            .to_vec();
        for s in samples.iter().take(left) {
            let p = grid.probe_index(s.probe);
            trace(p, s.direction, &mut rng, MovingAverage::STATIC);
            count(&mut rays, &mut closet, p, 1);
        }

        // 5. Query: the irradiance a renderer would shade the closet floor with.
        let e = texels.irradiance_at(point, normal, Vec3::Y, &QueryConfig::ADGI_RADIANCE);
        println!("{frame:>5}  {dynamic:>12}  {closet:>18}  {e:.3}");
    }
    Ok(())
}

fn uniforms(rng: &mut Pcg64Mcg) -> ProbeStepUniforms {
    ProbeStepUniforms {
        proposal: std::array::from_fn(|_| rng.random()),
        accept: rng.random(),
    }
}
