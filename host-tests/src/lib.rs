//! The test harness: what the host tests, the reports (examples/, src/bin/) and the tools'
//! tests share, one place for each.
//! - [`reply`] reads the console's replies; [`console`] is one console, the simulated board or
//!   QEMU, and the checks written once against it; [`sim_console`] drives the simulated board.
//! - [`image`] builds the firmware and bench images (cargo); [`qemu`] launches QEMU, talks to
//!   the console over a socket and reads the register trace; [`perf`] runs the bench images.
//! - [`report`] writes a generated section into docs/; [`hv`] steps the control core's stacks
//!   in time; [`cut_flash`] is the settings store's power-cut flash; [`synthetic`] a stack the
//!   HV sense sees, its current written from its capacitance and leakage.
//!
//! The continuum reference and the scene runner are crates of their own (tools/continuum,
//! tools/finger-scene), re-exported here under their old paths for the fidelity test and report.

pub mod console;
pub mod cut_flash;
pub mod hv;
pub mod image;
pub mod perf;
pub mod plant_runs;
pub mod qemu;
pub mod reply;
pub mod report;
pub mod sim_console;
pub mod synthetic;
pub use continuum;
pub use finger_scene::svg;
/// The scene runner (tools/finger-scene).
pub mod scene {
    pub use finger_scene::*;
}
