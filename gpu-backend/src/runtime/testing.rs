//! Support for tests that need a GPU.

use crate::GpuContext;

/// The environment variable that turns a missing adapter from a skip into a failure. CI
/// (`scripts/test`) installs lavapipe and sets it to `1`.
pub const REQUIRE_GPU_VAR: &str = "MCG_REQUIRE_GPU";

/// The shared [`GpuContext`] for a test named `test`, or `None` after printing why the test
/// is skipped when there is no adapter.
///
/// # Panics
/// When there is no adapter and `MCG_REQUIRE_GPU=1` is set: a CI run must not pass by
/// skipping its GPU tests.
#[must_use]
pub fn gpu_or_skip(test: &str) -> Option<&'static GpuContext> {
    match GpuContext::shared() {
        Ok(ctx) => Some(ctx),
        Err(e) => {
            if std::env::var(REQUIRE_GPU_VAR).is_ok_and(|v| v == "1") {
                panic!("{test}: {REQUIRE_GPU_VAR}=1 but {e}");
            }
            eprintln!("skipping {test}: {e} (set {REQUIRE_GPU_VAR}=1 to fail instead)");
            None
        }
    }
}
