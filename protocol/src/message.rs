//! A message as pieces in a row: text, numbers with their notation, a joint. A table of
//! messages (the model's errors: model/src/error.rs) is written once against [`Pieces`];
//! each side renders it with its own numbers: [`Formatted`] with core's formatting (the
//! host, `Display`), the firmware with its own f32 formats (src/num.rs: no core float
//! formatting in the image).
//!
//! What it is not: the reply line around a message ([`crate::reply`]).

use core::fmt;

use crate::ErrorCode;

/// Where a message's pieces go.
pub trait Pieces {
    /// Text as it is.
    fn text(&mut self, s: &str);
    /// `x` with `decimals` decimals (`{:.p}`).
    fn fixed(&mut self, x: f64, decimals: u8);
    /// `x` in exponent notation with `decimals` decimals (`{:.pe}`: `1.234e-5`).
    fn exp(&mut self, x: f64, decimals: u8);
    /// An unsigned integer.
    fn count(&mut self, n: u32);
    /// A joint: `joint k` (1..=n, from the base), or for joint 0 (a loaded finger's coupled
    /// equilibrium: no single joint to blame) `the tip-loaded finger`.
    fn joint(&mut self, k: usize) {
        if k == 0 {
            self.text("the tip-loaded finger");
        } else {
            self.text("joint ");
            self.count(k as u32);
        }
    }
}

/// An error with a console code and a message written as pieces (the model's errors).
pub trait Message {
    /// Its code in an `err <code>: <message>` reply.
    fn code(&self) -> ErrorCode;
    /// Its message, piece by piece (generic, not `dyn`: the firmware's renderer inlines, no
    /// vtable of its writer is built; the Cortex-M3 image's flash).
    fn message<P: Pieces + ?Sized>(&self, out: &mut P);
}

/// [`Pieces`] written to a `fmt::Write` with core's formatting; the first error is kept.
pub struct Formatted<W> {
    out: W,
    result: fmt::Result,
}

impl<W: fmt::Write> Formatted<W> {
    pub fn new(out: W) -> Self {
        Formatted { out, result: Ok(()) }
    }

    /// The first write error, if any.
    pub fn finish(self) -> fmt::Result {
        self.result
    }

    fn keep(&mut self, r: fmt::Result) {
        if self.result.is_ok() {
            self.result = r;
        }
    }
}

impl<W: fmt::Write> Pieces for Formatted<W> {
    fn text(&mut self, s: &str) {
        let r = self.out.write_str(s);
        self.keep(r);
    }

    fn fixed(&mut self, x: f64, decimals: u8) {
        let r = write!(self.out, "{x:.0$}", decimals as usize);
        self.keep(r);
    }

    fn exp(&mut self, x: f64, decimals: u8) {
        let r = write!(self.out, "{x:.0$e}", decimals as usize);
        self.keep(r);
    }

    fn count(&mut self, n: u32) {
        let r = write!(self.out, "{n}");
        self.keep(r);
    }
}

/// A [`Message`]'s text with core's formatting (a `Display` impl's body).
pub fn display<M: Message + ?Sized>(m: &M, f: &mut fmt::Formatter<'_>) -> fmt::Result {
    let mut p = Formatted::new(f);
    m.message(&mut p);
    p.finish()
}
