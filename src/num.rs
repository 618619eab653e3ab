//! Numbers to and from text without core's float parsing and formatting (issue 3: flash).
//!
//! core's `f64::from_str` (dec2flt, ~13 KB with its tables) and float `Display` (grisu and
//! dragon, ~10 KB) do not fit the 64 KiB image. The console needs much less: decimals of a few
//! significant digits in, fixed or exponent notation of an f32 out.
//!
//! - [`decimal_to_f64`]: mantissa digits and a decimal exponent to f64. Correctly rounded for
//!   up to 15 significant digits and exponents within ±22 (Clinger's fast path: one exact
//!   product or quotient), within a few ulp beyond; overflow is reported, not infinity.
//! - [`Fixed`], [`Short`], [`Exp`]: `Display` wrappers printing like core's `{:.p}`, `{}` and
//!   `{:.pe}` for the values the console shows. Finite values only matter here; NaN prints
//!   `NaN` and infinities `inf` / `-inf` as core does.

use core::fmt::{self, Write};

/// 10^e as f64 (exact for e <= 22), infinity past f64's range.
pub fn pow10(e: u32) -> f64 {
    let mut p = 1.0f64;
    let mut i = 0;
    while i < e {
        p *= 10.0;
        if p > f64::MAX {
            return f64::INFINITY;
        }
        i += 1;
    }
    p
}

/// `mant` x 10^`exp10`, `None` when it overflows f64.
pub fn decimal_to_f64(mant: u64, exp10: i32) -> Option<f64> {
    if mant == 0 {
        return Some(0.0);
    }
    let m = mant as f64;
    let v = if exp10 >= 0 {
        m * pow10(exp10 as u32)
    } else {
        // two steps keep 10^-e finite down to the subnormals
        let mut e = -(exp10 as i64);
        let mut v = m;
        while e > 300 {
            v /= 1e300;
            e -= 300;
        }
        v / pow10(e as u32)
    };
    if v.is_finite() {
        Some(v)
    } else {
        None
    }
}

/// Decimal digits of `v` into the end of `buf`, at least `min_digits`; the start index.
fn digits(mut v: u64, buf: &mut [u8; 24], min_digits: usize) -> usize {
    let mut i = buf.len();
    while v > 0 || buf.len() - i < min_digits.max(1) {
        i -= 1;
        buf[i] = b'0' + (v % 10) as u8;
        v /= 10;
    }
    i
}

/// Round a non-negative f64 below 2^64 to an integer, half to even (as core's formatting).
fn round_even(y: f64) -> u64 {
    let t = y as u64;
    let frac = y - t as f64;
    if frac > 0.5 || (frac == 0.5 && t & 1 == 1) {
        t + 1
    } else {
        t
    }
}

fn non_finite(f: &mut fmt::Formatter<'_>, x: f64) -> fmt::Result {
    f.write_str(if x.is_nan() {
        "NaN"
    } else if x > 0.0 {
        "inf"
    } else {
        "-inf"
    })
}

/// Write `r` / 10^`prec` with exactly `prec` decimals.
fn write_scaled(f: &mut fmt::Formatter<'_>, neg: bool, r: u64, prec: usize) -> fmt::Result {
    let mut buf = [0u8; 24];
    let s = digits(r, &mut buf, prec + 1);
    if neg {
        f.write_char('-')?;
    }
    let dot = buf.len() - prec;
    // ASCII digits only
    f.write_str(core::str::from_utf8(&buf[s..dot]).unwrap_or("?"))?;
    if prec > 0 {
        f.write_char('.')?;
        f.write_str(core::str::from_utf8(&buf[dot..]).unwrap_or("?"))?;
    }
    Ok(())
}

/// Largest value printed in fixed notation; beyond it [`Fixed`] falls back to [`Exp`].
const FIXED_MAX: f64 = 1.0e18;

/// `x` with `prec` decimals (`{:.prec}`), `prec` <= 9. Exact for f32 inputs (the product of a
/// 24-bit mantissa and 10^prec is exact in f64), so it prints as core does.
pub struct Fixed(pub f64, pub usize);

impl fmt::Display for Fixed {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let (x, prec) = (self.0, self.1.min(9));
        if !x.is_finite() {
            return non_finite(f, x);
        }
        let y = if x < 0.0 { -x } else { x } * pow10(prec as u32);
        if y >= FIXED_MAX {
            return Exp(x, prec).fmt(f);
        }
        write_scaled(f, x.is_sign_negative(), round_even(y), prec)
    }
}

/// The shortest fixed notation that reads back as the same f32 (`{}` of an f32; the same
/// text as core's for the console's values, 1e-6 <= |x| < 1e9 and 0).
pub struct Short(pub f32);

impl fmt::Display for Short {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let x = self.0;
        if !x.is_finite() {
            return non_finite(f, x as f64);
        }
        let a = if x < 0.0 { -(x as f64) } else { x as f64 };
        for prec in 0..=17usize {
            let scale = pow10(prec as u32);
            let y = a * scale;
            if y >= FIXED_MAX {
                return Exp(x as f64, 6).fmt(f);
            }
            // an exact tie: core's shortest digits round it up
            let t = y as u64;
            let r = if y - t as f64 >= 0.5 { t + 1 } else { t };
            if (r as f64 / scale) as f32 == a as f32 || prec == 17 {
                return write_scaled(f, x.is_sign_negative(), r, prec);
            }
        }
        Ok(())
    }
}

/// `x` in exponent notation with `prec` decimals (`{:.prec e}`: `1.2345e3`, `-5.0000e-4`).
pub struct Exp(pub f64, pub usize);

impl fmt::Display for Exp {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let (x, prec) = (self.0, self.1.min(9));
        if !x.is_finite() {
            return non_finite(f, x);
        }
        let mut a = if x < 0.0 { -x } else { x };
        let mut e: i32 = 0;
        if a != 0.0 {
            while a >= 10.0 {
                a /= 10.0;
                e += 1;
            }
            while a < 1.0 {
                a *= 10.0;
                e -= 1;
            }
        }
        let scale = pow10(prec as u32);
        let mut r = round_even(a * scale);
        if r as f64 >= 10.0 * scale {
            r = round_even(r as f64 / 10.0);
            e += 1;
        }
        write_scaled(f, x.is_sign_negative(), r, prec)?;
        f.write_char('e')?;
        if e < 0 {
            f.write_char('-')?;
        }
        let mut buf = [0u8; 24];
        let s = digits(e.unsigned_abs() as u64, &mut buf, 1);
        f.write_str(core::str::from_utf8(&buf[s..]).unwrap_or("?"))
    }
}

/// A comma-separated list of `v` with `prec` decimals.
pub struct List<'a>(pub &'a [f32], pub usize);

impl fmt::Display for List<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for (i, x) in self.0.iter().enumerate() {
            if i > 0 {
                f.write_char(',')?;
            }
            Fixed(*x as f64, self.1).fmt(f)?;
        }
        Ok(())
    }
}

/// The model's error as a console message, from its public fields, with the formatters above
/// (the model's own `Display` formats f64 with core and would link core's float formatting).
pub fn write_model_error<W: Write>(w: &mut W, e: &finger_model::Error) -> fmt::Result {
    use finger_model::Error as E;
    match *e {
        E::Param { name, range } => write!(w, "parameter {name} out of range: {range}"),
        E::NonFinite { input } => write!(w, "{input} is not a finite number"),
        E::Input { input, reason } => write!(w, "{input}: {reason}"),
        E::VoltageCeiling { joint, volts, ceiling } => write!(
            w,
            "joint {joint}: {} V is at or past the ceiling {} V (33 % pull-in limit with margin, or supply)",
            Fixed(volts, 0),
            Fixed(ceiling, 0)
        ),
        E::ThicknessLimit { joint, requested_mm, limit_mm } => write!(
            w,
            "joint {joint}: stack thickness {} mm is past the 33 % pull-in limit ({} mm)",
            Fixed(requested_mm, 3),
            Fixed(limit_mm, 3)
        ),
        E::Contact { joint, tension } => {
            write!(w, "joint {joint}: links in contact (cable span at its floor) at {} N", Fixed(tension, 3))
        }
        E::LimitPoint { joint, tension } => {
            write!(w, "joint {joint}: equilibrium limit point (singular tangent) at {} N", Fixed(tension, 3))
        }
        E::ForceLimit { tension, fmax } => write!(
            w,
            "tension {} N is past the end of the equilibrium branch fmax={} N",
            Fixed(tension, 3),
            Fixed(fmax, 3)
        ),
        E::NotConverged { iterations, residual } => {
            write!(w, "solver did not converge: {iterations} iterations, residual {}", Exp(residual, 3))
        }
        E::Singular { what } => write!(w, "singular {what}"),
        E::Unreachable { joint, needed, min, max } => write!(
            w,
            "joint {joint}: needs compliance {} rad/Nmm, the ceiling allows {}..{}",
            Exp(needed, 4),
            Exp(min, 4),
            Exp(max, 4)
        ),
        #[allow(unreachable_patterns)]
        _ => write!(w, "model error"),
    }
}
