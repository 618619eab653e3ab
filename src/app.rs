//! The application's command side: every command of docs/console.md, the HV ceilings, the
//! model calls, and [`App`], the whole application on one board for the host. One idea per
//! module; each imports only modules listed before it:
//!
//! - `errors`: [`CmdError`] and the shared argument checks; `params`: the parameter registry;
//!   `m3` (Cortex-M3 image) and `solves`: the forward solves; `help`: `help` and the replies'
//!   formatting; `film`: the board's film; `hv_cal`: the read-back's calibration (`cal
//!   show|vmon|c0`); `stored`: the stored record's checks.
//! - `commands`: [`Commands`], its state, the dispatch and the core commands; `hv_cal_cmd`,
//!   `pose`, `shape`: the commands that are theirs.
//! - `wire`: [`wire`], the parts built for a board (the chip, [`App`], the on-target tests);
//!   `host`: [`App`]; `config`: `save`, `config`, `factory` and the boot hook.

/// `err!(Code; pieces...)`: a console error, its code a [`finger_protocol::ErrorCode`]
/// variant, with a message written from pieces ([`crate::out::Emit`]).
macro_rules! err {
    ($code:ident; $($x:expr),+ $(,)?) => {{
        let mut msg: heapless::String<160> = heapless::String::new();
        let _ = w!(&mut msg; $($x),+);
        $crate::app::errors::CmdError { code: finger_protocol::ErrorCode::$code, msg }
    }};
}

pub mod errors;
pub mod params;
#[cfg(m3)]
mod m3;
mod solves;
mod planner;
mod help;
mod film;
#[cfg(not(m3))]
pub mod hv_cal;
#[cfg(feature = "settings")]
mod stored;
mod commands;
#[cfg(not(m3))]
mod hv_cal_cmd;
#[cfg(any(feature = "pose", feature = "contact", m3))]
pub mod pose;
#[cfg(feature = "shape")]
mod shape;
#[cfg(not(feature = "hw"))]
mod plant_cmd;
mod wire;
mod host;
#[cfg(feature = "settings")]
pub mod config;

pub use crate::control::HvRefused;
pub use commands::{Commands, TimingReport};
pub use errors::{CmdError, ErrorCode};
pub use help::is_command;
pub use host::App;
pub use params::{board_params, calibration_for, FwParamInfo, FwParams, CHANNELS, FW_PARAMS};
pub use wire::wire;
