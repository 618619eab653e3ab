//! Console text without core::fmt's formatting machinery (the image's flash).
//!
//! What it is: [`Emit`], "this value as console text", for the few kinds of value a reply
//! holds (text, unsigned integers, the number formats of [`crate::num`]), and [`crate::w!`], which
//! writes a sequence of them to any `core::fmt::Write` (a `heapless::String`, the UART, a
//! `Formatter`). `write!` builds `fmt::Arguments` at each call site and runs them through
//! `core::fmt::write`, `Formatter::pad` and integer `Display`: kilobytes of the image for
//! replies that are only ever pieces in a row. Here each piece is one `write_str` call.
//!
//! What it is not: a formatter. No width, padding or alignment; the number formats live in
//! `crate::num`. A write that does not fit a bounded string drops that piece (the console's
//! replies fit their buffers; the tests check the longest).

use core::fmt::Write;

/// A value that can be written as console text.
pub trait Emit {
    fn emit(&self, o: &mut dyn Write);
}

/// Write the pieces in order. Always `Ok` (see the module header on overflow); the `Result`
/// lets callers keep `?` where a `fmt::Result` is expected.
#[inline(never)]
pub fn put(o: &mut dyn Write, parts: &[&dyn Emit]) -> core::fmt::Result {
    for p in parts {
        p.emit(o);
    }
    Ok(())
}

/// `w!(out; a, b, ...)`: write `a`, `b`, ... ([`Emit`]) to `out` (`&mut impl fmt::Write`).
#[macro_export]
macro_rules! w {
    ($o:expr; $($x:expr),+ $(,)?) => {{
        let o: &mut dyn ::core::fmt::Write = $o;
        $( $crate::out::Emit::emit(&$x, o); )+
        ::core::fmt::Result::Ok(())
    }};
}

impl Emit for str {
    fn emit(&self, o: &mut dyn Write) {
        let _ = o.write_str(self);
    }
}

impl<T: Emit + ?Sized> Emit for &T {
    #[inline(always)]
    fn emit(&self, o: &mut dyn Write) {
        (**self).emit(o)
    }
}

impl<const N: usize> Emit for heapless::String<N> {
    fn emit(&self, o: &mut dyn Write) {
        let _ = o.write_str(self.as_str());
    }
}

const DIGITS: &str = "0123456789";

/// Decimal digits of `v` (no UTF-8 validation: each digit is a slice of `DIGITS`).
pub fn emit_u32(o: &mut dyn Write, v: u32) {
    let mut buf = [0u8; 10];
    let mut i = buf.len();
    let mut v = v;
    loop {
        i -= 1;
        buf[i] = b'0' + (v % 10) as u8;
        v /= 10;
        if v == 0 {
            break;
        }
    }
    for &d in &buf[i..] {
        let k = (d - b'0') as usize;
        let _ = o.write_str(DIGITS.get(k..k + 1).unwrap_or("?"));
    }
}

macro_rules! emit_unsigned {
    ($($t:ty),*) => {$(
        impl Emit for $t {
            #[inline(always)]
            fn emit(&self, o: &mut dyn Write) {
                emit_u32(o, *self as u32)
            }
        }
    )*};
}
emit_unsigned!(u8, u16, u32, usize);
