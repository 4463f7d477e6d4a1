//! Shared by the `markov_guide_*` suites: relative errors of a toy renderer's frame estimates
//! against the toy scene's closed-form irradiance.

/// Runs `warm_up + frames` frames through `render` (which returns one estimate per pixel, in the
/// order of `exact`) and returns the mean and the mean square of the relative error
/// estimate/E − 1 over the `frames` frames after warm-up and all pixels. Panics on an estimate
/// that is negative or not finite.
pub fn relative_error_moments(
    exact: &[f64],
    warm_up: usize,
    frames: usize,
    mut render: impl FnMut() -> Vec<f32>,
) -> (f64, f64) {
    let (mut sum, mut sum_sq, mut n) = (0.0, 0.0, 0.0);
    for frame in 0..warm_up + frames {
        let estimates = render();
        if frame >= warm_up {
            for (&e, &x) in estimates.iter().zip(exact) {
                assert!(e.is_finite() && e >= 0.0, "estimate {e}");
                let d = e as f64 / x - 1.0;
                sum += d;
                sum_sq += d * d;
                n += 1.0;
            }
        }
    }
    (sum / n, sum_sq / n)
}
