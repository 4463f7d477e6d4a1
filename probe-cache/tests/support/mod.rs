//! The proptest configuration shared by this crate's property tests: the integration tests
//! include it with `mod support;`, the unit tests through `#[path]` from `lib.rs`.

use proptest::test_runner::{Config as ProptestConfig, RngSeed};

/// `cases` cases from the fixed seed 0x7E57_0007, so every run checks the same cases, and no
/// regression files. `PROPTEST_RNG_SEED` / `PROPTEST_CASES`, when set, override the seed and
/// the case count (`scripts/fuzz` runs the properties with fresh seeds that way).
pub fn proptest_config(cases: u32) -> ProptestConfig {
    let set = |name: &str| std::env::var_os(name).is_some();
    // `default()` reads the PROPTEST_* environment variables.
    let from_env = ProptestConfig::default();
    ProptestConfig {
        cases: if set("PROPTEST_CASES") {
            from_env.cases
        } else {
            cases
        },
        rng_seed: if set("PROPTEST_RNG_SEED") {
            from_env.rng_seed
        } else {
            RngSeed::Fixed(0x7E57_0007)
        },
        failure_persistence: None,
        ..from_env
    }
}
