//! The console's wire format (docs/console.md), written once for everyone who speaks it: the
//! firmware emits through it; the `finger` client, the host tests, the Python package and the
//! web view parse through it. `no_std`, no allocation: a reply is parsed in place, its fields
//! are slices of the line.
//!
//! One idea per module:
//! - [`code`]: [`ErrorCode`], the codes of `err <code>: <message>`.
//! - [`command`]: [`Command`], a line's first word.
//! - [`message`]: [`message::Pieces`], a message as text and numbers in a row, so one table
//!   of messages (the model's errors, model/src/error.rs) renders through core's formatting
//!   on the host and through the firmware's own number formats on the board.
//! - [`field`]: [`field::FIELDS`], every documented reply field, its kind and its unit: the
//!   one place a new field is declared.
//! - [`reply`]: [`Reply`], a final line (`ok k=v ...` / `err <code>: <message>`): one parse,
//!   one emit.
//!
//! The grammar is a contract: codes and fields may be added, what exists does not change.
#![no_std]

pub mod code;
pub mod command;
pub mod field;
pub mod message;
pub mod reply;

pub use code::{ErrorCode, Never};
pub use command::Command;
pub use field::{Field, Kind};
pub use message::Pieces;
pub use reply::{Reply, Value};
