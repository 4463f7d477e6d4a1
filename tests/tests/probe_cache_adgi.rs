//! ADGI's claim at an equal ray budget (ADGI sec. 1, 5, Fig. 1 and 8): after a localised
//! dynamic event, the probe error near the event falls faster with adaptive sampling than with
//! DDGI's uniform rays per probe.
//!
//! Setup ([`ExperimentConfig::TEST`], `mcg_tests::probe_cache_reference` for every detail): the
//! two-room scene of `mcg_probe_cache::scene` (a lit 8 m room, a dark 0.9 m closet behind a
//! door that slides open over frames 16-17), 18 × 4 × 8 probes, 48 frames, 32 rays per probe
//! and frame for every policy (18 432 probe rays; ADGI sec. 5 gives Q-DDGI 32), seed
//! `0x8ad61`. Every run starts from the same converged cache of the closed-door scene. Errors
//! are relative RMS of the probes' irradiance at their texel directions against a reference of
//! 100 stratified rays per texel (plus next-event estimation of the light), over the 74 probes
//! near the event (in the closet or within 1 m of the doorway).
//!
//! Why the comparison is fair: every policy traces the same number of probe rays per frame
//! (asserted), each ray costs the same (one scene ray and one shadow ray), all start from the
//! same warm cache and see the same scene, and DDGI runs with the hysteresis ADGI compares
//! against (Q-DDGI's 0.94, Table 3). The constant-guide run spends ADGI's rays through the
//! same machinery with h ≡ 1, so the difference between it and ADGI is the guide alone.
//!
//! Hypotheses (deterministic: fixed seeds, single-threaded, so each number is exact):
//! - H1: ADGI first brings the near-event error below [`FRAMES_TO_ERROR_THRESHOLD`] (0.3, above
//!   both policies' pre-event errors, ≈ 0.14 and ≈ 0.19) in fewer frames after the event than
//!   uniform DDGI. Measured: ADGI 3 frames, DDGI 13, constant guide 29.
//! - H2: the mean near-event error over the 10 frames from the event is lower with ADGI than
//!   with uniform DDGI and than with the constant guide. Measured: 0.314, 0.417, 0.464.
//!
//! What the suite does NOT claim: that ADGI's error *stays* lower. After its dynamic phase its
//! near-event texels restart their moving average from N = 10 and take tens of frames to
//! reach N = 63 again, while DDGI's cosine-weighted blend uses every ray for half the texels;
//! over the last 10 frames DDGI's near-event error (0.19) is below ADGI's (0.34), and with
//! "stays below 0.3" as the criterion ADGI does not settle within 48 frames (DDGI: 13).
//! `cargo test -p mcg-tests --release --test probe_cache_adgi -- --nocapture` prints all of it.
//!
//! Break tried: running the ADGI policy with constant guides (the chains uniform over (p, ω),
//! `guided = false` for `Policy::Adgi`) makes H1 and H2 fail: 25 frames against DDGI's 13, mean
//! error 0.445 against 0.417.

use mcg_tests::{
    Experiment, ExperimentConfig, FRAMES_TO_ERROR_THRESHOLD, Policy, frames_to_error,
    frames_to_first_below, mean_error,
};

#[test]
fn adaptive_sampling_brings_the_error_near_the_event_down_faster() {
    let cfg = ExperimentConfig::TEST;
    let exp = Experiment::new(cfg);
    let budget = u64::from(cfg.rays_per_probe) * exp.scene.grid.probe_count() as u64;
    let runs: Vec<_> = [Policy::Adgi, Policy::UniformDdgi, Policy::AdgiUnguided]
        .iter()
        .map(|&p| exp.run(p, &[]))
        .collect();
    let t = FRAMES_TO_ERROR_THRESHOLD;
    let e = cfg.event_frame;
    let window = e + 10;
    for run in &runs {
        // Equal budget: never more than DDGI's rays, and ADGI's cut sample lists use all but a
        // handful of them.
        for (f, &r) in run.rays.iter().enumerate() {
            assert!(r <= budget, "{:?} frame {f}: {r} > {budget}", run.policy);
            assert!(
                r as f64 >= 0.99 * budget as f64,
                "{:?} frame {f}: {r} rays",
                run.policy
            );
        }
        println!(
            "{:<32} first below {t}: {:>4} frames, settles below {t}: {:>5}, mean near error \
             frames {e}-{}: {:.3}, before: {:.3}, last 10 frames: {:.3} (all probes {:.3}), \
             share of rays near the event in frames {e}-{}: {:.2}",
            run.policy.label(),
            fmt(frames_to_first_below(&run.error_near, e, t)),
            fmt(frames_to_error(&run.error_near, e, t)),
            window - 1,
            mean_error(&run.error_near, e, window),
            mean_error(&run.error_near, 4, e),
            mean_error(&run.error_near, cfg.frames - 10, cfg.frames),
            mean_error(&run.error_all, cfg.frames - 10, cfg.frames),
            window - 1,
            run.rays_near[e as usize..window as usize]
                .iter()
                .sum::<u64>() as f64
                / run.rays[e as usize..window as usize].iter().sum::<u64>() as f64,
        );
    }
    let (adgi, ddgi, unguided) = (&runs[0], &runs[1], &runs[2]);
    // Both start below the threshold, so it measures the recovery from the event.
    for run in &runs {
        assert!(
            mean_error(&run.error_near, 4, e) < t,
            "{:?}: pre-event error above the threshold",
            run.policy
        );
    }

    // H1.
    let first = |r: &mcg_tests::Run| frames_to_first_below(&r.error_near, e, t).unwrap_or(u32::MAX);
    assert!(
        first(adgi) < first(ddgi),
        "H1: ADGI needs {} frames to bring the near-event error below {t}, uniform DDGI {}",
        first(adgi),
        first(ddgi)
    );

    // H2.
    let m = |r: &mcg_tests::Run| mean_error(&r.error_near, e, window);
    assert!(
        m(adgi) < m(ddgi),
        "H2: mean near-event error after the event: ADGI {:.3}, uniform DDGI {:.3}",
        m(adgi),
        m(ddgi)
    );
    assert!(
        m(adgi) < m(unguided),
        "H2: mean near-event error after the event: ADGI {:.3}, constant guide {:.3}",
        m(adgi),
        m(unguided)
    );
}

fn fmt(v: Option<u32>) -> String {
    v.map_or_else(|| "never".to_owned(), |f| f.to_string())
}
