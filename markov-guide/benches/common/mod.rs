//! Inputs shared by the benchmarks and the instruction-count example.

pub mod vertices;
