//! ADGI's claim at an equal ray budget (ADGI sec. 1, 5, Fig. 1 and 8): after a localised
//! dynamic event, the probe error near the event falls faster with adaptive sampling than with
//! DDGI's uniform rays per probe.
//!
//! Setup ([`ExperimentConfig::TEST`]; `mcg_tests::probe_cache_reference` has every detail): the
//! two-room scene of `mcg_probe_cache::scene` (a lit 8 m room, a dark 0.9 m closet behind a
//! door that slides open over frames 16-17), 18 × 4 × 8 probes, 40 frames, at most 32 rays per
//! probe and frame for every policy (18 432 probe rays; ADGI sec. 5 gives Q-DDGI 32). Every
//! run starts from the same converged cache of the closed-door scene. Errors are relative RMS
//! of the probes' irradiance at their texel directions against a reference of 100 stratified
//! rays per texel plus 100 light samples (scene and reference seed `0x8ad61`), over the 74
//! probes near the event (in the closet or within 1 m of the doorway). Each policy runs with
//! the run seeds 1 to 8 (rays, chains, rounding, pilot directions); the hypotheses are about
//! all eight together, so no seed is picked.
//!
//! Why the comparison is fair: every policy traces at most the same number of probe rays per
//! frame (asserted, and ADGI uses ≥ 99 % of them), each ray costs the same (one scene ray and
//! one shadow ray), all start from the same warm cache and see the same scene, and DDGI runs
//! with the hysteresis ADGI compares against (Q-DDGI's 0.94, Table 3). The constant-guide run
//! spends ADGI's rays through the same machinery with h ≡ 1, so the difference between it and
//! ADGI is the guide alone.
//!
//! Hypotheses (deterministic: fixed seeds; the runs go on threads but each is sequential, so
//! every number is exact):
//! - H1: the (lower) median over the run seeds of the frames ADGI needs after the event to
//!   first bring the near-event error below [`FRAMES_TO_ERROR_THRESHOLD`] (0.3; above both
//!   policies' pre-event errors, 0.13-0.21) is smaller than uniform DDGI's. Measured: ADGI
//!   9, never, 4, 15, 5, 4, 7, never (median 7); DDGI 11, 12, 12, 10, 14, 13, 12, 11
//!   (median 12); constant guide never except 17 and 10 (median never).
//! - H2: the mean over the run seeds of the near-event error over the 10 frames from the event
//!   is lower with ADGI than with uniform DDGI, and lower than with the constant guide.
//!   Measured: ADGI 0.369 (0.306-0.439), DDGI 0.399 (0.363-0.417), constant guide 0.475.
//!
//! - H3 (issue 20 item 4, speed): with mcg's refill extension (`UpdatePolicy::AdgiRefill`,
//!   documented in `mcg_probe_cache::probe_update`), the lower median of those frames is at
//!   most 0.6 × DDGI's and ADGI is faster than DDGI on every seed; the paper's ADGI does not
//!   meet this (asserted too, so the suite notices if that changes). Measured: refill 6, 4, 7,
//!   4, 3, 6, 10, 4 (median 4 against 12); the paper's ADGI is faster on 5 of 8. The refill
//!   weight κ = 2 was picked from 1, 2, 4 on these seeds (κ = 1: 5, 4, 10, 4, 3, 5, 16, 4,
//!   slower for seed 7; κ = 4: 12, 4, 7, 4, 3, 6, 8, 4, slower for seed 1) and checked on the
//!   held-out seeds 9-16: refill 2, 2, 5, 2, 5, 8, 5, 4 against DDGI 11, 12, 10, 10, 11, 9,
//!   11, 13.
//! - H4: refill ends with a lower near-event error than the paper's ADGI (mean over the seeds
//!   of the last 10 frames). Measured: 0.171-0.269 against 0.254-0.394.
//! - H5 (why the radiance texels of the paper's ADGI and of refill cannot end below DDGI over
//!   all probes): the discretisation floor of radiance texels — the all-probe error of texels
//!   that hold the exact mean radiance of their texel (256 jittered rays each), after the
//!   event — is above DDGI's worst all-probe error over the last 10 frames. Measured: floor 0.102 (1024 rays per
//!   texel give 0.102 too; exact clipped-cosine texel weights instead of centre cosines 0.111),
//!   DDGI 0.086-0.099; ADGI ends at 0.129-0.139, refill at 0.124-0.131.
//!
//! - H6 (issue 20 item 4, whole: `UpdatePolicy::AdgiBlend`, mcg's blend extension — see
//!   `mcg_probe_cache::probe_update`): the blend meets H3's speed target *and* ends with a lower
//!   all-probe error than uniform DDGI (mean over the last 10 frames) on every seed. Measured:
//!   blend 4, 4, 2, 2, 3, 2, 2, 1 frames (median 2 against DDGI's 12); all-probe error over
//!   the last 10 frames 0.069-0.078 against DDGI's 0.086-0.099. Two parts of the blend do
//!   it: its uniform rays continue a per-probe R2 sequence from frame to frame
//!   (`UniformRays::Sequence`; with DDGI's rotated Fibonacci sets it ended at 0.092-0.115),
//!   and every probe whose change signal is on gets 96 extra rays (in proportion to the
//!   smoothed f_d it got 12-28 rays in all at the event and needed 7-13 frames; with the
//!   extra rays but DDGI's Fibonacci sets it needs 0-2 frames and ends at 0.102-0.127: each
//!   part alone fails H6). DDGI with the same sequence (not the paper's baseline) ends lower
//!   (H7: the blend spends 8 of its 32 rays per probe on pilots): see
//!   `mcg_probe_cache::uniform_rays`.
//! - H7 (the honest other side of H6): DDGI with the blend's ray sequence (not the paper's
//!   baseline) ends with a lower all-probe error than the blend, on average over the seeds.
//!   Measured: DDGI + sequence 0.059-0.062 against the blend's 0.069-0.078; it needs 9, 9,
//!   10, 10, 11, 8, 8, 9 frames to 0.3 near the event (the blend 1-4).
//!
//! Why the paper's ADGI is slow and uneven (measured, seed 2): the dynamic rays reach only the
//! (proxy, octant) pairs whose pilot rays saw the change; a closet probe's texels facing the
//! doorway kept their dark pre-event value with N = 63 to frame 39 (green E 0.01-0.09 against
//! a reference of 0.17-0.57), while its other octants were restarted at N = 10; 1442 of the 2664
//! near-event texels were never restarted, and the static chains (f_s knows nothing of
//! windows) give a texel under one ray per frame. The paper's version still wins on average:
//! for seeds 2 and 8 its error near the event never gets below 0.3, and for 2, 4 and 8 its
//! 10-frame mean is above DDGI's. ADGI puts 42-50 % of its rays near the event in those
//! frames, DDGI 13 %. Over all probes DDGI's error (0.086-0.099) stays below ADGI's
//! (0.129-0.139): the radiance-texel floor of H5.
//! `cargo test -p mcg-tests --release --test probe_cache_adgi -- --nocapture` prints it all.
//!
//! Break tried: running the ADGI policy with constant guides (the chains uniform over (p, ω),
//! `guided = false` for `UpdatePolicy::Adgi`) made H1 fail with the three seeds 1-3 this suite used
//! first: ADGI then needed never, 7 and 21 frames (median 21 against DDGI's 12). Turning off
//! the refill's restart (part 1, with κ = 1) made H3 fail: refill then needed 8, never, 10,
//! 10, 6, 6, 13, 6 frames (median 8 against 12, faster on 5 seeds).

use mcg_probe_cache::UniformRays;
use mcg_tests::{
    Experiment, ExperimentConfig, FRAMES_TO_ERROR_THRESHOLD, Run, UpdatePolicy, frames_to_error,
    frames_to_first_below, mean_error,
};

/// The run seeds.
const SEEDS: [u64; 8] = [1, 2, 3, 4, 5, 6, 7, 8];

/// The policies, in the order of the result tables; the last runs DDGI with mcg's ray
/// sequence (`UniformRays::Sequence`, not the paper's baseline; H7).
const POLICIES: [UpdatePolicy; 6] = [
    UpdatePolicy::Adgi,
    UpdatePolicy::Ddgi,
    UpdatePolicy::AdgiUnguided,
    UpdatePolicy::AdgiRefill,
    UpdatePolicy::AdgiBlend,
    UpdatePolicy::Ddgi,
];

/// Row of POLICIES that runs DDGI with the sequence.
const DDGI_SEQUENCE: usize = 5;

/// Every (policy, seed) run, on as many threads as the machine has (each run is
/// deterministic and independent, so the order does not change a number).
fn run_all(exp: &Experiment) -> Vec<Vec<Run>> {
    let jobs: Vec<(usize, usize)> = (0..POLICIES.len())
        .flat_map(|i| (0..SEEDS.len()).map(move |j| (i, j)))
        .collect();
    let run = |i: usize, j: usize| {
        let mut config = exp.update_config(SEEDS[j]);
        if i == DDGI_SEQUENCE {
            config.ddgi_rays = UniformRays::Sequence;
        }
        exp.run_with_config(POLICIES[i], SEEDS[j], config, &[])
    };
    let threads = std::thread::available_parallelism().map_or(1, usize::from);
    let mut done: Vec<(usize, usize, Run)> = std::thread::scope(|scope| {
        let handles: Vec<_> = jobs
            .chunks(jobs.len().div_ceil(threads))
            .map(|chunk| {
                let run = &run;
                scope.spawn(move || {
                    chunk
                        .iter()
                        .map(|&(i, j)| (i, j, run(i, j)))
                        .collect::<Vec<_>>()
                })
            })
            .collect();
        handles
            .into_iter()
            .flat_map(|h| h.join().expect("a run panicked"))
            .collect()
    });
    done.sort_by_key(|r| (r.0, r.1));
    let mut runs: Vec<Vec<Run>> = vec![Vec::new(); POLICIES.len()];
    for (i, _, run) in done {
        runs[i].push(run);
    }
    runs
}

#[test]
fn adaptive_sampling_brings_the_error_near_the_event_down_faster() {
    let cfg = ExperimentConfig::TEST;
    let exp = Experiment::new(cfg);
    let budget = u64::from(cfg.rays_per_probe) * exp.scene.grid.probe_count() as u64;
    let t = FRAMES_TO_ERROR_THRESHOLD;
    let e = cfg.event_frame;
    let window = e + 10;
    let runs = run_all(&exp);
    // first[policy][seed] (never = u32::MAX), mean[policy][seed], tail[policy][seed] (near
    // error over the last 10 frames), tail_all[policy][seed] (all probes, last 10 frames).
    let mut first = [[u32::MAX; SEEDS.len()]; POLICIES.len()];
    let mut mean = [[0.0_f64; SEEDS.len()]; POLICIES.len()];
    let mut tail = [[0.0_f64; SEEDS.len()]; POLICIES.len()];
    let mut tail_all = [[0.0_f64; SEEDS.len()]; POLICIES.len()];
    for (i, policy_runs) in runs.iter().enumerate() {
        for (j, run) in policy_runs.iter().enumerate() {
            let policy = run.policy;
            let seed = SEEDS[j];
            check_budget(run, budget);
            // All start below the threshold, so it measures the recovery from the event.
            assert!(
                mean_error(&run.error_near, 4, e) < t,
                "{policy:?}, seed {seed}: pre-event error above the threshold"
            );
            first[i][j] = frames_to_first_below(&run.error_near, e, t).unwrap_or(u32::MAX);
            mean[i][j] = mean_error(&run.error_near, e, window);
            tail[i][j] = mean_error(&run.error_near, cfg.frames - 10, cfg.frames);
            tail_all[i][j] = mean_error(&run.error_all, cfg.frames - 10, cfg.frames);
            let label = if i == DDGI_SEQUENCE {
                "DDGI + mcg's ray sequence"
            } else {
                policy.label()
            };
            report(run, label, seed, cfg, t);
        }
    }
    // Lower median (never counts as u32::MAX).
    let median = |v: [u32; SEEDS.len()]| {
        let mut v = v;
        v.sort_unstable();
        v[(v.len() - 1) / 2]
    };
    let average = |v: [f64; SEEDS.len()]| v.iter().sum::<f64>() / v.len() as f64;
    let (adgi, ddgi, unguided, refill, blend) = (0, 1, 2, 3, 4);
    let ddgi_sequence = DDGI_SEQUENCE;

    // H1.
    assert!(
        median(first[adgi]) < median(first[ddgi]),
        "H1: median frames to bring the near-event error below {t}: ADGI {:?}, uniform DDGI {:?}",
        first[adgi],
        first[ddgi]
    );
    // H2.
    assert!(
        average(mean[adgi]) < average(mean[ddgi]),
        "H2: mean near-event error over frames {e}-{}: ADGI {:?}, uniform DDGI {:?}",
        window - 1,
        mean[adgi],
        mean[ddgi]
    );
    assert!(
        average(mean[adgi]) < average(mean[unguided]),
        "H2: mean near-event error over frames {e}-{}: ADGI {:?}, constant guide {:?}",
        window - 1,
        mean[adgi],
        mean[unguided]
    );
    // H3: the refill extension meets the speed target; the paper's ADGI does not.
    let meets_speed_target = |p: usize| {
        let faster = (0..SEEDS.len())
            .filter(|&j| first[p][j] < first[ddgi][j])
            .count();
        10 * u64::from(median(first[p])) <= 6 * u64::from(median(first[ddgi]))
            && faster == SEEDS.len()
    };
    assert!(
        meets_speed_target(refill),
        "H3: ADGI + refill, frames to below {t}: {:?}, uniform DDGI {:?}",
        first[refill],
        first[ddgi]
    );
    assert!(
        !meets_speed_target(adgi),
        "H3: the paper's ADGI now meets the speed target too ({:?} against {:?}): \
         update the suite's docs",
        first[adgi],
        first[ddgi]
    );
    // H6: the blend meets the speed target and ends below DDGI over all probes on every seed.
    assert!(
        meets_speed_target(blend),
        "H6: ADGI + blend, frames to below {t}: {:?}, uniform DDGI {:?}",
        first[blend],
        first[ddgi]
    );
    for (j, seed) in SEEDS.iter().enumerate() {
        assert!(
            tail_all[blend][j] < tail_all[ddgi][j],
            "H6: seed {seed}: all-probe error over the last 10 frames: ADGI + blend {:?}, \
             uniform DDGI {:?}",
            tail_all[blend],
            tail_all[ddgi]
        );
    }
    // H7: DDGI with the same ray sequence ends below the blend (the pilots' cost).
    assert!(
        average(tail_all[ddgi_sequence]) < average(tail_all[blend]),
        "H7: all-probe error over the last 10 frames: DDGI with the sequence {:?}, ADGI + blend \
         {:?}",
        tail_all[ddgi_sequence],
        tail_all[blend]
    );
    // H4: refill ends with a lower near-event error than the paper's ADGI.
    assert!(
        average(tail[refill]) < average(tail[adgi]),
        "H4: near-event error over the last 10 frames: ADGI + refill {:?}, ADGI {:?}",
        tail[refill],
        tail[adgi]
    );
    // H5: why ADGI cannot end below DDGI over all probes: the radiance texels' own floor.
    let (floor_all, floor_near) = exp.radiance_texel_floor(cfg.frames - 1, FLOOR_STRATA);
    let ddgi_worst = tail_all[ddgi].iter().fold(0.0_f64, |m, &v| m.max(v));
    println!(
        "radiance-texel floor ({} rays per texel): all probes {floor_all:.4}, near {floor_near:.4}; \
         uniform DDGI all-probe error over the last 10 frames at most {ddgi_worst:.4}",
        FLOOR_STRATA * FLOOR_STRATA
    );
    assert!(
        floor_all > ddgi_worst,
        "H5: radiance-texel floor {floor_all} is not above DDGI's end error {ddgi_worst}"
    );
}

/// The floor of H5 uses `FLOOR_STRATA²` jittered rays per texel (its own noise is then well
/// below its value: 64 rays per texel gave 0.106, 256 give 0.102, 1024 gave 0.102).
const FLOOR_STRATA: u32 = 16;

/// Equal budget: never more than DDGI's rays, and ADGI's cut sample lists use nearly all.
fn check_budget(run: &Run, budget: u64) {
    for (f, &r) in run.rays.iter().enumerate() {
        assert!(r <= budget, "{:?} frame {f}: {r} > {budget}", run.policy);
        assert!(
            r as f64 >= 0.99 * budget as f64,
            "{:?} frame {f}: only {r} of {budget} rays",
            run.policy
        );
    }
}

fn report(run: &Run, label: &str, seed: u64, cfg: ExperimentConfig, t: f64) {
    let e = cfg.event_frame;
    let w = e + 10;
    let fmt = |v: Option<u32>| v.map_or_else(|| "never".to_owned(), |f| f.to_string());
    println!(
        "{:<31} seed {seed}: first below {t} after {:>5} frames, stays below after {:>5}; near \
         error before {:.3}, frames {e}-{} {:.3}, last 10 frames {:.3} (all probes {:.3}); rays \
         near the event in frames {e}-{}: {:.0} %; most probes with a change signal on {}",
        label,
        fmt(frames_to_first_below(&run.error_near, e, t)),
        fmt(frames_to_error(&run.error_near, e, t)),
        mean_error(&run.error_near, 4, e),
        w - 1,
        mean_error(&run.error_near, e, w),
        mean_error(&run.error_near, cfg.frames - 10, cfg.frames),
        mean_error(&run.error_all, cfg.frames - 10, cfg.frames),
        w - 1,
        100.0 * run.rays_near[e as usize..w as usize].iter().sum::<u64>() as f64
            / run.rays[e as usize..w as usize].iter().sum::<u64>() as f64,
        run.changed_probes[e as usize..w as usize]
            .iter()
            .max()
            .unwrap_or(&0),
    );
}
