//! Console input: line assembly into a bounded buffer, tokens, strict numbers.
//!
//! Lines end with CR, LF or CRLF (a CRLF counts once). A line longer than [`LINE_MAX`] bytes
//! is discarded whole and reported once, at its end, as [`Line::TooLong`]. Bytes are kept as
//! they come (non-ASCII included); the command layer rejects what it does not understand.
//! A terminal's escape sequences (arrow and function keys) and its other control characters
//! (Ctrl-L, backspace, NUL; tab is a separator) are dropped before line assembly
//! ([`EscFilter`]), so a key of the terminal's costs no error line.

use heapless::Vec;

/// Receive buffer: the longest line accepted, in bytes (docs/console.md asks for at least 120).
pub const LINE_MAX: usize = 128;
/// Most tokens on a line (command word included): `cal`'s eight factors need nine.
pub const MAX_TOKENS: usize = 9;

/// What a byte completed.
#[derive(Debug, PartialEq)]
pub enum Line<'a> {
    /// A complete line (without its terminator), lowercased ASCII letters.
    Text(&'a [u8]),
    /// The end of a line that overflowed the buffer; it was discarded.
    TooLong,
}

/// Drops a terminal's escape sequences from the byte stream: `ESC [` or `ESC O` then
/// parameter bytes up to one final byte (0x40..=0x7e), as arrow, Home/End and function keys
/// send them; `ESC` and any other byte (Alt+key) as a pair; any other control character
/// (0x00..0x1f but tab, and DEL) alone. A line ending always passes and ends the sequence, so
/// a line is never held back.
#[derive(Default, Clone, Copy)]
pub struct EscFilter {
    /// 0: text; 1: after ESC; 2: inside `ESC [` / `ESC O` before the final byte.
    state: u8,
}

impl EscFilter {
    pub const fn new() -> Self {
        EscFilter { state: 0 }
    }

    /// Whether `b` is line content (true) or part of an escape sequence (false).
    pub fn pass(&mut self, b: u8) -> bool {
        if b == b'\r' || b == b'\n' {
            self.state = 0;
            return true;
        }
        match self.state {
            0 if b == 0x1b => self.state = 1,
            0 => return !(b < 0x20 && b != b'\t' || b == 0x7f),
            1 => self.state = if b == b'[' || b == b'O' { 2 } else { 0 },
            _ => {
                if (0x40..=0x7e).contains(&b) {
                    self.state = 0;
                }
            }
        }
        false
    }
}

/// Assembles bytes into lines.
#[derive(Default)]
pub struct LineBuf {
    buf: Vec<u8, LINE_MAX>,
    overflow: bool,
    last_cr: bool,
    /// The buffer holds the line handed out last; clear it before the next byte.
    done: bool,
}

impl LineBuf {
    pub const fn new() -> Self {
        LineBuf { buf: Vec::new(), overflow: false, last_cr: false, done: false }
    }

    /// Feed one byte; returns a line when `b` ends one.
    pub fn push(&mut self, b: u8) -> Option<Line<'_>> {
        if self.done {
            self.buf.clear();
            self.done = false;
        }
        let was_cr = self.last_cr;
        self.last_cr = b == b'\r';
        if b == b'\n' && was_cr {
            return None; // the LF of a CRLF
        }
        if b == b'\r' || b == b'\n' {
            self.done = true;
            if self.overflow {
                self.overflow = false;
                return Some(Line::TooLong);
            }
            return Some(Line::Text(&self.buf));
        }
        if self.overflow {
            return None;
        }
        if self.buf.push(b.to_ascii_lowercase()).is_err() {
            self.overflow = true;
        }
        None
    }
}

/// Split a line into tokens on spaces and tabs. `None` when there are more than MAX_TOKENS.
pub fn tokens(line: &[u8]) -> Option<Vec<&[u8], MAX_TOKENS>> {
    let mut out = Vec::new();
    for t in line.split(|&c| c == b' ' || c == b'\t').filter(|t| !t.is_empty()) {
        out.push(t).ok()?;
    }
    Some(out)
}

/// Why a number was refused.
#[derive(Debug, PartialEq, Eq, Clone, Copy)]
pub enum NumError {
    /// Not of the form `[+-]digits[.digits][e[+-]digits]` (NaN, inf, hex, garbage...).
    Syntax,
    /// Well formed but beyond f32's range (|x| > 3.4e38).
    Overflow,
}

/// Significant digits kept (u32 mantissa; f32 holds ~7.2).
const SIG_DIGITS: u32 = 9;

/// Parse a decimal number to f32: optional sign, digits with an optional fraction, optional
/// exponent. Everything else (NaN, infinity, hex, trailing garbage, non-ASCII) is refused.
/// No core float parsing and no f64 (flash): the digits are gathered into a u32 mantissa (9
/// significant digits kept, the rest truncated) and a decimal exponent, see
/// [`crate::num::decimal_to_f32`]. Values below f32's range read as 0.
pub fn parse_number(tok: &[u8]) -> Result<f32, NumError> {
    let n = tok.len();
    let mut i = 0;
    let neg = i < n && tok[i] == b'-';
    if i < n && (tok[i] == b'+' || tok[i] == b'-') {
        i += 1;
    }
    let (mut mant, mut sig, mut exp10, mut digits) = (0u32, 0u32, 0i32, 0u32);
    let mut frac = false;
    while i < n {
        let c = tok[i];
        if c == b'.' && !frac {
            frac = true;
        } else if c.is_ascii_digit() {
            let d = (c - b'0') as u32;
            digits += 1;
            if mant == 0 && d == 0 {
                // a leading zero: no significant digit yet
                if frac {
                    exp10 = exp10.saturating_sub(1);
                }
            } else if sig < SIG_DIGITS {
                mant = mant * 10 + d;
                sig += 1;
                if frac {
                    exp10 -= 1;
                }
            } else if !frac {
                exp10 = exp10.saturating_add(1); // an integer digit past the ones kept
            }
        } else {
            break;
        }
        i += 1;
    }
    if digits == 0 {
        return Err(NumError::Syntax);
    }
    if i < n && (tok[i] == b'e' || tok[i] == b'E') {
        i += 1;
        let eneg = i < n && tok[i] == b'-';
        if i < n && (tok[i] == b'+' || tok[i] == b'-') {
            i += 1;
        }
        let (mut e, mut exp_digits) = (0i32, 0);
        while i < n && tok[i].is_ascii_digit() {
            e = (e * 10 + (tok[i] - b'0') as i32).min(1_000_000);
            i += 1;
            exp_digits += 1;
        }
        if exp_digits == 0 {
            return Err(NumError::Syntax);
        }
        exp10 = exp10.saturating_add(if eneg { -e } else { e });
    }
    if i != n {
        return Err(NumError::Syntax);
    }
    let exp10 = exp10.clamp(-100_000, 100_000);
    let v = crate::num::decimal_to_f32(mant, exp10).ok_or(NumError::Overflow)?;
    Ok(if neg { -v } else { v })
}

/// A token as text for messages: itself when printable ASCII (at most 24 bytes), else
/// `(non-printable)`. Written byte by byte from a table of the printable characters, so the
/// image needs no UTF-8 validation (its flash).
pub fn printable(tok: &[u8]) -> Printable<'_> {
    Printable(tok)
}

/// See [`printable`].
pub struct Printable<'a>(&'a [u8]);

/// The printable ASCII characters 0x21..=0x7e, in order.
const ASCII: &str = "!\"#$%&'()*+,-./0123456789:;<=>?@ABCDEFGHIJKLMNOPQRSTUVWXYZ[\\]^_`abcdefghijklmnopqrstuvwxyz{|}~";

impl crate::out::Emit for Printable<'_> {
    fn emit(&self, o: &mut dyn core::fmt::Write) {
        let t = self.0;
        if !(t.len() <= 24 && t.iter().all(|c| (0x21..0x7f).contains(c))) {
            let _ = o.write_str("(non-printable)");
            return;
        }
        for &c in t {
            let i = (c - 0x21) as usize;
            let _ = o.write_str(ASCII.get(i..i + 1).unwrap_or("?"));
        }
    }
}
