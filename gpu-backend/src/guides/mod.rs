//! The GPU guides: a WGSL module of the shader library and a host object each (buffers, bind
//! group layout, per-frame bind group).

pub mod mcmm;
