//! Weighted reservoir sampling in one pass (Chao 1982), the resampling step of MCMM Alg. 1 and
//! MCPG Alg. 1.

/// A one-item weighted reservoir: after candidates with weights w₁ … w_m have been offered,
/// candidate i is held with probability wᵢ / Σ w (Chao 1982, *A general purpose unequal
/// probability sampling plan*), using one caller uniform per candidate.
///
/// Weights that are NaN, infinite or negative count as 0: such a candidate is never selected
/// and does not change the sum. The sum saturates at `f32::MAX` instead of overflowing to +∞
/// (a finite sum beyond that is not representable; a candidate offered after the sum has
/// saturated is kept with probability w / `f32::MAX`), so every positive weight stays
/// selectable.
///
/// # Example
/// ```
/// use mcg_markov_guide::Reservoir;
/// let mut r = Reservoir::new();
/// r.offer('a', 1.0, 0.3);
/// r.offer('b', 3.0, 0.5); // kept: 0.5 < 3/4
/// r.offer('c', 0.0, 0.0); // zero weight: never kept
/// assert_eq!(r.selected(), Some(&'b'));
/// assert_eq!(r.weight_sum(), 4.0);
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Reservoir<T> {
    selected: Option<T>,
    weight_sum: f32,
}

impl<T> Default for Reservoir<T> {
    fn default() -> Self {
        Self::new()
    }
}

impl<T> Reservoir<T> {
    /// An empty reservoir.
    #[inline]
    #[must_use]
    pub const fn new() -> Self {
        Self {
            selected: None,
            weight_sum: 0.0,
        }
    }

    /// Offers `candidate` with weight `weight`; it replaces the held item when
    /// `u · Σw < weight` (MCPG Alg. 1 lines 8-11). Returns whether it was taken.
    #[inline]
    pub fn offer(&mut self, candidate: T, weight: f32, u: f32) -> bool {
        let weight = crate::math::finite_non_negative_or_zero(weight);
        // Saturates at f32::MAX (a no-op below it): a sum of +∞ would make every later
        // candidate unselectable.
        self.weight_sum = (self.weight_sum + weight).min(f32::MAX);
        // Weight 0 is never taken.
        let take = weight > 0.0 && u * self.weight_sum < weight;
        if take {
            self.selected = Some(candidate);
        }
        take
    }

    /// The held item, if any candidate with positive weight was offered.
    #[inline]
    #[must_use]
    pub const fn selected(&self) -> Option<&T> {
        self.selected.as_ref()
    }

    /// Σ w over all offered candidates (`sum_mc` of MCPG Alg. 1).
    #[inline]
    #[must_use]
    pub const fn weight_sum(&self) -> f32 {
        self.weight_sum
    }

    /// The held item and the weight sum.
    #[inline]
    #[must_use]
    pub fn into_parts(self) -> (Option<T>, f32) {
        (self.selected, self.weight_sum)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn selection_frequencies_follow_weights_exactly_on_a_grid() {
        // With u on a fine stratified grid per step, the selection probabilities are exact
        // up to the grid resolution: enumerate all (u1, u2, u3) on a 60³ grid.
        let weights = [1.0_f32, 2.0, 3.0];
        let n = 60;
        let mut counts = [0u32; 3];
        for a in 0..n {
            for b in 0..n {
                for c in 0..n {
                    let us = [a, b, c].map(|k| (k as f32 + 0.5) / n as f32);
                    let mut r = Reservoir::new();
                    for i in 0..3 {
                        r.offer(i, weights[i], us[i]);
                    }
                    counts[*r.selected().unwrap()] += 1;
                }
            }
        }
        let total = (n * n * n) as f32;
        for i in 0..3 {
            let p = counts[i] as f32 / total;
            mcg_test_support::assert_close!(p, weights[i] / 6.0, 0.01, "{i}: {p}");
        }
    }

    #[test]
    fn huge_weights_saturate_the_sum() {
        // Issue 14 row 10: two offers of f32::MAX made the sum +∞ and nothing selectable.
        let mut r = Reservoir::new();
        assert!(r.offer(0, f32::MAX, 0.9));
        assert!(r.offer(1, f32::MAX, 0.5));
        assert_eq!(r.weight_sum(), f32::MAX);
        assert!(r.offer(2, f32::MAX, 0.25));
        assert!(!r.offer(3, f32::MAX, 1.0));
        assert_eq!(r.selected(), Some(&2));
        assert_eq!(r.weight_sum(), f32::MAX);
    }

    #[test]
    fn bad_weights_are_ignored() {
        let mut r = Reservoir::new();
        assert!(r.offer(1, 1.0, 0.9));
        for bad in [f32::NAN, -2.0, f32::INFINITY, 0.0] {
            assert!(!r.offer(2, bad, 0.0));
        }
        assert_eq!(r.into_parts(), (Some(1), 1.0));
        let empty: Reservoir<u8> = Reservoir::new();
        assert_eq!(empty.selected(), None);
    }
}
