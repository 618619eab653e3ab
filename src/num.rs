//! Numbers to and from text without core's float parsing and formatting, and without f64
//! (the image's flash: docs/firmware.md "Console numbers" says why and how).
//!
//! - [`decimal_to_f32`]: mantissa digits and a decimal exponent to f32, correctly rounded for
//!   decimal exponents -16..=10 of the (9-digit) mantissa, a few ulp beyond.
//! - [`Fixed`], [`Short`], [`Exp`]: `Display` wrappers printing like core's `{:.p}`, `{}` and
//!   `{:.pe}` of an f32 ([`Fixed`] exactly up to 1e18, [`Short`] as core's `{}` for
//!   1e-8 <= |x| < 1e18, [`Exp`] to its last digit). NaN prints `NaN`, infinities `inf` /
//!   `-inf`, as core does.
//!
//! What it is not: the console's tokens (`crate::console`) or the reply's pieces (`crate::out`).

use core::fmt::{self, Write};

use crate::out::Emit;

/// 10^e, exact in f32 for e <= 10.
const POW10: [f32; 11] = [1e0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10];
/// 10^e as u32, e <= 9.
const POW10U: [u32; 10] = [1, 10, 100, 1_000, 10_000, 100_000, 1_000_000, 10_000_000, 100_000_000, 1_000_000_000];

/// `v` x 10^`e` in f32 steps of at most 10^10 (one rounding when |e| <= 10).
fn scale10(mut v: f32, mut e: i32) -> f32 {
    while e > 10 {
        v *= 1e10;
        e -= 10;
        if !v.is_finite() {
            return v;
        }
    }
    while e < -10 {
        v /= 1e10;
        e += 10;
        if v == 0.0 {
            return v;
        }
    }
    if e >= 0 {
        v * POW10[e as usize]
    } else {
        v / POW10[(-e) as usize]
    }
}

/// `mant` x 10^`exp10` as f32; `None` when it overflows f32. Correctly rounded for
/// -16 <= exp10 <= 10 (the f32 estimate is corrected against the decimal's exact value with
/// u64 products), within a few ulp beyond.
pub fn decimal_to_f32(mant: u32, exp10: i32) -> Option<f32> {
    if mant == 0 {
        return Some(0.0);
    }
    let mut v = scale10(mant as f32, exp10);
    let exact = mant <= 1 << 24 && (-10..=10).contains(&exp10);
    if !exact && (-16..=10).contains(&exp10) && v.is_finite() && v > 0.0 {
        for _ in 0..3 {
            let b = v.to_bits();
            let be = (b >> 23) as i32;
            let (m, e) = if be == 0 { (b & 0x7f_ffff, -149) } else { ((b & 0x7f_ffff) | 0x80_0000, be - 150) };
            let odd = m & 1 == 1;
            // the midpoints to the neighbours: (2m+1) 2^(e-1) above, (2m-1) 2^(e-1) below
            // ((4m-1) 2^(e-2) at a power of two)
            let up = cmp_decimal(mant, exp10, 2 * m as u64 + 1, e - 1);
            let down =
                if m == 0x80_0000 && be > 1 { cmp_decimal(mant, exp10, 4 * m as u64 - 1, e - 2) } else { cmp_decimal(mant, exp10, 2 * m as u64 - 1, e - 1) };
            if up == Greater || (up == Equal && odd) {
                v = f32::from_bits(b + 1);
            } else if m > 0 && (down == Less || (down == Equal && odd)) {
                v = f32::from_bits(b - 1);
            } else {
                break;
            }
        }
    }
    if v.is_finite() {
        Some(v)
    } else {
        None
    }
}

use core::cmp::Ordering::{self, Equal, Greater, Less};

/// `mant` x 10^`exp10` against `k` x 2^`e` (exactly; -16 <= exp10 <= 10, k < 2^26).
fn cmp_decimal(mant: u32, exp10: i32, k: u64, e: i32) -> Ordering {
    // mant 5^j 2^j vs k 2^e  <=>  mant 5^j vs k 2^(e-j)          (exp10 = j >= 0)
    // mant 2^-j 5^-j vs k 2^e  <=>  mant vs k 5^j 2^(e+j)         (exp10 = -j < 0)
    let (a, b, t) = if exp10 >= 0 {
        (mant as u64 * POW5[exp10 as usize], k, e - exp10)
    } else {
        let j = (-exp10) as usize;
        (mant as u64, k * POW5[j], e + j as i32)
    };
    // a vs b 2^t
    if t >= 0 {
        let t = t as u32;
        if t >= 64 || b.leading_zeros() < t {
            return Less;
        }
        a.cmp(&(b << t))
    } else {
        let t = (-t) as u32;
        if t >= 64 || a.leading_zeros() < t {
            return Greater;
        }
        (a << t).cmp(&b)
    }
}

/// Decimal digits of `v` into the end of `buf`, at least `min_digits`; the start index.
fn digits(mut v: u32, buf: &mut [u8; 20], min_digits: usize) -> usize {
    let mut i = buf.len();
    while v > 0 || buf.len() - i < min_digits.max(1) {
        i -= 1;
        buf[i] = b'0' + (v % 10) as u8;
        v /= 10;
    }
    i
}

fn write_u32(f: &mut dyn Write, v: u32, min_digits: usize) -> fmt::Result {
    let mut buf = [0u8; 20];
    let s = digits(v, &mut buf, min_digits);
    for &c in &buf[s..] {
        f.write_char(c as char)?;
    }
    Ok(())
}

fn non_finite(f: &mut dyn Write, x: f32) -> fmt::Result {
    f.write_str(if x.is_nan() {
        "NaN"
    } else if x > 0.0 {
        "inf"
    } else {
        "-inf"
    })
}

/// 5^e, e <= 17 (5^17 < 2^40: times a 24-bit mantissa it fits a u64).
const POW5: [u64; 18] = {
    let mut t = [1u64; 18];
    let mut i = 1;
    while i < 18 {
        t[i] = t[i - 1] * 5;
        i += 1;
    }
    t
};

/// |x| rounded to `prec` (<= 17) decimals, exactly (half to even as core's `{:.p}`, or half
/// up with `tie_up`): the
/// integer part in two base-1e9 limbs (high, low) and the decimals as an integer below
/// 10^prec, plus whether the decimal reads back as x (its error under half an ulp).
/// `None` past 1e18 or when the decimals do not fit a u32 (only past 9 decimals).
struct Rounded {
    hi: u32,
    lo: u32,
    frac: u32,
    exact_back: bool,
}

fn round_fixed(x: f32, prec: usize, tie_up: bool) -> Option<Rounded> {
    let bits = x.to_bits() & 0x7fff_ffff;
    let be = (bits >> 23) as i32;
    let m = bits & 0x7f_ffff;
    let (m, e) = if be == 0 { (m, -149) } else { (m | 0x80_0000, be - 150) };
    if e >= 0 {
        // an integer: m x 2^e in base-1e9 limbs (m < 2^24 < 1e9)
        let (mut hi, mut lo) = (0u32, m);
        for _ in 0..e {
            hi *= 2;
            lo *= 2;
            if lo >= 1_000_000_000 {
                lo -= 1_000_000_000;
                hi += 1;
            }
            if hi >= 1_000_000_000 {
                return None;
            }
        }
        return Some(Rounded { hi, lo, frac: 0, exact_back: true });
    }
    let s = (-e) as u32;
    let int = if s >= 32 { 0 } else { m >> s };
    let fr = if s >= 32 { m } else { m & ((1u32 << s) - 1) };
    // fr / 2^s x 10^p = fr x 5^p / 2^(s - p): a u64 product, no division
    let prod = fr as u64 * POW5[prec];
    let sp = s as i32 - prec as i32;
    let (q, err, below) = if sp <= 0 {
        // exact: the decimals are an integer
        let sh = (-sp) as u32;
        if sh >= 32 || prod >> (32 - sh) != 0 {
            return None;
        }
        (prod << sh, 0, false)
    } else if sp >= 64 {
        (0, u64::MAX, true) // far below 10^-prec / 2: rounds to 0, does not read back
    } else {
        let sp = sp as u32;
        let q = prod >> sp;
        let rem = prod & ((1u64 << sp) - 1);
        let half = 1u64 << (sp - 1);
        // the last digit: of the decimals, or of the integer part at 0 decimals
        let odd = if prec == 0 { int & 1 == 1 } else { q & 1 == 1 };
        let up = rem > half || (rem == half && (tie_up || odd));
        // |decimal - x| in units of 2^-s / 5^prec
        (q + up as u64, if up { (1u64 << sp) - rem } else { rem }, !up)
    };
    if q > u32::MAX as u64 {
        return None;
    }
    // it reads back when under half an ulp of x (2^-s; a quarter of it below a power of two)
    let k: u64 = if m == 0x80_0000 && below && be > 1 { 4 } else { 2 };
    let exact_back = m == 0 || err == 0 || (err < u64::MAX / 4 && k * err < POW5[prec]);
    let (mut lo, mut frac) = (int, q as u32);
    if prec <= 9 && frac >= POW10U[prec] {
        frac -= POW10U[prec];
        lo += 1;
    } else if prec > 9 && int == 0 && q >= 10u64.pow(prec as u32) {
        return None; // 1 at this precision: shorter ones read back first
    }
    Some(Rounded { hi: 0, lo, frac, exact_back })
}

fn write_rounded(f: &mut dyn Write, neg: bool, r: &Rounded, prec: usize) -> fmt::Result {
    if neg {
        f.write_char('-')?;
    }
    if r.hi > 0 {
        write_u32(f, r.hi, 1)?;
        write_u32(f, r.lo, 9)?;
    } else {
        write_u32(f, r.lo, 1)?;
    }
    if prec > 0 {
        f.write_char('.')?;
        write_u32(f, r.frac, prec)?;
    }
    Ok(())
}

/// `x` with `prec` decimals (`{:.prec}`), `prec` <= 9; exact, as core prints it. Past 1e18
/// in exponent notation ([`Exp`]).
pub struct Fixed(pub f32, pub usize);

impl Fixed {
    /// Write it (the `Display` and [`Emit`] impls below call this).
    pub fn write(&self, f: &mut dyn Write) -> fmt::Result {
        let (x, prec) = (self.0, self.1.min(9));
        if !x.is_finite() {
            return non_finite(f, x);
        }
        match round_fixed(x, prec, false) {
            Some(r) => write_rounded(f, x.is_sign_negative(), &r, prec),
            None => Exp(x, prec).write(f),
        }
    }
}

/// The shortest fixed notation that reads back as the same f32 (`{}` of an f32; the same
/// text as core's for 1e-8 <= |x| < 1e18 and 0; otherwise exponent notation with 9 digits).
pub struct Short(pub f32);

impl Short {
    /// Write it (the `Display` and [`Emit`] impls below call this).
    pub fn write(&self, f: &mut dyn Write) -> fmt::Result {
        let x = self.0;
        if !x.is_finite() {
            return non_finite(f, x);
        }
        for prec in 0..=17usize {
            // an exact tie: core's shortest digits round it up
            if let Some(r) = round_fixed(x, prec, true) {
                if r.exact_back {
                    return write_rounded(f, x.is_sign_negative(), &r, prec);
                }
            }
        }
        Exp(x, 8).write(f)
    }
}

/// `x` in exponent notation with `prec` (<= 9) decimals (`{:.prec e}`: `1.2345e3`,
/// `-5.0000e-4`). Scaled in f32: the last digit may differ from core's.
pub struct Exp(pub f32, pub usize);

// same shape as `Fixed::write` (the non-finite guard, then the digits): another notation
impl Exp {
    /// Write it (the `Display` and [`Emit`] impls below call this).
    pub fn write(&self, f: &mut dyn Write) -> fmt::Result {
        let (x, prec) = (self.0, self.1.min(8));
        if !x.is_finite() {
            return non_finite(f, x);
        }
        let a = if x < 0.0 { -x } else { x };
        let mut e: i32 = 0;
        if a != 0.0 {
            // the decimal exponent from the binary one (log10(2) ~ 0.30103), then corrected
            let be = ((a.to_bits() >> 23) as i32 - 127).max(-149);
            e = (be * 30103).div_euclid(100_000);
            while scale10(a, -e) >= 10.0 {
                e += 1;
            }
            while scale10(a, -e) < 1.0 {
                e -= 1;
            }
        }
        let y = scale10(a, prec as i32 - e); // 10^prec <= y < 10^(prec+1), below 2^32
        let mut r = y as u32;
        let fr = y - r as f32;
        if fr > 0.5 || (fr == 0.5 && r & 1 == 1) {
            r += 1;
        }
        if r >= POW10U[prec] * 10 {
            r /= 10;
            e += 1;
        }
        if x.is_sign_negative() {
            f.write_char('-')?;
        }
        let p = POW10U[prec];
        write_u32(f, r / p, 1)?;
        if prec > 0 {
            f.write_char('.')?;
            write_u32(f, r % p, prec)?;
        }
        f.write_char('e')?;
        if e < 0 {
            f.write_char('-')?;
        }
        write_u32(f, e.unsigned_abs(), 1)
    }
}

/// A comma-separated list of `v` with `prec` decimals.
pub struct List<'a>(pub &'a [f32], pub usize);

impl List<'_> {
    /// Write it (the `Display` and [`Emit`] impls below call this).
    pub fn write(&self, f: &mut dyn Write) -> fmt::Result {
        for (i, x) in self.0.iter().enumerate() {
            if i > 0 {
                f.write_char(',')?;
            }
            Fixed(*x, self.1).write(f)?;
        }
        Ok(())
    }
}

/// The console side of a message's pieces ([`finger_protocol::Pieces`]): text as it is,
/// numbers with the formats above (in f32: no f64 formatting is linked). The model's errors'
/// messages are written once, in the model (model/src/error.rs), and rendered here.
pub struct Console<'a>(pub &'a mut dyn Write);

impl finger_protocol::Pieces for Console<'_> {
    #[inline(always)]
    fn text(&mut self, s: &str) {
        let _ = self.0.write_str(s);
    }
    #[inline(always)]
    fn fixed(&mut self, x: f64, decimals: u8) {
        let _ = Fixed(x as f32, decimals as usize).write(self.0);
    }
    #[inline(always)]
    fn exp(&mut self, x: f64, decimals: u8) {
        let _ = Exp(x as f32, decimals as usize).write(self.0);
    }
    #[inline(always)]
    fn count(&mut self, n: u32) {
        crate::out::emit_u32(self.0, n);
    }
}

/// The model's error as a console message ([`Console`] over the model's one table).
pub fn write_model_error(w: &mut dyn Write, e: &finger_model::Error) -> fmt::Result {
    finger_protocol::message::Message::message(e, &mut Console(w));
    Ok(())
}

/// `Emit` (the console) and `Display` (host tests, against core's formatting) for a number
/// format, both through its `write`.
macro_rules! emit_and_display {
    ($($t:ty),*) => {$(
        impl Emit for $t {
            fn emit(&self, o: &mut dyn Write) {
                let _ = self.write(o);
            }
        }

        impl fmt::Display for $t {
            fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                self.write(f)
            }
        }
    )*};
}
emit_and_display!(Fixed, Short, Exp, List<'_>);
