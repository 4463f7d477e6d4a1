//! The linear-time path form (MCPG eq. 6; MMIS eq. 14 reorganised as a product of sums) equals
//! the naive sum over all technique combinations, and both match an f64 reference.
//!
//! Paths of k = 1…6 vertices on S², each vertex with a set of 1…5 vMF lobes (κ up to 200, so
//! densities span many orders of magnitude) as `SphereTechnique`s. Deterministic sweep (fixed
//! seed) plus a proptest over random sets; relative tolerance 2·10⁻⁵ between the two f32 forms
//! (both accumulate k·Πₙ rounding errors of about 6·10⁻⁸) and 10⁻⁴ against f64.

use mcg_smis::{Technique, path_mixture_pdf, path_pdf, path_pdf_naive};
use mcg_tests::{SphereTechnique, seeded_rng, uniform2, vmf_pdf};
use mcg_vmf::Vmf;
use mcg_vmf::glam::{Vec2, Vec3};
use proptest::prelude::*;

mod support;
use rand::RngExt;

fn lobe(mu: Vec3, kappa: f32) -> SphereTechnique {
    SphereTechnique::Lobe {
        vmf: Vmf::new(mu, kappa).unwrap(),
        eps: 0.0,
    }
}

/// Π_v Σ_s p(x_v | s) in f64 from the reference vMF density.
fn reference(sets: &[Vec<SphereTechnique>], xs: &[Vec3]) -> f64 {
    sets.iter()
        .zip(xs)
        .map(|(set, x)| {
            set.iter()
                .map(|t| match t {
                    SphereTechnique::Lobe { vmf, .. } => {
                        vmf_pdf(vmf.mu().as_dvec3(), f64::from(vmf.kappa()), x.as_dvec3())
                    }
                    _ => unreachable!(),
                })
                .sum::<f64>()
        })
        .product()
}

fn check(sets: &[Vec<SphereTechnique>], xs: &[Vec3]) -> Result<(), String> {
    let refs: Vec<&[SphereTechnique]> = sets.iter().map(Vec::as_slice).collect();
    let linear = path_pdf(&refs, xs);
    let naive = path_pdf_naive(&refs, xs);
    let exact = reference(sets, xs);
    let rel = |a: f64, b: f64| (a - b).abs() / b.abs().max(1e-300);
    if rel(f64::from(linear), f64::from(naive)) > 2e-5 {
        return Err(format!("linear {linear:e} vs naive {naive:e}"));
    }
    if rel(f64::from(linear), exact) > 1e-4 {
        return Err(format!("linear {linear:e} vs f64 {exact:e}"));
    }
    let count: usize = sets.iter().map(Vec::len).product();
    let mixture = path_mixture_pdf(&refs, xs);
    if rel(f64::from(mixture) * count as f64, f64::from(linear)) > 2e-5 {
        return Err(format!("mixture {mixture:e} · {count} vs {linear:e}"));
    }
    Ok(())
}

#[test]
fn linear_equals_naive_for_one_to_six_vertices() {
    let mut rng = seeded_rng(0x531A_0001);
    for k in 1..=6 {
        for _ in 0..200 {
            let mut sets = Vec::with_capacity(k);
            let mut xs = Vec::with_capacity(k);
            for _ in 0..k {
                let n = rng.random_range(1..=5);
                let set: Vec<SphereTechnique> = (0..n)
                    .map(|_| {
                        let mu = SphereTechnique::Uniform.sample(uniform2(&mut rng));
                        lobe(mu, 200.0_f32.powf(rng.random::<f32>()) - 1.0)
                    })
                    .collect();
                // The vertex is sampled from one of its set's lobes, as in a path tracer.
                let j = rng.random_range(0..n);
                xs.push(set[j].sample(uniform2(&mut rng)));
                sets.push(set);
            }
            check(&sets, &xs).unwrap_or_else(|e| panic!("k = {k}: {e}"));
        }
    }
}

fn arb_set() -> impl Strategy<Value = Vec<SphereTechnique>> {
    proptest::collection::vec(
        (0.0_f32..1.0, 0.0_f32..1.0, 0.0_f32..100.0).prop_map(|(a, b, kappa)| {
            lobe(SphereTechnique::Uniform.sample(Vec2::new(a, b)), kappa)
        }),
        1..5,
    )
}

proptest! {
    #![proptest_config(support::proptest_config(256, 0x7E57_0004))]
    #[test]
    fn linear_equals_naive_property(
        sets in proptest::collection::vec(arb_set(), 1..6),
        picks in proptest::collection::vec((0.0_f32..1.0, 0.0_f32..1.0, 0.0_f32..1.0), 6),
    ) {
        let xs: Vec<Vec3> = sets
            .iter()
            .zip(&picks)
            .map(|(set, &(s, a, b))| {
                let j = ((s * set.len() as f32) as usize).min(set.len() - 1);
                set[j].sample(Vec2::new(a, b))
            })
            .collect();
        prop_assert!(check(&sets, &xs).is_ok(), "{:?}", check(&sets, &xs));
    }
}
