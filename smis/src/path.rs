//! The path form of SMIS/MMIS: a product over path vertices of a sum over each vertex's
//! technique set (MCPG eq. 6, MMIS eq. 14), in time linear in the number of vertices.

use crate::technique::{Technique, pdf_sum, ratio, saturate};

/// The most vertices [`path_pdf_naive`] enumerates (its combination counter lives on the stack).
pub const MAX_NAIVE_PATH_VERTICES: usize = 16;

/// Π_v Σ_{s ∈ S_v} p(x_v | s): the SMIS denominator of a path x̄ = (x₁ … x_k) whose vertex v was
/// sampled from one technique of the set S_v (MCPG eq. 6; the reorganised MMIS eq. 14).
///
/// Expanding the product gives MMIS eq. 14's sum over all Π_v |S_v| combinations of one
/// technique per vertex of the product of their conditional densities — exponential in k when
/// evaluated as written ([`path_pdf_naive`]), linear here: Σ_v |S_v| pdf evaluations and
/// k − 1 multiplications.
///
/// `vertex_sets[v]` is the set S_v that vertex `vertices[v]` was sampled from; each set's
/// techniques already carry their conditioning (the previous vertex, the accessed Markov chain
/// states). For the density of the path as sampled — one technique of each set chosen
/// uniformly — use [`path_mixture_pdf`]; MCPG's eq. 6 writes the sum without the 1/|S_v|
/// factors, which only rescales the estimate by the constant Π_v |S_v|.
///
/// The product is formed in f32 and saturates at `f32::MAX` where the densities' product
/// exceeds 3.4·10³⁸ (so finite densities give a finite result). An empty path gives 1.
///
/// # Panics
/// If `vertex_sets` and `vertices` differ in length.
#[inline]
#[must_use]
pub fn path_pdf<T: Technique>(vertex_sets: &[&[T]], vertices: &[T::Sample]) -> f32 {
    assert_eq!(
        vertex_sets.len(),
        vertices.len(),
        "one technique set per vertex"
    );
    vertex_sets
        .iter()
        .zip(vertices)
        .map(|(set, x)| pdf_sum(set, x))
        .fold(1.0, |p, s| saturate(p * s))
}

/// Π_v (1/|S_v|) Σ_{s ∈ S_v} p(x_v | s): the density of a path whose vertex v was drawn from a
/// technique of S_v chosen uniformly (MCMM eq. 9 at every vertex; the path form of MCPG eq. 6
/// with its sums normalised). Linear in the number of vertices; an empty set makes it 0.
///
/// # Panics
/// If `vertex_sets` and `vertices` differ in length.
#[inline]
#[must_use]
pub fn path_mixture_pdf<T: Technique>(vertex_sets: &[&[T]], vertices: &[T::Sample]) -> f32 {
    assert_eq!(
        vertex_sets.len(),
        vertices.len(),
        "one technique set per vertex"
    );
    vertex_sets
        .iter()
        .zip(vertices)
        .map(|(set, x)| {
            if set.is_empty() {
                0.0
            } else {
                pdf_sum(set, x) / set.len() as f32
            }
        })
        .fold(1.0, |p, s| saturate(p * s))
}

/// The one-sample path estimate f(x̄) / [`path_mixture_pdf`] (MCPG eq. 6 with uniform choice of
/// one technique per vertex); 0 where the density is 0 or overflows.
#[inline]
#[must_use]
pub fn path_estimate<T: Technique>(
    value: f32,
    vertex_sets: &[&[T]],
    vertices: &[T::Sample],
) -> f32 {
    ratio(value, path_mixture_pdf(vertex_sets, vertices))
}

/// Reference for [`path_pdf`]: MMIS eq. 14 as written, the sum over every combination
/// (s₁ ∈ S₁, …, s_k ∈ S_k) of Π_v p(x_v | s_v), accumulated in f32.
///
/// Costs k · Π_v |S_v| pdf evaluations — exponential in k. It exists for tests and benchmarks
/// that show the linear form equals it; never call it in a renderer.
///
/// # Panics
/// If `vertex_sets` and `vertices` differ in length or there are more than
/// [`MAX_NAIVE_PATH_VERTICES`] vertices.
#[must_use]
pub fn path_pdf_naive<T: Technique>(vertex_sets: &[&[T]], vertices: &[T::Sample]) -> f32 {
    let k = vertices.len();
    assert_eq!(vertex_sets.len(), k, "one technique set per vertex");
    assert!(
        k <= MAX_NAIVE_PATH_VERTICES,
        "the naive path form enumerates at most 16 vertices"
    );
    if vertex_sets.iter().any(|s| s.is_empty()) {
        return 0.0;
    }
    let mut choice = [0_usize; MAX_NAIVE_PATH_VERTICES];
    let mut sum = 0.0_f32;
    loop {
        let mut product = 1.0_f32;
        for v in 0..k {
            product = saturate(product * vertex_sets[v][choice[v]].pdf(&vertices[v]));
        }
        sum = saturate(sum + product);
        // Advance the mixed-radix counter; stop after the last combination.
        let mut v = 0;
        loop {
            if v == k {
                return sum;
            }
            choice[v] += 1;
            if choice[v] < vertex_sets[v].len() {
                break;
            }
            choice[v] = 0;
            v += 1;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::technique::tests::Boxcar;

    fn sets() -> ([Boxcar; 2], [Boxcar; 3], [Boxcar; 1]) {
        (
            [Boxcar { a: 0.0, w: 1.0 }, Boxcar { a: 0.0, w: 0.5 }],
            [
                Boxcar { a: 0.0, w: 1.0 },
                Boxcar { a: 0.25, w: 0.5 },
                Boxcar { a: 0.2, w: 0.25 },
            ],
            [Boxcar { a: 0.0, w: 0.125 }],
        )
    }

    #[test]
    fn linear_equals_naive() {
        let (a, b, c) = sets();
        let vs: [&[Boxcar]; 3] = [&a, &b, &c];
        let xs = [0.3_f32, 0.3, 0.1];
        // (1 + 2)(1 + 2 + 4)(8)
        assert_eq!(path_pdf(&vs, &xs), 168.0);
        assert_eq!(path_pdf_naive(&vs, &xs), 168.0);
        assert_eq!(path_mixture_pdf(&vs, &xs), 168.0 / 6.0);
        assert_eq!(path_estimate(28.0, &vs, &xs), 1.0);
    }

    #[test]
    fn edge_cases() {
        let none: [&[Boxcar]; 0] = [];
        assert_eq!(path_pdf(&none, &[]), 1.0);
        assert_eq!(path_pdf_naive(&none, &[]), 1.0);
        let (a, ..) = sets();
        let empty: [Boxcar; 0] = [];
        let vs: [&[Boxcar]; 2] = [&a, &empty];
        assert_eq!(path_pdf(&vs, &[0.1, 0.1]), 0.0);
        assert_eq!(path_pdf_naive(&vs, &[0.1, 0.1]), 0.0);
        assert_eq!(path_mixture_pdf(&vs, &[0.1, 0.1]), 0.0);
        assert_eq!(path_estimate(1.0, &vs, &[0.1, 0.1]), 0.0);
        // Overflowing product: saturates at f32::MAX (was +∞), the estimate is ~0, not NaN.
        let tiny = [Boxcar { a: 0.0, w: 1e-30 }];
        let vs: [&[Boxcar]; 2] = [&tiny, &tiny];
        assert_eq!(path_pdf(&vs, &[0.0, 0.0]), f32::MAX);
        assert_eq!(path_pdf_naive(&vs, &[0.0, 0.0]), f32::MAX);
        assert_eq!(path_mixture_pdf(&vs, &[0.0, 0.0]), f32::MAX);
        assert_eq!(path_estimate(1.0, &vs, &[0.0, 0.0]), 1.0 / f32::MAX);
    }

    #[test]
    fn value_stability() {
        let (a, b, _) = sets();
        let vs: [&[Boxcar]; 2] = [&a, &b];
        assert_eq!(path_pdf(&vs, &[0.7, 0.5]), 1.0 * 3.0);
        assert_eq!(path_mixture_pdf(&vs, &[0.7, 0.5]), 0.5 * 1.0);
    }
}
