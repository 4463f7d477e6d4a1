//! MCPG on the GPU: `mcg::mcpg`, the whole guide as one WGSL module, and its host object.
//!
//! A renderer's WGSL path tracer imports the guide and binds one group:
//!
//! ```wgsl
//! #import mcg::mcpg::{McpgBeginUniforms, McpgFinishUniforms, McpgSampleUniforms,
//!     mcpg_begin, mcpg_finish, mcpg_observation_hit, mcpg_sample, mcpg_surface_vertex}
//!
//! var v = mcpg_begin(mcpg_surface_vertex(x, n), begin_uniforms);  // MCPG Alg. 1
//! let s = mcpg_sample(&v, sample_uniforms);                        // Alg. 2, s.pdf exact
//! // trace s.direction; weight = f·cos/s.pdf
//! mcpg_finish(&v, s, mcpg_observation_hit(y, n_y, emitted, weight), finish_uniforms); // Alg. 3
//! ```
//!
//! `mcpg_begin` returns the vertex by value, which WGSL zero-initialises and copies (a few hundred
//! bytes); a tracer that keeps one vertex per path and begins into it at each bounce calls
//! `mcpg_begin_at(vertex, u, &v)` instead (the same vertex, 15 % off the bench's guided kernel
//! on lavapipe, `benches/README.md`).
//!
//! A tracer that also samples its lights and weights the emission `s.direction` hit by MIS
//! sets `obs.emission_weight` on the observation to that weight before `mcpg_finish` (the
//! chain then learns only the share its direction carries; `VertexObservation::emission_weight`).
//!
//! A tracer that finishes its vertices only when the path is done, to train each on the
//! path's own estimate of the radiance reflected at its next hit (`obs.has_reflected = 1`,
//! `obs.reflected`), keeps `mcpg_pending(&v, s)` (an `McpgPending`, 96 bytes: what Alg. 3
//! needs of the vertex, without its lobes) and calls `mcpg_finish_pending(p, obs, u)` at the
//! end; `mcpg_finish(&v, s, obs, u)` is exactly that composition (the CPU's
//! `GuidedVertex::pending` and `PendingFinish::finish`).
//!
//! The module is composed with [`GpuMcpgGuide::shader_defs`]`(group)`, its pipeline layout holding
//! [`GpuMcpgGuide::bind_group_layout`] at `group`, and [`GpuMcpgGuide::bind_group`] set there.
//! After the frame's dispatches, [`GpuMcpgGuide::record_end_frame`] records the cache's fold,
//! the eviction of idle states and cells, and the frame advance into the same encoder.
//!
//! The functions mirror `mcg_markov_guide::mcpg::Guide`'s vertex API call for call
//! (`Vertex::surface`/`volume` → `mcpg_surface_vertex`/`mcpg_volume_vertex`, `begin`, `sample`,
//! `pdf`, `finish`, `pending`, `end_frame`); for the same states, inputs and uniforms they make the same
//! choices (the parity tests hold them to it). States stay the CPU's 32-byte `GridState`; each
//! slot adds a guard word that makes racing stores safe (see the module's header).
//!
//! Performance: on lavapipe (llvmpipe, software) a guided vertex costs 31-69× a
//! cosine-sampled one in `benches/mcpg.rs` on an idle 2-vCPU VM (146-165× on a loaded one; the
//! target of 6× is not met: llvmpipe runs every branch masked and makes each of the vertex's
//! storage accesses a loop over 8 lanes); `benches/README.md` has the measurements and the GPU
//! demo's frame-time ratios.

#[cfg(feature = "runtime")]
mod guide;
mod params;

#[cfg(feature = "runtime")]
pub use guide::{GpuMcpgGuide, McpgMemory, McpgReadBack};
pub use params::{MCPG_MAX_PROBES, McpgBufferWords, McpgGpuParams};
