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
//! Hypotheses (deterministic: fixed seeds, single-threaded, so every number is exact):
//! - H1: the (lower) median over the run seeds of the frames ADGI needs after the event to
//!   first bring the near-event error below [`FRAMES_TO_ERROR_THRESHOLD`] (0.3; above both
//!   policies' pre-event errors, 0.13-0.21) is smaller than uniform DDGI's. Measured: ADGI
//!   9, never, 4, 15, 5, 4, 7, never (median 7); DDGI 11, 12, 12, 10, 14, 13, 12, 11
//!   (median 12); constant guide never except 17 and 10 (median never).
//! - H2: the mean over the run seeds of the near-event error over the 10 frames from the event
//!   is lower with ADGI than with uniform DDGI, and lower than with the constant guide.
//!   Measured: ADGI 0.369 (0.306-0.439), DDGI 0.399 (0.363-0.417), constant guide 0.475.
//!
//! The claim holds on average, not for every seed: for seeds 2 and 8 ADGI's error near the
//! event never gets below 0.3, and for 2, 4 and 8 its 10-frame mean is above DDGI's. The
//! margins are modest (median 7 against 12 frames; 8 % lower mean error). ADGI puts 42-50 % of
//! its rays near the event in those frames, DDGI 13 %.
//!
//! What the suite does NOT claim: that ADGI's error *stays* lower. After its dynamic phase its
//! near-event texels restart their moving average from N = 10 and take tens of frames to
//! reach N = 63 again, while DDGI's cosine-weighted blend uses every ray for half the texels;
//! over the last 10 frames DDGI's near-event error (0.18-0.28) is below ADGI's (0.25-0.39)
//! for every seed, and over all probes DDGI's (0.086-0.099) is below ADGI's (0.129-0.139):
//! ADGI spends its rays near the event and the rest of the grid ages.
//! `cargo test -p mcg-tests --release --test probe_cache_adgi -- --nocapture` prints it all.
//!
//! Break tried: running the ADGI policy with constant guides (the chains uniform over (p, ω),
//! `guided = false` for `UpdatePolicy::Adgi`) made H1 fail with the three seeds 1-3 this suite used
//! first: ADGI then needed never, 7 and 21 frames (median 21 against DDGI's 12).

use mcg_tests::{
    Experiment, ExperimentConfig, FRAMES_TO_ERROR_THRESHOLD, Run, UpdatePolicy, frames_to_error,
    frames_to_first_below, mean_error,
};

/// The run seeds.
const SEEDS: [u64; 8] = [1, 2, 3, 4, 5, 6, 7, 8];

#[test]
fn adaptive_sampling_brings_the_error_near_the_event_down_faster() {
    let cfg = ExperimentConfig::TEST;
    let exp = Experiment::new(cfg);
    let budget = u64::from(cfg.rays_per_probe) * exp.scene.grid.probe_count() as u64;
    let t = FRAMES_TO_ERROR_THRESHOLD;
    let e = cfg.event_frame;
    let window = e + 10;
    let policies = [
        UpdatePolicy::Adgi,
        UpdatePolicy::Ddgi,
        UpdatePolicy::AdgiUnguided,
    ];
    // first[policy][seed], mean[policy][seed].
    let mut first = [[u32::MAX; SEEDS.len()]; 3];
    let mut mean = [[0.0_f64; SEEDS.len()]; 3];
    for (i, &policy) in policies.iter().enumerate() {
        for (j, &seed) in SEEDS.iter().enumerate() {
            let run = exp.run_with_seed(policy, seed, &[]);
            check_budget(&run, budget);
            // Both start below the threshold, so it measures the recovery from the event.
            assert!(
                mean_error(&run.error_near, 4, e) < t,
                "{policy:?}, seed {seed}: pre-event error above the threshold"
            );
            first[i][j] = frames_to_first_below(&run.error_near, e, t).unwrap_or(u32::MAX);
            mean[i][j] = mean_error(&run.error_near, e, window);
            report(&run, seed, cfg, t);
        }
    }
    // Lower median (never counts as u32::MAX).
    let median = |v: [u32; SEEDS.len()]| {
        let mut v = v;
        v.sort_unstable();
        v[(v.len() - 1) / 2]
    };
    let average = |v: [f64; SEEDS.len()]| v.iter().sum::<f64>() / v.len() as f64;
    let (adgi, ddgi, unguided) = (0, 1, 2);

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
}

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

fn report(run: &Run, seed: u64, cfg: ExperimentConfig, t: f64) {
    let e = cfg.event_frame;
    let w = e + 10;
    let fmt = |v: Option<u32>| v.map_or_else(|| "never".to_owned(), |f| f.to_string());
    println!(
        "{:<31} seed {seed}: first below {t} after {:>5} frames, stays below after {:>5}; near \
         error before {:.3}, frames {e}-{} {:.3}, last 10 frames {:.3} (all probes {:.3}); rays \
         near the event in frames {e}-{}: {:.0} %",
        run.policy.label(),
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
    );
}
