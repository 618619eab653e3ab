//! Host-side tools shared by the tests and binaries in this package.

pub mod paper;
pub mod scene;
pub mod svg;
pub mod continuum;
pub mod perf;
pub mod qemu;
pub mod domain;
