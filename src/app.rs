//! The application's command side: every command of docs/console.md, the HV ceilings, the
//! model calls, and [`App`], the whole application on one board for the host. One idea per
//! module; each imports only the ones above it in this list:
//!
//! - `errors`: [`CmdError`], the shared argument checks; `params`: the parameter registry;
//!   `film`: the board's film; `solves` (`m3` on the Cortex-M3 image): the forward solves;
//!   `help`: `help` and the replies' formatting.
//! - `commands`: [`Commands`], its state, the dispatch and the core commands; `pose`, `shape`,
//!   `config` (with `stored`, the record's checks): the commands that are theirs.
//! - `host`: [`App`], the host's composition; [`wire`] builds the parts for every composition.

/// `err!(code; pieces...)`: a console error with a message written from pieces
/// ([`crate::out::Emit`]).
macro_rules! err {
    ($code:expr; $($x:expr),+ $(,)?) => {{
        let mut msg: heapless::String<160> = heapless::String::new();
        let _ = w!(&mut msg; $($x),+);
        $crate::app::errors::CmdError { code: $code, msg }
    }};
}

pub mod errors;
pub mod params;
mod film;
#[cfg(m3)]
mod m3;
mod solves;
mod help;
mod commands;
#[cfg(any(feature = "pose", feature = "contact", m3))]
pub mod pose;
#[cfg(feature = "shape")]
mod shape;
#[cfg(feature = "settings")]
mod stored;
#[cfg(feature = "settings")]
pub mod config;
mod host;
mod wire;

pub use commands::Commands;
pub use errors::CmdError;
pub use host::App;
pub use wire::wire;
pub use params::{board_params, calibration_for, FwParamInfo, FwParams, CHANNELS, FW_PARAMS};
pub use crate::control::HvRefused;
