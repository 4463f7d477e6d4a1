//! Reference renderer loops on the [toy scene](crate::toy_scene): the whole guide at work,
//! from the renderer's side (requires the `toy` feature, which brings a `rand` generator for
//! the renderer's uniforms).
//!
//! These loops are what the statistical suites, the demo and the `toy_loop` example run; each
//! reads top to bottom as the frame a renderer would execute.

mod mcmm_loop;
mod mcpg_loop;

pub use mcmm_loop::{Decorrelation, McmmToyConfig, McmmToyRenderer, Sampling};
pub use mcpg_loop::{MAX_CANDIDATES, McpgFrame, McpgToyConfig, McpgToyRenderer};
