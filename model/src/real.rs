//! The scalar the model computes in: one code path for f32 (target) and f64 (host reference).
//!
//! What it is: a small trait with the arithmetic and the few elementary functions the model
//! needs, each routed to one explicitly chosen implementation. On the host, `x.sin()` on an
//! `f32` silently means std's sine; the model never calls inherent float methods, only these,
//! so host and target compute the same numbers.
//!
//! - `f64`: libm throughout (the reference).
//! - `f32`: libm by default; with the `micromath` feature, trig, atan2 and sqrt go through
//!   micromath (about 50x cheaper on a Cortex-M4F, ~1e-4 relative error on sin/cos).
//!
//! What it is not: a general numeric tower. Fixed point implements it elsewhere (`fixed`).

use core::fmt::Debug;
use core::ops::{Add, AddAssign, Div, DivAssign, Mul, MulAssign, Neg, Sub, SubAssign};

/// The scalar type of the model.
pub trait Real:
    Copy
    + Debug
    + PartialOrd
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
    + AddAssign
    + SubAssign
    + MulAssign
    + DivAssign
{
    /// Machine epsilon of the type (relative resolution).
    const EPS: f64;
    /// Name for reports.
    const NAME: &'static str;
    /// Square root of `EPS` (a constant: no f64 arithmetic at run time on the target).
    const SQRT_EPS: f64;
    fn from_f64(x: f64) -> Self;
    /// An integer as a scalar (counts, indices): converted directly, never through f64, so an
    /// f32 build on the target does no double-precision arithmetic.
    fn from_u32(n: u32) -> Self;
    fn to_f64(self) -> f64;
    /// The integer part of a non-negative scalar (a table index; saturating, 0 for NaN).
    /// f32 converts directly, never through f64.
    #[inline(always)]
    fn to_index(self) -> usize {
        self.to_f64() as usize
    }
    fn sqrt(self) -> Self;
    /// (sin x, cos x): the one trig a scalar must give; `sin` and `cos` default to its halves.
    fn sin_cos(self) -> (Self, Self);
    #[inline(always)]
    fn sin(self) -> Self {
        self.sin_cos().0
    }
    #[inline(always)]
    fn cos(self) -> Self {
        self.sin_cos().1
    }
    /// The turn rule, (sin x, cos x) of a rotation x (a sub-element's, a link's): the Taylor
    /// series to x⁵ and x⁶ below `small` (`finger::march::small_turn`: exact to the scalar's
    /// resolution there), the series one term longer (to x⁷ and x⁸, exact to the resolution up
    /// to 0.6 in f32, 0.07 in f64) below 2 `small`, else x's sin/cos; on a soft-float core
    /// (no room for the series' code in the M3 image's 64 KiB) always x's sin/cos. The bounds
    /// are tested on x², which the series needs anyway.
    #[inline(always)]
    fn turn(self, small: Self) -> (Self, Self) {
        if cfg!(target_abi = "eabi") {
            return self.sin_cos();
        }
        let z = self * self;
        let s = self * (Self::one() - z * (Self::from_f64(1.0 / 6.0) - z * Self::from_f64(1.0 / 120.0)));
        let c = Self::one() - z * (Self::from_f64(0.5) - z * (Self::from_f64(1.0 / 24.0) - z * Self::from_f64(1.0 / 720.0)));
        let small2 = small * small;
        if z < small2 {
            (s, c)
        } else if z < small2 * Self::from_f64(4.0) {
            // the next terms, -x⁷/7! and x⁸/8!
            let z3 = z * z * z;
            (s - self * z3 * Self::from_f64(1.0 / 5040.0), c + z3 * z * Self::from_f64(1.0 / 40320.0))
        } else {
            self.sin_cos()
        }
    }
    /// (sin, cos) of θ + x from (sin θ, cos θ) and (sin x, cos x) (`turn`): the rotations
    /// composed. `angle` is θ + x: dual numbers take their derivative from it (cos and -sin
    /// times its own), the others ignore it.
    #[inline(always)]
    fn compose_turn((s, c): (Self, Self), (sx, cx): (Self, Self), _angle: Self) -> (Self, Self) {
        (s * cx + c * sx, c * cx - s * sx)
    }
    fn atan2(self, x: Self) -> Self;
    fn is_finite(self) -> bool;
    /// e^x (the material's relaxation factors, computed once per time step, never per tick).
    /// The default goes through f64; f32 and f64 override it with libm.
    fn exp(self) -> Self {
        Self::from_f64(libm::exp(self.to_f64()))
    }
    /// Cube root (the film's pull-in stretch).
    fn cbrt(self) -> Self {
        Self::from_f64(libm::cbrt(self.to_f64()))
    }

    #[inline(always)]
    fn zero() -> Self {
        Self::from_f64(0.0)
    }
    #[inline(always)]
    fn one() -> Self {
        Self::from_f64(1.0)
    }
    #[inline(always)]
    fn abs(self) -> Self {
        if self < Self::zero() {
            -self
        } else {
            self
        }
    }
    #[inline(always)]
    fn max(self, o: Self) -> Self {
        if self > o {
            self
        } else {
            o
        }
    }
    #[inline(always)]
    fn min(self, o: Self) -> Self {
        if self < o {
            self
        } else {
            o
        }
    }
    /// `x * x`
    #[inline(always)]
    fn sq(self) -> Self {
        self * self
    }
}

/// `Real` for a primitive float: the methods f32 and f64 share, written once; each names its
/// square root, e^x and cube root, and brings its own trig (`sin`, `cos`, `sin_cos`, `atan2`).
macro_rules! float_real {
    ($t:ident, sqrt_eps: $sqrt_eps:expr, name: $name:expr, sqrt: $sqrt:path, exp: $exp:path, cbrt: $cbrt:path, trig: { $($trig:tt)* }) => {
        impl Real for $t {
            const EPS: f64 = $t::EPSILON as f64;
            const SQRT_EPS: f64 = $sqrt_eps;
            const NAME: &'static str = $name;
            #[inline(always)]
            fn from_f64(x: f64) -> Self {
                x as $t
            }
            #[inline(always)]
            fn from_u32(n: u32) -> Self {
                n as $t
            }
            #[inline(always)]
            fn to_index(self) -> usize {
                self as usize
            }
            #[inline(always)]
            fn to_f64(self) -> f64 {
                self as f64
            }
            #[inline(always)]
            fn sqrt(self) -> Self {
                $sqrt(self)
            }
            #[inline(always)]
            fn is_finite(self) -> bool {
                $t::is_finite(self)
            }
            #[inline(always)]
            fn exp(self) -> Self {
                $exp(self)
            }
            #[inline(always)]
            fn cbrt(self) -> Self {
                $cbrt(self)
            }
            $($trig)*
        }
    };
}

float_real!(f64, sqrt_eps: 1.4901161193847656e-8, name: "f64/libm", sqrt: libm::sqrt, exp: libm::exp, cbrt: libm::cbrt, trig: {
    #[inline(always)]
    fn sin(self) -> Self {
        libm::sin(self)
    }
    #[inline(always)]
    fn cos(self) -> Self {
        libm::cos(self)
    }
    #[inline(always)]
    fn sin_cos(self) -> (Self, Self) {
        libm::sincos(self)
    }
    #[inline(always)]
    fn atan2(self, x: Self) -> Self {
        libm::atan2(self, x)
    }
});

/// f32: libm, `fast-trig` or micromath for the trig (with `micromath`, `fast-trig` has no
/// effect); the square root is `sqrt_f32` in every case (micromath's is an approximation; the
/// correctly rounded one is cheap).
const F32_NAME: &str = if cfg!(feature = "micromath") {
    "f32/micromath"
} else if cfg!(feature = "fast-trig") {
    "f32/fast-trig"
} else {
    "f32/libm"
};

float_real!(f32, sqrt_eps: 3.4526698300124393e-4, name: F32_NAME, sqrt: sqrt_f32, exp: libm::expf, cbrt: cbrt_f32, trig: {
    // same shape as `cos`: each names its own routine of the feature's trig
    #[inline(always)]
    fn sin(self) -> Self {
        #[cfg(feature = "micromath")]
        return micromath::F32(self).sin().0;
        #[cfg(all(feature = "fast-trig", not(feature = "micromath")))]
        return fast_trig::sin_cos(self).0;
        #[cfg(not(any(feature = "fast-trig", feature = "micromath")))]
        libm::sinf(self)
    }
    #[inline(always)]
    fn cos(self) -> Self {
        #[cfg(feature = "micromath")]
        return micromath::F32(self).cos().0;
        #[cfg(all(feature = "fast-trig", not(feature = "micromath")))]
        return fast_trig::sin_cos(self).1;
        #[cfg(not(any(feature = "fast-trig", feature = "micromath")))]
        libm::cosf(self)
    }
    // micromath has no joint sine and cosine
    #[cfg(feature = "micromath")]
    #[inline(always)]
    fn sin_cos(self) -> (Self, Self) {
        sin_then_cos(self)
    }
    #[cfg(not(feature = "micromath"))]
    #[inline(always)]
    fn sin_cos(self) -> (Self, Self) {
        #[cfg(feature = "fast-trig")]
        return fast_trig::sin_cos(self);
        #[cfg(not(feature = "fast-trig"))]
        libm::sincosf(self)
    }
    #[inline(always)]
    fn atan2(self, x: Self) -> Self {
        #[cfg(feature = "micromath")]
        return micromath::F32(self).atan2(micromath::F32(x)).0;
        #[cfg(not(feature = "micromath"))]
        libm::atan2f(self, x)
    }
});

/// (sin x, cos x) as two calls. Generic and without an inline hint, so the optimiser decides
/// per image whether to inline it (the micromath images' instruction counts depend on it).
#[cfg(feature = "micromath")]
fn sin_then_cos<R: Real>(x: R) -> (R, R) {
    (x.sin(), x.cos())
}

/// The f32 cube root. Not libm's `cbrtf`: it computes in f64, which is soft-float code (about
/// 2.5 KB) on a core without a double-precision FPU. Newton from the exponent-thirds guess
/// (within 6 %): three steps reach f32's resolution.
fn cbrt_f32(x: f32) -> f32 {
    if x == 0.0 || !x.is_finite() {
        return x;
    }
    let a = if x < 0.0 { -x } else { x };
    let mut y = f32::from_bits(a.to_bits() / 3 + 0x2a51_37a0);
    for _ in 0..3 {
        y -= (y * y * y - a) / (3.0 * y * y);
    }
    if x < 0.0 {
        -y
    } else {
        y
    }
}

/// The correctly rounded f32 square root. On a Cortex-M with a single-precision FPU (the
/// M4F) it is the one `vsqrt.f32` instruction (14 cycles); stable Rust has no intrinsic for
/// it in `no_std`, and libm's `sqrtf` is a software routine there (~600 bytes, ~100
/// instructions). IEEE 754 requires sqrt correctly rounded, so both give the same bits and the
/// host (libm) and the target compute the same numbers. NaN for x < 0, as libm.
#[inline(always)]
fn sqrt_f32(x: f32) -> f32 {
    #[cfg(all(target_arch = "arm", target_abi = "eabihf"))]
    return fpu_sqrt::sqrt(x);
    #[cfg(not(all(target_arch = "arm", target_abi = "eabihf")))]
    return libm::sqrtf(x);
}

/// `vsqrt.f32` as a leaf function (the argument and the result in s0, hard-float ABI).
/// Inline `asm!` cannot name the FPU registers on this target in stable Rust (its `sreg`
/// class needs the double-precision `vfp2` feature, which the M4F's FPU does not have), so
/// the instruction lives in a two-instruction function the assembler builds for fpv4-sp-d16.
#[cfg(all(target_arch = "arm", target_abi = "eabihf"))]
#[allow(unsafe_code)]
mod fpu_sqrt {
    core::arch::global_asm!(
        ".section .text.finger_model_vsqrtf,\"ax\",%progbits",
        ".global finger_model_vsqrtf",
        ".type finger_model_vsqrtf,%function",
        ".fpu fpv4-sp-d16",
        ".thumb_func",
        "finger_model_vsqrtf:",
        "    vsqrt.f32 s0, s0",
        "    bx lr",
        ".size finger_model_vsqrtf, . - finger_model_vsqrtf",
    );
    extern "C" {
        fn finger_model_vsqrtf(x: f32) -> f32;
    }
    #[inline(always)]
    pub fn sqrt(x: f32) -> f32 {
        // SAFETY: a leaf function of two instructions, FPU registers only (s0 in and out, as
        // the eabihf calling convention passes f32), no memory, no stack.
        unsafe { finger_model_vsqrtf(x) }
    }
}

/// f32 sine and cosine computed in f32 (feature `fast-trig`): libm's `sinf`/`cosf`
/// reduce and evaluate in f64, which a Cortex-M4F (single-precision FPU) runs in software
/// (~1,000 instructions a call). Here: Cody-Waite reduction by pi/2 with a three-part pi/2
/// (exact for |x| < 2^13 · pi/2), then the Cephes minimax polynomials on [-pi/4, pi/4]
/// (error about 1 ulp, like libm's f32 results); ~40 instructions for both.
///
/// Beyond |x| = 12868 (2^13 · pi/2, about 2,000 turns) the result is NaN, not libm's: the
/// model's angles are joint and chain angles (a few radians); only a diverging iterate gets
/// there, and the solvers' finiteness checks turn its NaN into a typed error. Leaving libm's
/// reduction out keeps its f64 code (and the soft-float kernels under it, ~6 KB) out of the
/// firmware image.
#[cfg(all(feature = "fast-trig", not(feature = "micromath")))]
mod fast_trig {
    pub fn sin_cos(x: f32) -> (f32, f32) {
        if !(x.abs() < 12868.0) {
            return (f32::NAN, f32::NAN);
        }
        // nearest multiple of pi/2 (round half away from zero)
        let kf = x * core::f32::consts::FRAC_2_PI;
        let k = (kf + if kf < 0.0 { -0.5 } else { 0.5 }) as i32;
        let kf = k as f32;
        // pi/2 = P1 + P2 + P3, P1 and P2 with few significant bits so k·P1, k·P2 are exact
        const P1: f32 = 1.5703125;
        // the exact binary values, digit for digit
        #[allow(clippy::excessive_precision)]
        const P2: f32 = 4.837512969970703125e-4;
        #[allow(clippy::excessive_precision)]
        const P3: f32 = 7.549_789_954_891_882e-8;
        let r = ((x - kf * P1) - kf * P2) - kf * P3;
        let z = r * r;
        let s = r + r * z * (-1.666_665_5e-1 + z * (8.332_161e-3 + z * -1.951_529_6e-4));
        let c = 1.0 - 0.5 * z + z * z * (4.166_664_6e-2 + z * (-1.388_731_6e-3 + z * 2.443_315_7e-5));
        match k & 3 {
            0 => (s, c),
            1 => (c, -s),
            2 => (-s, -c),
            _ => (-c, s),
        }
    }

    #[cfg(test)]
    #[test]
    fn nan_beyond_the_reduction_range() {
        for x in [12868.0f32, -2.0e4, 1.0e30, f32::INFINITY, f32::NEG_INFINITY, f32::NAN] {
            let (s, c) = sin_cos(x);
            assert!(s.is_nan() && c.is_nan(), "{x}: {s} {c}");
        }
        assert!(sin_cos(12867.0).0.is_finite());
    }

    #[cfg(test)]
    #[test]
    fn matches_f64_sine_and_cosine() {
        let mut x = -12000.0f32;
        while x < 12000.0 {
            for d in [0.0f32, 0.123, 0.785, core::f32::consts::FRAC_PI_2, core::f32::consts::PI] {
                let v = x + d;
                let (s, c) = sin_cos(v);
                let (s64, c64) = libm::sincos(v as f64);
                assert!((s as f64 - s64).abs() <= 2.5e-7, "sin {v}: {s} vs {s64}");
                assert!((c as f64 - c64).abs() <= 2.5e-7, "cos {v}: {c} vs {c64}");
            }
            x += 0.37 + x.abs() * 0.01;
        }
    }
}

#[cfg(test)]
mod cbrt_tests {
    use super::Real;

    #[test]
    fn f32_cube_root_is_within_two_ulps_of_f64s() {
        let mut x = 1e-6f32;
        while x < 1e6 {
            for v in [x, -x] {
                let exact = (v as f64).cbrt();
                let got = Real::cbrt(v) as f64;
                assert!((got - exact).abs() <= 2.0 * f32::EPSILON as f64 * exact.abs(), "{v}: {got} vs {exact}");
            }
            x *= 1.37;
        }
        assert_eq!(Real::cbrt(0.0f32), 0.0);
        assert!(Real::cbrt(f32::NAN).is_nan());
    }
}
