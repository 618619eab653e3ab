//! The fuzz targets' checks, one module per target: each `check(data)` runs one input and
//! panics when an invariant breaks. The libFuzzer targets (`fuzz_targets/`) call them; so do
//! the plain regression tests (`tests/regressions.rs`), on every committed corpus and
//! regression input, without libFuzzer.
//!
//! What it is not: a second implementation of what it checks. The invariants are the
//! contracts (shared/CONSOLE.md, MODEL.md), written as assertions on what comes out.

pub mod config;
pub mod console;
pub mod material;
pub mod model;
pub mod rx;
pub mod scene;
