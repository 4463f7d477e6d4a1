//! False-match rate of the 32-bit checksum, measured as checksum collisions among distinct keys.
//!
//! A lookup confuses two keys when they share a probe window *and* a checksum; the second
//! event has probability 2⁻³² per pair for an ideal 32-bit checksum. Counting pairs of equal
//! checksums among n distinct keys (sort, then count equal neighbours per run, C(run, 2)) gives
//! an unbiased estimate of that per-pair probability: the count is ≈ Poisson with mean
//! λ = C(n, 2) · 2⁻³² (the birthday expectation n²/2 · 2⁻³²).
//!
//! What this can resolve: with n = 2²¹ structured keys (λ ≈ 512), a 5σ test (|count − λ| <
//! 5√λ ≈ 113) detects a checksum whose collision rate is off by more than ≈ 22 %, i.e. one
//! with fewer than ≈ 31.7 effective bits, or one that is structurally weak on grid keys (the
//! xor-of-primes checksum of MCPG would be tested the same way). What it cannot resolve: rates
//! for keys not like these (adversarial keys), and the per-lookup false-match probability of a
//! table directly (≈ probes · 2⁻³² ≈ 2·10⁻⁹ per lookup, far below anything a test can count).

use glam::IVec3;
use mcg_hashgrid::{CellKey, checksum, hash_fold, hash_mix};

/// 2²¹ distinct structured keys: a 128³ block of vertices (2²¹) spread over 8 levels and
/// 6 normal classes by coordinate parity, so the stream is planes, lines and levels at once.
fn keys() -> Vec<CellKey> {
    let mut keys = Vec::with_capacity(1 << 21);
    for z in 0..128 {
        for y in 0..128 {
            for x in 0..128 {
                let level = ((x ^ y ^ z) & 7) as u8;
                let class = ((x + 2 * y + 3 * z) % 6) as u8;
                keys.push(CellKey::new(
                    IVec3::new(x - 64, y - 64, z * 3),
                    level,
                    class,
                ));
            }
        }
    }
    keys
}

/// Pairs of equal values in `words` (sorted in place).
fn equal_pairs(words: &mut [u32]) -> u64 {
    words.sort_unstable();
    let mut pairs = 0_u64;
    let mut run = 1_u64;
    for i in 1..words.len() {
        if words[i] == words[i - 1] {
            run += 1;
        } else {
            pairs += run * (run - 1) / 2;
            run = 1;
        }
    }
    pairs + run * (run - 1) / 2
}

/// H₀: distinct keys share a checksum with probability 2⁻³²(1 + 2⁻³¹) per pair. n = 2²¹
/// keys (deterministic stream), λ = C(n, 2) · 2⁻³² ≈ 512, 5σ Poisson bound. (Measured: see
/// the printed count.)
#[test]
fn checksum_collisions_match_the_birthday_expectation() {
    let keys = keys();
    let n = keys.len() as f64;
    let mut words: Vec<u32> = keys.iter().map(checksum).collect();
    let pairs = equal_pairs(&mut words) as f64;
    let lambda = n * (n - 1.0) / 2.0 * 2f64.powi(-32) * (1.0 + 2f64.powi(-31));
    let z = (pairs - lambda) / lambda.sqrt();
    println!(
        "checksum: n = {n}, equal pairs = {pairs}, expected {lambda:.1}, z = {z:.2}, \
         measured per-pair rate = {:.3e} (2⁻³² = {:.3e})",
        pairs / (n * (n - 1.0) / 2.0),
        2f64.powi(-32)
    );
    assert!(
        z.abs() < 5.0,
        "collision count {pairs} vs {lambda:.1}: z = {z:.2}"
    );
}

/// The checksum and the bucket hash are independent: among the ≈ 512 pairs of distinct keys
/// with equal checksums (n = 2²¹, as above), none also has an equal 32-bit `Fold` (the
/// default; excluded by construction, see `fold_and_checksum`) or `Mix` bucket hash
/// (expected 512 · 2⁻³² ≈ 10⁻⁷). A checksum derived from the bucket hash (e.g. a bijection of
/// it, such as a second finaliser of the same 32-bit intermediate) would put every such pair
/// in the same probe window, so that each checksum collision became a false match. (Tried:
/// `checksum = rotl(hash_mix, 7) ⊕ c` passes the birthday test above but fails this one with
/// 473 of 473 collisions sharing the bucket hash.)
#[test]
fn checksum_collisions_do_not_share_buckets() {
    let keys = keys();
    let mut pairs: Vec<(u32, u32, u32)> = keys
        .iter()
        .map(|k| (checksum(k), hash_fold(k), hash_mix(k)))
        .collect();
    pairs.sort_unstable();
    let (mut colliding, mut same_bucket) = (0, 0);
    for w in pairs.windows(2) {
        if w[0].0 == w[1].0 {
            colliding += 1;
            same_bucket += u32::from(w[0].1 == w[1].1 || w[0].2 == w[1].2);
        }
    }
    println!("{colliding} checksum collisions, {same_bucket} of them with equal bucket hashes");
    assert!(colliding > 400, "{colliding}");
    assert_eq!(same_bucket, 0);
}

/// The same method on MCPG's 16-bit truncation of the checksum (its 36-byte state keeps
/// 16 bits): n = 2¹², λ = C(n, 2) · 2⁻¹⁶ ≈ 128, 5σ. Shows the method resolves rates, and that
/// 16 bits means ≈ 1/65 536 false matches per pair.
#[test]
fn sixteen_bit_checksum_collides_at_one_in_65536() {
    let keys = keys();
    let n = 4096.0;
    let mut words: Vec<u32> = keys
        .iter()
        .step_by(512)
        .take(4096)
        .map(|k| checksum(k) & 0xFFFF)
        .collect();
    let pairs = equal_pairs(&mut words) as f64;
    let lambda = n * (n - 1.0) / 2.0 * 2f64.powi(-16);
    let z = (pairs - lambda) / lambda.sqrt();
    println!("16-bit: equal pairs = {pairs}, expected {lambda:.1}, z = {z:.2}");
    assert!(
        z.abs() < 5.0,
        "16-bit collision count {pairs} vs {lambda:.1}: z = {z:.2}"
    );
}

#[test]
fn equal_pairs_counts_runs() {
    assert_eq!(equal_pairs(&mut [3, 1, 3, 3, 2, 1]), 3 + 1);
    assert_eq!(equal_pairs(&mut [1, 2, 3]), 0);
    assert_eq!(equal_pairs(&mut []), 0);
}
