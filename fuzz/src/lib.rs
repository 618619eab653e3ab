//! The fuzz targets' checks, one module per target: each `check(data)` runs one input and
//! panics when an invariant breaks. The libFuzzer targets (`fuzz_targets/`) call them; so do
//! the plain regression tests (`tests/regressions.rs`), on every committed corpus and
//! regression input, without libFuzzer.
//!
//! What it is not: a second implementation of what it checks. The invariants are the
//! contracts (docs/console.md, docs/model.md), written as assertions on what comes out.

pub mod config;
pub mod console;
pub mod material;
pub mod model;
pub mod model_contact;
pub mod model_fmax;
pub mod model_forward;
pub mod model_inverse;
pub mod plant;
pub mod rx;
pub mod scene;

/// The console's terminal escape sequences as CONSOLE's grammar drops them (arrow, Home/End and
/// function keys): `ESC [` or `ESC O` then bytes up to a final byte 0x40..=0x7e, or `ESC` and
/// one other byte; and any other control character alone (0x00..0x1f but tab, and DEL); a line
/// ending always passes and ends a sequence. The checks' own model.
#[derive(Default)]
pub(crate) struct Escapes(u8);

impl Escapes {
    /// Whether `b` is line content (or a line ending).
    pub(crate) fn content(&mut self, b: u8) -> bool {
        if b == b'\r' || b == b'\n' {
            self.0 = 0;
            return true;
        }
        match self.0 {
            0 if b == 0x1b => self.0 = 1,
            0 => return !(b < 0x20 && b != b'\t' || b == 0x7f),
            1 => self.0 = if b == b'[' || b == b'O' { 2 } else { 0 },
            _ if (0x40..=0x7e).contains(&b) => self.0 = 0,
            _ => {}
        }
        false
    }
}
