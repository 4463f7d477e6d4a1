//! ADGI's guiding function h over (position, direction) (sec. 3.2, eq. 2; static form sec. 4.8;
//! dynamic form sec. 4.9).
//!
//! ```text
//! h(x) = exp(α · ĝ(x) / f(x)) · f(x)                     (eq. 2)
//! h    = exp(min(ĝ_r / f_s, 1)) · f_s                    (static chains, sec. 4.8)
//! h    = f_d  on the 3×3×3 proxies (α = 0)               (dynamic chains, sec. 4.9)
//! ```
//!
//! f is a heuristic of [`heuristics`](crate::heuristics) (f_s or f_d, in [0, 1]) and ĝ the
//! feedback of the irradiance cache (the luminance of a coarse mip of the probe's irradiance,
//! from the previous frame). Both are **tabulated per probe (or proxy) and octant** — the
//! heuristics LUT of sec. 4.1/4.3, read with the nearest probe and the octant of ω ("a mapping
//! function that maps the continuous position p and direction ω to the corresponding texel in
//! the LUT") — so h is piecewise constant, which sec. 3.5 (eq. 8) needs for the texel estimates
//! to stay unbiased.
//!
//! Eq. 2 grows without bound as f → 0 with ĝ > 0; the exponent is therefore capped
//! ([`GuideParams::exponent_cap`], 1 in the static form as in sec. 4.8, at most
//! [`MAX_EXPONENT`]), which keeps h finite, non-negative and ≤ e^cap · f.

use glam::Vec3;
use mcg_color_codec::HeuristicsWord;

use crate::heuristics::{OCTANTS, decode, octant, unit};
use crate::proxies::ProxyGrid;
use crate::{LayoutError, ParameterError};

/// The largest exponent cap [`GuideParams::new`] accepts: e⁶⁴ ≈ 6·10²⁷, so h ≤ e⁶⁴ stays far
/// from f32 overflow.
pub const MAX_EXPONENT: f32 = 64.0;

/// The parameters of eq. 2: the confidence α ≥ 0 in the irradiance cache, and the cap on the
/// exponent α ĝ / f.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GuideParams {
    alpha: f32,
    exponent_cap: f32,
}

impl GuideParams {
    /// The static chains' form (sec. 4.8): `h = exp(min(ĝ_r / f_s, 1)) · f_s`, i.e. α = 1 and
    /// the exponent capped at 1, so f ≤ h ≤ e · f.
    pub const STATIC: Self = Self {
        alpha: 1.0,
        exponent_cap: 1.0,
    };

    /// The dynamic chains' form (sec. 4.9): α = 0 ("we also drop the sampled evidence"), so
    /// `h = f` (with f = f_d on the proxies).
    pub const DYNAMIC: Self = Self {
        alpha: 0.0,
        exponent_cap: 0.0,
    };

    /// Eq. 2 with confidence `alpha` and the exponent α ĝ / f capped at `exponent_cap`.
    ///
    /// # Errors
    /// [`ParameterError::GuideOutOfRange`] unless `alpha` is finite and ≥ 0 and
    /// `exponent_cap` is in [0, [`MAX_EXPONENT`]].
    pub fn new(alpha: f32, exponent_cap: f32) -> Result<Self, ParameterError> {
        if !(alpha >= 0.0) || !alpha.is_finite() {
            return Err(ParameterError::GuideOutOfRange {
                parameter: "alpha",
                value: alpha,
            });
        }
        if !(0.0..=MAX_EXPONENT).contains(&exponent_cap) {
            return Err(ParameterError::GuideOutOfRange {
                parameter: "exponent_cap",
                value: exponent_cap,
            });
        }
        Ok(Self {
            alpha,
            exponent_cap,
        })
    }

    /// α, the confidence in the cache.
    #[inline]
    #[must_use]
    pub fn alpha(&self) -> f32 {
        self.alpha
    }

    /// The cap on the exponent α ĝ / f.
    #[inline]
    #[must_use]
    pub fn exponent_cap(&self) -> f32 {
        self.exponent_cap
    }

    /// `h = exp(min(α ĝ / f, cap)) · f` (eq. 2), finite and in [0, e^cap].
    ///
    /// Edge cases: f is clamped to [0, 1] (NaN → 0) and f = 0 gives h = 0 whatever ĝ; a NaN or
    /// negative ĝ counts as 0, ĝ = +∞ reaches the cap (for α > 0); α = 0 ignores ĝ entirely.
    ///
    /// # Example
    /// ```
    /// use mcg_probe_cache::GuideParams;
    /// // Static form: f = 0.5, ĝ = 0.25: exp(min(0.5, 1)) · 0.5 = 0.824361.
    /// assert!((GuideParams::STATIC.guiding_value(0.5, 0.25) - 0.824_361).abs() < 1e-6);
    /// assert_eq!(GuideParams::DYNAMIC.guiding_value(0.5, 100.0), 0.5);
    /// ```
    #[inline]
    #[must_use]
    pub fn guiding_value(&self, f: f32, g_hat: f32) -> f32 {
        let f = unit(f);
        if !(f > 0.0) {
            return 0.0;
        }
        let g = if g_hat > 0.0 { g_hat } else { 0.0 }; // NaN → 0
        let exponent = if self.alpha > 0.0 && g > 0.0 {
            // α g / f ∈ (0, +∞]; min with the finite cap.
            (self.alpha * g / f).min(self.exponent_cap)
        } else {
            0.0
        };
        exponent.exp() * f
    }

    /// h(f, ĝ) of ADGI eq. 2: the old name of [`GuideParams::guiding_value`].
    #[deprecated(note = "renamed to `guiding_value`")]
    #[inline]
    #[must_use]
    pub fn h(&self, f: f32, g_hat: f32) -> f32 {
        self.guiding_value(f, g_hat)
    }
}

impl Default for GuideParams {
    /// [`GuideParams::STATIC`].
    fn default() -> Self {
        Self::STATIC
    }
}

/// A guide the chains can sample: a non-negative, finite function of a world position and a
/// direction (not necessarily unit). Implemented by [`GuidingFunction`] and by closures
/// `Fn(Vec3, Vec3) -> f32`. Values that are NaN, infinite or negative count as 0.
pub trait Guide {
    /// The guiding function's value h(p, ω) (ADGI eq. 2).
    fn guiding_value(&self, position: Vec3, direction: Vec3) -> f32;

    /// h(p, ω): the old name of [`Guide::guiding_value`] (implement that one).
    #[deprecated(note = "renamed to `guiding_value`")]
    #[inline]
    fn h(&self, position: Vec3, direction: Vec3) -> f32 {
        self.guiding_value(position, direction)
    }
}

impl<F: Fn(Vec3, Vec3) -> f32> Guide for F {
    #[inline]
    fn guiding_value(&self, position: Vec3, direction: Vec3) -> f32 {
        self(position, direction)
    }
}

/// ADGI's tabulated guiding function (eq. 2): per cell (probe or proxy, see [`ProxyGrid`]) and
/// octant, a heuristic f and optionally the cache feedback ĝ; h(p, ω) reads the cell that owns
/// p (nearest probe) and the octant of ω.
///
/// Tables are indexed `cell · 8 + octant` ([`octant`]); the guide borrows them, so building
/// one per frame is free.
///
/// # Example
/// ```
/// use mcg_probe_cache::{GuideParams, GuidingFunction, ProbeGrid, ProxyGrid, glam::{UVec3, Vec3}};
///
/// let grid = ProbeGrid::new(Vec3::ZERO, Vec3::ONE, UVec3::new(2, 1, 1))?;
/// // f_s of probe 0 is 0.5 in every octant; probe 1 sees 0.2 in octant 0 (+, +, +) only.
/// let mut f_s = vec![0.5; 16];
/// f_s[8..].copy_from_slice(&[0.2, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]);
/// let feedback = vec![0.1; 16];
/// let h = GuidingFunction::new(ProxyGrid::probes(grid), &f_s, Some(&feedback), GuideParams::STATIC)?;
/// // Probe 1, octant 0: exp(min(0.1/0.2, 1)) · 0.2 = e^0.5 · 0.2.
/// let v = h.guiding_value(Vec3::new(1.2, 0.0, 0.1), Vec3::new(0.3, 0.5, 0.8));
/// assert!((v - 0.5f32.exp() * 0.2).abs() < 1e-6);
/// assert_eq!(h.guiding_value(Vec3::new(1.2, 0.0, 0.1), Vec3::new(-0.3, 0.5, 0.8)), 0.0);
/// assert_eq!(h.guiding_value(Vec3::new(9.0, 0.0, 0.0), Vec3::Z), 0.0); // outside the grid
/// # Ok::<(), mcg_probe_cache::ProbeError>(())
/// ```
#[derive(Clone, Copy, Debug)]
pub struct GuidingFunction<'a> {
    cells: ProxyGrid,
    f: &'a [f32],
    feedback: Option<&'a [f32]>,
    params: GuideParams,
}

impl<'a> GuidingFunction<'a> {
    /// The guide over `cells` with heuristic table `f` and feedback table `feedback` (`None`:
    /// ĝ = 0, so h = f).
    ///
    /// # Errors
    /// [`LayoutError::TableLengthMismatch`] unless each table has `cells.table_len()` entries.
    pub fn new(
        cells: ProxyGrid,
        f: &'a [f32],
        feedback: Option<&'a [f32]>,
        params: GuideParams,
    ) -> Result<Self, LayoutError> {
        let n = cells.table_len();
        LayoutError::check_tables(n, &[f.len(), feedback.map_or(n, <[f32]>::len)])?;
        Ok(Self {
            cells,
            f,
            feedback,
            params,
        })
    }

    /// The cells (probes or proxies) the tables are indexed by.
    #[inline]
    #[must_use]
    pub fn cells(&self) -> ProxyGrid {
        self.cells
    }

    /// The parameters of eq. 2.
    #[inline]
    #[must_use]
    pub fn params(&self) -> GuideParams {
        self.params
    }

    /// h of cell `cell` in octant `octant` (0 for an index outside the tables).
    #[inline]
    #[must_use]
    pub fn value(&self, cell: usize, octant: usize) -> f32 {
        let i = cell * OCTANTS + (octant & 7);
        let Some(&f) = self.f.get(i) else { return 0.0 };
        let g = self.feedback.and_then(|g| g.get(i).copied()).unwrap_or(0.0);
        self.params.guiding_value(f, g)
    }

    /// h(p, ω): the cell owning `position` and the octant of `direction`; 0 outside the
    /// sampling domain ([`ProxyGrid::nearest_probe`]) or for a non-finite direction.
    #[inline]
    #[must_use]
    pub fn guiding_value(&self, position: Vec3, direction: Vec3) -> f32 {
        if !direction.is_finite() {
            return 0.0;
        }
        match self.cells.proxy_at(position) {
            Some(cell) => self.value(cell, octant(direction)),
            None => 0.0,
        }
    }

    /// h(p, ω): the old name of [`GuidingFunction::guiding_value`].
    #[deprecated(note = "renamed to `guiding_value`")]
    #[inline]
    #[must_use]
    pub fn h(&self, position: Vec3, direction: Vec3) -> f32 {
        self.guiding_value(position, direction)
    }
}

impl Guide for GuidingFunction<'_> {
    #[inline]
    fn guiding_value(&self, position: Vec3, direction: Vec3) -> f32 {
        GuidingFunction::guiding_value(self, position, direction)
    }
}

/// Rec. 709 / sRGB luminance weights, for the feedback ĝ of [`octant_feedback`].
pub const LUMINANCE: Vec3 = Vec3::new(0.2126, 0.7152, 0.0722);

/// The feedback ĝ of eq. 2 for one probe: per octant, the mean luminance of the irradiance
/// texels whose centre direction lies in it — a coarse, per-octant "mip" of the irradiance
/// cache, as sec. 4.8 asks ("from a higher mip-level"). Compute it from the previous frame's
/// cache so the target stays fixed within a frame.
///
/// `texel_directions[t]` is the centre direction of texel `t`, `irradiance(t)` its decoded
/// irradiance (RGB). Non-finite or negative luminances count as 0; an octant without texels
/// gets 0.
///
/// # Example
/// ```
/// use mcg_probe_cache::{guiding_function::octant_feedback, glam::Vec3};
/// let dirs = [Vec3::new(1.0, 1.0, 1.0), Vec3::new(1.0, 2.0, 0.5), Vec3::new(-1.0, -1.0, -1.0)];
/// let mut g = [0.0; 8];
/// octant_feedback(&dirs, |t| Vec3::splat(t as f32 + 1.0), &mut g);
/// assert!((g[0] - 1.5).abs() < 1e-6 && (g[7] - 3.0).abs() < 1e-6 && g[1] == 0.0);
/// ```
pub fn octant_feedback(
    texel_directions: &[Vec3],
    mut irradiance: impl FnMut(usize) -> Vec3,
    out: &mut [f32; OCTANTS],
) {
    let mut sum = [0.0f32; OCTANTS];
    let mut n = [0u32; OCTANTS];
    for (t, &d) in texel_directions.iter().enumerate() {
        let o = octant(d);
        let y = irradiance(t).dot(LUMINANCE);
        sum[o] += if y > 0.0 && y.is_finite() { y } else { 0.0 };
        n[o] += 1;
    }
    for o in 0..OCTANTS {
        out[o] = if n[o] > 0 { sum[o] / n[o] as f32 } else { 0.0 };
    }
}

/// Which heuristic of a heuristics word a guide samples.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum HeuristicField {
    /// f_v (eq. 11).
    Visibility,
    /// f_s = f_c f_v (eq. 19), the static chains' f.
    Static,
    /// f_d (eq. 20, normalised), the dynamic chains' f.
    Dynamic,
}

/// Decodes one field of a table of heuristics words (ADGI sec. 4.3) into `out`, e.g. f_s for
/// the static guide or f_d to [`max_pool`](ProxyGrid::max_pool) into the proxies.
///
/// # Errors
/// [`LayoutError::TableLengthMismatch`] when the slices differ in length.
pub fn decode_field(
    words: &[HeuristicsWord],
    field: HeuristicField,
    out: &mut [f32],
) -> Result<(), LayoutError> {
    LayoutError::check_tables(words.len(), &[out.len()])?;
    for (o, &w) in out.iter_mut().zip(words) {
        let h = decode(w);
        *o = match field {
            HeuristicField::Visibility => h.f_v,
            HeuristicField::Static => h.f_s,
            HeuristicField::Dynamic => h.f_d,
        };
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use glam::UVec3;
    use mcg_color_codec::Heuristics;

    use super::*;
    use crate::ProbeGrid;

    #[test]
    fn eq2_by_hand() {
        let s = GuideParams::STATIC;
        // f = 0.4, ĝ = 0.1: exp(0.25)·0.4 = 1.2840254·0.4 = 0.51361016.
        mcg_test_support::assert_close!(s.guiding_value(0.4, 0.1), 0.513_610_2, 1e-6);
        // ĝ/f = 3 > 1 → capped: e·0.4 = 1.0873127.
        mcg_test_support::assert_close!(s.guiding_value(0.4, 1.2), 1.087_312_7, 1e-6);
        // Eq. 2 with α = 2, cap 10: f = 0.5, ĝ = 0.75: exp(2·0.75/0.5) · 0.5 = e³/2 = 10.042768.
        let p = GuideParams::new(2.0, 10.0).unwrap();
        mcg_test_support::assert_close!(p.guiding_value(0.5, 0.75), 10.042_768, 1e-4);
        // Tiny f with ĝ > 0 hits the cap: e^10 · 1e-30, finite.
        mcg_test_support::assert_close!(p.guiding_value(1e-30, 1.0), 1e-30 * 10.0f32.exp(), 1e-33);
        assert_eq!(p.guiding_value(0.0, 1.0), 0.0);
        assert_eq!(p.guiding_value(f32::NAN, 1.0), 0.0);
        assert_eq!(p.guiding_value(-1.0, 1.0), 0.0);
        assert_eq!(p.guiding_value(0.5, f32::NAN), 0.5);
        mcg_test_support::assert_close!(
            p.guiding_value(0.5, f32::INFINITY),
            0.5 * 10.0f32.exp(),
            1e-2
        );
        // f above 1 saturates.
        assert_eq!(GuideParams::DYNAMIC.guiding_value(7.0, 1.0), 1.0);
        assert_eq!(GuideParams::DYNAMIC.guiding_value(0.3, f32::INFINITY), 0.3);
        assert_eq!(GuideParams::default(), GuideParams::STATIC);
    }

    #[test]
    fn params_are_validated() {
        for (a, c) in [
            (-1.0, 1.0),
            (f32::NAN, 1.0),
            (f32::INFINITY, 1.0),
            (1.0, 65.0),
            (1.0, -0.1),
            (1.0, f32::NAN),
        ] {
            let (parameter, value) = if a >= 0.0 && a.is_finite() {
                ("exponent_cap", c)
            } else {
                ("alpha", a)
            };
            let e = GuideParams::new(a, c);
            assert!(
                matches!(e, Err(ParameterError::GuideOutOfRange { parameter: p, value: v })
                    if p == parameter && v.to_bits() == value.to_bits()),
                "{a} {c}: {e:?}"
            );
        }
        let p = GuideParams::new(0.5, MAX_EXPONENT).unwrap();
        assert_eq!((p.alpha(), p.exponent_cap()), (0.5, 64.0));
        assert!(p.guiding_value(1.0, f32::INFINITY).is_finite());
    }

    #[test]
    fn tabulated_guide_by_hand() {
        let grid = ProbeGrid::new(
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::splat(2.0),
            UVec3::new(3, 2, 1),
        )
        .unwrap();
        let cells = ProxyGrid::probes(grid);
        // f = (probe + 1)/10 + octant/100; ĝ = 0.05 everywhere.
        let f: Vec<f32> = (0..48)
            .map(|k| ((k / 8) + 1) as f32 / 10.0 + (k % 8) as f32 / 100.0)
            .collect();
        let g = vec![0.05; 48];
        let guide = GuidingFunction::new(cells, &f, Some(&g), GuideParams::STATIC).unwrap();
        // Position (3.4, 2.9, 0.3) → t = ((2.4, 2.9, 0.3)/2 + 0.5) = (1.7, 1.95, 0.65) → probe
        // (1, 1, 0) = index 4; direction (−1, 2, −3) → octant 0b101 = 5.
        // f = 0.5 + 0.05 = 0.55; h = exp(0.05/0.55)·0.55 = e^0.090909·0.55 = 1.0951705·0.55
        // = 0.6023438.
        let v = guide.guiding_value(Vec3::new(3.4, 2.9, 0.3), Vec3::new(-1.0, 2.0, -3.0));
        mcg_test_support::assert_close!(v, 0.602_343_8, 1e-6, "{v}");
        assert_eq!(v, guide.value(4, 5));
        assert_eq!(guide.value(6, 0), 0.0);
        assert_eq!(
            guide.guiding_value(Vec3::new(3.4, 2.9, 0.3), Vec3::NAN),
            0.0
        );
        assert_eq!(guide.guiding_value(Vec3::new(-0.1, 0.0, 0.0), Vec3::X), 0.0);
        assert_eq!(guide.cells(), cells);
        assert_eq!(guide.params(), GuideParams::STATIC);
        // Without feedback h = f.
        let plain = GuidingFunction::new(cells, &f, None, GuideParams::STATIC).unwrap();
        mcg_test_support::assert_close!(plain.value(4, 5), 0.55, 1e-7);
        assert_eq!(
            GuidingFunction::new(cells, &f[1..], None, GuideParams::STATIC).err(),
            Some(LayoutError::TableLengthMismatch {
                expected: f.len(),
                found: f.len() - 1
            })
        );
        assert_eq!(
            GuidingFunction::new(cells, &f, Some(&g[1..]), GuideParams::STATIC).err(),
            Some(LayoutError::TableLengthMismatch {
                expected: f.len(),
                found: g.len() - 1
            })
        );
    }

    #[test]
    fn decode_fields() {
        let words: Vec<HeuristicsWord> = [(0.2, 0.4, 0.6), (1.0, 0.0, 0.5)]
            .iter()
            .map(|&(f_v, f_s, f_d)| {
                crate::heuristics::encode(Heuristics {
                    f_v,
                    f_s,
                    f_d,
                    flags: 0,
                })
            })
            .collect();
        let mut out = [0.0; 2];
        decode_field(&words, HeuristicField::Static, &mut out).unwrap();
        assert!((out[0] - 0.4).abs() < 1e-3 && out[1] == 0.0);
        decode_field(&words, HeuristicField::Dynamic, &mut out).unwrap();
        assert!((out[0] - 0.6).abs() < 1e-3 && (out[1] - 0.5).abs() < 1e-3);
        decode_field(&words, HeuristicField::Visibility, &mut out).unwrap();
        assert!((out[0] - 0.2).abs() < 1e-2 && out[1] == 1.0);
        assert_eq!(
            decode_field(&words, HeuristicField::Static, &mut [0.0; 3]),
            Err(LayoutError::TableLengthMismatch {
                expected: 2,
                found: 3
            })
        );
    }

    #[test]
    fn octant_feedback_by_hand() {
        // Two texels in octant 3 (−x, −y, +z): luminances of (1, 0, 0) and (0, 1, 0) are 0.2126
        // and 0.7152, mean 0.4639; one NaN texel in octant 4 counts as 0.
        let dirs = [
            Vec3::new(-1.0, -1.0, 1.0),
            Vec3::new(-0.2, -3.0, 0.1),
            Vec3::new(1.0, 1.0, -1.0),
        ];
        let values = [Vec3::X, Vec3::Y, Vec3::NAN];
        let mut g = [9.0; 8];
        octant_feedback(&dirs, |t| values[t], &mut g);
        mcg_test_support::assert_close!(g[3], 0.4639, 1e-6, "{g:?}");
        assert_eq!(g[4], 0.0);
        assert!(g.iter().enumerate().all(|(o, &v)| o == 3 || v == 0.0));
    }

    #[test]
    fn value_stability() {
        let p = GuideParams::new(0.7, 3.0).unwrap();
        let got: Vec<u32> = [(0.3, 0.2), (0.05, 1.0), (1.0, 0.0), (0.8, 0.9)]
            .iter()
            .map(|&(f, g)| p.guiding_value(f, g).to_bits())
            .collect();
        // By hand: e^{0.7·0.2/0.3}·0.3 = 0.47840; cap 3: e³·0.05 = 1.00428; 1; e^{0.7875}·0.8 = 1.75836.
        assert_eq!(
            got,
            vec![0x3ef4_f0f7, 0x3f80_8c25, 0x3f80_0000, 0x3fe1_107f],
            "{got:x?}"
        );
    }
}
