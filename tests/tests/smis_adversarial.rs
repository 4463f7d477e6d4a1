//! Adversarial properties of mcg-smis: every public function called with techniques whose
//! finite densities range from 0 through subnormals to `f32::MAX`, with NaN, ±∞ and huge
//! values, `u32::MAX` sample counts, out-of-range uniforms and every tile size and mask.
//!
//! Asserted: no panic except the documented ones (mismatched lengths, empty sets, tiles of
//! the wrong size — never provoked here); densities, denominators and estimates are finite
//! for finite input (sums and products of huge densities saturate at `f32::MAX`); estimates
//! are finite for any input. CI runs this with overflow checks and debug assertions on
//! (`--profile ci`).
//!
//! Deterministic: 1024 cases from the fixed seed 0x7E57_00A3 (`support::proptest_config`).

use mcg_smis::{
    CyclicShift, Defensive, Mmis, SmisError, Technique, XorPermutation, balance_denominator,
    cyclic_source_lane, mis_balance, mixture_pdf, path_estimate, path_mixture_pdf, path_pdf,
    path_pdf_naive, pdf_sum, sample_uniform_mixture, select_uniform, smis, smis_one_sample,
    xor_source_lane,
};
use proptest::prelude::*;

mod support;
use support::{any_f32, any_u32, any_uniform, finite_f32};

/// A box density: `height` on [a, a + w), 0 elsewhere (not normalised: the estimators must
/// stay finite for any finite, non-negative density).
#[derive(Clone, Copy, Debug)]
struct Boxcar {
    a: f32,
    w: f32,
    height: f32,
}

impl Technique for Boxcar {
    type Sample = f32;
    type Uniform = f32;
    fn pdf(&self, x: &f32) -> f32 {
        if *x >= self.a && *x < self.a + self.w {
            self.height
        } else {
            0.0
        }
    }
    #[allow(clippy::manual_clamp)] // `clamp` would keep NaN
    fn sample(&self, u: f32) -> f32 {
        // `max` maps NaN to 0.
        self.a + self.w * u.max(0.0).min(1.0)
    }
}

fn boxcar() -> impl Strategy<Value = Boxcar> {
    (
        -1e30f32..1e30,
        prop_oneof![Just(f32::MIN_POSITIVE), 1e-6f32..1e30, 0.0f32..2.0],
        prop_oneof![
            Just(0.0f32),
            Just(f32::from_bits(1)),
            Just(f32::MAX),
            Just(1e38f32),
            0.0f32..10.0
        ],
    )
        .prop_map(|(a, w, height)| Boxcar { a, w, height })
}

fn set() -> impl Strategy<Value = Vec<Boxcar>> {
    proptest::collection::vec(boxcar(), 1..6)
}

fn finite_non_negative(x: f32) -> bool {
    x.is_finite() && x >= 0.0
}

proptest! {
    #![proptest_config(support::proptest_config(1024, 0x7E57_00A3))]

    #[test]
    fn densities_and_estimates_are_finite(
        set in set(), x in finite_f32(), value in finite_f32(), any_value in any_f32(),
        u in any_uniform(), counts in proptest::collection::vec(any_u32(), 6),
    ) {
        prop_assert!(finite_non_negative(pdf_sum(&set, &x)), "{}", pdf_sum(&set, &x));
        prop_assert!(finite_non_negative(mixture_pdf(&set, &x)));
        prop_assert!(pdf_sum::<Boxcar>(&[], &x) == 0.0 && mixture_pdf::<Boxcar>(&[], &x) == 0.0);
        let j = select_uniform(set.len(), u);
        prop_assert!(j < set.len());
        let (j, s) = sample_uniform_mixture(&set, u, u);
        prop_assert!(j < set.len() && s.is_finite());
        let samples: Vec<f32> = set.iter().map(|t| t.sample(u)).collect();
        let values = vec![value; set.len()];
        for v in [value, any_value] {
            prop_assert!(smis_one_sample(&set, &s, v).is_finite());
            prop_assert!(smis(&set, &samples, &vec![v; set.len()]).is_finite());
        }
        prop_assert!(smis(&set, &samples, &values).is_finite());
        let counts = &counts[..set.len()];
        let d = balance_denominator(&set, counts, &x);
        prop_assert!(finite_non_negative(d), "{d}");
        prop_assert!(mis_balance(&set, counts, &samples, &values).is_finite());
        prop_assert!(mis_balance(&set, counts, &samples, &vec![any_value; set.len()]).is_finite());
    }

    #[test]
    fn path_forms_are_finite(
        sets in proptest::collection::vec(set(), 0..5), u in any_uniform(),
        value in any_f32(),
    ) {
        let refs: Vec<&[Boxcar]> = sets.iter().map(|s| s.as_slice()).collect();
        let vertices: Vec<f32> = sets.iter().map(|s| s[0].sample(u)).collect();
        for p in [path_pdf(&refs, &vertices), path_mixture_pdf(&refs, &vertices), path_pdf_naive(&refs, &vertices)] {
            prop_assert!(finite_non_negative(p), "{p}");
        }
        prop_assert!(path_estimate(value, &refs, &vertices).is_finite());
    }

    #[test]
    fn mmis_is_finite(
        spaces in proptest::collection::vec(set(), 1..4), classical in set(),
        counts in proptest::collection::vec(0u32..3, 6), x in finite_f32(), value in any_f32(),
    ) {
        let refs: Vec<&[Boxcar]> = spaces.iter().map(|s| s.as_slice()).collect();
        let plain = Mmis::new(&refs);
        prop_assert!(finite_non_negative(plain.denominator(&x)));
        let counts = &counts[..classical.len()];
        let Ok(mixed) = plain.with_classical(&classical, counts) else {
            return Ok(());
        };
        prop_assert!(finite_non_negative(mixed.denominator(&x)));
        let n = mixed.sample_count();
        let samples = vec![x; n];
        prop_assert!(mixed.estimate(&samples, &vec![value; n]).is_finite());
    }

    #[test]
    fn defensive_mixtures_validate_and_stay_finite(
        classical in boxcar(), p in any_f32(), set in proptest::collection::vec(boxcar(), 0..4),
        u in (any_uniform(), any_uniform()), x in finite_f32(), value in any_f32(),
    ) {
        match Defensive::new(classical, p, &set) {
            Ok(d) => {
                let (j, s) = d.sample_with_index(u.0, u.1);
                prop_assert!(j.is_none_or(|j| j < set.len()) && s.is_finite());
                prop_assert!(finite_non_negative(d.pdf(&x)), "{}", d.pdf(&x));
                prop_assert!(d.estimate(&s, value).is_finite());
                prop_assert!(finite_non_negative(d.pdf(&d.sample((u.0, u.1)))));
            }
            Err(e) => { let expected = match e {
                SmisError::ProbabilityOutOfRange { probability } => {
                    !(0.0..=1.0).contains(&p) && probability.to_bits() == p.to_bits()
                }
                SmisError::EmptyTechniqueSet => set.is_empty(),
                _ => false,
            }; prop_assert!(expected, "{e:?}"); },
        }
    }

    #[test]
    fn permutations_stay_in_the_tile(size in any_u32(), mask in any_u32(), shift in any_u32(), lane in any_u32(), u in any_f32()) {
        let _ = xor_source_lane(lane, mask);
        if let Ok(p) = XorPermutation::new(size, mask) {
            prop_assert!(p.size() == size && p.mask() < size);
            if lane < size {
                prop_assert!(p.source(lane) < size);
            }
            if size <= 64 {
                let mut tile: Vec<u32> = (0..size).collect();
                p.apply(&mut tile);
                tile.sort_unstable();
                prop_assert!(tile.iter().copied().eq(0..size));
            }
        }
        if let Ok(p) = XorPermutation::from_uniform(size, u) {
            prop_assert!(p.mask() < size);
        }
        if size > 0 {
            let _ = cyclic_source_lane(lane, size, shift);
        }
        if let Ok(c) = CyclicShift::new(size, shift) {
            prop_assert!(c.size() == size && c.shift() < size);
            if lane < size {
                prop_assert!(c.source(lane) < size && c.destination(lane) < size);
                prop_assert_eq!(c.source(c.destination(lane)), lane);
            }
            if size <= 64 {
                let mut tile: Vec<u32> = (0..size).collect();
                c.apply(&mut tile);
                tile.sort_unstable();
                prop_assert!(tile.iter().copied().eq(0..size));
            }
        }
    }
}
