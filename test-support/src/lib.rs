//! # mcg-test-support: helpers shared by the tests of every mcg crate
//!
//! A dev-dependency of the crates (and of `mcg-tests`) that depends on no mcg crate, so a crate's
//! `no_std` test build (`--no-default-features --features libm`) keeps its features.
//!
//! | item | what it is |
//! |---|---|
//! | [`proptest_config`] | a proptest configuration with a fixed seed and no regression files, overridable from the environment (`scripts/fuzz`) |
//! | [`assert_close!`] | `|a − b| ≤ tol` with both values, the difference and the tolerance in the message |
//! | [`hit_room`], [`ROOM_MIN`], [`ROOM_MAX`] | the box room of the hash-grid key streams (demo, hashgrid benches) |
//!
//! ## Example
//! ```
//! use mcg_test_support::assert_close;
//! assert_close!(0.1_f32 + 0.2, 0.3, 1e-6);
//! assert_close!(1.0_f64, 1.0 + 1e-12, 1e-9, "at step {}", 3);
//! ```

mod room;

pub use room::{ROOM_MAX, ROOM_MIN, hit_room};

use proptest::test_runner::{Config as ProptestConfig, RngSeed};

/// The configuration of a `proptest!` block: `cases` cases from the fixed seed `seed`, so CI
/// checks the same cases on every run, and no regression files.
///
/// `PROPTEST_RNG_SEED` and `PROPTEST_CASES`, when set, override the seed and the case count:
/// `scripts/fuzz` runs the same properties with fresh seeds that way.
#[must_use]
pub fn proptest_config(cases: u32, seed: u64) -> ProptestConfig {
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
            RngSeed::Fixed(seed)
        },
        failure_persistence: None,
        ..from_env
    }
}

/// Asserts `|a − b| ≤ tol` (`a`, `b`, `tol` of one float type); a NaN anywhere fails.
///
/// The panic message carries both expressions, both values, their difference and the
/// tolerance, then the optional `format!` arguments:
/// `assert_close!(a, b, tol)` or `assert_close!(a, b, tol, "context {}", x)`.
///
/// See also glam's `assert_approx_eq!` (its `tests/support/macros.rs`), which this follows.
#[macro_export]
macro_rules! assert_close {
    ($a:expr, $b:expr, $tol:expr $(,)?) => {
        $crate::assert_close!($a, $b, $tol, "")
    };
    ($a:expr, $b:expr, $tol:expr, $($arg:tt)+) => {{
        let (a, b, tol) = ($a, $b, $tol);
        let diff = (a - b).abs();
        if !(diff <= tol) {
            panic!(
                "assert_close!({}, {}) failed: {:?} vs {:?}, |difference| {:?} > tolerance {:?} {}",
                stringify!($a),
                stringify!($b),
                a,
                b,
                diff,
                tol,
                format_args!($($arg)+)
            );
        }
    }};
}

#[cfg(test)]
mod tests {
    #[test]
    fn close_values_pass() {
        assert_close!(1.0_f32, 1.0 + 1e-7, 1e-6);
        assert_close!(-2.0_f64, -2.0, 0.0);
        assert_close!(3.0_f32, 3.5, 0.5, "edge {}", 1);
    }

    #[test]
    #[should_panic(expected = "1.0 vs 1.1")]
    fn far_values_fail_with_both_values() {
        assert_close!(1.0_f64, 1.1, 0.05);
    }

    #[test]
    #[should_panic(expected = "tolerance 0.01 at x = 7")]
    fn message_carries_tolerance_and_context() {
        assert_close!(0.0_f32, 1.0, 0.01, "at x = {}", 7);
    }

    #[test]
    #[should_panic(expected = "NaN")]
    fn nan_fails() {
        assert_close!(f32::NAN, 0.0, 1.0);
    }

    #[test]
    fn fixed_seed_unless_the_environment_says_otherwise() {
        let c = super::proptest_config(17, 42);
        if std::env::var_os("PROPTEST_CASES").is_none() {
            assert_eq!(c.cases, 17);
        }
        if std::env::var_os("PROPTEST_RNG_SEED").is_none() {
            assert_eq!(c.rng_seed, proptest::test_runner::RngSeed::Fixed(42));
        }
        assert!(c.failure_persistence.is_none());
    }
}
