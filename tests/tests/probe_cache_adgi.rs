//! probe (exploration)
use mcg_tests::{Experiment, ExperimentConfig, Policy, frames_to_error, mean_error};

#[test]
fn explore() {
    let t = std::time::Instant::now();
    let cfg = ExperimentConfig::TEST;
    let exp = Experiment::new(cfg);
    eprintln!("reference {:?}, near {}", t.elapsed(), exp.near.len());
    for p in [Policy::UniformDdgi, Policy::Adgi, Policy::AdgiUnguided] {
        let t = std::time::Instant::now();
        let r = exp.run(p, &[]);
        eprintln!("{:?} {:?}", p, t.elapsed());
        eprintln!("  dyn {:?}", r.rays_dynamic);
        eprintln!("  near {:?}", r.error_near.iter().map(|e| format!("{e:.3}")).collect::<Vec<_>>());
        eprintln!("  all  {:?}", r.error_all.iter().map(|e| format!("{e:.3}")).collect::<Vec<_>>());
        eprintln!("  rays {:?}", &r.rays[..4]);
        eprintln!("  near rays {:?}", r.rays_near.iter().map(|e| format!("{e}")).collect::<Vec<_>>());
        for th in [0.1, 0.15, 0.2, 0.3] {
            eprintln!("  ftt {th}: {:?}", frames_to_error(&r.error_near, cfg.event_frame, th));
        }
        eprintln!("  mean after {:.3}", mean_error(&r.error_near, cfg.event_frame, cfg.event_frame + 12));
    }
}

#[test]
fn explore_dyn() {
    let cfg = ExperimentConfig::TEST;
    let exp = Experiment::new(cfg);
    let r = exp.run(Policy::Adgi, &[]);
    eprintln!("dyn rays {:?}", r.rays_dynamic);
    let mut c2 = cfg; c2.rays_per_probe = 256; c2.frames = 30; c2.event_frame = 100;
    let exp = Experiment::new(c2);
    for p in [Policy::UniformDdgi, Policy::Adgi] {
    let r = exp.run(p, &[]);
    eprintln!("{p:?} 256 rays static near {:?}", r.error_near.iter().map(|e| format!("{e:.3}")).collect::<Vec<_>>());
    eprintln!("{p:?} 256 rays static all {:?}", r.error_all.iter().map(|e| format!("{e:.3}")).collect::<Vec<_>>());
    }
}

#[test]
fn explore_bias() {
    let mut c2 = ExperimentConfig::TEST; c2.rays_per_probe = 256; c2.frames = 20; c2.event_frame = 100;
    let exp = Experiment::new(c2);
    let r = exp.run(Policy::UniformDdgi, &[19]);
    let est = &r.snapshots[0].1;
    let reference = exp.reference(19);
    let n = exp.texels.len();
    // worst probes
    let mut per_probe: Vec<(f64, usize)> = (0..exp.scene.grid.probe_count()).map(|p| {
        let e: f64 = (p*n..(p+1)*n).map(|k| f64::from((est[k]-reference[k]).length_squared())).sum();
        (e, p)}).collect();
    per_probe.sort_by(|a, b| b.0.partial_cmp(&a.0).unwrap());
    let tot: f64 = per_probe.iter().map(|x| x.0).sum();
    eprintln!("total {tot}, top {:?}", &per_probe[..8]);
    let p = per_probe[0].1;
    eprintln!("probe {p} at {}", exp.scene.grid.probe_position(exp.scene.grid.probe_coords(p)));
    for k in 0..n { eprintln!("  dir {:?} est {:?} ref {:?}", exp.texels[k].1, est[p*n+k], reference[p*n+k]); }
}

#[test]
fn explore_blend() {
    use mcg_probe_cache::glam::{Vec2, Vec3};
    use rand::RngExt;
    let exp = Experiment::new({let mut c = ExperimentConfig::TEST; c.frames = 1; c});
    let p = 183;
    let pos = exp.scene.grid.probe_position(exp.scene.grid.probe_coords(p));
    let scene = exp.scene.at_frame(0);
    let mut rng = mcg_tests::seeded_rng(5);
    let n = exp.texels.len();
    let mut num = vec![Vec3::ZERO; n];
    let mut den = vec![0.0f32; n];
    for _ in 0..200_000 {
        let d = mcg_tests::uniform_sphere_direction(&mut rng).as_vec3();
        let l = scene.trace_probe_ray(pos, d, Vec2::new(rng.random(), rng.random())).radiance;
        for (k, t) in exp.texels.iter().enumerate() {
            let w = t.1.dot(d).max(0.0);
            num[k] += w * l; den[k] += w;
        }
    }
    let reference = exp.reference(0);
    for k in 0..n { eprintln!("dir {:?} blend {:?} ref {:?}", exp.texels[k].1, num[k] / den[k] * std::f32::consts::PI, reference[p*n+k]); }
}

#[test]
fn explore_ref() {
    use mcg_probe_cache::glam::{Vec2, Vec3};
    use rand::RngExt;
    let exp = Experiment::new({let mut c = ExperimentConfig::TEST; c.frames = 1; c.reference_strata = 1; c});
    let p = 183;
    let pos = exp.scene.grid.probe_position(exp.scene.grid.probe_coords(p));
    let scene = exp.scene.at_frame(0);
    let n = Vec3::new(0.2672614, -0.80178374, 0.53452235);
    for s in [4, 12, 32, 64, 128] {
        let e = mcg_probe_cache::reference_irradiance(&scene, pos, &[n], s, 3)[0];
        eprintln!("strata {s}: {e}");
    }
    let mut rng = mcg_tests::seeded_rng(5);
    // plain MC cosine
    let mut sum = Vec3::ZERO; let m = 400_000;
    for _ in 0..m {
        let d = mcg_probe_cache::reference::cosine_hemisphere(n, Vec2::new(rng.random(), rng.random()));
        sum += scene.trace_probe_ray(pos, d, Vec2::new(rng.random(), rng.random())).radiance;
    }
    eprintln!("plain cosine MC {}", sum / m as f32 * std::f32::consts::PI);
    let mut num = Vec3::ZERO; let mut den = 0.0;
    for _ in 0..m {
        let d = mcg_tests::uniform_sphere_direction(&mut rng).as_vec3();
        let w = d.dot(n).max(0.0);
        num += w * scene.trace_probe_ray(pos, d, Vec2::new(rng.random(), rng.random())).radiance; den += w;
    }
    eprintln!("uniform blend {}", num / den * std::f32::consts::PI);
}

#[test]
fn explore_floor() {
    use mcg_probe_cache::glam::{Vec2, Vec3};
    use mcg_probe_cache::{ProbeTexels, TexelContent};
    use rand::RngExt;
    let mut c = ExperimentConfig::TEST; c.frames = 1;
    let exp = Experiment::new(c);
    let scene = exp.scene.at_frame(0);
    let texels = ProbeTexels::new(exp.scene.grid, exp.texel_config);
    let map = exp.texel_config.irradiance_map;
    let mut rng = mcg_tests::seeded_rng(5);
    for p in 0..exp.scene.grid.probe_count() {
        let pos = exp.scene.grid.probe_position(exp.scene.grid.probe_coords(p));
        let mut sum = vec![Vec3::ZERO; map.texel_count()];
        let mut cnt = vec![0u32; map.texel_count()];
        for _ in 0..20_000 {
            let d = mcg_tests::uniform_sphere_direction(&mut rng).as_vec3();
            let t = map.index(map.texel(d));
            sum[t] += scene.trace_probe_ray(pos, d, Vec2::new(rng.random(), rng.random())).radiance;
            cnt[t] += 1;
        }
        for t in 0..map.texel_count() { if cnt[t] > 0 { texels.set_irradiance(p, t, sum[t] / cnt[t] as f32, 63); } }
    }
    let est = exp.estimate(&texels, TexelContent::Radiance);
    let r = exp.reference(0);
    eprintln!("radiance-texel floor: near {:.3} all {:.3}", exp.relative_rms(&est, r, exp.near.iter().copied()), exp.relative_rms(&est, r, 0..exp.scene.grid.probe_count()));
}

#[test]
fn explore_adgi() {
    let cfg = ExperimentConfig::TEST;
    let exp = Experiment::new(cfg);
    let r = exp.run(Policy::Adgi, &[]);
    eprintln!("near {:?}", r.error_near.iter().map(|e| format!("{e:.2}")).collect::<Vec<_>>().join(" "));
    eprintln!("all {:?}", r.error_all.iter().map(|e| format!("{e:.2}")).collect::<Vec<_>>().join(" "));
    eprintln!("dyn {:?}", r.rays_dynamic);
    eprintln!("nearrays {:?}", r.rays_near);
}
