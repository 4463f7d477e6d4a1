//! A small weighted mixture of lobes in structure-of-arrays form, evaluated lane-wise.
//!
//! [`Vmf::pdf`] calls the platform's `exp` once per lobe, and a loop over a handful of lobes
//! stays scalar. [`VmfLanes`] keeps the lobes' μ, κ and weight·C(κ) as arrays, one lane per
//! lobe, and evaluates the mixture density with the inlined, branch-free `exp` of
//! [`sample_batch`](crate::sample_batch) (Cephes' `expf` polynomial), so that the compiler runs
//! the lanes four or eight at a time. A guide that keeps the candidates of one vertex and asks
//! for their mixture's density several times (MCPG's estimator denominator, eq. 6-7) needs
//! exactly that.

use glam::Vec3;

use crate::KAPPA_MAX;
use crate::constants::KAPPA_SATURATED;
use crate::math;
use crate::sphere::UNIFORM_SPHERE_PDF;
use crate::{MapPrior, SufficientStats, Vmf};

/// The smallest exponent handed to the polynomial `exp`: e^{−87} ≈ 1.6·10⁻³⁸ is still a normal
/// float (below it 2ⁿ of the range reduction is not). A lobe's density that far from its
/// mean, times C(κ) ≤ 3.2·10⁵, is below 10⁻³² sr⁻¹: the clamp changes no density a renderer
/// can tell from 0.
const EXP_FLOOR: f32 = -87.0;

/// What [`VmfLanes::set_from_inputs`] builds its lobes from, lane-wise (structure of arrays):
/// per lane the offset ȳ − x from the shading point to the statistics' mean target, the parts
/// of [`SufficientStats::to_vmf`]'s MAP posterior (N_eff, N_p and 1 − r_p, from
/// [`MapPrior`]: the posterior complement is (N_eff (1 − r̄) + N_p (1 − r_p)) / (N_eff + N_p)),
/// 1 − r̄, and the mixture weight.
///
/// [`set`](Self::set) fills a lane from statistics and a prior as
/// [`VmfLanes::from_stats`] does. A guide whose per-lane quantities come from its own
/// arrays (MCPG's distance prior N_p = max(N_min, s/|ȳ − x|²), its shares) can instead write
/// the arrays in passes over whole lanes, which the compiler vectorises, and hand them over
/// once. A lane with weight 0 (or a weight that is not finite and positive) stays empty.
///
/// # Example
/// ```
/// use mcg_vmf::{LobeInputs, MapPrior, SufficientStats, VmfLanes, glam::Vec3};
///
/// let stats = SufficientStats {
///     mean_target: Vec3::new(0.0, 0.0, 4.0),
///     weight_sum: 2.0,
///     one_minus_mean_cosine: 0.05,
///     sample_count: 12,
/// };
/// let x = Vec3::ZERO;
/// let prior = MapPrior::inverse_square_distance(1.0, 1e-4, stats.target_distance(x));
/// let mut inputs = LobeInputs::<4>::EMPTY;
/// inputs.set(1, &stats, x, prior, 0.5);
/// let mut lanes = VmfLanes::<4>::EMPTY;
/// lanes.set_from_inputs(&inputs, None);
/// // The lobe `SufficientStats::to_vmf` builds, in lane 1 with weight ½.
/// assert_eq!(lanes.lobe(1), stats.to_vmf(x, prior).unwrap());
/// assert_eq!(lanes.weight(1), 0.5);
/// assert!(!lanes.is_set(0));
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LobeInputs<const N: usize> {
    /// x of ȳ − x.
    pub offset_x: [f32; N],
    /// y of ȳ − x.
    pub offset_y: [f32; N],
    /// z of ȳ − x.
    pub offset_z: [f32; N],
    /// N_eff, the sample count as the prior's decay weighs it (N² or N,
    /// [`PriorDecay`](crate::PriorDecay)).
    pub n_eff: [f32; N],
    /// N_p ≥ 0, the prior's virtual samples (+∞: the prior alone).
    pub prior_weight: [f32; N],
    /// 1 − r_p, the complement of the prior's mean cosine.
    pub prior_complement: [f32; N],
    /// 1 − r̄, the complement of the statistics' mean cosine.
    pub one_minus_mean_cosine: [f32; N],
    /// The lane's mixture weight; 0 for a lane without a lobe (N = 0 or w̄ = 0).
    pub weight: [f32; N],
}

impl<const N: usize> Default for LobeInputs<N> {
    fn default() -> Self {
        Self::EMPTY
    }
}

impl<const N: usize> LobeInputs<N> {
    /// Every lane without a lobe (all zero, no prior).
    pub const EMPTY: Self = Self {
        offset_x: [0.0; N],
        offset_y: [0.0; N],
        offset_z: [0.0; N],
        n_eff: [0.0; N],
        prior_weight: [0.0; N],
        prior_complement: [1.0; N],
        one_minus_mean_cosine: [0.0; N],
        weight: [0.0; N],
    };

    /// Lane `i` from `stats` seen from `x` with `prior` and mixture weight `weight` (0 when the
    /// statistics are empty: N = 0 or w̄ = 0), what [`VmfLanes::from_stats`] gathers per lane.
    ///
    /// # Panics
    /// If `i ≥ N`.
    #[inline(always)]
    pub fn set(
        &mut self,
        i: usize,
        stats: &SufficientStats,
        x: Vec3,
        prior: MapPrior,
        weight: f32,
    ) {
        let d = stats.mean_target - x;
        let (n_eff, prior_weight, prior_complement) = stats.posterior_parts(prior);
        // w̄ > 0 (`is_valid`) and N ≠ 0, as 1/0 for the lane pass.
        let has = (stats.sample_count != 0) & stats.is_valid();
        self.offset_x[i] = d.x;
        self.offset_y[i] = d.y;
        self.offset_z[i] = d.z;
        self.n_eff[i] = n_eff;
        self.prior_weight[i] = prior_weight;
        self.prior_complement[i] = prior_complement;
        self.one_minus_mean_cosine[i] = stats.one_minus_mean_cosine;
        self.weight[i] = if has { weight } else { 0.0 };
    }
}

/// Up to `N` vMF lobes with mixture weights, stored lane-wise: the density
/// Σᵢ wᵢ V(ω | μᵢ, κᵢ) in one pass over the lanes.
///
/// Lanes never set are empty (weight 0) and add exactly 0. Densities agree with
/// Σᵢ wᵢ·[`Vmf::pdf`] to a few units in the last place (the polynomial `exp` and `expm1` round
/// differently from the platform's), not bit for bit.
///
/// # Example
/// ```
/// use mcg_vmf::{Vmf, VmfLanes, glam::Vec3};
///
/// let a = Vmf::new(Vec3::Z, 20.0)?;
/// let b = Vmf::new(Vec3::X, 3.0)?;
/// let mut lanes = VmfLanes::<4>::EMPTY;
/// lanes.set(0, &a, 0.25);
/// lanes.set(2, &b, 0.75);
/// let w = Vec3::new(0.3, 0.1, 1.0).normalize();
/// let want = 0.25 * a.pdf(w) + 0.75 * b.pdf(w);
/// assert!((lanes.pdf(w) - want).abs() < 1e-6 * want);
/// assert_eq!(lanes.lobe(2), b);
/// # Ok::<(), mcg_vmf::VmfError>(())
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VmfLanes<const N: usize> {
    mu_x: [f32; N],
    mu_y: [f32; N],
    mu_z: [f32; N],
    kappa: [f32; N],
    /// wᵢ, 0 for an empty lane.
    weight: [f32; N],
    /// wᵢ·C(κᵢ), 0 for an empty lane.
    scale: [f32; N],
}

impl<const N: usize> Default for VmfLanes<N> {
    fn default() -> Self {
        Self::EMPTY
    }
}

impl<const N: usize> VmfLanes<N> {
    /// Every lane empty (weight 0, the uniform lobe): density 0 everywhere.
    pub const EMPTY: Self = Self {
        mu_x: [0.0; N],
        mu_y: [0.0; N],
        mu_z: [1.0; N],
        kappa: [0.0; N],
        weight: [0.0; N],
        scale: [0.0; N],
    };

    /// Empties every lane: `self` becomes [`EMPTY`](Self::EMPTY), written array by array
    /// (assigning the constant copies it from memory, a `memcpy` call for eight lanes).
    #[inline]
    pub fn clear(&mut self) {
        self.mu_x = [0.0; N];
        self.mu_y = [0.0; N];
        self.mu_z = [1.0; N];
        self.kappa = [0.0; N];
        self.weight = [0.0; N];
        self.scale = [0.0; N];
    }

    /// Puts `lobe` with mixture weight `weight` into lane `i`. A weight that is not finite and
    /// positive (0, negative, NaN, ∞) empties the lane.
    ///
    /// # Panics
    /// If `i ≥ N`.
    #[inline]
    pub fn set(&mut self, i: usize, lobe: &Vmf, weight: f32) {
        let mu = lobe.mu();
        let ok = weight > 0.0 && weight.is_finite();
        self.mu_x[i] = mu.x;
        self.mu_y[i] = mu.y;
        self.mu_z[i] = mu.z;
        self.kappa[i] = lobe.kappa();
        self.weight[i] = if ok { weight } else { 0.0 };
        self.scale[i] = self.weight[i] * normalization_lane(lobe.kappa());
    }

    /// The lobes [`SufficientStats::to_vmf`] builds at `x`, each multiplied by `product`
    /// ([`Vmf::product_lobe`]) when given, with mixture weights: `lane(i)` gives lane `i`'s
    /// statistics, prior and weight (called once per lane, into [`LobeInputs`]). What a guide that
    /// reconstructs every accessed state's lobe at a shading point (MCPG Alg. 2 lines 6-8,
    /// with Open PGL's cosine product) does per vertex, in one pass over the lanes. Lanes
    /// whose `to_vmf` gives `None` (empty statistics, ȳ at `x`) or whose weight is not finite
    /// and positive stay empty.
    ///
    /// μ and κ of every lane are bit-identical to the scalar path's (`to_vmf` then
    /// `product_lobe`): the lane pass does the same operations in the same order, with
    /// selects for branches; a lane whose |ȳ − x|² leaves the normal range, where `to_vmf`
    /// rescales first, is redone by the scalar path.
    #[inline]
    #[must_use]
    pub fn from_stats(
        x: Vec3,
        product: Option<&Vmf>,
        lane: impl Fn(usize) -> (SufficientStats, MapPrior, f32),
    ) -> Self {
        let mut out = Self::EMPTY;
        out.set_from_stats(x, product, lane);
        out
    }

    /// [`from_stats`](Self::from_stats) written over `self`: every lane is overwritten (the
    /// previous contents do not matter), with the same lanes bit for bit. For a caller that
    /// keeps its lanes in a larger value, so that the lanes are built where they live instead
    /// of being returned and copied.
    #[inline]
    pub fn set_from_stats(
        &mut self,
        x: Vec3,
        product: Option<&Vmf>,
        lane: impl Fn(usize) -> (SufficientStats, MapPrior, f32),
    ) {
        // Gather the lanes' inputs (the fields of the statistics, the posterior's parts and
        // the weights) into arrays, then do the arithmetic over whole lanes.
        let mut inputs = LobeInputs::EMPTY;
        for i in 0..N {
            let (s, prior, weight) = lane(i);
            inputs.set(i, &s, x, prior, weight);
        }
        self.set_from_inputs(&inputs, product);
    }

    /// The lobes of `inputs` (see [`LobeInputs`]), each multiplied by `product`
    /// ([`Vmf::product_lobe`]) when given, with their weights: every lane of `self` is
    /// overwritten. μ and κ of every lane are bit-identical to [`SufficientStats::to_vmf`]'s
    /// (then `product_lobe`'s) for the statistics and prior the lane's inputs come from (see
    /// [`from_stats`](Self::from_stats)); a lane whose |ȳ − x|² leaves the normal range is
    /// redone by the scalar path.
    #[inline]
    pub fn set_from_inputs(&mut self, inputs: &LobeInputs<N>, product: Option<&Vmf>) {
        match product {
            Some(p) => self.lobes_from_inputs::<true>(inputs, p),
            None => self.lobes_from_inputs::<false>(inputs, &Vmf::uniform()),
        }
        // A lane marked by a negative weight has |ȳ − x|² outside the normal range: `to_vmf`'s
        // μ (`normalize_robust`, which rescales) with the same κ.
        for i in 0..N {
            if self.weight[i] < 0.0 {
                self.set(i, &Vmf::uniform(), 0.0);
                let d = Vec3::new(inputs.offset_x[i], inputs.offset_y[i], inputs.offset_z[i]);
                if let Some(mu) = math::normalize_robust(d) {
                    let kappa = kappa_lane(
                        inputs.n_eff[i],
                        inputs.prior_weight[i],
                        inputs.prior_complement[i],
                        inputs.one_minus_mean_cosine[i],
                    );
                    let lobe = Vmf::from_unit_mean(mu, kappa);
                    let lobe = product.map_or(lobe, |p| lobe.product_lobe(p));
                    self.set(i, &lobe, inputs.weight[i]);
                }
            }
        }
    }

    /// The lanes from `inputs`: μ from the offsets ȳ − x, κ from the posterior's parts
    /// (N_eff, N_p, 1 − r_p, 1 − r̄), times `product` when `PRODUCT`, and the scales. A lane
    /// whose |ȳ − x|² leaves the normal range gets the negated weight (the caller redoes it by
    /// the scalar path). Writes every lane of `self`.
    #[inline(always)]
    fn lobes_from_inputs<const PRODUCT: bool>(&mut self, inputs: &LobeInputs<N>, product: &Vmf) {
        let LobeInputs {
            offset_x: dx,
            offset_y: dy,
            offset_z: dz,
            n_eff,
            prior_weight,
            prior_complement,
            one_minus_mean_cosine: sample,
            weight,
        } = inputs;
        for i in 0..N {
            let d = Vec3::new(dx[i], dy[i], dz[i]);
            let l2 = d.length_squared();
            // `to_vmf`'s `normalize_robust` is `try_normalize` (d · 1/|d|) in this range.
            let fast = (f32::MIN_POSITIVE..=f32::MAX).contains(&l2);
            let mu = d * (1.0 / math::sqrt(l2));
            let kappa = kappa_lane(n_eff[i], prior_weight[i], prior_complement[i], sample[i]);
            let (mu, k) = if PRODUCT {
                product_lane(mu, kappa, product)
            } else {
                (mu, kappa)
            };
            // `&`, not `&&`: compares and no branches.
            let w = weight[i];
            let w = if (w > 0.0) & (w < f32::INFINITY) {
                w
            } else {
                0.0
            };
            let w = if fast { w } else { -w };
            self.mu_x[i] = mu.x;
            self.mu_y[i] = mu.y;
            self.mu_z[i] = mu.z;
            self.kappa[i] = k;
            self.weight[i] = w;
            self.scale[i] = w * normalization_lane(k);
        }
    }

    /// The lobe in lane `i` (the uniform lobe for a lane never set).
    ///
    /// # Panics
    /// If `i ≥ N`.
    #[inline]
    #[must_use]
    pub fn lobe(&self, i: usize) -> Vmf {
        Vmf::from_unit_mean(
            Vec3::new(self.mu_x[i], self.mu_y[i], self.mu_z[i]),
            self.kappa[i],
        )
    }

    /// Lane `i`'s mixture weight wᵢ (0 for an empty lane).
    ///
    /// # Panics
    /// If `i ≥ N`.
    #[inline]
    #[must_use]
    pub fn weight(&self, i: usize) -> f32 {
        self.weight[i]
    }

    /// `true` when lane `i` carries weight.
    ///
    /// # Panics
    /// If `i ≥ N`.
    #[inline]
    #[must_use]
    pub fn is_set(&self, i: usize) -> bool {
        self.weight[i] > 0.0
    }

    /// The mixture density Σᵢ wᵢ V(ω | μᵢ, κᵢ) at unit `w`, per steradian (MCPG eq. 4 per
    /// lane: C(κ) e^{−κ|ω − μ|²/2}, the form of [`Vmf::pdf`]). NaN in `w` gives NaN when any
    /// lane is set.
    #[inline]
    #[must_use]
    pub fn pdf(&self, w: Vec3) -> f32 {
        let mut terms = [0.0_f32; N];
        for (i, t) in terms.iter_mut().enumerate() {
            let (dx, dy, dz) = (w.x - self.mu_x[i], w.y - self.mu_y[i], w.z - self.mu_z[i]);
            let d2 = (dx * dx + dy * dy + dz * dz).min(f32::MAX);
            let exponent = (-0.5 * self.kappa[i] * d2).max(EXP_FLOOR);
            *t = self.scale[i] * math::exp_expm1_fast(exponent).0;
        }
        terms.iter().sum()
    }
}

/// κ of `to_vmf`: Banerjee's κ (`kappa_from_one_minus_mean_cosine`) of the posterior
/// complement (N_eff (1 − r̄) + N_p (1 − r_p)) / (N_eff + N_p)
/// (`posterior_one_minus_mean_cosine`), the same operations with the branches as selects.
#[inline(always)]
fn kappa_lane(n_eff: f32, prior_weight: f32, prior_complement: f32, sample: f32) -> f32 {
    let total = n_eff + prior_weight;
    let e = (n_eff * sample.clamp(0.0, 1.0) + prior_weight * prior_complement) / total;
    let e = if total > 0.0 { e } else { 1.0 };
    let e = if prior_weight == f32::INFINITY {
        prior_complement
    } else {
        e
    };
    let r = 1.0 - e;
    let kappa = (r * (3.0 - r * r) / (e * (2.0 - e))).min(KAPPA_MAX);
    let kappa = if e > 0.0 { kappa } else { KAPPA_MAX };
    if e < 1.0 { kappa } else { 0.0 }
}

/// [`Vmf::product_lobe`] of the lobe (μ, κ) with `other`, the same operations in the same order
/// with its branches as selects (bit-identical results).
#[inline(always)]
fn product_lane(mu: Vec3, kappa: f32, other: &Vmf) -> (Vec3, f32) {
    let m = mu * kappa + other.mu() * other.kappa();
    let length = m.length();
    let unit = if length > 0.0 { m / length } else { mu };
    let rcp = 1.0 / unit.length();
    // `rcp.is_finite() && rcp > 0.0` of `try_normalize`, as two compares (LLVM lowers
    // `is_finite` to integer class tests).
    let unit = if (rcp > 0.0) & (rcp < f32::INFINITY) {
        unit * rcp
    } else {
        mu
    };
    (unit, length)
}

/// C(κ) of [`Vmf::normalization`] in branch-free form: g(−2κ)/(4π) with g(x) = x/expm1(x)
/// from the polynomial `expm1` at or below κ = [`KAPPA_SATURATED`], κ/(2π) above it (where
/// e^{−2κ} < 2⁻²⁵ vanishes next to 1, as in the scalar form). A few ulps from the scalar
/// value below the switch, the same value above it.
#[inline(always)]
fn normalization_lane(kappa: f32) -> f32 {
    let x = (-2.0 * kappa).max(-2.0 * KAPPA_SATURATED);
    let expm1 = math::exp_expm1_fast(x).1;
    let g = if x == 0.0 { 1.0 } else { x / expm1 };
    if kappa > KAPPA_SATURATED {
        kappa * (0.5 * core::f32::consts::FRAC_1_PI)
    } else {
        g * UNIFORM_SPHERE_PDF
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The lane form of C(κ) is within 4·10⁻⁷ relative of the scalar one (about 3 ulps) on a
    /// dense grid of κ over [0, 10⁶] with the switch at κ = 9 on both sides.
    #[test]
    fn normalization_matches_the_scalar_form() {
        let mut kappas = std::vec![0.0, 1e-30, 1e-7, 0.3465, 0.3466, 8.999_999, 9.0, 9.000_001];
        let mut k = 1e-6_f32;
        while k < 1e6 {
            kappas.push(k);
            k *= 1.01;
        }
        for kappa in kappas {
            let want = crate::vmf::normalization(kappa);
            let got = normalization_lane(kappa);
            mcg_test_support::assert_close!(got, want, 4e-7 * want, "kappa {kappa}");
        }
    }

    /// The lane mixture equals Σ wᵢ Vmf::pdf to 10⁻⁶ relative (plus 10⁻³⁰ absolute for the
    /// far tails the floor of the `exp` clamps) for lobes from uniform to κ = 10⁶, directions
    /// at the peak, in the tails and opposite, and with empty and zero-weight lanes.
    #[test]
    fn pdf_is_the_weighted_mixture() {
        let kappas = [0.0, 1e-4, 0.2, 2.0, 9.0, 40.0, 3e3, 1e6];
        let mut lanes = VmfLanes::<8>::EMPTY;
        let mut lobes = std::vec::Vec::new();
        for (i, &kappa) in kappas.iter().enumerate() {
            let mu = Vec3::new(0.3 * i as f32 - 1.0, 0.5, 0.2 + 0.1 * i as f32);
            let lobe = Vmf::new(mu, kappa).unwrap();
            let weight = if i == 5 { 0.0 } else { 0.05 + 0.1 * i as f32 };
            lanes.set(i, &lobe, weight);
            assert_eq!(lanes.lobe(i), lobe);
            assert_eq!(lanes.is_set(i), weight > 0.0);
            lobes.push((lobe, weight));
        }
        let mut directions: std::vec::Vec<Vec3> = lobes.iter().map(|(l, _)| l.mu()).collect();
        for i in 0..64 {
            let t = i as f32 * 0.7;
            directions.push(Vec3::new(t.cos(), (0.3 * t).sin(), t.sin()).normalize());
        }
        for w in directions {
            for n in [1, 3, 8] {
                let mut part = VmfLanes::<8>::EMPTY;
                for (i, (lobe, weight)) in lobes.iter().enumerate().take(n) {
                    part.set(i, lobe, *weight);
                }
                let want: f32 = lobes.iter().take(n).map(|(l, wt)| wt * l.pdf(w)).sum();
                let got = part.pdf(w);
                mcg_test_support::assert_close!(got, want, 1e-6 * want + 1e-30, "{w} {n}");
            }
        }
        assert_eq!(VmfLanes::<4>::EMPTY.pdf(Vec3::Z), 0.0);
    }

    /// `from_stats` gives the scalar path's lobes bit for bit (μ, κ) and its normalisation to
    /// 4·10⁻⁷: 4096 random statistics seen from random points, with and without the product,
    /// plus the edge cases (N = 0, w̄ = 0, ȳ at x, ȳ far enough that |ȳ − x|² overflows or
    /// near enough that it underflows, an infinite prior, weights 0 and NaN). `set_from_stats`
    /// over earlier lanes gives `from_stats`' bits.
    #[test]
    fn from_stats_equals_the_scalar_lobes() {
        let mut state = 0x9e37_79b9_u32;
        let mut next = || {
            state = state.wrapping_mul(747_796_405).wrapping_add(2_891_336_453);
            (state >> 8) as f32 / (1u32 << 24) as f32
        };
        let cosine = Vmf::clamped_cosine(Vec3::new(0.1, 1.0, -0.2)).unwrap();
        let bits = |l: &VmfLanes<8>| {
            [l.mu_x, l.mu_y, l.mu_z, l.kappa, l.weight, l.scale].map(|a| a.map(f32::to_bits))
        };
        let mut reused = VmfLanes::<8>::EMPTY;
        reused.set(3, &cosine, 0.5);
        let mut cases = 0;
        for round in 0..512 {
            let x = Vec3::new(next(), next(), next()) * 4.0 - 2.0;
            let mut stats = [SufficientStats::EMPTY; 8];
            let mut priors = [MapPrior::NONE; 8];
            let mut weights = [0.0; 8];
            for i in 0..8 {
                let target = Vec3::new(next(), next(), next()) * 6.0 - 3.0;
                stats[i] = SufficientStats {
                    mean_target: match (round + i) % 23 {
                        0 => x,
                        1 => x + Vec3::new(1e-24, 0.0, 0.0),
                        2 => Vec3::new(3e19, -1e19, 2e19),
                        _ => target,
                    },
                    weight_sum: if (round + i) % 17 == 3 {
                        0.0
                    } else {
                        next() * 5.0
                    },
                    one_minus_mean_cosine: next().powi(3) * 1.5,
                    sample_count: if (round + i) % 19 == 4 {
                        0
                    } else {
                        1 + (next() * 40.0) as u32
                    },
                };
                priors[i] =
                    MapPrior::inverse_square_distance(0.3, 1e-4, stats[i].target_distance(x));
                weights[i] = match (round + i) % 13 {
                    5 => 0.0,
                    6 => f32::NAN,
                    _ => next(),
                };
            }
            for product in [None, Some(&cosine)] {
                let lanes =
                    VmfLanes::<8>::from_stats(x, product, |i| (stats[i], priors[i], weights[i]));
                // Written over the previous round's lanes: the same bits.
                reused.set_from_stats(x, product, |i| (stats[i], priors[i], weights[i]));
                assert_eq!(bits(&reused), bits(&lanes), "round {round}");
                for i in 0..8 {
                    let want = stats[i]
                        .to_vmf(x, priors[i])
                        .map(|l| product.map_or(l, |p| l.product_lobe(p)))
                        .filter(|_| weights[i] > 0.0 && weights[i].is_finite());
                    match want {
                        Some(lobe) => {
                            cases += 1;
                            assert!(lanes.is_set(i), "round {round} lane {i}");
                            assert_eq!(lanes.lobe(i), lobe, "round {round} lane {i}");
                            let scale = weights[i] * lobe.normalization();
                            mcg_test_support::assert_close!(lanes.scale[i], scale, 4e-7 * scale);
                        }
                        None => assert!(!lanes.is_set(i), "round {round} lane {i}"),
                    }
                }
            }
        }
        assert!(cases > 5000, "{cases}");
    }

    #[test]
    fn weights_that_are_not_positive_and_finite_empty_the_lane() {
        let lobe = Vmf::new(Vec3::Z, 5.0).unwrap();
        for weight in [0.0, -1.0, f32::NAN, f32::INFINITY] {
            let mut lanes = VmfLanes::<2>::EMPTY;
            lanes.set(1, &lobe, weight);
            assert!(!lanes.is_set(1));
            assert_eq!(lanes.pdf(Vec3::Z), 0.0);
        }
    }
}
