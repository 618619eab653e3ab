//! Q formats: `Q<F>` is an `i32` holding `x * 2^F`; each quantity has its own F so that its
//! range uses the word. Products are 32x32 -> 64 (`SMULL` on the M3) with one rounding shift
//! to the destination format; results that do not fit saturate and are caught as non-finite
//! by the caller's range checks (`Q::is_sat`).
//!
//! Formats (range, resolution):
//! - [`Mm`] lengths, Q22: +-512 mm, 2.4e-7 mm
//! - [`Nt`] forces, Q22: +-512 N
//! - [`Nmm`] moments, Q18: +-8192 N mm
//! - [`Rad`] angles, Q28: +-8 rad
//! - [`Unit`] sines, cosines, dimensionless ratios, Q30: +-2
//! - compliances: [`Scaled`], a Q30 mantissa with a per-entry exponent.

use core::ops::{Add, Neg, Sub};

#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Default)]
pub struct Q<const F: i32>(pub i32);

pub type Mm = Q<22>;
pub type Nt = Q<22>;
pub type Nmm = Q<18>;
pub type Rad = Q<28>;
pub type Unit = Q<30>;

/// Round-to-nearest shift of a 64-bit value by `s` bits (left when `s` < 0).
#[inline(always)]
pub fn shr_round(v: i64, s: i32) -> i64 {
    if s <= -63 {
        if v == 0 {
            0
        } else if v > 0 {
            i64::MAX
        } else {
            i64::MIN
        }
    } else if s <= 0 {
        v.saturating_mul(1i64 << (-s))
    } else if s >= 64 {
        0
    } else {
        (v + (1i64 << (s - 1))) >> s
    }
}

#[inline(always)]
fn sat(v: i64) -> i32 {
    if v > i32::MAX as i64 {
        i32::MAX
    } else if v < i32::MIN as i64 {
        i32::MIN
    } else {
        v as i32
    }
}

impl<const F: i32> Q<F> {
    pub const ZERO: Self = Q(0);
    pub const MAX: Self = Q(i32::MAX);
    pub const MIN: Self = Q(i32::MIN);
    pub const FRAC: i32 = F;
    /// From a float (host and set-up only); saturates.
    pub fn from_f64(x: f64) -> Self {
        let v = x * (1u64 << F) as f64;
        if v.is_nan() {
            return Self::MAX;
        }
        Q(if v >= i32::MAX as f64 {
            i32::MAX
        } else if v <= i32::MIN as f64 {
            i32::MIN
        } else {
            libm::round(v) as i32
        })
    }
    pub fn from_f32(x: f32) -> Self {
        let v = x * (1u64 << F) as f32;
        if v.is_nan() {
            return Self::MAX;
        }
        Q(if v >= 2147483520.0 {
            i32::MAX
        } else if v <= -2147483648.0 {
            i32::MIN
        } else {
            libm::roundf(v) as i32
        })
    }
    /// From the model's float type: through f32 when that is the type (no soft-float f64
    /// arithmetic in an f32 image), else through f64.
    #[inline(always)]
    pub fn from_real<R: crate::real::Real>(x: R) -> Self {
        if R::EPS > 1e-10 {
            Self::from_f32(x.to_f64() as f32)
        } else {
            Self::from_f64(x.to_f64())
        }
    }
    pub fn to_f64(self) -> f64 {
        self.0 as f64 / (1u64 << F) as f64
    }
    /// To the model's float type (through f32 when that is the type, as [`Q::from_real`]).
    #[inline(always)]
    pub fn to_real<R: crate::real::Real>(self) -> R {
        if R::EPS > 1e-10 {
            R::from_f64(self.to_f32() as f64)
        } else {
            R::from_f64(self.to_f64())
        }
    }
    /// For an error's report (f64 fields): through f32 (no f64 arithmetic on the M3).
    #[inline(always)]
    pub fn to_report(self) -> f64 {
        self.to_f32() as f64
    }
    pub fn to_f32(self) -> f32 {
        self.0 as f32 / (1u64 << F) as f32
    }
    /// From a raw 64-bit value at this format's frac (saturating).
    #[inline(always)]
    pub fn from_raw_sat(v: i64) -> Self {
        Q(sat(v))
    }
    /// Saturated (the format's end): treated as not finite.
    pub fn is_sat(self) -> bool {
        self.0 == i32::MAX || self.0 == i32::MIN
    }
    /// The value in another format (rounded, saturating).
    #[inline(always)]
    pub fn to<const G: i32>(self) -> Q<G> {
        Q(sat(shr_round(self.0 as i64, F - G)))
    }
    /// `self * o` in format G (one 32x32 -> 64 product, one shift).
    #[inline(always)]
    pub fn mul_q<const G: i32, const H: i32>(self, o: Q<G>) -> Q<H> {
        Q(sat(shr_round(self.0 as i64 * o.0 as i64, F + G - H)))
    }
    /// The raw 64-bit product at frac F + G (for sums before one final shift).
    #[inline(always)]
    pub fn wide<const G: i32>(self, o: Q<G>) -> i64 {
        self.0 as i64 * o.0 as i64
    }
    /// `self / o` in format H; `None` for a zero divisor or a quotient past H's range.
    #[inline(always)]
    pub fn div_q<const G: i32, const H: i32>(self, o: Q<G>) -> Option<Q<H>> {
        if o.0 == 0 {
            return None;
        }
        // (a 2^F / b 2^G) 2^H = (a 2^(H + G - F)) / b
        let s = H + G - F;
        let n = if s >= 0 { (self.0 as i64).checked_shl(s as u32)? } else { (self.0 as i64) >> (-s) };
        let qv = n.checked_div(o.0 as i64)?;
        if qv > i32::MAX as i64 || qv < i32::MIN as i64 {
            return None;
        }
        Some(Q(qv as i32))
    }
    pub fn abs(self) -> Self {
        Q(self.0.saturating_abs())
    }
}

/// A 64-bit sum of products at frac F, to format H.
#[inline(always)]
pub fn narrow<const H: i32>(v: i64, frac: i32) -> Q<H> {
    Q(sat(shr_round(v, frac - H)))
}

impl<const F: i32> Add for Q<F> {
    type Output = Self;
    #[inline(always)]
    fn add(self, o: Self) -> Self {
        Q(self.0.saturating_add(o.0))
    }
}
impl<const F: i32> Sub for Q<F> {
    type Output = Self;
    #[inline(always)]
    fn sub(self, o: Self) -> Self {
        Q(self.0.saturating_sub(o.0))
    }
}
impl<const F: i32> Neg for Q<F> {
    type Output = Self;
    #[inline(always)]
    fn neg(self) -> Self {
        Q(self.0.saturating_neg())
    }
}

/// A compliance entry with its own scale: `m * 2^-sh`, |m| < 2^30 (the tiny hinge
/// compliances keep 30 significant bits whatever their magnitude).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub struct Scaled {
    pub m: i32,
    pub sh: i32,
}

impl Scaled {
    /// From the float's bits (integer operations only: no soft-float arithmetic on the M3).
    pub fn from_f64(x: f64) -> Self {
        let bits = x.to_bits();
        let exp = ((bits >> 52) & 0x7ff) as i32;
        if exp == 0 || exp == 0x7ff {
            return Scaled { m: 0, sh: 0 }; // zero, subnormal (below any compliance), inf, NaN
        }
        // |x| = mant 2^(exp - 1075), mant in [2^52, 2^53): keep its top 30 bits
        let mant = (bits & ((1u64 << 52) - 1)) | (1u64 << 52);
        let (mut m, mut sh) = (((mant >> 22) + 1) >> 1, 1052 - exp);
        if m >= 1 << 30 {
            m >>= 1;
            sh -= 1;
        }
        let m = m as i32;
        Scaled { m: if bits >> 63 != 0 { -m } else { m }, sh }
    }
    pub fn to_f64(self) -> f64 {
        self.m as f64 * libm::exp2(-self.sh as f64)
    }
    /// `x * self` as a 64-bit value at frac `acc` (for sums of products).
    #[inline(always)]
    pub fn wide<const F: i32>(self, x: Q<F>, acc: i32) -> i64 {
        shr_round(x.0 as i64 * self.m as i64, F + self.sh - acc)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn products_and_quotients_round_to_the_destination_format() {
        let a = Mm::from_f64(12.345678);
        let b = Nt::from_f64(-0.75);
        let p: Nmm = a.mul_q(b);
        assert!((p.to_f64() + 12.345678 * 0.75).abs() <= 1.0 / 262144.0);
        let d: Option<Unit> = b.div_q(a);
        assert!((d.unwrap().to_f64() + 0.75 / 12.345678).abs() < 1e-8);
        assert_eq!(a.div_q::<22, 22>(Mm::ZERO), None);
        let big = Mm::from_f64(500.0);
        assert!(big.mul_q::<22, 22>(big).is_sat());
    }

    #[test]
    fn scaled_entries_keep_thirty_bits() {
        for x in [1.234e-9, -4.2e-5, 3.3, 0.0, 7.0e3] {
            let s = Scaled::from_f64(x);
            assert!((s.to_f64() - x).abs() <= x.abs() * 2e-9, "{x} {s:?}");
        }
        let c = Scaled::from_f64(2.5e-4);
        let f = Nt::from_f64(2.0);
        assert!((c.wide(f, 40) as f64 / (1u64 << 40) as f64 - 5e-4).abs() < 1e-11);
    }
}
