//! Console errors: [`CmdError`] (a code of docs/console.md, [`ErrorCode`], and a message), the
//! model's errors as console errors, [`head`] (every error line's start, through the protocol
//! crate), and the argument checks every command shares (no arguments, a strict number, a
//! cable tension).
//!
//! What it is not: the commands that raise them (`super::commands` and its handlers).

use core::fmt::Write;

use finger_model::Error as ModelError;
pub use finger_protocol::ErrorCode;
use heapless::String;

use crate::console::{self, NumError};
use crate::num::{self, Exp};

/// A refused command: its code (docs/console.md) and a human message.
#[derive(Debug)]
pub struct CmdError {
    pub code: ErrorCode,
    pub msg: String<160>,
}

impl CmdError {
    /// A console error with a fixed message.
    pub fn new(code: ErrorCode, msg: &str) -> Self {
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

impl CmdError {
    /// Write its reply line's text: `err <code>: <message>` (without the line ending).
    pub fn emit(&self, out: &mut dyn Write) {
        head(out, self.code);
        let _ = out.write_str(&self.msg);
    }
}

/// Write `err <code>: `, the start of every error line (the protocol's); the message follows.
#[inline(never)]
pub fn head(out: &mut dyn Write, code: ErrorCode) {
    let _ = finger_protocol::reply::emit_err_head(out, &code);
}

pub(crate) fn no_args(args: &[&[u8]], cmd: &str) -> Result<(), CmdError> {
    if args.is_empty() {
        Ok(())
    } else {
        Err(err!(Usage; cmd, " takes no arguments"))
    }
}

pub(crate) fn number(tok: &[u8], what: &str) -> Result<f32, CmdError> {
    console::parse_number(tok).map_err(|e| {
        let why = match e {
            NumError::Syntax => " is not a decimal number",
            NumError::Overflow => " is out of range",
        };
        err!(BadNumber; what, ": ", (console::printable(tok)), why)
    })
}

/// A cable tension: >= 0 (usage), representable (limit: far past any fmax).
pub(crate) fn tension(p: f32) -> Result<f32, CmdError> {
    if !(p >= 0.0) {
        return Err(err!(Usage; "tension must be >= 0 (a cable cannot push)"));
    }
    if !(p <= 1e6) {
        return Err(err!(Limit; "tension ", Exp(p, 3), " N is past fmax"));
    }
    Ok(p)
}
