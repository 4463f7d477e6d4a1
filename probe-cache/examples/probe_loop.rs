//! The whole renderer loop of ADGI on the CPU with [`ProbeUpdater`]: scene → pilot rays →
//! change detection → guided Metropolis chains → traced rays → per-sample texel updates →
//! irradiance queries. The updater runs the steps; this loop only traces the rays it asks for
//! and queries the texels.
//!
//! The scene is the crate's two-room test scene (`mcg_probe_cache::scene`): a lit room and a
//! dark closet behind a door that slides open at frame 12. The loop prints, per frame, how many
//! rays the dynamic chains spent, how many of all rays started in the closet, and the
//! irradiance the probes give at a floor point inside the closet next to the reference.
//!
//! Run with `cargo run --release -p mcg-probe-cache --example probe_loop`.

use mcg_probe_cache::glam::Vec3;
use mcg_probe_cache::{
    DynamicScene, ProbeUpdater, QueryConfig, UpdateConfig, UpdatePolicy, reference_irradiance,
};
use rand::{RngExt, SeedableRng};
use rand_pcg::Pcg64Mcg;

fn main() -> Result<(), mcg_probe_cache::ProbeError> {
    let scene = DynamicScene::door_opens(12, 2);
    let grid = scene.grid;
    let mut rng = Pcg64Mcg::seed_from_u64(7);
    // 16 rays per probe and frame, the budget a DDGI renderer would spend; 32 dynamic chains.
    let mut config = UpdateConfig::DEFAULT;
    config.rays_per_probe = 16;
    config.dynamic_chains = 32;
    let mut updater = ProbeUpdater::new(grid, UpdatePolicy::Adgi, config, || rng.random())?;

    // A floor point in the closet, and its reference irradiance with the door open.
    let (point, normal) = (Vec3::new(8.55, 0.0, 2.0), Vec3::Y);
    let truth = reference_irradiance(&scene.after, point + 1e-3 * normal, &[normal], 32, 1)[0];
    println!(
        "frame  dynamic rays  rays in the closet  E at the closet floor (reference {truth:.3})"
    );
    for frame in 0..32u32 {
        let now = scene.at_frame(frame);
        let mut closet = 0_u64;
        // Steps 1-4 (pilot rays, heuristics, dynamic and static chains); the camera sees the
        // whole grid (the default camera threshold gives f_c = 1).
        let rays = updater.frame(
            u64::from(frame),
            grid.origin(),
            || rng.random(),
            |requests, samples| {
                for (ray, sample) in requests.iter().zip(samples.iter_mut()) {
                    let hit = now.trace_probe_ray(ray.origin, ray.direction, ray.u);
                    sample.radiance = hit.radiance;
                    sample.distance = hit.distance;
                    closet += u64::from(scene.event_region.contains(ray.origin));
                }
            },
        );
        // 5. Query: the irradiance a renderer would shade the closet floor with.
        let e = updater
            .texels()
            .irradiance_at(point, normal, Vec3::Y, &QueryConfig::ADGI_RADIANCE);
        println!(
            "{frame:>5}  {:>12}  {closet:>18}  {e:.3}",
            rays.rays_dynamic
        );
    }
    Ok(())
}
