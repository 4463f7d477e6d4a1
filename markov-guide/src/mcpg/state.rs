//! The 32-byte world-space chain state of MCPG (Table 1).

use bytemuck::{Pod, Zeroable};
use half::f16;
use mcg_vmf::glam::Vec3;
use mcg_vmf::{MapPrior, SufficientStats, Vmf};

/// MCPG's Markov chain state at a hash-grid vertex (Alber et al. 2025, Table 1):
/// w̄, N, ȳ, r̄, T and v in 32 bytes. The collision-detecting key ("hash" in Table 1) lives in the
/// hash table's checksum array beside the states, not here.
///
/// # Packing
/// | bytes | field | type | precision |
/// |---|---|---|---|
/// | 0..12 | ȳ, `mean_target` | 3 × f32 | full |
/// | 12..16 | w̄, `weight_sum` | f32 | full |
/// | 16..20 | 1 − r̄, `one_minus_mean_cosine` | f32 | full (complement form, see [`SufficientStats`]) |
/// | 20..24 | T, `time` | f32 | exact for frame numbers below 2²⁴, or seconds to ~10⁻⁷ relative |
/// | 24..30 | v, velocity | 3 × f16 | 11 significant bits (relative error ≤ 2⁻¹¹ ≈ 4.9·10⁻⁴), |v| components ≤ 65504 |
/// | 30..32 | N, sample count | u16 | exact (N_max ≤ 65535; the paper uses 1024) |
///
/// The paper's state takes 44 bytes (ȳ, v as f32 vectors, a u32 N and the 32-bit hash inside);
/// the only precision we give up is the velocity's, which eq. 10 multiplies by one frame's time
/// step, so its error moves ȳ by less than 5·10⁻⁴ of the distance a light travels per frame.
/// All zeros is the empty state.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GridState {
    /// ȳ, the luminance-weighted mean light source position.
    pub mean_target: Vec3,
    /// w̄, the luminance estimate of eq. 1, the resampling weight. 0 means empty.
    pub weight_sum: f32,
    /// 1 − r̄, the complement of the weighted mean cosine.
    pub one_minus_mean_cosine: f32,
    /// T, the time of the last update (frame number or seconds; the renderer's choice).
    pub time: f32,
    velocity: [u16; 3],
    sample_count: u16,
}

const _: () = assert!(core::mem::size_of::<GridState>() == 32);

impl GridState {
    /// The empty state ({0} in MCPG Alg. 1 line 2, Alg. 2 line 4).
    pub const EMPTY: Self = Self {
        mean_target: Vec3::ZERO,
        weight_sum: 0.0,
        one_minus_mean_cosine: 0.0,
        time: 0.0,
        velocity: [0; 3],
        sample_count: 0,
    };

    /// A state from fit statistics, an update time and a velocity ([`GridState::set_velocity`]
    /// rules apply). N is clamped to 65535; a NaN or infinite `time` stores 0.
    #[inline]
    #[must_use]
    pub fn from_stats(stats: &SufficientStats, time: f32, velocity: Vec3) -> Self {
        let mut s = Self {
            mean_target: stats.mean_target,
            weight_sum: stats.weight_sum,
            one_minus_mean_cosine: stats.one_minus_mean_cosine,
            time: mcg_smis::finite_or_zero(time),
            velocity: [0; 3],
            sample_count: stats.sample_count.min(u16::MAX as u32) as u16,
        };
        s.set_velocity(velocity);
        s
    }

    /// The fit statistics (ȳ, w̄, r̄, N) of this state.
    #[inline]
    #[must_use]
    pub fn stats(&self) -> SufficientStats {
        SufficientStats {
            mean_target: self.mean_target,
            weight_sum: self.weight_sum,
            one_minus_mean_cosine: self.one_minus_mean_cosine,
            sample_count: self.sample_count as u32,
        }
    }

    /// N, the number of samples absorbed.
    #[inline]
    #[must_use]
    pub const fn sample_count(&self) -> u32 {
        self.sample_count as u32
    }

    /// v, the last known velocity of the light source (eq. 9), decoded from f16.
    #[inline]
    #[must_use]
    pub fn velocity(&self) -> Vec3 {
        Vec3::from_array(self.velocity.map(|b| f16::from_bits(b).to_f32()))
    }

    /// Stores v rounded to f16. Components beyond ±65504 saturate; NaN and a non-finite
    /// velocity store 0 (a broken velocity estimate must not move ȳ).
    #[inline]
    pub fn set_velocity(&mut self, velocity: Vec3) {
        // +0 in every component (every static scene) is the bits 0: skip the f16 encoding,
        // which baseline x86-64 does in software (~50 instructions for three components).
        if velocity.to_array().map(f32::to_bits) == [0; 3] {
            self.velocity = [0; 3];
            return;
        }
        let v = if crate::math::all_finite(velocity) {
            velocity
        } else {
            Vec3::ZERO
        };
        self.velocity = v
            .to_array()
            .map(|c| f16::from_f32(c.clamp(-65504.0, 65504.0)).to_bits());
    }

    /// `true` when the state carries weight (w̄ > 0 and finite) and a finite target.
    #[inline]
    #[must_use]
    pub fn is_valid(&self) -> bool {
        // Compares joined by `&`: no branches, and no `is_finite` class tests.
        (self.weight_sum > 0.0)
            & (self.weight_sum < f32::INFINITY)
            & crate::math::all_finite(self.mean_target)
    }

    /// The resampling weight w̄ (MCPG Alg. 1 line 8), 0 for an invalid state.
    #[inline]
    #[must_use]
    pub fn resampling_weight(&self) -> f32 {
        if self.is_valid() {
            self.weight_sum
        } else {
            0.0
        }
    }

    /// Velocity prediction on load (MCPG eq. 10): ȳ ← ȳ + (t_now − T)·v, written for the
    /// normalised ȳ we store (the paper's w̄·ȳ form divided by w̄). Invalid states and
    /// non-finite results are returned unchanged.
    #[inline]
    #[must_use]
    pub fn predicted(&self, now: f32) -> Self {
        let mut s = *self;
        if s.is_valid() {
            s.predict_valid(now);
        }
        s
    }

    /// [`predicted`](Self::predicted) in place, for a state known to be valid.
    #[inline]
    pub(crate) fn predict_valid(&mut self, now: f32) {
        // v = 0 (every static scene) moves nothing: skip the f16 decoding.
        if self.velocity == [0; 3] {
            return;
        }
        let moved = self.mean_target + (now - self.time) * self.velocity();
        if crate::math::all_finite(moved) {
            self.mean_target = moved;
        }
    }

    /// The lobe at shading point `x` (MCPG Alg. 2 lines 6-8) with prior `prior`, `None` for an
    /// invalid state or when ȳ coincides with `x`.
    #[inline]
    #[must_use]
    pub fn lobe(&self, x: Vec3, prior: MapPrior) -> Option<Vmf> {
        if !self.is_valid() {
            return None;
        }
        self.stats().to_vmf(x, prior)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn zeroed_is_empty() {
        let z: GridState = Zeroable::zeroed();
        assert_eq!(z, GridState::EMPTY);
        assert!(!z.is_valid());
        assert_eq!(z.velocity(), Vec3::ZERO);
    }

    #[test]
    fn field_offsets_match_the_documented_packing() {
        let mut s = GridState::EMPTY;
        s.mean_target = Vec3::new(1.0, 2.0, 3.0);
        s.weight_sum = 4.0;
        s.one_minus_mean_cosine = 5.0;
        s.time = 6.0;
        s.set_velocity(Vec3::new(1.0, -2.0, 0.5));
        s.sample_count = 7;
        let words: &[u32; 8] = bytemuck::cast_ref(&s);
        for (i, want) in [1.0f32, 2.0, 3.0, 4.0, 5.0, 6.0].iter().enumerate() {
            assert_eq!(words[i], want.to_bits());
        }
        // Little-endian u16 pairs: (vx, vy), (vz, N).
        assert_eq!(words[6], 0x3c00 | (0xc000 << 16));
        assert_eq!(words[7], 0x3800 | (7 << 16));
    }

    #[test]
    fn velocity_round_trips_within_f16_precision_and_saturates() {
        let mut s = GridState::EMPTY;
        for v in [Vec3::new(0.1, -3.7, 1234.5), Vec3::splat(1e-3)] {
            s.set_velocity(v);
            let back = s.velocity();
            assert!(
                ((back - v).abs().cmple(v.abs() * 4.9e-4 + 1e-7)).all(),
                "{v} -> {back}"
            );
        }
        s.set_velocity(Vec3::new(1e9, -1e9, 0.0));
        assert_eq!(s.velocity(), Vec3::new(65504.0, -65504.0, 0.0));
        s.set_velocity(Vec3::new(f32::NAN, 1.0, 1.0));
        assert_eq!(s.velocity(), Vec3::ZERO);
    }

    #[test]
    fn prediction_moves_the_target_by_velocity_times_age() {
        let mut stats = SufficientStats::EMPTY;
        stats.update(
            Vec3::ZERO,
            Vec3::new(0.0, 0.0, 2.0),
            1.0,
            &mcg_vmf::FitParams::MCPG,
        );
        let s = GridState::from_stats(&stats, 10.0, Vec3::new(0.5, 0.0, 0.0));
        assert_eq!(s.predicted(12.0).mean_target, Vec3::new(1.0, 0.0, 2.0));
        assert_eq!(s.predicted(10.0), s);
        assert_eq!(GridState::EMPTY.predicted(5.0), GridState::EMPTY);
        assert_eq!(s.predicted(f32::INFINITY).mean_target, s.mean_target);
        assert_eq!(s.stats(), stats);
    }
}
