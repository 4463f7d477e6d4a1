//! The moving average of ADGI sec. 4.7 on count-carrying words, and its lock-free atomic form.

use core::ops::{Add, Mul, Sub};
#[cfg(target_has_atomic = "32")]
use core::sync::atomic::{AtomicU32, Ordering};

use glam::{Vec2, Vec3};

use crate::error::CodecError;
use crate::irradiance_word::{IrradianceLayout, IrradianceWord};
use crate::quantize::Rounding;
use crate::visibility_word::{VisibilityLayout, VisibilityWord};

/// A packed layout whose words carry a value and a sample count N, so that
/// [`MovingAverage`] can update them. Implemented by [`IrradianceLayout`] (RGB, [`Vec3`]) and
/// [`VisibilityLayout`] (moments (d̄, d̄²), [`Vec2`]).
pub trait CountedLayout {
    /// What a word holds besides its count.
    type Value: Copy
        + Add<Output = Self::Value>
        + Sub<Output = Self::Value>
        + Mul<f32, Output = Self::Value>;

    /// The value of a raw word.
    fn decode_value(&self, word: u32) -> Self::Value;
    /// A raw word holding `value` and `count` (saturated).
    fn encode_value(&self, value: Self::Value, count: u32, rounding: Rounding) -> u32;
    /// The count N of a raw word.
    fn count_of(&self, word: u32) -> u32;
    /// The largest count the layout stores.
    fn count_capacity(&self) -> u32;
    /// The sample with negative components set to 0, or `None` if any component is NaN.
    fn sanitize(value: Self::Value) -> Option<Self::Value>;
}

impl CountedLayout for IrradianceLayout {
    type Value = Vec3;

    #[inline(always)]
    fn decode_value(&self, word: u32) -> Vec3 {
        self.decode(IrradianceWord(word))
    }
    #[inline(always)]
    fn encode_value(&self, value: Vec3, count: u32, rounding: Rounding) -> u32 {
        self.encode(value, count, rounding).0
    }
    #[inline(always)]
    fn count_of(&self, word: u32) -> u32 {
        self.count(IrradianceWord(word))
    }
    #[inline(always)]
    fn count_capacity(&self) -> u32 {
        self.max_count()
    }
    #[inline(always)]
    fn sanitize(value: Vec3) -> Option<Vec3> {
        (!value.is_nan()).then(|| value.max(Vec3::ZERO))
    }
}

impl CountedLayout for VisibilityLayout {
    type Value = Vec2;

    #[inline(always)]
    fn decode_value(&self, word: u32) -> Vec2 {
        self.decode(VisibilityWord(word))
    }
    #[inline(always)]
    fn encode_value(&self, value: Vec2, count: u32, rounding: Rounding) -> u32 {
        self.encode(value, count, rounding).0
    }
    #[inline(always)]
    fn count_of(&self, word: u32) -> u32 {
        self.count(VisibilityWord(word))
    }
    #[inline(always)]
    fn count_capacity(&self) -> u32 {
        self.max_count()
    }
    #[inline(always)]
    fn sanitize(value: Vec2) -> Option<Vec2> {
        (!value.is_nan()).then(|| value.max(Vec2::ZERO))
    }
}

/// The temporal accumulation of ADGI sec. 4.7 (Algorithm 3): a true average while the count
/// grows, then an exponential moving average with hysteresis (N_max − 1)/N_max.
///
/// For a word holding value v̄ and count N, a sample x gives
///
/// ```text
/// N' = min(N + 1, N_max)        v̄' = v̄ + (x − v̄) / N'        (v̄' = x when N = 0)
/// ```
///
/// then v̄' is re-encoded with the caller's [`Rounding`]. N_max is capped by the layout's count
/// field (63 for ADGI's 6 bits); a stored count above N_max is brought down to it by the next update.
///
/// # Rounding and the stall
/// With [`Rounding::Down`] (ADGI's choice) a dark sample always moves the code down, so
/// a texel decays to exactly zero; but an update smaller than one quantum is lost when the value
/// rises, so a texel at N = N_max settles where `(x − v̄)/N_max` < quantum: for the log codec with
/// an M-code channel, at the latest where `x/v̄ ≈ 1 + N_max(e^{β/M} − 1)(1 + 1/(γv̄))` — 1.62× for
/// ADGI's 9-bit channels and 2.25× for the 8-bit blue at N_max = 63 (large v̄; more when dark).
/// [`Rounding::Stochastic`] with a fresh uniform per update removes the stall (the expected code
/// follows the exact average) and still decays to zero; [`Rounding::Nearest`] stalls both ways
/// and never reaches zero.
///
/// # Bad input
/// A sample with a NaN component is ignored: the word is returned unchanged and the count does
/// not advance (a NaN is a failed ray, not a black one). Negative components count as 0.
/// An infinite component saturates that channel at the codec's maximum (and counts).
///
/// # Example
/// ```
/// use core::sync::atomic::AtomicU32;
/// use mcg_color_codec::{IrradianceLayout, MovingAverage, Rounding, glam::Vec3};
/// let layout = IrradianceLayout::ADGI;
/// let texel = AtomicU32::new(0);
/// for _ in 0..4 {
///     MovingAverage::STATIC.update_atomic(&layout, &texel, Vec3::splat(0.5), Rounding::Down);
/// }
/// let word = texel.into_inner().into();
/// assert_eq!(layout.count(word), 4);
/// assert!((layout.decode(word) - Vec3::splat(0.5)).abs().max_element() < 0.01);
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MovingAverage {
    max_count: u32,
}

impl MovingAverage {
    /// ADGI's static setting, N_max = 63 (hysteresis 62/63 ≈ 0.98; Table 3).
    pub const STATIC: MovingAverage = MovingAverage { max_count: 63 };

    /// ADGI's dynamic setting, N_max = 10 (hysteresis 0.9; Table 3 lists 0.91).
    pub const DYNAMIC: MovingAverage = MovingAverage { max_count: 10 };

    /// A moving average with the given N_max ≥ 1.
    ///
    /// # Errors
    /// [`CodecError::MaxCountZero`] if `max_count` is 0.
    pub const fn new(max_count: u32) -> Result<Self, CodecError> {
        if max_count == 0 {
            return Err(CodecError::MaxCountZero);
        }
        Ok(Self { max_count })
    }

    /// N_max.
    #[inline]
    #[must_use]
    pub const fn max_count(&self) -> u32 {
        self.max_count
    }

    /// The hysteresis (N_max − 1)/N_max of the exponential phase.
    #[inline]
    #[must_use]
    pub fn hysteresis(&self) -> f32 {
        (self.max_count - 1) as f32 / self.max_count as f32
    }

    /// Applies one sample to a raw word and returns the new word (pure `word → word`).
    #[inline]
    #[must_use]
    pub fn update<L: CountedLayout>(
        &self,
        layout: &L,
        word: u32,
        sample: L::Value,
        rounding: Rounding,
    ) -> u32 {
        let Some(x) = L::sanitize(sample) else {
            return word;
        };
        let cap = self.max_count.min(layout.count_capacity());
        let n = layout.count_of(word);
        let next = (n + 1).min(cap);
        let value = if n == 0 {
            x
        } else {
            let old = layout.decode_value(word);
            old + (x - old) * (1.0 / next as f32)
        };
        layout.encode_value(value, next, rounding)
    }

    /// [`update`](Self::update) on an atomic word, in a compare-and-swap loop
    /// (`compare_exchange_weak`, retried on spurious failure) that never loses an update: each
    /// call is applied to the value current at its successful swap, as if the calls ran one after
    /// another. Returns the word this call wrote (or found unchanged, for a no-op update).
    ///
    /// Memory order: `AcqRel` on success, `Relaxed` loads; the word is self-contained, so no
    /// other memory is ordered by it.
    #[cfg(target_has_atomic = "32")]
    #[inline]
    pub fn update_atomic<L: CountedLayout>(
        &self,
        layout: &L,
        word: &AtomicU32,
        sample: L::Value,
        rounding: Rounding,
    ) -> u32 {
        self.update_atomic_swap(layout, word, sample, rounding).1
    }

    /// [`update_atomic`](Self::update_atomic) returning `(before, after)`: the word this call's
    /// update was applied to and the word it wrote (equal for a no-op update). The pairs of all
    /// calls on one word chain into the serial order the swaps took effect in — a caller can
    /// check a concurrent run against it, or compute the change an update made (a temporal
    /// gradient) without a second read.
    #[cfg(target_has_atomic = "32")]
    #[inline]
    pub fn update_atomic_swap<L: CountedLayout>(
        &self,
        layout: &L,
        word: &AtomicU32,
        sample: L::Value,
        rounding: Rounding,
    ) -> (u32, u32) {
        let mut current = word.load(Ordering::Relaxed);
        loop {
            let new = self.update(layout, current, sample, rounding);
            if new == current {
                return (current, new);
            }
            match word.compare_exchange_weak(current, new, Ordering::AcqRel, Ordering::Relaxed) {
                Ok(_) => return (current, new),
                Err(actual) => current = actual,
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const L: IrradianceLayout = IrradianceLayout::ADGI;

    #[test]
    fn true_average_then_exponential() {
        let avg = MovingAverage::new(4).unwrap();
        let mut w = 0;
        let samples = [1.0, 2.0, 3.0, 4.0, 9.0];
        for (i, &s) in samples.iter().enumerate() {
            w = avg.update(
                &VisibilityLayout::ADGI,
                w,
                Vec2::new(s, s),
                Rounding::Nearest,
            );
            let m = VisibilityLayout::ADGI.decode(VisibilityWord(w)).x;
            let want = match i {
                0 => 1.0,
                1 => 1.5,
                2 => 2.0,
                3 => 2.5,
                _ => 2.5 + (9.0 - 2.5) / 4.0,
            };
            mcg_test_support::assert_close!(m, want, 2e-3 * want, "{i}: {m} vs {want}");
            assert_eq!(
                VisibilityLayout::ADGI.count(VisibilityWord(w)),
                (i as u32 + 1).min(4)
            );
        }
        mcg_test_support::assert_close!(MovingAverage::STATIC.hysteresis(), 62.0 / 63.0, 1e-7);
        assert_eq!(MovingAverage::new(0), Err(CodecError::MaxCountZero));
    }

    #[test]
    fn bad_samples() {
        let avg = MovingAverage::STATIC;
        let w = avg.update(&L, 0, Vec3::splat(0.5), Rounding::Down);
        assert_eq!(
            avg.update(&L, w, Vec3::new(f32::NAN, 1.0, 1.0), Rounding::Down),
            w
        );
        let neg = avg.update(&L, w, Vec3::splat(-5.0), Rounding::Down);
        assert_eq!(L.count(neg.into()), 2);
        let expect = avg.update(&L, w, Vec3::ZERO, Rounding::Down);
        assert_eq!(neg, expect);
        let inf = avg.update(&L, w, Vec3::new(f32::INFINITY, 0.5, 0.5), Rounding::Down);
        assert_eq!(L.codes(inf.into())[0], 511);
        assert!(L.decode(inf.into()).is_finite());
        // A count above N_max (set by the caller) is brought down to it.
        let big = L.with_count(w.into(), 63).0;
        let after = MovingAverage::DYNAMIC.update(&L, big, Vec3::splat(0.5), Rounding::Down);
        assert_eq!(L.count(after.into()), 10);
    }

    #[test]
    fn round_down_decays_to_zero() {
        let avg = MovingAverage::STATIC;
        let mut w = L.encode(Vec3::splat(9.0), 63, Rounding::Down).0;
        let mut steps = 0;
        while L.codes(w.into()) != [0, 0, 0] {
            w = avg.update(&L, w, Vec3::ZERO, Rounding::Down);
            steps += 1;
            assert!(steps < 10_000);
        }
        assert_eq!(L.decode(w.into()), Vec3::ZERO);
    }

    #[test]
    fn atomic_single_thread_matches_pure() {
        let a = AtomicU32::new(0);
        let mut w = 0;
        for i in 0..100 {
            let s = Vec3::new(i as f32 * 0.01, 0.3, 1.0);
            let r = Rounding::Stochastic((i as f32 * 0.377) % 1.0);
            w = MovingAverage::STATIC.update(&L, w, s, r);
            assert_eq!(MovingAverage::STATIC.update_atomic(&L, &a, s, r), w);
        }
        assert_eq!(a.into_inner(), w);
    }

    #[test]
    fn atomic_swap_reports_before_and_after() {
        let a = AtomicU32::new(0);
        let mut w = 0;
        for i in 0..20 {
            let s = Vec3::new(0.1 * i as f32, 0.2, 0.3);
            let (before, after) =
                MovingAverage::DYNAMIC.update_atomic_swap(&L, &a, s, Rounding::Down);
            assert_eq!(before, w);
            w = MovingAverage::DYNAMIC.update(&L, w, s, Rounding::Down);
            assert_eq!(after, w);
        }
        // A no-op (NaN) update reports the unchanged word twice.
        let nan = Vec3::new(f32::NAN, 0.0, 0.0);
        assert_eq!(
            MovingAverage::DYNAMIC.update_atomic_swap(&L, &a, nan, Rounding::Down),
            (w, w)
        );
    }
}
