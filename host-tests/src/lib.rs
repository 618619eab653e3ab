//! Host-side tools shared by the tests and binaries in this package. The continuum reference
//! and the scene runner are crates of their own (tools/continuum, tools/finger-scene),
//! re-exported here under their old paths for the fidelity test and report.

pub mod hv;
pub mod cut_flash;
pub mod perf;
pub mod qemu;
pub mod sim_console;
pub use continuum;
pub use finger_scene::svg;
/// The scene runner (tools/finger-scene).
pub mod scene {
    pub use finger_scene::*;
}
