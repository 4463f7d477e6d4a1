//! Quantisation of a value in code units to a k-bit integer with a rounding mode
//! (ADGI appendix B: round-down, the paper's choice, and round-to-nearest; plus stochastic
//! rounding, which removes the round-down stall of the moving average).

/// How a value between two codes is rounded.
///
/// ADGI (appendix B) rounds **down** so that a moving average of dark samples reaches exactly
/// zero; round-to-**nearest** is more accurate per encode but "the colors may never go to zero".
/// Round-down makes a 1/N moving average stall below a rising target, because an update smaller
/// than one quantum is lost ([`crate::MovingAverage`] docs); **stochastic** rounding keeps both:
/// it rounds up with probability equal to the fractional part, so the expected code equals the
/// unrounded one and decay still ends at zero.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Rounding {
    /// Round toward zero in code space: the largest code whose decoded value is ≤ the input.
    Down,
    /// Round to the nearest code in code space (ties up).
    Nearest,
    /// Round up with probability equal to the fractional part, using the caller's uniform
    /// `u ∈ [0, 1)`: the code is ⌊x⌋ + 1 when `u < x − ⌊x⌋`, else ⌊x⌋. A `u` at or above 1 never
    /// rounds up; a negative or NaN `u` counts as 0 (rounds any fraction up). Exact codes never
    /// move.
    Stochastic(f32),
}

/// The step of the golden-ratio Weyl sequence that rotates a stochastic rounding's uniform
/// per channel: (√5 − 1)/2 ≈ 0.618034.
pub(crate) const CHANNEL_STEP: f32 = 0.618_034;

impl Rounding {
    /// The same mode with the uniform of [`Rounding::Stochastic`] rotated by `k` steps of the
    /// golden-ratio Weyl sequence, `u + k·0.618… mod 1`, so the channels of one word round with
    /// different (each still uniform) offsets from one caller uniform.
    #[inline(always)]
    #[must_use]
    pub(crate) fn for_channel(self, k: u32) -> Rounding {
        match self {
            // Channel 0 keeps the caller's uniform as is (so a `u` ≥ 1 never rounds up there).
            Rounding::Stochastic(u) if k > 0 => {
                let v = u + k as f32 * CHANNEL_STEP;
                // v < 3 here; subtracting the truncated part keeps it in [0, 1).
                Rounding::Stochastic(v - (v as u32) as f32)
            }
            other => other,
        }
    }
}

/// The largest code [`quantize`] returns, 2²⁴ − 1: every code up to it is exact in f32.
pub const MAX_QUANTIZE_CODE: u32 = (1 << 24) - 1;

/// Rounds `x`, a value in code units, to an integer code in `0..=max_code` with `rounding`.
///
/// `x` below 0 and NaN give 0, `x` above `max_code` (and +∞) give `max_code`. Codes must fit
/// an f32 exactly: a `max_code` above [`MAX_QUANTIZE_CODE`] = 2²⁴ − 1 is treated as 2²⁴ − 1
/// (this crate's fields have at most 16 bits).
///
/// # Example
/// ```
/// use mcg_color_codec::{quantize, Rounding};
/// assert_eq!(quantize(2.7, 255, Rounding::Down), 2);
/// assert_eq!(quantize(2.7, 255, Rounding::Nearest), 3);
/// assert_eq!(quantize(2.7, 255, Rounding::Stochastic(0.8)), 2);
/// assert_eq!(quantize(2.7, 255, Rounding::Stochastic(0.6)), 3);
/// assert_eq!(quantize(f32::NAN, 255, Rounding::Nearest), 0);
/// assert_eq!(quantize(1e9, 255, Rounding::Down), 255);
/// ```
#[inline(always)]
#[must_use]
pub fn quantize(x: f32, max_code: u32, rounding: Rounding) -> u32 {
    // Branch-free so that loops over texels vectorise: `max` maps NaN to 0, the clamp keeps
    // the value in i32 range (codes are < 2²⁴), truncation is then ⌊x⌋, and the difference is
    // exact in f32.
    let max_code = max_code.min(MAX_QUANTIZE_CODE);
    let x = x.max(0.0).min(max_code as f32);
    let q = x as i32;
    let frac = x - q as f32;
    let up = match rounding {
        Rounding::Down => false,
        Rounding::Nearest => frac >= 0.5,
        Rounding::Stochastic(u) => frac > u.max(0.0),
    };
    (q + up as i32) as u32
}

/// Quantises `x ∈ [0, 1]` to a `bits`-bit UNORM code, `quantize(x · (2^bits − 1))`.
/// Out-of-range inputs saturate, NaN gives 0. `bits` above 24 is treated as 24 (the widest
/// code [`quantize`] supports); 0 bits give code 0.
#[inline(always)]
#[must_use]
pub fn quantize_unorm(x: f32, bits: u32, rounding: Rounding) -> u32 {
    let max = (1u32 << bits.min(24)) - 1;
    quantize(x * max as f32, max, rounding)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn modes() {
        assert_eq!(quantize(0.0, 7, Rounding::Down), 0);
        assert_eq!(quantize(6.999, 7, Rounding::Down), 6);
        assert_eq!(quantize(6.5, 7, Rounding::Nearest), 7);
        assert_eq!(quantize(0.499_999_97, 7, Rounding::Nearest), 0);
        assert_eq!(
            quantize(3.999_999_8, 7, Rounding::Stochastic(0.999_999_94)),
            3
        );
        assert_eq!(quantize(6.49, 7, Rounding::Nearest), 6);
        assert_eq!(quantize(9.0, 7, Rounding::Nearest), 7);
        assert_eq!(quantize(-3.0, 7, Rounding::Nearest), 0);
        assert_eq!(quantize(f32::INFINITY, 7, Rounding::Down), 7);
        assert_eq!(quantize(f32::NEG_INFINITY, 7, Rounding::Down), 0);
        // Exact integers never round up, whatever the uniform.
        for u in [0.0, 0.5, 0.999_999_9, 1.0, 7.0, f32::NAN, -1.0] {
            assert_eq!(quantize(3.0, 7, Rounding::Stochastic(u)), 3, "u = {u}");
        }
        assert_eq!(quantize_unorm(1.0, 10, Rounding::Nearest), 1023);
        assert_eq!(quantize_unorm(0.5, 1, Rounding::Down), 0);
    }

    #[test]
    fn wide_codes_saturate_instead_of_overflowing() {
        // Issue 14 row 6: overflowed (debug panic; release returned 2³¹ or 0).
        for rounding in [Rounding::Down, Rounding::Nearest, Rounding::Stochastic(0.0)] {
            assert_eq!(
                quantize(f32::INFINITY, u32::MAX, rounding),
                MAX_QUANTIZE_CODE
            );
            assert_eq!(quantize(f32::MAX, 1 << 30, rounding), MAX_QUANTIZE_CODE);
            assert_eq!(quantize(-1.0, u32::MAX, rounding), 0);
            assert_eq!(quantize(f32::NAN, u32::MAX, rounding), 0);
            assert_eq!(quantize(1000.5, u32::MAX, Rounding::Down), 1000);
            assert_eq!(quantize_unorm(1.0, 32, rounding), MAX_QUANTIZE_CODE);
            assert_eq!(quantize_unorm(1.0, u32::MAX, rounding), MAX_QUANTIZE_CODE);
            assert_eq!(quantize_unorm(0.5, 0, rounding), 0);
        }
        assert_eq!(
            quantize(16_777_214.6, u32::MAX, Rounding::Nearest),
            MAX_QUANTIZE_CODE
        );
        assert_eq!(
            quantize_unorm(1.0, 24, Rounding::Nearest),
            MAX_QUANTIZE_CODE
        );
    }

    #[test]
    fn stochastic_is_unbiased() {
        // Over a uniform grid of u, the mean code equals x exactly (to the grid's resolution).
        let x = 4.3;
        let n = 10_000;
        let sum: u32 = (0..n)
            .map(|i| quantize(x, 15, Rounding::Stochastic((i as f32 + 0.5) / n as f32)))
            .sum();
        mcg_test_support::assert_close!(sum as f32 / n as f32, x, 1e-3);
    }

    #[test]
    fn channel_rotation_stays_uniform() {
        for k in 0..3 {
            for u in [0.0, 0.3, 0.999_999_9] {
                let Rounding::Stochastic(v) = Rounding::Stochastic(u).for_channel(k) else {
                    panic!()
                };
                assert!((0.0..1.0).contains(&v), "{u} {k} {v}");
            }
        }
        assert_eq!(Rounding::Down.for_channel(2), Rounding::Down);
    }
}
