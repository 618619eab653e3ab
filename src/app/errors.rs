//! Console errors: [`CmdError`] (a code of docs/console.md and a message), the model's errors
//! as console errors, and the argument checks every command shares (no arguments, a strict
//! number, a cable tension).
//!
//! What it is not: the commands that raise them (`super::commands` and its handlers).

use finger_model::Error as ModelError;
use heapless::String;

use crate::console::{self, NumError};
use crate::num::{self, Exp};

/// A refused command: its code (docs/console.md) and a human message.
#[derive(Debug)]
pub struct CmdError {
    pub code: &'static str,
    pub msg: String<160>,
}

impl CmdError {
    /// A console error with a fixed message.
    pub fn new(code: &'static str, msg: &str) -> Self {
        let mut m = String::new();
        for c in msg.chars() {
            if m.push(c).is_err() {
                break;
            }
        }
        CmdError { code, msg: m }
    }
}

/// A model error as a console error: its code, and a message written from its fields by
/// [`num::write_model_error`] (never the model's `Display`: it links core's float formatting).
pub(crate) fn model_err(e: ModelError) -> CmdError {
    let mut msg = String::new();
    let _ = num::write_model_error(&mut msg, &e);
    CmdError { code: e.code(), msg }
}

pub(crate) fn no_args(args: &[&[u8]], cmd: &str) -> Result<(), CmdError> {
    if args.is_empty() {
        Ok(())
    } else {
        Err(err!("usage"; cmd, " takes no arguments"))
    }
}

pub(crate) fn number(tok: &[u8], what: &str) -> Result<f32, CmdError> {
    console::parse_number(tok).map_err(|e| {
        let why = match e {
            NumError::Syntax => " is not a decimal number",
            NumError::Overflow => " is out of range",
        };
        err!("bad-number"; what, ": ", (console::printable(tok)), why)
    })
}

/// A cable tension: >= 0 (usage), representable (limit: far past any fmax).
pub(crate) fn tension(p: f32) -> Result<f32, CmdError> {
    if !(p >= 0.0) {
        return Err(err!("usage"; "tension must be >= 0 (a cable cannot push)"));
    }
    if !(p <= 1e6) {
        return Err(err!("limit"; "tension ", Exp(p, 3), " N is past fmax"));
    }
    Ok(p)
}
