//! The log codec of ADGI eq. 21 and its k-bit quantisation.

use crate::error::CodecError;
use crate::math::{fast_exp2, fast_ln_ge1};
use crate::quantize::{Rounding, quantize};

/// Widest value field this crate packs: 16 bits, so that every code and quantum is exact in f32.
pub const MAX_FIELD_BITS: u32 = 16;

/// The logarithmic non-linearity of ADGI eq. 21, with parameters (β, γ):
///
/// ```text
/// u = min(ln(γ·v + 1), β) / β            v = (e^{β·u} − 1) / γ
/// ```
///
/// It maps v ∈ [0, v_max], `v_max = (e^β − 1)/γ`, onto u ∈ [0, 1], spreading quantisation error
/// evenly in relative terms above v ≈ 1/γ and linearly below it. γ sets where the curve turns
/// from linear to logarithmic, β the covered range. ADGI uses (5, 15) for irradiance and mean
/// distance (v_max ≈ 9.83) and (8, 20) for squared distance (v_max ≈ 149); the paper found
/// (5, 15) by a grid search against an f32 reference (appendix B, Fig. 11).
///
/// Quantisation to k bits goes through [`LogCodec::field`], which precomputes the scales.
///
/// # Example
/// ```
/// use mcg_color_codec::{LogCodec, Rounding};
/// let codec = LogCodec::IRRADIANCE;
/// assert!((codec.inverse(codec.forward(0.3)) - 0.3).abs() < 1e-5);
/// let field = codec.field(9);
/// let code = field.encode(0.3, Rounding::Down);
/// assert!(field.decode(code) <= 0.3 && 0.3 - field.decode(code) <= field.error_bound(0.3, Rounding::Down));
/// ```
///
/// # Notes
/// The hot path uses a branch-free `ln` and `exp2` (see the crate's `math` module), accurate to
/// a few f32 ulps; encodings are identical with the `std` and `libm` features.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LogCodec {
    beta: f32,
    gamma: f32,
}

impl LogCodec {
    /// Largest accepted β: e^β must stay finite in f32 (e^88.7 overflows), with margin.
    pub const BETA_MAX: f32 = 80.0;

    /// ADGI's irradiance codec, (β, γ) = (5, 15) (sec. 4.5).
    pub const IRRADIANCE: LogCodec = LogCodec {
        beta: 5.0,
        gamma: 15.0,
    };

    /// ADGI's mean-distance codec, (β, γ) = (5, 15) (sec. 4.6); distances are normalised by
    /// the probe cage diagonal.
    pub const DISTANCE: LogCodec = LogCodec::IRRADIANCE;

    /// ADGI's mean-squared-distance codec, (β, γ) = (8, 20) (sec. 4.6).
    pub const SQUARED_DISTANCE: LogCodec = LogCodec {
        beta: 8.0,
        gamma: 20.0,
    };

    /// A codec with range parameter β ∈ (0, [`BETA_MAX`](Self::BETA_MAX)] and scale γ > 0 (finite).
    ///
    /// # Errors
    /// [`CodecError::BetaOutOfRange`] or [`CodecError::GammaNotPositive`] (NaN fails both checks).
    pub const fn new(beta: f32, gamma: f32) -> Result<Self, CodecError> {
        if !(beta > 0.0 && beta <= Self::BETA_MAX) {
            return Err(CodecError::BetaOutOfRange);
        }
        if !(gamma > 0.0 && gamma < f32::INFINITY) {
            return Err(CodecError::GammaNotPositive);
        }
        Ok(Self { beta, gamma })
    }

    /// β, the range parameter.
    #[inline]
    #[must_use]
    pub const fn beta(&self) -> f32 {
        self.beta
    }

    /// γ, the scale parameter.
    #[inline]
    #[must_use]
    pub const fn gamma(&self) -> f32 {
        self.gamma
    }

    /// The largest encodable value, `(e^β − 1)/γ`; larger inputs saturate to it.
    #[inline]
    #[must_use]
    pub fn max_value(&self) -> f32 {
        self.inverse(1.0)
    }

    /// u = min(ln(γv + 1), β)/β ∈ [0, 1] (eq. 21). Negative inputs and NaN give 0, +∞ gives 1.
    #[inline]
    #[must_use]
    pub fn forward(&self, v: f32) -> f32 {
        let v = if v >= 0.0 { v } else { 0.0 };
        fast_ln_ge1(self.gamma * v + 1.0).min(self.beta) / self.beta
    }

    /// v = (e^{βu} − 1)/γ, the inverse of [`forward`](Self::forward) on [0, 1]; `u` is clamped to
    /// [0, 1] (NaN → 0), so the result is finite and non-negative.
    #[inline]
    #[must_use]
    pub fn inverse(&self, u: f32) -> f32 {
        let u = if u >= 0.0 { u.min(1.0) } else { 0.0 };
        ((fast_exp2(u * self.beta * core::f32::consts::LOG2_E) - 1.0) / self.gamma).max(0.0)
    }

    /// This codec quantised to `bits` bits (1 ..= [`MAX_FIELD_BITS`]; clamped into that range).
    #[must_use]
    pub const fn field(self, bits: u32) -> LogField {
        let bits = if bits < 1 {
            1
        } else if bits > MAX_FIELD_BITS {
            MAX_FIELD_BITS
        } else {
            bits
        };
        let max_code = (1u32 << bits) - 1;
        let m = max_code as f32;
        LogField {
            codec: self,
            bits,
            max_code,
            max_code_f: m,
            encode_scale: m / self.beta,
            decode_scale: self.beta / (m * core::f32::consts::LN_2),
            inv_gamma: 1.0 / self.gamma,
            // How far (in codes) the fast `ln` estimate can be from the boundary that the fast
            // `exp2` decode defines: a few f32 ulps of the log relative to the code scale M
            // (≈ 2·10⁻⁷·M each way), with margin. Inside the band, rounding down decides
            // exactly against `decode`.
            down_tolerance: 8e-6 * m + 1.0 / 4096.0,
        }
    }
}

/// A [`LogCodec`] quantised to a `bits`-bit field: codes 0 ..= 2^bits − 1, code q decoding to
/// `(e^{β q/M} − 1)/γ` with M = 2^bits − 1 (eq. 21 with u = q/M).
///
/// # Round-trip error bound
/// Let v ∈ [0, v_max] and v̂ = decode(encode(v)). Rounding moves u by less than 1/M (down,
/// stochastic) or at most 1/(2M) (nearest), and `(γv̂ + 1)/(γv + 1) = e^{β(û − u)}`, so
///
/// ```text
/// down:       0 ≤ v − v̂ < (1 − e^{−β/M}) (v + 1/γ)
/// nearest:    |v − v̂| ≤ (e^{β/(2M)} − 1) (v + 1/γ)
/// stochastic: |v − v̂| < (e^{β/M} − 1) (v + 1/γ)
/// ```
///
/// i.e. a relative error of about β/M above v ≈ 1/γ and an absolute error of about β/(γM) below.
/// For ADGI's 9-bit channels (β = 5, M = 511) that is ≤ 0.97 % + 6.5·10⁻⁴ (down); for the 8-bit
/// blue channel ≤ 1.94 % + 1.3·10⁻³. Above v_max the value saturates. [`error_bound`](Self::error_bound)
/// evaluates these (plus a few f32 ulps).
///
/// # Rounding down exactly
/// [`Rounding::Down`] returns the largest code whose decoded value is ≤ v, computed against the
/// same [`decode`](Self::decode): ⌊x⌋ of the fast-`ln` estimate x when x is farther than
/// `8·10⁻⁶·M + 2⁻¹²` codes from a code boundary (the estimate's error is well inside that band),
/// otherwise an estimate biased by −⅛ code and one check of the next code against `decode`.
/// So `encode(decode(q)) = q` for every code (tested for every code of widths 1-16), encode is
/// monotone, and a
/// value below `decode(1)` always encodes to 0 — the property that lets a moving average decay to
/// black (ADGI appendix B).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LogField {
    codec: LogCodec,
    bits: u32,
    max_code: u32,
    max_code_f: f32,
    encode_scale: f32,
    decode_scale: f32,
    inv_gamma: f32,
    down_tolerance: f32,
}

impl LogField {
    /// The codec.
    #[inline]
    #[must_use]
    pub const fn codec(&self) -> LogCodec {
        self.codec
    }

    /// Width of the field in bits.
    #[inline]
    #[must_use]
    pub const fn bits(&self) -> u32 {
        self.bits
    }

    /// The largest code, M = 2^bits − 1.
    #[inline]
    #[must_use]
    pub const fn max_code(&self) -> u32 {
        self.max_code
    }

    /// v in code units, `min(ln(γv + 1)·M/β, M)`; negative and NaN → 0, +∞ → M.
    #[inline(always)]
    pub(crate) fn code_units(&self, v: f32) -> f32 {
        fast_ln_ge1(self.codec.gamma * v + 1.0) * self.encode_scale
    }

    /// Encodes `v` to a code in 0 ..= M with `rounding` (see the type docs for the error bound).
    ///
    /// Negative inputs and NaN encode to 0; values above [`LogCodec::max_value`] (and +∞)
    /// saturate to M.
    #[inline(always)]
    #[must_use]
    pub fn encode(&self, v: f32, rounding: Rounding) -> u32 {
        // `max` maps NaN to 0.
        let v = v.max(0.0);
        let x = self.code_units(v);
        match rounding {
            Rounding::Down => {
                let x = x.min(self.max_code_f);
                let q = x as i32;
                let frac = x - q as f32;
                if frac > self.down_tolerance && frac < 1.0 - self.down_tolerance {
                    return q as u32;
                }
                // Near a code boundary the estimate could be off by one: decide exactly.
                let q0 = quantize(x - 0.125, self.max_code, Rounding::Down);
                let next = (q0 + 1).min(self.max_code);
                if self.decode_unmasked(next) <= v {
                    next
                } else {
                    q0
                }
            }
            _ => quantize(x, self.max_code, rounding),
        }
    }

    /// Decodes a code: `(e^{β q/M} − 1)/γ`. Codes above M are masked to the field's bits first,
    /// so every `u32` decodes to a finite, non-negative value.
    #[inline(always)]
    #[must_use]
    pub fn decode(&self, code: u32) -> f32 {
        self.decode_unmasked(code & self.max_code)
    }

    /// [`decode`](Self::decode) for a code known to be ≤ M.
    #[inline(always)]
    pub(crate) fn decode_unmasked(&self, code: u32) -> f32 {
        let q = code as i32 as f32;
        ((fast_exp2(q * self.decode_scale) - 1.0) * self.inv_gamma).max(0.0)
    }

    /// The size of the step from code `q` to `q + 1` in value units (0 at the top code).
    #[must_use]
    pub fn quantum_at(&self, code: u32) -> f32 {
        let q = code.min(self.max_code);
        if q == self.max_code {
            return 0.0;
        }
        self.decode(q + 1) - self.decode(q)
    }

    /// The round-trip error bound of the type docs at `v` for `rounding`, plus 4·10⁻⁶·(v + 1/γ)
    /// for f32 rounding. For v above [`LogCodec::max_value`] the saturation error is added.
    #[must_use]
    pub fn error_bound(&self, v: f32, rounding: Rounding) -> f32 {
        let v = if v >= 0.0 { v } else { 0.0 };
        let top = self.decode(self.max_code);
        let clamped = v.min(top);
        let step = self.codec.beta / self.max_code_f * core::f32::consts::LOG2_E;
        let rel = match rounding {
            Rounding::Down => 1.0 - 1.0 / fast_exp2(step),
            Rounding::Nearest => fast_exp2(0.5 * step) - 1.0,
            Rounding::Stochastic(_) => fast_exp2(step) - 1.0,
        };
        (rel + 4e-6) * (clamped + self.inv_gamma) + (v - top).max(0.0)
    }
}

/// Four [`LogField`]s side by side as plain per-lane arrays, so that encoding or decoding all
/// channels of a word compiles to straight-line 4-wide SIMD (lane `i` gives the same result
/// as `fields[i].encode` / `decode`, the stochastic uniform rotated per lane like
/// [`Rounding`]'s channels). Unused lanes repeat a field and are fed 0.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct LogLanes {
    gamma: [f32; 4],
    inv_gamma: [f32; 4],
    encode_scale: [f32; 4],
    decode_scale: [f32; 4],
    max_code: [i32; 4],
    down_tolerance: [f32; 4],
}

impl LogLanes {
    pub(crate) const fn new(f: [LogField; 4]) -> Self {
        let mut lanes = LogLanes {
            gamma: [0.0; 4],
            inv_gamma: [0.0; 4],
            encode_scale: [0.0; 4],
            decode_scale: [0.0; 4],
            max_code: [0; 4],
            down_tolerance: [0.0; 4],
        };
        let mut i = 0;
        while i < 4 {
            lanes.gamma[i] = f[i].codec.gamma;
            lanes.inv_gamma[i] = f[i].inv_gamma;
            lanes.encode_scale[i] = f[i].encode_scale;
            lanes.decode_scale[i] = f[i].decode_scale;
            lanes.max_code[i] = f[i].max_code as i32;
            lanes.down_tolerance[i] = f[i].down_tolerance;
            i += 1;
        }
        lanes
    }

    #[inline(always)]
    pub(crate) fn decode(&self, code: [u32; 4]) -> [f32; 4] {
        let mut out = [0.0_f32; 4];
        for i in 0..4 {
            let q = (code[i] as i32).min(self.max_code[i]) as f32;
            out[i] = ((fast_exp2(q * self.decode_scale[i]) - 1.0) * self.inv_gamma[i]).max(0.0);
        }
        out
    }

    #[inline(always)]
    pub(crate) fn encode(&self, v: [f32; 4], rounding: Rounding) -> [u32; 4] {
        let mut vv = [0.0_f32; 4];
        let mut x = [0.0_f32; 4];
        for i in 0..4 {
            vv[i] = v[i].max(0.0);
            x[i] = (fast_ln_ge1(self.gamma[i] * vv[i] + 1.0) * self.encode_scale[i])
                .min(self.max_code[i] as f32);
        }
        let mut out = [0_u32; 4];
        match rounding {
            Rounding::Down => {
                // As in `LogField::encode`: ⌊x⌋ unless some lane is within its tolerance of a
                // code boundary; then all lanes decide exactly against the decoded next code.
                let mut ambiguous = false;
                for i in 0..4 {
                    let q = x[i] as i32;
                    let frac = x[i] - q as f32;
                    ambiguous |=
                        !(frac > self.down_tolerance[i] && frac < 1.0 - self.down_tolerance[i]);
                    out[i] = q as u32;
                }
                if ambiguous {
                    for i in 0..4 {
                        let q0 = (x[i] - 0.125).max(0.0) as i32;
                        let next = (q0 + 1).min(self.max_code[i]);
                        let at_next = ((fast_exp2(next as f32 * self.decode_scale[i]) - 1.0)
                            * self.inv_gamma[i])
                            .max(0.0);
                        out[i] = (q0 + (at_next <= vv[i]) as i32) as u32;
                    }
                }
            }
            _ => {
                let mut threshold = [0.0_f32; 4];
                for (i, t) in threshold.iter_mut().enumerate() {
                    *t = match rounding.for_channel(i as u32) {
                        Rounding::Stochastic(u) => u.max(0.0),
                        // frac ≥ ½ ⟺ frac > the float below ½.
                        _ => 0.499_999_97,
                    };
                }
                for i in 0..4 {
                    let q = x[i] as i32;
                    let frac = x[i] - q as f32;
                    out[i] = (q + (frac > threshold[i]) as i32) as u32;
                }
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn construction() {
        assert_eq!(LogCodec::new(5.0, 15.0), Ok(LogCodec::IRRADIANCE));
        assert_eq!(LogCodec::new(0.0, 15.0), Err(CodecError::BetaOutOfRange));
        assert_eq!(
            LogCodec::new(f32::NAN, 15.0),
            Err(CodecError::BetaOutOfRange)
        );
        assert_eq!(LogCodec::new(81.0, 15.0), Err(CodecError::BetaOutOfRange));
        assert_eq!(LogCodec::new(5.0, 0.0), Err(CodecError::GammaNotPositive));
        assert_eq!(
            LogCodec::new(5.0, f32::NAN),
            Err(CodecError::GammaNotPositive)
        );
        assert_eq!(
            LogCodec::new(5.0, f32::INFINITY),
            Err(CodecError::GammaNotPositive)
        );
        assert!(LogCodec::new(80.0, 1e-3).is_ok());
        assert_eq!(LogCodec::IRRADIANCE.field(0).bits(), 1);
        assert_eq!(LogCodec::IRRADIANCE.field(40).bits(), 16);
    }

    #[test]
    fn eq21_values() {
        let c = LogCodec::IRRADIANCE;
        assert_eq!(c.forward(0.0), 0.0);
        assert_eq!(c.forward(-1.0), 0.0);
        assert_eq!(c.forward(f32::NAN), 0.0);
        assert_eq!(c.forward(f32::INFINITY), 1.0);
        assert_eq!(c.forward(1e6), 1.0);
        let v = 0.7_f64;
        let want = (15.0 * v + 1.0).ln() / 5.0;
        assert!((c.forward(0.7) as f64 - want).abs() < 1e-6);
        let max = (5f64.exp() - 1.0) / 15.0;
        assert!((c.max_value() as f64 - max).abs() < 1e-5 * max);
        let sq = LogCodec::SQUARED_DISTANCE.max_value() as f64;
        assert!((sq - (8f64.exp() - 1.0) / 20.0).abs() < 1e-5 * sq);
        assert_eq!(c.inverse(f32::NAN), 0.0);
        assert_eq!(c.inverse(2.0), c.max_value());
    }

    #[test]
    fn down_is_exact_and_idempotent_for_every_code() {
        for codec in [
            LogCodec::IRRADIANCE,
            LogCodec::SQUARED_DISTANCE,
            LogCodec::new(0.5, 0.01).unwrap(),
        ] {
            for bits in [1, 6, 8, 9, 10, 13, 16] {
                let f = codec.field(bits);
                let mut prev = -1.0_f32;
                for q in 0..=f.max_code() {
                    let v = f.decode(q);
                    assert!(v.is_finite() && v > prev, "{bits} {q}");
                    prev = v;
                    assert_eq!(f.encode(v, Rounding::Down), q, "{bits} bits, q = {q}");
                    assert_eq!(f.encode(v, Rounding::Nearest), q, "{bits} bits, q = {q}");
                    if q > 0 {
                        let below = f32::from_bits(v.to_bits() - 1);
                        assert_eq!(
                            f.encode(below, Rounding::Down),
                            q - 1,
                            "{bits} bits, q = {q}"
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn value_stability() {
        let f9 = LogCodec::IRRADIANCE.field(9);
        let f13 = LogCodec::SQUARED_DISTANCE.field(13);
        let codes: [u32; 6] = [
            f9.encode(0.001, Rounding::Down),
            f9.encode(0.5, Rounding::Down),
            f9.encode(0.5, Rounding::Nearest),
            f9.encode(3.0, Rounding::Stochastic(0.7)),
            f13.encode(2.5, Rounding::Down),
            f13.encode(100.0, Rounding::Nearest),
        ];
        // ln(8.5)/5·511 = 218.7; ln(46)/5·511 = 391.3; ln(51)/8·8191 = 4025.9; ln(2001)/8·8191 = 7782.9.
        assert_eq!(codes, [1, 218, 219, 391, 4025, 7783]);
        let d9 = ((5.0 * 218.0 / 511.0_f64).exp() - 1.0) / 15.0;
        let d13 = ((8.0 * 4025.0 / 8191.0_f64).exp() - 1.0) / 20.0;
        assert!((f9.decode(218) as f64 / d9 - 1.0).abs() < 1e-6);
        assert!((f13.decode(4025) as f64 / d13 - 1.0).abs() < 1e-6);
        assert_eq!(
            [f9.decode(218).to_bits(), f13.decode(4025).to_bits()],
            [1_056_832_093, 1_075_831_689],
            "{} {}",
            f9.decode(218),
            f13.decode(4025)
        );
    }
}
