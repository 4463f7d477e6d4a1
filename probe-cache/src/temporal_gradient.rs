//! ADGI's change detection (sec. 4.1.4-4.1.5, eq. 13-18): temporal gradients of the probe
//! visibility and radiance heuristics, the temporal trigger, and the spatial smoothing over
//! neighbouring probes and octants.
//!
//! ```text
//! f_0 = f_v^t − f_v^{t−1}      f_1 = Tr(f_0, θ)      f_Δv = Σ_{i,j} f_1(p − p_i, ω − ω_j)   (eq. 13-15)
//! f_2 = f_r^t − f_r^{t−1}      f_3 = Tr(f_2, θ)      f_Δr = Σ_{i,j} f_3(p − p_i, ω − ω_j)   (eq. 16-18)
//! ```
//!
//! Every function works on per-probe octant tables: slices of `probe_count · 8` values indexed
//! `grid.probe_index(coords) · 8 + octant` ([`octant`](crate::heuristics::octant)).
//!
//! # Our reading of what the paper leaves open
//! - **Trigger** (Fig. 6a, "converts a pulse in time to a decaying signal controlled by θ"): a
//!   peak hold with geometric decay, `y_t = max(|x_t|, θ · y_{t−1})` with θ ∈ [0, 1) the decay
//!   per detection. It takes the gradient's magnitude (a light switching off matters as much as
//!   one switching on), so with f_v, f_r ∈ [0, 1] its output is in [0, 1].
//! - **Convolution** (eq. 15, 18: "a 5 × 5 × 5 and 3 × 3 convolution in space and direction"):
//!   a box filter, normalised to a mean so f_Δ stays in [0, 1] and fits the heuristics word
//!   (eq. 20's bound 1 + μ); at the grid's faces it averages the neighbours that exist. In
//!   direction, the 8 octant texels of a probe are the 8 triangles of the octahedral map; a 3 × 3
//!   kernel around one reaches the 3 triangles sharing its edges, which are the octants that
//!   differ in one sign ([`octant`](crate::heuristics::octant) `o ^ 1`, `o ^ 2`, `o ^ 4`), so
//!   the directional kernel averages an octant with those three.

use crate::heuristics::OCTANTS;
use crate::{ControlError, LayoutError, ProbeGrid};

/// The temporal gradient of eq. 13 / 16: `out[i] = current[i] − previous[i]`. A NaN or
/// infinite difference (from NaN or infinite inputs) is written as 0.
///
/// # Errors
/// [`LayoutError::TableLengthMismatch`] when the three slices differ in length.
pub fn temporal_gradient(
    current: &[f32],
    previous: &[f32],
    out: &mut [f32],
) -> Result<(), LayoutError> {
    LayoutError::check_tables(current.len(), &[previous.len(), out.len()])?;
    for ((o, &c), &p) in out.iter_mut().zip(current).zip(previous) {
        let d = c - p;
        *o = if d.is_finite() { d } else { 0.0 };
    }
    Ok(())
}

/// ADGI's temporal trigger Tr(·, θ) (eq. 14, 17; Fig. 6a): turns a pulse of the temporal
/// gradient into a signal that decays over the following detections, so the chains' target
/// does not jump (sec. 3.3, "distribution stationarity").
///
/// `y_t = max(|x_t|, θ · y_{t−1})`: the output jumps to the pulse's magnitude and then decays
/// by θ per detection (half-life `ln 2 / −ln θ` detections).
///
/// # Example
/// ```
/// use mcg_probe_cache::temporal_gradient::TemporalTrigger;
/// let tr = TemporalTrigger::new(0.5)?;
/// let mut y = 0.0;
/// let mut out = vec![];
/// for x in [0.0, 0.8, 0.0, 0.0, -0.3] {
///     y = tr.apply(x, y);
///     out.push(y);
/// }
/// assert_eq!(out, [0.0, 0.8, 0.4, 0.2, 0.3]);
/// # Ok::<(), mcg_probe_cache::ProbeError>(())
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TemporalTrigger {
    decay: f32,
}

impl TemporalTrigger {
    /// Our default decay θ = 0.9 per detection (the paper gives no value): a half-life of
    /// 6.6 detections, 13 frames with the alternating pilot pattern.
    pub const DEFAULT: Self = Self { decay: 0.9 };

    /// A trigger decaying by `decay` = θ per detection.
    ///
    /// # Errors
    /// [`ControlError::TriggerDecayOutOfRange`] unless θ ∈ [0, 1).
    pub fn new(decay: f32) -> Result<Self, ControlError> {
        if !(0.0..1.0).contains(&decay) {
            return Err(ControlError::TriggerDecayOutOfRange { decay });
        }
        Ok(Self { decay })
    }

    /// θ, the decay per detection.
    #[inline]
    #[must_use]
    pub fn decay(&self) -> f32 {
        self.decay
    }

    /// One detection: the new state `max(|pulse|, θ · state)`. A NaN pulse counts as 0, a NaN
    /// or negative state as 0; an infinite pulse saturates at `f32::MAX`.
    #[inline]
    #[must_use]
    pub fn apply(&self, pulse: f32, state: f32) -> f32 {
        let x = if pulse.is_nan() {
            0.0
        } else {
            pulse.abs().min(f32::MAX)
        };
        let y = if state > 0.0 {
            state.min(f32::MAX)
        } else {
            0.0
        };
        x.max(self.decay * y)
    }

    /// [`Self::apply`] over a table: `state[i] = max(|pulses[i]|, θ · state[i])`.
    ///
    /// # Errors
    /// [`LayoutError::TableLengthMismatch`] when the slices differ in length.
    pub fn apply_slice(&self, pulses: &[f32], state: &mut [f32]) -> Result<(), LayoutError> {
        LayoutError::check_tables(pulses.len(), &[state.len()])?;
        for (s, &x) in state.iter_mut().zip(pulses) {
            *s = self.apply(x, *s);
        }
        Ok(())
    }
}

impl Default for TemporalTrigger {
    /// [`TemporalTrigger::DEFAULT`].
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// The smoothing kernel of eq. 15 / 18: a box of `(2r + 1)³` probes and, optionally, an octant
/// with its three edge-adjacent octants (see the module docs).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct SmoothingKernel {
    /// r, the spatial radius in probes (2 for ADGI's 5 × 5 × 5).
    pub spatial_radius: u32,
    /// Whether to average each octant with its three edge-adjacent octants (ADGI's 3 × 3).
    pub directional: bool,
}

impl SmoothingKernel {
    /// ADGI's kernel: 5 × 5 × 5 probes and the 3 × 3 directional neighbourhood (sec. 4.1.4).
    pub const ADGI: Self = Self {
        spatial_radius: 2,
        directional: true,
    };
}

impl Default for SmoothingKernel {
    /// [`SmoothingKernel::ADGI`].
    fn default() -> Self {
        Self::ADGI
    }
}

/// The spatial and directional smoothing of eq. 15 / 18 as a normalised box filter: `out` at
/// (probe, octant) is the mean of `input` over the probes within `spatial_radius` along each
/// axis that exist in the grid, and (with `directional`) over the octant and its three
/// edge-adjacent octants. Non-finite inputs count as 0 and means that overflow saturate at
/// ±`f32::MAX`, so the output is always finite. A radius beyond the grid covers the whole axis.
/// `scratch` is a buffer of the same length (its contents are overwritten).
///
/// The filter is separable (a box of in-grid probes is a product of per-axis intervals), so it
/// costs `(3 · (2r + 1) + 4)` reads per entry.
///
/// # Errors
/// [`LayoutError::TableLengthMismatch`] unless all three slices have `probe_count · 8` entries.
pub fn spatial_smoothing(
    grid: &ProbeGrid,
    kernel: SmoothingKernel,
    input: &[f32],
    out: &mut [f32],
    scratch: &mut [f32],
) -> Result<(), LayoutError> {
    let n = grid.probe_count() * OCTANTS;
    LayoutError::check_tables(n, &[input.len(), out.len(), scratch.len()])?;
    let finite = |x: f32| if x.is_finite() { x } else { 0.0 };
    // Direction first (into `out`), then x → scratch, y → out, z → scratch, copy to out.
    for (o_chunk, i_chunk) in out
        .chunks_exact_mut(OCTANTS)
        .zip(input.chunks_exact(OCTANTS))
    {
        for o in 0..OCTANTS {
            o_chunk[o] = if kernel.directional {
                // ¼ applied to each term: the same bits as ¼ of the sum for every normal
                // value (scaling by a power of two is exact), but no overflow for huge ones.
                0.25 * finite(i_chunk[o])
                    + 0.25 * finite(i_chunk[o ^ 1])
                    + 0.25 * finite(i_chunk[o ^ 2])
                    + 0.25 * finite(i_chunk[o ^ 4])
            } else {
                finite(i_chunk[o])
            };
        }
    }
    let counts = grid.counts();
    let r = kernel.spatial_radius;
    let strides = [
        OCTANTS,
        OCTANTS * counts.x as usize,
        OCTANTS * (counts.x * counts.y) as usize,
    ];
    let mut src_is_out = true;
    for axis in 0..3 {
        let len = counts[axis];
        let stride = strides[axis];
        let (src, dst): (&[f32], &mut [f32]) = if src_is_out {
            (&*out, &mut *scratch)
        } else {
            (&*scratch, &mut *out)
        };
        for probe in 0..grid.probe_count() {
            let i = grid.probe_coords(probe)[axis];
            let lo = i.saturating_sub(r);
            let hi = i.saturating_add(r).min(len - 1);
            let inv = 1.0 / (hi - lo + 1) as f32;
            let base = probe * OCTANTS;
            for o in 0..OCTANTS {
                let mut s = 0.0;
                for j in lo..=hi {
                    // Same probe with coordinate `j` on this axis.
                    let k = base + o + (j as usize) * stride - (i as usize) * stride;
                    s += src[k];
                }
                // A sum of huge finite values can overflow; keep the table finite.
                dst[base + o] = (s * inv).clamp(-f32::MAX, f32::MAX);
            }
        }
        src_is_out = !src_is_out;
    }
    // Three passes: the result is in `scratch`.
    out.copy_from_slice(scratch);
    Ok(())
}

/// The whole change detector of sec. 4.1.4-4.1.5 for a grid: it keeps the reference
/// measurement, the triggers' states and the smoothed outputs f_Δv, f_Δr.
///
/// With the alternating pilot pattern (sec. 4.4, [`PilotSchedule`](crate::pilot_rays::PilotSchedule)),
/// call [`Self::set_reference`] with the f_v, f_r tables of the first frame of each direction
/// set and [`Self::detect`] with the later ones', so each gradient compares identical ray sets.
/// `detect` then keeps its input as the reference of the next `detect` (for holds > 2).
#[derive(Clone, Debug)]
pub struct ChangeDetector {
    grid: ProbeGrid,
    trigger: TemporalTrigger,
    kernel: SmoothingKernel,
    /// Gradients of a smaller magnitude count as 0 ([`Self::with_pulse_threshold`]).
    pulse_threshold: f32,
    reference_v: Vec<f32>,
    reference_r: Vec<f32>,
    state_v: Vec<f32>,
    state_r: Vec<f32>,
    delta_v: Vec<f32>,
    delta_r: Vec<f32>,
    scratch: Vec<f32>,
}

impl ChangeDetector {
    /// A detector for `grid` with all states 0.
    #[must_use]
    pub fn new(grid: ProbeGrid, trigger: TemporalTrigger, kernel: SmoothingKernel) -> Self {
        let n = grid.probe_count() * OCTANTS;
        Self {
            grid,
            trigger,
            kernel,
            reference_v: vec![0.0; n],
            reference_r: vec![0.0; n],
            state_v: vec![0.0; n],
            state_r: vec![0.0; n],
            delta_v: vec![0.0; n],
            delta_r: vec![0.0; n],
            scratch: vec![0.0; n],
            pulse_threshold: 0.0,
        }
    }

    /// This detector with gradients (eq. 13, 16) of a magnitude below `threshold` counted as
    /// 0 before the trigger — mcg's extension for probes whose pilot rays read a noisy cache
    /// (multi-bounce: the pilot hit's radiance includes last frame's probe irradiance there,
    /// so f_r changes a little on every frame). The paper's detector has none (0, the
    /// default of [`Self::new`]).
    ///
    /// # Errors
    /// [`ControlError::PulseThresholdOutOfRange`] unless `threshold` is finite and ≥ 0.
    pub fn with_pulse_threshold(mut self, threshold: f32) -> Result<Self, ControlError> {
        if !(threshold >= 0.0 && threshold.is_finite()) {
            return Err(ControlError::PulseThresholdOutOfRange { threshold });
        }
        self.pulse_threshold = threshold;
        Ok(self)
    }

    /// Stores the reference f_v, f_r tables (the first frame of a pilot pair). A NaN or
    /// infinite entry is no measurement: the reference keeps its previous value there.
    ///
    /// # Errors
    /// [`LayoutError::TableLengthMismatch`] unless both have `probe_count · 8` entries; the
    /// detector is then unchanged.
    pub fn set_reference(&mut self, f_v: &[f32], f_r: &[f32]) -> Result<(), LayoutError> {
        self.check_lengths(f_v, f_r)?;
        keep_finite(&mut self.reference_v, f_v);
        keep_finite(&mut self.reference_r, f_r);
        Ok(())
    }

    /// Both tables have `probe_count · 8` entries.
    fn check_lengths(&self, f_v: &[f32], f_r: &[f32]) -> Result<(), LayoutError> {
        LayoutError::check_tables(self.reference_v.len(), &[f_v.len()])?;
        LayoutError::check_tables(self.reference_r.len(), &[f_r.len()])
    }

    /// One detection (a later frame of a pilot direction set): gradients against the reference
    /// (eq. 13, 16), triggers (eq. 14, 17), smoothing (eq. 15, 18); the input becomes the new
    /// reference. Returns (f_Δv, f_Δr), also available from [`Self::delta_visibility`] and
    /// [`Self::delta_radiance`].
    ///
    /// A NaN or infinite entry is no measurement: its gradient is 0 (as in
    /// [`temporal_gradient`]) and the reference keeps its previous value there, so the next
    /// finite measurement is still compared with the last finite one.
    ///
    /// # Errors
    /// [`LayoutError::TableLengthMismatch`] unless both have `probe_count · 8` entries; the
    /// detector (reference, trigger states, outputs) is then unchanged.
    pub fn detect(&mut self, f_v: &[f32], f_r: &[f32]) -> Result<(&[f32], &[f32]), LayoutError> {
        // Validate both tables before touching any state.
        self.check_lengths(f_v, f_r)?;
        for (current, reference, state, delta) in [
            (
                f_v,
                &mut self.reference_v,
                &mut self.state_v,
                &mut self.delta_v,
            ),
            (
                f_r,
                &mut self.reference_r,
                &mut self.state_r,
                &mut self.delta_r,
            ),
        ] {
            temporal_gradient(current, reference, delta)?;
            for d in delta.iter_mut() {
                if !(d.abs() >= self.pulse_threshold) {
                    *d = 0.0;
                }
            }
            self.trigger.apply_slice(delta, state)?;
            spatial_smoothing(&self.grid, self.kernel, state, delta, &mut self.scratch)?;
            keep_finite(reference, current);
        }
        Ok((&self.delta_v, &self.delta_r))
    }

    /// f_Δv of the last detection (eq. 15).
    #[must_use]
    pub fn delta_visibility(&self) -> &[f32] {
        &self.delta_v
    }

    /// f_Δr of the last detection (eq. 18).
    #[must_use]
    pub fn delta_radiance(&self) -> &[f32] {
        &self.delta_r
    }

    /// The triggers' states (f_1, f_3 of eq. 14, 17) before smoothing.
    #[must_use]
    pub fn trigger_states(&self) -> (&[f32], &[f32]) {
        (&self.state_v, &self.state_r)
    }
}

/// `reference[i] = current[i]` where `current[i]` is finite; other entries keep their value.
fn keep_finite(reference: &mut [f32], current: &[f32]) {
    for (r, &c) in reference.iter_mut().zip(current) {
        if c.is_finite() {
            *r = c;
        }
    }
}

#[cfg(test)]
mod tests {
    use glam::{UVec3, Vec3};

    use super::*;

    fn line(n: u32) -> ProbeGrid {
        ProbeGrid::new(Vec3::ZERO, Vec3::ONE, UVec3::new(n, 1, 1)).unwrap()
    }

    #[test]
    fn gradient_by_hand() {
        let mut out = [9.0; 4];
        temporal_gradient(
            &[0.5, 0.2, f32::NAN, 1.0],
            &[0.25, 0.7, 0.0, f32::INFINITY],
            &mut out,
        )
        .unwrap();
        assert_eq!(out, [0.25, -0.5, 0.0, 0.0]);
        assert_eq!(
            temporal_gradient(&[0.0], &[0.0, 1.0], &mut out),
            Err(LayoutError::TableLengthMismatch {
                expected: 1,
                found: 2
            })
        );
    }

    #[test]
    fn trigger_by_hand() {
        let tr = TemporalTrigger::new(0.5).unwrap();
        // Pulses 0, 0.8, 0, 0, −0.3, 0 → 0, 0.8, 0.4, 0.2, max(0.3, 0.1) = 0.3, 0.15.
        let mut y = 0.0;
        let got: Vec<f32> = [0.0, 0.8, 0.0, 0.0, -0.3, 0.0]
            .iter()
            .map(|&x| {
                y = tr.apply(x, y);
                y
            })
            .collect();
        assert_eq!(got, [0.0, 0.8, 0.4, 0.2, 0.3, 0.15]);
        assert_eq!(tr.apply(f32::NAN, 0.4), 0.2);
        assert_eq!(tr.apply(0.1, f32::NAN), 0.1);
        assert_eq!(tr.apply(f32::NEG_INFINITY, 0.0), f32::MAX);
        assert!(TemporalTrigger::new(1.0).is_err());
        assert!(TemporalTrigger::new(f32::NAN).is_err());
        assert!(TemporalTrigger::new(-0.1).is_err());
        assert_eq!(TemporalTrigger::default().decay(), 0.9);
        let mut state = [0.5, 0.0];
        tr.apply_slice(&[0.1, -0.7], &mut state).unwrap();
        assert_eq!(state, [0.25, 0.7]);
    }

    #[test]
    fn smoothing_by_hand_on_a_line() {
        // 3 × 1 × 1 probes, impulse 1 at probe 0 octant 0.
        let g = line(3);
        let mut input = vec![0.0; 24];
        input[0] = 1.0;
        let (mut out, mut scratch) = (vec![0.0; 24], vec![0.0; 24]);
        let k = SmoothingKernel {
            spatial_radius: 1,
            directional: true,
        };
        spatial_smoothing(&g, k, &input, &mut out, &mut scratch).unwrap();
        // Direction: octants 0, 1, 2, 4 of probe 0 get 1/4. Space (r = 1): probe 0 averages
        // probes {0, 1} → 1/8; probe 1 averages {0, 1, 2} → 1/12; probe 2 averages {1, 2} → 0.
        for o in 0..8 {
            let w = if [0, 1, 2, 4].contains(&o) { 1.0 } else { 0.0 };
            mcg_test_support::assert_close!(out[o], w / 8.0, 1e-7, "{o}");
            mcg_test_support::assert_close!(out[8 + o], w / 12.0, 1e-7, "{o}");
            assert_eq!(out[16 + o], 0.0);
        }
        // ADGI's r = 2 covers the whole line from every probe: 1/4 · 1/3 each.
        spatial_smoothing(&g, SmoothingKernel::ADGI, &input, &mut out, &mut scratch).unwrap();
        for p in 0..3 {
            mcg_test_support::assert_close!(out[p * 8 + 4], 1.0 / 12.0, 1e-7);
            assert_eq!(out[p * 8 + 3], 0.0);
        }
    }

    #[test]
    fn smoothing_by_hand_in_3d() {
        // 3 × 3 × 3 probes, r = 1, no directional smoothing; impulse 27 at the centre probe's
        // octant 5: every probe's window contains the centre, with 2 or 3 probes per axis:
        // corner (0, 0, 0): 2·2·2 = 8 → 27/8; face centre (1, 1, 0): 3·3·2 = 18 → 1.5;
        // centre: 27 → 1.
        let g = ProbeGrid::new(Vec3::ZERO, Vec3::ONE, UVec3::splat(3)).unwrap();
        let mut input = vec![0.0; 27 * 8];
        input[g.probe_index(UVec3::ONE) * 8 + 5] = 27.0;
        input[7] = f32::NAN; // ignored
        let (mut out, mut scratch) = (vec![0.0; 27 * 8], vec![0.0; 27 * 8]);
        let k = SmoothingKernel {
            spatial_radius: 1,
            directional: false,
        };
        spatial_smoothing(&g, k, &input, &mut out, &mut scratch).unwrap();
        mcg_test_support::assert_close!(out[5], 27.0 / 8.0, 1e-6);
        mcg_test_support::assert_close!(out[g.probe_index(UVec3::new(1, 1, 0)) * 8 + 5], 1.5, 1e-6);
        mcg_test_support::assert_close!(out[g.probe_index(UVec3::ONE) * 8 + 5], 1.0, 1e-6);
        assert!(out.iter().enumerate().all(|(i, &v)| i % 8 == 5 || v == 0.0));
        // A constant field stays constant (normalised).
        let ones = vec![0.6; 27 * 8];
        spatial_smoothing(&g, SmoothingKernel::ADGI, &ones, &mut out, &mut scratch).unwrap();
        assert!(out.iter().all(|&v| (v - 0.6).abs() < 1e-6));
        assert_eq!(
            spatial_smoothing(&g, k, &ones[1..], &mut out, &mut scratch),
            Err(LayoutError::TableLengthMismatch {
                expected: 27 * 8,
                found: 27 * 8 - 1
            })
        );
    }

    #[test]
    fn detector_fires_and_decays() {
        let g = line(2);
        let mut d = ChangeDetector::new(
            g,
            TemporalTrigger::new(0.5).unwrap(),
            SmoothingKernel {
                spatial_radius: 0,
                directional: false,
            },
        );
        let v0 = vec![0.3; 16];
        let r0 = vec![0.1; 16];
        d.set_reference(&v0, &r0).unwrap();
        let mut v1 = v0.clone();
        v1[9] = 0.9; // probe 1, octant 1: a surface appears
        let (dv, dr) = d.detect(&v1, &r0).unwrap();
        mcg_test_support::assert_close!(dv[9], 0.6, 1e-6);
        assert!(dv.iter().enumerate().all(|(i, &x)| i == 9 || x == 0.0));
        assert!(dr.iter().all(|&x| x == 0.0));
        // Next detection (the reference is now v1): no change → the trigger halves.
        d.detect(&v1, &r0).unwrap();
        mcg_test_support::assert_close!(d.delta_visibility()[9], 0.3, 1e-6);
        mcg_test_support::assert_close!(d.trigger_states().0[9], 0.3, 1e-6);
        assert!(d.delta_radiance().iter().all(|&x| x == 0.0));
        assert!(d.detect(&v1[1..], &r0).is_err());
    }

    #[test]
    fn pulse_threshold_ignores_small_gradients_only() {
        let kernel = SmoothingKernel {
            spatial_radius: 0,
            directional: false,
        };
        let trigger = TemporalTrigger::new(0.5).unwrap();
        let mut d = ChangeDetector::new(line(2), trigger, kernel)
            .with_pulse_threshold(0.05)
            .unwrap();
        let v0 = vec![0.3; 16];
        let r0 = vec![0.1; 16];
        d.set_reference(&v0, &r0).unwrap();
        let mut r1 = r0.clone();
        r1[2] = 0.14; // a flicker of 0.04: below the threshold
        r1[12] = 0.05; // a change of −0.05: at it
        let (dv, dr) = d.detect(&v0, &r1).unwrap();
        assert!(dv.iter().all(|&x| x == 0.0));
        assert_eq!(dr[2], 0.0);
        mcg_test_support::assert_close!(dr[12], 0.05, 1e-6);
        // Without a threshold (the paper's detector) the flicker fires.
        let mut d = ChangeDetector::new(line(2), trigger, kernel);
        d.set_reference(&v0, &r0).unwrap();
        mcg_test_support::assert_close!(d.detect(&v0, &r1).unwrap().1[2], 0.04, 1e-6);
        for bad in [-0.1, f32::NAN, f32::INFINITY] {
            let e = ChangeDetector::new(line(2), trigger, kernel)
                .with_pulse_threshold(bad)
                .unwrap_err();
            assert!(
                matches!(e, ControlError::PulseThresholdOutOfRange { .. }),
                "{e:?}"
            );
        }
    }

    #[test]
    fn huge_radius_covers_the_axis() {
        // Issue 14 row 15: `i + r` overflowed for r = u32::MAX (debug panic; release used a
        // wrong window).
        let g = ProbeGrid::new(Vec3::ZERO, Vec3::ONE, UVec3::new(4, 3, 2)).unwrap();
        let input: Vec<f32> = (0..24 * 8).map(|i| ((i * 37) % 11) as f32 / 10.0).collect();
        let (mut a, mut b, mut scratch) = (vec![0.0; 192], vec![0.0; 192], vec![0.0; 192]);
        for directional in [false, true] {
            let huge = SmoothingKernel {
                spatial_radius: u32::MAX,
                directional,
            };
            let whole = SmoothingKernel {
                spatial_radius: 3,
                directional,
            };
            spatial_smoothing(&g, huge, &input, &mut a, &mut scratch).unwrap();
            spatial_smoothing(&g, whole, &input, &mut b, &mut scratch).unwrap();
            assert_eq!(a, b);
        }
    }

    #[test]
    fn huge_values_smooth_to_finite_values() {
        let g = line(3);
        let input = vec![f32::MAX; 24];
        let (mut out, mut scratch) = (vec![0.0; 24], vec![0.0; 24]);
        spatial_smoothing(&g, SmoothingKernel::ADGI, &input, &mut out, &mut scratch).unwrap();
        assert!(out.iter().all(|&v| v == f32::MAX), "{out:?}");
    }

    #[test]
    fn failed_detection_leaves_the_detector_unchanged() {
        // Issue 14 row 18: a good f_v with a short f_r returned Err after the reference,
        // trigger state and delta of f_v had already changed.
        let g = line(2);
        let mut d =
            ChangeDetector::new(g, TemporalTrigger::new(0.5).unwrap(), SmoothingKernel::ADGI);
        d.set_reference(&[0.3; 16], &[0.1; 16]).unwrap();
        d.detect(&[0.5; 16], &[0.2; 16]).unwrap();
        let snapshot = |d: &ChangeDetector| {
            (
                d.reference_v.clone(),
                d.reference_r.clone(),
                d.trigger_states().0.to_vec(),
                d.trigger_states().1.to_vec(),
                d.delta_visibility().to_vec(),
                d.delta_radiance().to_vec(),
            )
        };
        let before = snapshot(&d);
        assert_eq!(
            d.detect(&[0.9; 16], &[0.4; 15]),
            Err(LayoutError::TableLengthMismatch {
                expected: 16,
                found: 15
            })
        );
        assert_eq!(snapshot(&d), before);
        assert!(d.detect(&[0.9; 17], &[0.4; 16]).is_err());
        assert!(d.set_reference(&[0.9; 16], &[0.4; 3]).is_err());
        assert_eq!(snapshot(&d), before);
    }

    #[test]
    fn non_finite_frames_do_not_become_the_reference() {
        // Issue 14 row 19: a NaN frame became the reference, and the next real 0 → 1 change
        // reported 0.
        let g = line(1);
        let none = SmoothingKernel {
            spatial_radius: 0,
            directional: false,
        };
        for bad in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
            let mut d = ChangeDetector::new(g, TemporalTrigger::new(0.5).unwrap(), none);
            d.set_reference(&[0.0; 8], &[0.0; 8]).unwrap();
            d.detect(&[bad; 8], &[bad; 8]).unwrap();
            assert!(d.delta_visibility().iter().all(|&x| x == 0.0));
            let (dv, dr) = d.detect(&[1.0; 8], &[1.0; 8]).unwrap();
            assert!(dv.iter().chain(dr).all(|&x| x == 1.0), "{bad}: {dv:?}");
            // The same through set_reference.
            let mut d = ChangeDetector::new(g, TemporalTrigger::new(0.5).unwrap(), none);
            d.set_reference(&[bad; 8], &[bad; 8]).unwrap();
            let (dv, _) = d.detect(&[1.0; 8], &[1.0; 8]).unwrap();
            assert!(dv.iter().all(|&x| x == 1.0), "{bad}: {dv:?}");
        }
    }

    #[test]
    fn value_stability() {
        let g = ProbeGrid::new(Vec3::ZERO, Vec3::ONE, UVec3::new(3, 2, 2)).unwrap();
        let input: Vec<f32> = (0..96).map(|i| ((i * 37) % 11) as f32 / 10.0).collect();
        let (mut out, mut scratch) = (vec![0.0; 96], vec![0.0; 96]);
        spatial_smoothing(&g, SmoothingKernel::ADGI, &input, &mut out, &mut scratch).unwrap();
        let pins: Vec<u32> = [0, 13, 50, 95].iter().map(|&i| out[i].to_bits()).collect();
        assert_eq!(
            pins,
            vec![0x3efc_ccce, 0x3f02_2222, 0x3ef6_6666, 0x3efd_dddf],
            "{pins:x?}"
        );
    }
}
