//! Fixed-point scalars for the model, for cores without an FPU (Cortex-M3): newtypes over the
//! `fixed` crate's I16F16 (`Q16`, 32-bit words, resolution 1.5e-5) and I32F32 (`Q32`, 64-bit
//! words, resolution 2.3e-10), implementing the model's `Real`.
//!
//! - Arithmetic saturates instead of wrapping or panicking; the saturated values MIN and MAX
//!   play the role of infinity: `is_finite` is false for them, so an overflow surfaces as the
//!   model's typed error for a non-finite result, never as a wrong number or a panic.
//!   Division by zero saturates too (0/0 gives MAX, "not finite").
//! - sin/cos: reduction by the nearest multiple of pi/2, then Taylor polynomials on
//!   [-pi/4, pi/4] in Horner form (degree 7/8 for Q16, 11/12 for Q32: truncation below the
//!   resolution). atan2: octant reduction and a Taylor series on |t| <= tan(pi/8) (only the
//!   hinge quadrature uses it, which the bench runs in f32: see `prep`).
//! - sqrt: digit-by-digit integer square root of the raw bits shifted by the fraction width.
//! - The model's intermediate products in the hinge quadrature (E w t^3 reaches 1e5..1e8) do
//!   not fit I16F16, and eps0 = 8.9e-12 is below both resolutions: `prep` computes the finger's
//!   hinge compliances and the joint compliances once in f32 and casts them
//!   (`Finger::cast`, `Compliances::cast`), so the solve itself runs in fixed point.

use core::ops::{Add, AddAssign, Div, DivAssign, Mul, MulAssign, Neg, Sub, SubAssign};
use finger_model::{Compliances, Error, Finger, Real};

macro_rules! fixed_real {
    ($name:ident, $fx:ty, $raw:ty, $uwide:ty, $frac:expr, $label:expr, $sin:expr, $cos:expr) => {
        #[derive(Clone, Copy, Debug, PartialEq, PartialOrd)]
        pub struct $name(pub $fx);

        impl $name {
            const MAX: Self = $name(<$fx>::MAX);
            const MIN: Self = $name(<$fx>::MIN);
            #[inline(always)]
            fn c(x: f64) -> Self {
                <Self as Real>::from_f64(x)
            }
            /// Horner: c[0] + u (c[1] + u (c[2] + ...)).
            #[inline(always)]
            fn horner(u: Self, coef: &[f64]) -> Self {
                let mut acc = Self::c(coef[coef.len() - 1]);
                let mut i = coef.len() - 1;
                while i > 0 {
                    i -= 1;
                    acc = Self::c(coef[i]) + u * acc;
                }
                acc
            }
        }

        impl Add for $name {
            type Output = Self;
            #[inline(always)]
            fn add(self, o: Self) -> Self {
                $name(self.0.saturating_add(o.0))
            }
        }
        impl Sub for $name {
            type Output = Self;
            #[inline(always)]
            fn sub(self, o: Self) -> Self {
                $name(self.0.saturating_sub(o.0))
            }
        }
        impl Mul for $name {
            type Output = Self;
            #[inline(always)]
            fn mul(self, o: Self) -> Self {
                $name(self.0.saturating_mul(o.0))
            }
        }
        impl Div for $name {
            type Output = Self;
            #[inline(always)]
            fn div(self, o: Self) -> Self {
                if o.0 == <$fx>::ZERO {
                    if self.0 < <$fx>::ZERO {
                        Self::MIN
                    } else {
                        Self::MAX
                    }
                } else {
                    $name(self.0.saturating_div(o.0))
                }
            }
        }
        impl Neg for $name {
            type Output = Self;
            #[inline(always)]
            fn neg(self) -> Self {
                $name(self.0.saturating_neg())
            }
        }
        impl AddAssign for $name {
            #[inline(always)]
            fn add_assign(&mut self, o: Self) {
                *self = *self + o;
            }
        }
        impl SubAssign for $name {
            #[inline(always)]
            fn sub_assign(&mut self, o: Self) {
                *self = *self - o;
            }
        }
        impl MulAssign for $name {
            #[inline(always)]
            fn mul_assign(&mut self, o: Self) {
                *self = *self * o;
            }
        }
        impl DivAssign for $name {
            #[inline(always)]
            fn div_assign(&mut self, o: Self) {
                *self = *self / o;
            }
        }

        impl Real for $name {
            const EPS: f64 = 1.0 / ((1u64 << $frac) as f64);
            const SQRT_EPS: f64 = 1.0 / ((1u64 << ($frac / 2)) as f64);
            const NAME: &'static str = $label;
            #[inline(always)]
            fn from_f64(x: f64) -> Self {
                match <$fx>::checked_from_num(x) {
                    Some(v) => $name(v),
                    None if x < 0.0 => Self::MIN,
                    None => Self::MAX, // too large, or NaN: "not finite"
                }
            }
            #[inline(always)]
            fn from_u32(n: u32) -> Self {
                match <$fx>::checked_from_num(n) {
                    Some(v) => $name(v),
                    None => Self::MAX,
                }
            }
            #[inline(always)]
            fn to_f64(self) -> f64 {
                self.0.to_num::<f64>()
            }
            fn sqrt(self) -> Self {
                let r = self.0.to_bits();
                if r <= 0 {
                    return $name(<$fx>::ZERO);
                }
                // sqrt(r 2^-f) = sqrt(r 2^f) 2^-f
                // same loop as the model's `fixed::trig::isqrt`, which takes u64 only (Q32 needs u128) and is not in these images
                let n: $uwide = (r as $uwide) << $frac;
                let mut rem = n;
                let mut res: $uwide = 0;
                let mut bit: $uwide = 1 << (<$uwide>::BITS - 2);
                while bit > n {
                    bit >>= 2;
                }
                while bit != 0 {
                    if rem >= res + bit {
                        rem -= res + bit;
                        res = (res >> 1) + bit;
                    } else {
                        res >>= 1;
                    }
                    bit >>= 2;
                }
                $name(<$fx>::from_bits(res as $raw))
            }
            fn sin_cos(self) -> (Self, Self) {
                if !self.is_finite() {
                    return (Self::MAX, Self::MAX);
                }
                // x = k pi/2 + r, |r| <= pi/4
                let k = (self * Self::c(core::f64::consts::FRAC_2_PI)).0.round();
                let kf = $name(k);
                let r = (self - kf * Self::c(core::f64::consts::FRAC_PI_2)) - kf * Self::c(6.123233995736766e-17);
                let u = r * r;
                let s = r * Self::horner(u, $sin);
                let c = Self::horner(u, $cos);
                match k.to_num::<i32>() & 3 {
                    0 => (s, c),
                    1 => (c, -s),
                    2 => (-s, -c),
                    _ => (-c, s),
                }
            }
            fn atan2(self, x: Self) -> Self {
                let y = self;
                let zero = Self::c(0.0);
                if x == zero && y == zero {
                    return zero;
                }
                let (ax, ay) = (x.abs(), y.abs());
                let swap = ay > ax;
                let t = if swap { ax / ay } else { ay / ax }; // [0, 1]
                                                              // atan(t) for t in [0, 1]: past tan(pi/8) use pi/4 + atan((t-1)/(t+1))
                let one = Self::c(1.0);
                let (base, v) = if t > Self::c(0.41421356237309503) { (Self::c(core::f64::consts::FRAC_PI_4), (t - one) / (t + one)) } else { (zero, t) };
                const ATAN: [f64; 14] = [
                    1.0,
                    -1.0 / 3.0,
                    1.0 / 5.0,
                    -1.0 / 7.0,
                    1.0 / 9.0,
                    -1.0 / 11.0,
                    1.0 / 13.0,
                    -1.0 / 15.0,
                    1.0 / 17.0,
                    -1.0 / 19.0,
                    1.0 / 21.0,
                    -1.0 / 23.0,
                    1.0 / 25.0,
                    -1.0 / 27.0,
                ];
                let mut a = base + v * Self::horner(v * v, &ATAN);
                if swap {
                    a = Self::c(core::f64::consts::FRAC_PI_2) - a;
                }
                if x < zero {
                    a = Self::c(core::f64::consts::PI) - a;
                }
                if y < zero {
                    -a
                } else {
                    a
                }
            }
            #[inline(always)]
            fn is_finite(self) -> bool {
                self != Self::MAX && self != Self::MIN
            }
        }
    };
}

const SIN7: &[f64] = &[1.0, -1.0 / 6.0, 1.0 / 120.0, -1.0 / 5040.0];
const COS8: &[f64] = &[1.0, -0.5, 1.0 / 24.0, -1.0 / 720.0, 1.0 / 40320.0];
const SIN11: &[f64] = &[1.0, -1.0 / 6.0, 1.0 / 120.0, -1.0 / 5040.0, 1.0 / 362880.0, -1.0 / 39916800.0];
const COS12: &[f64] = &[1.0, -0.5, 1.0 / 24.0, -1.0 / 720.0, 1.0 / 40320.0, -1.0 / 3628800.0, 1.0 / 479001600.0];

fixed_real!(Q16, fixed::types::I16F16, i32, u64, 16, "i16f16", SIN7, COS8);
fixed_real!(Q32, fixed::types::I32F32, i64, u128, 32, "i32f32", SIN11, COS12);

/// The finger and the scene's compliances computed in f32 and cast to fixed point; the
/// returned ticks are the f32 compliance computation plus the cast.
#[allow(dead_code)]
pub fn prep<S: Real>(s: &crate::scenes::Scene) -> Result<(Finger<S>, Compliances<S>, u64), Error> {
    let f = Finger::new(crate::params(s).cast::<f32>())?;
    let v = [s.volts[0] as f32, s.volts[1] as f32, s.volts[2] as f32];
    let t0 = crate::cycles::now();
    let c = f.compliances(&v)?.cast::<S>();
    let t1 = crate::cycles::now();
    Ok((f.cast::<S>(), c, t1 - t0))
}
