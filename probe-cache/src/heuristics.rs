//! ADGI's heuristics (sec. 4.1-4.3): distance from the camera f_c (eq. 10), probe visibility f_v
//! (eq. 11), incoming radiance f_r (eq. 12), their static and dynamic compositions f_s and f_d
//! (eq. 19-20), and the 6-10-10 heuristics word they are stored in.
//!
//! All functions are pure, take and return `f32`, and never return NaN or an infinity: each
//! documents what it does with NaN, infinite, negative and zero inputs.
//!
//! The heuristics are tabulated per probe and per **octant** of directions (sec. 4.1: "each
//! probe has eight texels corresponding to an octant"); [`octant`] gives the octant of a
//! direction and [`OCTANTS`] is their number.

use glam::Vec3;
use mcg_color_codec::{Heuristics, HeuristicsLayout, HeuristicsWord};

use crate::{LayoutError, ParameterError};

/// Octants per probe: the heuristics LUT has one texel per octant (ADGI sec. 4.1, Fig. 5a).
pub const OCTANTS: usize = 8;

/// The octant of a direction: bit 0, 1, 2 set when the x, y, z component is negative
/// (`0` is the octant (+, +, +), `7` the octant (−, −, −)). Zero and NaN components count as
/// positive. The opposite direction lies in octant `o ^ 7`.
///
/// # Example
/// ```
/// use mcg_probe_cache::{heuristics::octant, glam::Vec3};
/// assert_eq!(octant(Vec3::new(1.0, -2.0, 0.5)), 0b010);
/// assert_eq!(octant(-Vec3::new(1.0, -2.0, 0.5)), 0b010 ^ 7);
/// ```
#[inline]
#[must_use]
pub fn octant(direction: Vec3) -> usize {
    usize::from(direction.x < 0.0)
        | usize::from(direction.y < 0.0) << 1
        | usize::from(direction.z < 0.0) << 2
}

/// The sign vector (±1 per axis) of octant `o` (only its three low bits are read).
#[inline]
#[must_use]
pub fn octant_signs(o: usize) -> Vec3 {
    let s = |bit: usize| if o >> bit & 1 == 1 { -1.0 } else { 1.0 };
    Vec3::new(s(0), s(1), s(2))
}

/// Distance-from-camera heuristic f_c (ADGI eq. 10):
///
/// ```text
/// f_c = 1                   if ‖p − c‖ < k,
///       e^{−(‖p − c‖ − k)}  otherwise,
/// ```
///
/// with p the probe position, c the camera position and k the user's threshold (in scene
/// units; the exponent is in the same units, as in the paper).
///
/// Edge cases: a non-finite distance (NaN or infinite positions) gives 0; a NaN or negative
/// `k` is treated as 0, an infinite `k` gives 1 for every finite distance. The result is in
/// [0, 1].
///
/// # Example
/// ```
/// use mcg_probe_cache::{heuristics::camera_distance, glam::Vec3};
/// assert_eq!(camera_distance(Vec3::new(3.0, 0.0, 0.0), Vec3::ZERO, 5.0), 1.0);
/// // ‖p − c‖ = 6, k = 5: e^{−1}.
/// let f = camera_distance(Vec3::new(6.0, 0.0, 0.0), Vec3::ZERO, 5.0);
/// assert!((f - (-1.0f32).exp()).abs() < 1e-7);
/// ```
#[inline]
#[must_use]
pub fn camera_distance(probe: Vec3, camera: Vec3, k: f32) -> f32 {
    let d = probe.distance(camera);
    if !d.is_finite() {
        return 0.0;
    }
    let k = if k >= 0.0 { k } else { 0.0 }; // NaN → 0
    if d < k { 1.0 } else { (-(d - k)).exp() }
}

/// Probe-visibility heuristic f_v (ADGI eq. 11): `e^{−2t/s}`, with t the distance of the
/// nearest surface traced from the probe along −ω and s the diagonal of a grid voxel
/// ([`ProbeGrid::cell_diagonal`](crate::ProbeGrid::cell_diagonal)).
///
/// Probes close to a surface (t ≪ s) get values near 1, a probe one diagonal away e^{−2}.
///
/// Edge cases: a miss (t = +∞) or a NaN distance gives 0 (no surface seen); t ≤ 0 (a hit at
/// the probe or behind it) gives 1. A non-positive or NaN `s` gives 0 for t > 0, an infinite
/// `s` gives 1 for finite t (and 0 for t = +∞). The result is in [0, 1].
///
/// # Example
/// ```
/// use mcg_probe_cache::heuristics::probe_visibility;
/// // t = s/2: e^{−1}.
/// assert!((probe_visibility(0.5, 1.0) - (-1.0f32).exp()).abs() < 1e-7);
/// assert_eq!(probe_visibility(f32::INFINITY, 1.0), 0.0);
/// ```
#[inline]
#[must_use]
pub fn probe_visibility(t: f32, s: f32) -> f32 {
    if t.is_nan() {
        return 0.0;
    }
    if t <= 0.0 {
        return 1.0;
    }
    if !(s > 0.0) {
        return 0.0;
    }
    // t > 0, s > 0: the ratio is in [0, +∞] (exp(−∞) = 0), or NaN for t = s = +∞.
    let ratio = 2.0 * t / s;
    if ratio.is_nan() { 0.0 } else { (-ratio).exp() }
}

/// ADGI's dynamic-range parameter β of the radiance heuristic (sec. 4.1.3: "we set β = 5").
pub const RADIANCE_RANGE: f32 = 5.0;

/// Incoming-radiance heuristic f_r (ADGI eq. 12): `min(r, β)/β` with r the luminance arriving
/// along ω (direct light at the pilot ray's hit point) and β the dynamic range
/// ([`RADIANCE_RANGE`] = 5 in the paper).
///
/// Edge cases: NaN or negative luminance gives 0, +∞ gives 1; a NaN, non-positive or infinite
/// `β` gives 0 (no range). The result is in [0, 1].
///
/// # Example
/// ```
/// use mcg_probe_cache::heuristics::{RADIANCE_RANGE, incoming_radiance};
/// assert_eq!(incoming_radiance(2.0, RADIANCE_RANGE), 0.4);
/// assert_eq!(incoming_radiance(9.0, RADIANCE_RANGE), 1.0);
/// ```
#[inline]
#[must_use]
pub fn incoming_radiance(r: f32, beta: f32) -> f32 {
    if !(beta > 0.0) || !beta.is_finite() || !(r > 0.0) {
        return 0.0;
    }
    r.min(beta) / beta
}

/// ADGI's weight μ of lighting change against geometry change in f_d (sec. 4.2: "we use
/// μ = 2 in all our experiments").
pub const LIGHTING_WEIGHT: f32 = 2.0;

/// Static heuristic f_s = f_c · f_v (ADGI eq. 19). Inputs are clamped to [0, 1] (NaN → 0), so
/// the result is in [0, 1].
#[inline]
#[must_use]
pub fn static_heuristic(f_c: f32, f_v: f32) -> f32 {
    unit(f_c) * unit(f_v)
}

/// Dynamic heuristic f_d = f_c f_v (f_Δv + μ f_Δr) (ADGI eq. 20), **divided by its bound
/// 1 + μ** so that it lies in [0, 1] and fits the heuristics word's UNORM field.
///
/// f_Δv and f_Δr are the smoothed, triggered temporal changes of visibility and radiance
/// (eq. 15, 18; see [`temporal_gradient`](crate::temporal_gradient)), each in [0, 1]. Every input is
/// clamped to [0, 1] (NaN → 0) and a NaN, negative or infinite μ is treated as 0. Dividing by
/// the constant 1 + μ does not change the distribution a chain samples from f_d.
#[inline]
#[must_use]
pub fn dynamic_heuristic(f_c: f32, f_v: f32, f_dv: f32, f_dr: f32, mu: f32) -> f32 {
    let mu = if mu >= 0.0 && mu.is_finite() { mu } else { 0.0 };
    static_heuristic(f_c, f_v) * (unit(f_dv) + mu * unit(f_dr)) / (1.0 + mu)
}

/// `x` clamped to [0, 1], NaN → 0.
#[inline]
pub(crate) fn unit(x: f32) -> f32 {
    if x > 0.0 { x.min(1.0) } else { 0.0 }
}

/// The parameters of ADGI's heuristics: the camera threshold k (eq. 10), the voxel diagonal
/// s (eq. 11), the radiance range β (eq. 12) and the lighting weight μ (eq. 20).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HeuristicParams {
    camera_threshold: f32,
    voxel_diagonal: f32,
    radiance_range: f32,
    lighting_weight: f32,
}

impl HeuristicParams {
    /// Heuristics with camera threshold `k`, voxel diagonal `s`, and the paper's β = 5, μ = 2.
    ///
    /// # Errors
    /// [`ParameterError::HeuristicOutOfRange`] unless `k` is finite and ≥ 0 and `s` is
    /// finite and > 0.
    pub fn new(camera_threshold: f32, voxel_diagonal: f32) -> Result<Self, ParameterError> {
        Self::with_ranges(
            camera_threshold,
            voxel_diagonal,
            RADIANCE_RANGE,
            LIGHTING_WEIGHT,
        )
    }

    /// Heuristics with every parameter given.
    ///
    /// # Errors
    /// [`ParameterError::HeuristicOutOfRange`] unless `k ≥ 0`, `s > 0`, `β > 0`, `μ ≥ 0`,
    /// all finite.
    pub fn with_ranges(
        camera_threshold: f32,
        voxel_diagonal: f32,
        radiance_range: f32,
        lighting_weight: f32,
    ) -> Result<Self, ParameterError> {
        for (parameter, value, positive) in [
            ("camera_threshold", camera_threshold, false),
            ("voxel_diagonal", voxel_diagonal, true),
            ("radiance_range", radiance_range, true),
            ("lighting_weight", lighting_weight, false),
        ] {
            let in_range = if positive { value > 0.0 } else { value >= 0.0 };
            if !(in_range && value.is_finite()) {
                return Err(ParameterError::HeuristicOutOfRange { parameter, value });
            }
        }
        Ok(Self {
            camera_threshold,
            voxel_diagonal,
            radiance_range,
            lighting_weight,
        })
    }

    /// The camera threshold k of eq. 10.
    #[inline]
    #[must_use]
    pub fn camera_threshold(&self) -> f32 {
        self.camera_threshold
    }

    /// The voxel diagonal s of eq. 11.
    #[inline]
    #[must_use]
    pub fn voxel_diagonal(&self) -> f32 {
        self.voxel_diagonal
    }

    /// The radiance range β of eq. 12.
    #[inline]
    #[must_use]
    pub fn radiance_range(&self) -> f32 {
        self.radiance_range
    }

    /// The lighting weight μ of eq. 20.
    #[inline]
    #[must_use]
    pub fn lighting_weight(&self) -> f32 {
        self.lighting_weight
    }

    /// The camera-distance heuristic f_c for a probe at `probe` seen from `camera` (eq. 10).
    #[inline]
    #[must_use]
    pub fn camera_distance(&self, probe: Vec3, camera: Vec3) -> f32 {
        camera_distance(probe, camera, self.camera_threshold)
    }

    /// The probe-visibility heuristic f_v for a hit at distance `t` along −ω (eq. 11).
    #[inline]
    #[must_use]
    pub fn probe_visibility(&self, t: f32) -> f32 {
        probe_visibility(t, self.voxel_diagonal)
    }

    /// The incoming-radiance heuristic f_r for luminance `r` arriving along ω (eq. 12).
    #[inline]
    #[must_use]
    pub fn incoming_radiance(&self, r: f32) -> f32 {
        incoming_radiance(r, self.radiance_range)
    }

    /// f_c: the old name of [`HeuristicParams::camera_distance`].
    #[deprecated(note = "renamed to `camera_distance`")]
    #[inline]
    #[must_use]
    pub fn f_c(&self, probe: Vec3, camera: Vec3) -> f32 {
        self.camera_distance(probe, camera)
    }

    /// f_v: the old name of [`HeuristicParams::probe_visibility`].
    #[deprecated(note = "renamed to `probe_visibility`")]
    #[inline]
    #[must_use]
    pub fn f_v(&self, t: f32) -> f32 {
        self.probe_visibility(t)
    }

    /// f_r: the old name of [`HeuristicParams::incoming_radiance`].
    #[deprecated(note = "renamed to `incoming_radiance`")]
    #[inline]
    #[must_use]
    pub fn f_r(&self, r: f32) -> f32 {
        self.incoming_radiance(r)
    }

    /// The stored heuristics of one probe octant (sec. 4.3): f_v, f_s = f_c f_v (eq. 19) and
    /// f_d = f_c f_v (f_Δv + μ f_Δr)/(1 + μ) (eq. 20, normalised), with `flags`.
    #[inline]
    #[must_use]
    pub fn compose(&self, f_c: f32, f_v: f32, f_dv: f32, f_dr: f32, flags: u32) -> Heuristics {
        Heuristics {
            f_v: unit(f_v),
            f_s: static_heuristic(f_c, f_v),
            f_d: dynamic_heuristic(f_c, f_v, f_dv, f_dr, self.lighting_weight),
            flags,
        }
    }
}

/// The heuristics words of a whole grid for one frame (sec. 4.1-4.3): for every probe and
/// octant, f_c of the probe's distance to `camera` (eq. 10), f_v from the pilot rays (eq. 11),
/// f_s and f_d composed with the smoothed changes f_Δv, f_Δr (eq. 19-20, see
/// [`ChangeDetector`](crate::temporal_gradient::ChangeDetector)), packed into `out` (sec. 4.3).
/// The flag bits already in `out` are kept. Tables are indexed `probe_index · 8 + octant`.
///
/// # Errors
/// [`LayoutError::TableLengthMismatch`] unless every table has `probe_count · 8` entries.
pub fn compose_grid(
    grid: &crate::ProbeGrid,
    params: &HeuristicParams,
    camera: Vec3,
    f_v: &[f32],
    delta_v: &[f32],
    delta_r: &[f32],
    out: &mut [HeuristicsWord],
) -> Result<(), LayoutError> {
    let n = grid.probe_count() * OCTANTS;
    LayoutError::check_tables(n, &[f_v.len(), delta_v.len(), delta_r.len(), out.len()])?;
    let layout = HeuristicsLayout::ADGI;
    for probe in 0..grid.probe_count() {
        let f_c = params.camera_distance(grid.probe_position(grid.probe_coords(probe)), camera);
        for o in 0..OCTANTS {
            let i = probe * OCTANTS + o;
            let flags = layout.flags(out[i]);
            out[i] = layout.encode(params.compose(f_c, f_v[i], delta_v[i], delta_r[i], flags));
        }
    }
    Ok(())
}

/// Packs heuristics into ADGI's 6-10-10 + 6-flag word (sec. 4.3, [`HeuristicsLayout::ADGI`]),
/// rounding to nearest.
#[inline]
#[must_use]
pub fn encode(h: Heuristics) -> HeuristicsWord {
    HeuristicsLayout::ADGI.encode(h)
}

/// Unpacks ADGI's heuristics word (every value in [0, 1]).
#[inline]
#[must_use]
pub fn decode(word: HeuristicsWord) -> Heuristics {
    HeuristicsLayout::ADGI.decode(word)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn octants_and_signs() {
        for o in 0..OCTANTS {
            let s = octant_signs(o);
            assert_eq!(octant(s), o);
            assert_eq!(octant(-s), o ^ 7);
        }
        assert_eq!(octant(Vec3::ZERO), 0);
        assert_eq!(octant(Vec3::NAN), 0);
        assert_eq!(octant(Vec3::new(-0.1, 0.2, -0.3)), 0b101);
    }

    #[test]
    fn camera_distance_by_hand() {
        let c = Vec3::new(1.0, 2.0, 3.0);
        // ‖(4, 6, 3) − (1, 2, 3)‖ = ‖(3, 4, 0)‖ = 5 < k = 6 → 1.
        assert_eq!(camera_distance(Vec3::new(4.0, 6.0, 3.0), c, 6.0), 1.0);
        // Distance 5, k = 2 → e^{−3} = 0.049787068.
        let f = camera_distance(Vec3::new(4.0, 6.0, 3.0), c, 2.0);
        mcg_test_support::assert_close!(f, 0.049_787_07, 1e-7, "{f}");
        // Exactly at k: e^0 = 1 (continuous).
        assert_eq!(camera_distance(Vec3::new(4.0, 6.0, 3.0), c, 5.0), 1.0);
        assert_eq!(camera_distance(Vec3::NAN, c, 1.0), 0.0);
        assert_eq!(camera_distance(Vec3::INFINITY, c, 1.0), 0.0);
        // NaN k → 0: distance 5 → e^{−5}.
        let f = camera_distance(Vec3::new(4.0, 6.0, 3.0), c, f32::NAN);
        mcg_test_support::assert_close!(f, (-5.0f32).exp(), 1e-8);
        assert_eq!(
            camera_distance(Vec3::new(4.0, 6.0, 3.0), c, f32::INFINITY),
            1.0
        );
        // Far away underflows to 0, not NaN.
        assert_eq!(camera_distance(Vec3::splat(1e30), c, 1.0), 0.0);
    }

    #[test]
    fn probe_visibility_by_hand() {
        // s = √3 (unit voxel diagonal), t = 0.25: e^{−0.5/√3} = e^{−0.288675} = 0.749256.
        let f = probe_visibility(0.25, 3.0f32.sqrt());
        mcg_test_support::assert_close!(f, 0.749_255_6, 1e-6, "{f}");
        // t = s: e^{−2} = 0.135335.
        mcg_test_support::assert_close!(probe_visibility(2.0, 2.0), 0.135_335_28, 1e-7);
        assert_eq!(probe_visibility(0.0, 1.0), 1.0);
        assert_eq!(probe_visibility(-3.0, 1.0), 1.0);
        assert_eq!(probe_visibility(f32::INFINITY, 1.0), 0.0);
        assert_eq!(probe_visibility(f32::NAN, 1.0), 0.0);
        assert_eq!(probe_visibility(1.0, 0.0), 0.0);
        assert_eq!(probe_visibility(1.0, f32::NAN), 0.0);
        assert_eq!(probe_visibility(1.0, f32::INFINITY), 1.0);
        assert_eq!(probe_visibility(f32::INFINITY, f32::INFINITY), 0.0);
        assert_eq!(probe_visibility(1e30, 1e-30), 0.0);
    }

    #[test]
    fn incoming_radiance_by_hand() {
        assert_eq!(incoming_radiance(0.0, 5.0), 0.0);
        assert_eq!(incoming_radiance(1.0, 5.0), 0.2);
        assert_eq!(incoming_radiance(5.0, 5.0), 1.0);
        assert_eq!(incoming_radiance(f32::INFINITY, 5.0), 1.0);
        assert_eq!(incoming_radiance(f32::NAN, 5.0), 0.0);
        assert_eq!(incoming_radiance(-1.0, 5.0), 0.0);
        assert_eq!(incoming_radiance(1.0, 0.0), 0.0);
        assert_eq!(incoming_radiance(1.0, f32::INFINITY), 0.0);
    }

    #[test]
    fn composition_by_hand() {
        let p = HeuristicParams::new(4.0, 1.0).unwrap();
        // f_c = 0.5, f_v = 0.8: f_s = 0.4; f_d = 0.4·(0.25 + 2·0.5)/3 = 0.4·1.25/3 = 0.1666…
        let h = p.compose(0.5, 0.8, 0.25, 0.5, 3);
        assert_eq!(h.f_v, 0.8);
        mcg_test_support::assert_close!(h.f_s, 0.4, 1e-7);
        mcg_test_support::assert_close!(h.f_d, 0.166_666_67, 1e-7, "{}", h.f_d);
        assert_eq!(h.flags, 3);
        // Saturated changes reach the bound 1 exactly when f_c = f_v = 1.
        assert_eq!(p.compose(1.0, 1.0, 1.0, 1.0, 0).f_d, 1.0);
        // NaN and out-of-range inputs are clamped.
        let h = p.compose(f32::NAN, 2.0, -1.0, f32::INFINITY, 0);
        assert_eq!((h.f_v, h.f_s, h.f_d), (1.0, 0.0, 0.0));
        assert_eq!(dynamic_heuristic(1.0, 1.0, 0.5, 1.0, f32::NAN), 0.5);
    }

    #[test]
    fn params_are_validated() {
        assert!(HeuristicParams::new(0.0, 1.0).is_ok());
        for (k, s) in [
            (-1.0, 1.0),
            (f32::NAN, 1.0),
            (1.0, 0.0),
            (1.0, f32::INFINITY),
        ] {
            let (parameter, value) = if k >= 0.0 && k.is_finite() {
                ("voxel_diagonal", s)
            } else {
                ("camera_threshold", k)
            };
            let e = HeuristicParams::new(k, s);
            assert!(
                matches!(e, Err(ParameterError::HeuristicOutOfRange { parameter: p, value: v })
                    if p == parameter && v.to_bits() == value.to_bits()),
                "{k} {s}: {e:?}"
            );
        }
        assert!(HeuristicParams::with_ranges(1.0, 1.0, 0.0, 2.0).is_err());
        assert!(HeuristicParams::with_ranges(1.0, 1.0, 5.0, -2.0).is_err());
        let p = HeuristicParams::with_ranges(1.0, 2.0, 4.0, 3.0).unwrap();
        assert_eq!(
            (
                p.camera_threshold(),
                p.voxel_diagonal(),
                p.radiance_range(),
                p.lighting_weight()
            ),
            (1.0, 2.0, 4.0, 3.0)
        );
        assert_eq!(p.incoming_radiance(2.0), 0.5);
        assert_eq!(p.probe_visibility(0.0), 1.0);
        assert_eq!(p.camera_distance(Vec3::ZERO, Vec3::X), 1.0);
    }

    #[test]
    fn word_round_trip() {
        let p = HeuristicParams::new(4.0, 1.0).unwrap();
        let h = p.compose(0.9, 0.7, 0.3, 0.1, 0b10_1010);
        let back = decode(encode(h));
        mcg_test_support::assert_close!(back.f_v, h.f_v, 0.5 / 63.0);
        mcg_test_support::assert_close!(back.f_s, h.f_s, 0.5 / 1023.0);
        mcg_test_support::assert_close!(back.f_d, h.f_d, 0.5 / 1023.0);
        assert_eq!(back.flags, h.flags);
    }

    #[test]
    fn compose_grid_by_hand() {
        let grid = crate::ProbeGrid::new(Vec3::ZERO, Vec3::ONE, glam::UVec3::new(2, 1, 1)).unwrap();
        let p = HeuristicParams::new(0.5, 1.0).unwrap();
        let f_v = [0.5; 16];
        let mut dv = [0.0; 16];
        dv[9] = 1.0; // probe 1, octant 1
        let dr = [0.0; 16];
        let mut out = [HeuristicsWord(0); 16];
        out[9] = HeuristicsLayout::ADGI.with_flags(out[9], 5);
        compose_grid(&grid, &p, Vec3::ZERO, &f_v, &dv, &dr, &mut out).unwrap();
        // Probe 0 at the camera: f_c = 1, f_s = 0.5. Probe 1 at distance 1, k = 0.5:
        // f_c = e^{−0.5} = 0.60653, f_s = 0.30327; octant 1: f_d = 0.30327 · 1/3 = 0.10109.
        let h0 = decode(out[0]);
        assert!((h0.f_s - 0.5).abs() < 1e-3 && h0.f_d == 0.0);
        let h9 = decode(out[9]);
        mcg_test_support::assert_close!(h9.f_s, 0.303_27, 1e-3, "{h9:?}");
        mcg_test_support::assert_close!(h9.f_d, 0.101_09, 1e-3, "{h9:?}");
        assert_eq!(h9.flags, 5);
        assert!(compose_grid(&grid, &p, Vec3::ZERO, &f_v[1..], &dv, &dr, &mut out).is_err());
    }

    #[test]
    fn value_stability() {
        let p = HeuristicParams::new(2.0, 0.866_025_4).unwrap();
        let probe = Vec3::new(1.0, 2.0, 3.0);
        let f_c = p.camera_distance(probe, Vec3::new(0.0, 0.0, 0.5));
        let f_v = p.probe_visibility(0.3);
        // f_c = e^{−(√11.25 − 2)} = 0.25818, f_v = e^{−0.6/0.866} = 0.50016,
        // f_s = 0.12913, f_d = 0.12913 · (0.2 + 2 · 0.6)/3 = 0.060261.
        let h = p.compose(f_c, f_v, 0.2, 0.6, 1);
        assert_eq!(encode(h).0, 0x043e_2120, "{:#x} from {h:?}", encode(h).0);
    }
}
