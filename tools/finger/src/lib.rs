//! The host client for the finger driver board: the console contract (docs/console.md) over
//! a serial port (the real board), finger-sim's stdin/stdout, or the QEMU image's console
//! socket, with the same commands everywhere. `finger --help` lists them.
pub mod console;
pub mod link;
pub mod log;
pub mod monitor;
pub mod run;

pub use console::{CommandError, Console, ErrorCode, Reply};
pub use link::{Link, LinkError};
