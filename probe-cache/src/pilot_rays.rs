//! ADGI's pilot rays (sec. 4.1, 4.4): one stratified ray per probe octant, with directions that
//! change every other frame in an `AABBCCDD…` pattern, from the probes of the outer clip volume.
//!
//! Sec. 4.4: "We change the ray-directions at alternate frames in an AABBCCDD... pattern,
//! improving the detection of temporally varying light-field surrounding the probes. We measure
//! the time-delta (equation 13 and 16) between two frames with identical set of ray-queries,
//! avoiding noisy gradients. \[...\] We use a stratified-random ray-direction such that there is
//! always one ray per octant. We update the irradiance and visibility cache at each alternate
//! frame."
//!
//! So frame `2k` (phase [`PilotPhase::Reference`]) traces direction set `k` and its results
//! also update the caches; frame `2k + 1` ([`PilotPhase::Detect`]) traces the same set again and
//! its results are compared with frame `2k`'s (the [`ChangeDetector`](crate::temporal_gradient::ChangeDetector)).
//! The same set twice must use the same uniforms: the caller's uniform source is keyed by
//! (pattern, probe, octant) — e.g. a hash of them with a seed — not by frame.
//!
//! **Blind spot.** A change that happens exactly between two pairs (after frame `2k + 1`, before
//! frame `2k + 2`) never shows in a gradient — each gradient compares two frames of one pair —
//! so a light that switches on at that instant is not detected (sec. 4.4 accepts "halving the
//! detection frequency"; gradual changes are always seen). [`PilotSchedule::new`] with a longer
//! hold (`AAAABBBB…`) detects at every frame but the first of each set, so only one transition
//! in `hold` is blind; [`PilotSchedule::ADGI`] (hold 2) is the paper's pattern.
//!
//! A pilot ray along ω measures two heuristics (eq. 11, 12): f_r of octant(ω) (the luminance
//! arriving along ω) and f_v of octant(−ω) = `octant(ω) ^ 7` (eq. 11 traces t = trace(p, −ω)).

use glam::{Vec2, Vec3};

use crate::heuristics::{HeuristicParams, OCTANTS, octant_signs};
use crate::{ControlError, ProbeGrid};

/// The two frames of a pilot direction set (sec. 4.4).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum PilotPhase {
    /// First frame of a pair: new directions; the results update the caches and become the
    /// reference of the temporal gradient.
    Reference,
    /// Second frame of a pair: the same directions; the results are compared with the
    /// reference (eq. 13, 16).
    Detect,
}

/// How long each pilot direction set is held: ADGI's `AABBCC…` (hold 2, sec. 4.4) or longer.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct PilotSchedule {
    hold: u32,
}

impl PilotSchedule {
    /// ADGI's pattern: each direction set on two consecutive frames (`AABBCC…`).
    pub const ADGI: Self = Self { hold: 2 };

    /// Each direction set held for `hold` consecutive frames; the first frame of each set is
    /// the reference, the others detect changes against the frame before.
    ///
    /// # Errors
    /// [`ControlError::PilotHoldTooShort`] for `hold < 2` (a gradient needs two frames with the
    /// same rays).
    pub const fn new(hold: u32) -> Result<Self, ControlError> {
        if hold < 2 {
            return Err(ControlError::PilotHoldTooShort { hold });
        }
        Ok(Self { hold })
    }

    /// Frames per direction set.
    #[inline]
    #[must_use]
    pub const fn hold(&self) -> u32 {
        self.hold
    }

    /// The pilot frame of frame number `frame`.
    #[inline]
    #[must_use]
    pub const fn frame(&self, frame: u64) -> PilotFrame {
        let hold = self.hold as u64;
        PilotFrame {
            pattern: frame / hold,
            phase: if frame.is_multiple_of(hold) {
                PilotPhase::Reference
            } else {
                PilotPhase::Detect
            },
        }
    }
}

impl Default for PilotSchedule {
    /// [`PilotSchedule::ADGI`].
    fn default() -> Self {
        Self::ADGI
    }
}

/// Which direction set a frame traces and what its results are for (sec. 4.4's `AABBCC…`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct PilotFrame {
    /// Index of the direction set, `frame / hold` (A = 0, B = 1, …); key the uniforms by it.
    pub pattern: u64,
    /// First or second frame of the pair.
    pub phase: PilotPhase,
}

impl PilotFrame {
    /// The pilot frame of frame number `frame` in ADGI's pattern ([`PilotSchedule::ADGI`]).
    ///
    /// # Example
    /// ```
    /// use mcg_probe_cache::pilot_rays::{PilotFrame, PilotPhase};
    /// let f: Vec<_> = (0..4).map(PilotFrame::of).map(|f| (f.pattern, f.phase)).collect();
    /// assert_eq!(f, [(0, PilotPhase::Reference), (0, PilotPhase::Detect),
    ///                (1, PilotPhase::Reference), (1, PilotPhase::Detect)]);
    /// ```
    #[inline]
    #[must_use]
    pub const fn of(frame: u64) -> Self {
        PilotSchedule::ADGI.frame(frame)
    }

    /// Whether this frame's pilot results update the irradiance and visibility caches (the
    /// first frame of each set; later frames would add the same directions again).
    #[inline]
    #[must_use]
    pub const fn updates_caches(&self) -> bool {
        matches!(self.phase, PilotPhase::Reference)
    }

    /// Whether this frame measures the temporal gradient against the frame before (same rays).
    #[inline]
    #[must_use]
    pub const fn measures_gradient(&self) -> bool {
        matches!(self.phase, PilotPhase::Detect)
    }
}

/// A direction uniform within octant `octant` (only its three low bits are read) from two
/// uniforms: `z = u.x`, `φ = u.y · π/2` in the (+, +, +) octant, then the octant's signs.
/// Equal-area (dω = dz dφ), so uniform `u` gives a uniform direction in the octant — the
/// stratification of sec. 4.4 ("always one ray per octant"). Inputs are clamped to
/// [2⁻²⁴, 1 − 2⁻²⁴] (NaN → 0.5), so no component is zero and the octant is exact.
///
/// # Example
/// ```
/// use mcg_probe_cache::{heuristics::octant, pilot_rays::pilot_direction, glam::Vec2};
/// let d = pilot_direction(5, Vec2::new(0.3, 0.6));
/// assert_eq!(octant(d), 5);
/// assert!((d.length() - 1.0).abs() < 1e-6);
/// ```
#[inline]
#[must_use]
pub fn pilot_direction(octant: usize, u: Vec2) -> Vec3 {
    // Open interval, so no component is ±0 and `octant` of the result is exact.
    const LO: f32 = 1.0 / 16_777_216.0; // 2⁻²⁴
    const HI: f32 = 1.0 - LO;
    let open = |x: f32| if x.is_nan() { 0.5 } else { x.clamp(LO, HI) };
    let z = open(u.x);
    let phi = open(u.y) * core::f32::consts::FRAC_PI_2;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let (s, c) = phi.sin_cos();
    Vec3::new(r * c, r * s, z) * octant_signs(octant)
}

/// One pilot ray: from probe `probe` (linear index) at `origin` along `direction`, which lies in
/// octant `octant`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PilotRay {
    /// Linear probe index.
    pub probe: u32,
    /// The octant of `direction`.
    pub octant: u8,
    /// The probe's position.
    pub origin: Vec3,
    /// Unit direction.
    pub direction: Vec3,
}

/// The 8 pilot rays of every probe for which `include(probe)` holds (e.g. the probes of the
/// outer clip volume, [`ClipVolumes::traces_pilots`](crate::clip_volume::ClipVolumes::traces_pilots)),
/// for frame `frame`: directions from `uniforms(pattern, probe, octant)`, which must return the
/// same value for the same arguments so both frames of a pair trace the same rays.
pub fn pilot_rays(
    grid: &ProbeGrid,
    frame: PilotFrame,
    mut include: impl FnMut(usize) -> bool,
    mut uniforms: impl FnMut(u64, usize, usize) -> Vec2,
    mut emit: impl FnMut(PilotRay),
) {
    for probe in 0..grid.probe_count() {
        if !include(probe) {
            continue;
        }
        let origin = grid.probe_position(grid.probe_coords(probe));
        for o in 0..OCTANTS {
            emit(PilotRay {
                probe: probe as u32,
                octant: o as u8,
                origin,
                direction: pilot_direction(o, uniforms(frame.pattern, probe, o)),
            });
        }
    }
}

/// What a pilot ray found: the hit distance (+∞ for a miss) and the luminance of the direct
/// light at the hit point arriving along the ray (0 for a miss unless the sky is lit).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PilotHit {
    /// Distance to the nearest surface along the ray, +∞ for a miss.
    pub distance: f32,
    /// Luminance arriving at the probe along the ray.
    pub luminance: f32,
}

/// The heuristics f_v and f_r of a probe's 8 octants from its 8 pilot hits, `hits[o]` being the
/// ray traced in octant `o`: `f_r[o] = f_r(hits[o].luminance)` (eq. 12) and
/// `f_v[o] = f_v(hits[o ^ 7].distance)` (eq. 11: f_v of ω uses the hit along −ω).
#[inline]
#[must_use]
pub fn octant_heuristics(
    hits: &[PilotHit; OCTANTS],
    params: &HeuristicParams,
) -> ([f32; OCTANTS], [f32; OCTANTS]) {
    let f_v = core::array::from_fn(|o| params.probe_visibility(hits[o ^ 7].distance));
    let f_r = core::array::from_fn(|o| params.incoming_radiance(hits[o].luminance));
    (f_v, f_r)
}

#[cfg(test)]
mod tests {
    use glam::UVec3;

    use super::*;
    use crate::heuristics::octant;

    #[test]
    fn schedule_alternates_in_pairs() {
        for frame in 0..10u64 {
            let f = PilotFrame::of(frame);
            assert_eq!(f.pattern, frame / 2);
            assert_eq!(f.updates_caches(), frame % 2 == 0);
            assert_eq!(f.measures_gradient(), frame % 2 == 1);
        }
    }

    #[test]
    fn longer_holds() {
        let s = PilotSchedule::new(4).unwrap();
        let phases: Vec<bool> = (0..8).map(|f| s.frame(f).measures_gradient()).collect();
        assert_eq!(phases, [false, true, true, true, false, true, true, true]);
        assert_eq!(s.frame(7).pattern, 1);
        assert_eq!(s.hold(), 4);
        assert_eq!(
            PilotSchedule::new(1),
            Err(ControlError::PilotHoldTooShort { hold: 1 })
        );
        assert_eq!(PilotSchedule::default(), PilotSchedule::ADGI);
    }

    #[test]
    fn directions_stay_in_their_octant() {
        for o in 0..8 {
            for &(a, b) in &[
                (0.0, 0.0),
                (1.0, 1.0),
                (0.5, 0.5),
                (0.999, 0.001),
                (f32::NAN, 2.0),
            ] {
                let d = pilot_direction(o, Vec2::new(a, b));
                assert_eq!(octant(d), o, "{o} {a} {b} {d}");
                mcg_test_support::assert_close!(d.length(), 1.0, 1e-6);
            }
        }
        // u = (0.5, 0.5) in octant 0: z = 0.5, φ = π/4: (√0.75/√2, √0.75/√2, 0.5).
        let d = pilot_direction(0, Vec2::splat(0.5));
        let c = (0.75f32).sqrt() / 2.0f32.sqrt();
        assert!((d - Vec3::new(c, c, 0.5)).length() < 1e-6);
    }

    #[test]
    fn rays_repeat_within_a_pair() {
        let grid = ProbeGrid::new(Vec3::ZERO, Vec3::ONE, UVec3::new(2, 2, 1)).unwrap();
        let key = |pattern: u64, probe: usize, o: usize| {
            let h = (pattern * 131 + probe as u64 * 17 + o as u64 * 7) as f32;
            Vec2::new((h * 0.618_034).fract(), (h * 0.754_878).fract())
        };
        let collect = |frame| {
            let mut v = vec![];
            pilot_rays(&grid, PilotFrame::of(frame), |p| p != 2, key, |r| v.push(r));
            v
        };
        let (a0, a1, b0) = (collect(4), collect(5), collect(6));
        assert_eq!(a0, a1);
        assert_ne!(a0, b0);
        assert_eq!(a0.len(), 3 * 8);
        for r in &a0 {
            assert_eq!(octant(r.direction), r.octant as usize);
            assert_eq!(
                r.origin,
                grid.probe_position(grid.probe_coords(r.probe as usize))
            );
            assert_ne!(r.probe, 2);
        }
    }

    #[test]
    fn octant_heuristics_by_hand() {
        let p = HeuristicParams::new(1.0, 2.0).unwrap();
        let mut hits = [PilotHit {
            distance: f32::INFINITY,
            luminance: 0.0,
        }; 8];
        // The ray in octant 3 (−x, −y, +z) hits at t = 1 with luminance 2.5.
        hits[3] = PilotHit {
            distance: 1.0,
            luminance: 2.5,
        };
        let (f_v, f_r) = octant_heuristics(&hits, &p);
        // f_r[3] = 2.5/5 = 0.5; f_v[3 ^ 7 = 4] = e^{−2·1/2} = e^{−1}; all else 0.
        for o in 0..8 {
            assert_eq!(f_r[o], if o == 3 { 0.5 } else { 0.0 });
            let want = if o == 4 { (-1.0f32).exp() } else { 0.0 };
            mcg_test_support::assert_close!(f_v[o], want, 1e-7);
        }
    }

    #[test]
    fn value_stability() {
        let d = pilot_direction(6, Vec2::new(0.25, 0.8));
        // z = −0.25, φ = 0.8 · π/2 = 1.2566, r = √(1 − 1/16) = 0.968246:
        // (−0.968246 · cos 1.2566, −0.968246 · sin 1.2566, −0.25) = (0.29920, −0.92086, −0.25)
        // with octant 6's signs (+x, −y, −z).
        assert_eq!(
            d.to_array().map(f32::to_bits),
            [1050227026, 3211509057, 3196059648],
            "{d}"
        );
    }
}
