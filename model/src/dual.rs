//! Dual numbers over a scalar R: a value and its derivatives with respect to two unknowns
//! (forward-mode automatic differentiation). `D<R>` is itself a `Real`, so any code generic
//! over `Real` (the joint march) gives its exact 2-column Jacobian in one pass. Nothing else.

use crate::real::Real;
use core::cmp::Ordering;
use core::ops::{Add, AddAssign, Div, DivAssign, Mul, MulAssign, Neg, Sub, SubAssign};

/// A dual number: value and its derivatives with respect to the two hole coordinates.
#[derive(Clone, Copy, Debug)]
pub struct D<R> {
    pub v: R,
    pub d: [R; 2],
}

impl<R: Real> D<R> {
    #[inline(always)]
    pub fn c(v: R) -> Self {
        D { v, d: [R::zero(); 2] }
    }
}

impl<R: Real> PartialEq for D<R> {
    fn eq(&self, o: &Self) -> bool {
        self.v == o.v
    }
}
impl<R: Real> PartialOrd for D<R> {
    fn partial_cmp(&self, o: &Self) -> Option<Ordering> {
        self.v.partial_cmp(&o.v)
    }
}
impl<R: Real> Add for D<R> {
    type Output = Self;
    #[inline(always)]
    fn add(self, o: Self) -> Self {
        D { v: self.v + o.v, d: [self.d[0] + o.d[0], self.d[1] + o.d[1]] }
    }
}
impl<R: Real> Sub for D<R> {
    type Output = Self;
    #[inline(always)]
    fn sub(self, o: Self) -> Self {
        D { v: self.v - o.v, d: [self.d[0] - o.d[0], self.d[1] - o.d[1]] }
    }
}
impl<R: Real> Mul for D<R> {
    type Output = Self;
    #[inline(always)]
    fn mul(self, o: Self) -> Self {
        D { v: self.v * o.v, d: [self.v * o.d[0] + self.d[0] * o.v, self.v * o.d[1] + self.d[1] * o.v] }
    }
}
impl<R: Real> Div for D<R> {
    type Output = Self;
    #[inline(always)]
    fn div(self, o: Self) -> Self {
        let v = self.v / o.v;
        let inv = R::one() / o.v;
        D { v, d: [(self.d[0] - v * o.d[0]) * inv, (self.d[1] - v * o.d[1]) * inv] }
    }
}
impl<R: Real> Neg for D<R> {
    type Output = Self;
    #[inline(always)]
    fn neg(self) -> Self {
        D { v: -self.v, d: [-self.d[0], -self.d[1]] }
    }
}
impl<R: Real> Mul<R> for D<R> {
    type Output = Self;
    #[inline(always)]
    fn mul(self, o: R) -> Self {
        D { v: self.v * o, d: [self.d[0] * o, self.d[1] * o] }
    }
}
impl<R: Real> Add<R> for D<R> {
    type Output = Self;
    #[inline(always)]
    fn add(self, o: R) -> Self {
        D { v: self.v + o, d: self.d }
    }
}
impl<R: Real> Sub<R> for D<R> {
    type Output = Self;
    #[inline(always)]
    fn sub(self, o: R) -> Self {
        D { v: self.v - o, d: self.d }
    }
}
/// `a op= b` as `a = a op b`, for each compound assignment.
macro_rules! assign_by_op {
    ($($trait:ident $method:ident $op:tt),*) => {
        $(impl<R: Real> $trait for D<R> {
            #[inline(always)]
            fn $method(&mut self, o: Self) {
                *self = *self $op o;
            }
        })*
    };
}
assign_by_op!(AddAssign add_assign +, SubAssign sub_assign -, MulAssign mul_assign *, DivAssign div_assign /);

impl<R: Real> Real for D<R> {
    const EPS: f64 = R::EPS;
    const SQRT_EPS: f64 = R::SQRT_EPS;
    const NAME: &'static str = "dual";
    #[inline(always)]
    fn from_f64(x: f64) -> Self {
        D::c(R::from_f64(x))
    }
    #[inline(always)]
    fn from_u32(n: u32) -> Self {
        D::c(R::from_u32(n))
    }
    #[inline(always)]
    fn to_f64(self) -> f64 {
        self.v.to_f64()
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        let s = self.v.sqrt();
        if !(s > R::zero()) {
            return D::c(s);
        }
        let k = R::one() / (s + s);
        D { v: s, d: [self.d[0] * k, self.d[1] * k] }
    }
    #[inline(always)]
    fn sin_cos(self) -> (Self, Self) {
        let (s, c) = self.v.sin_cos();
        (D { v: s, d: [c * self.d[0], c * self.d[1]] }, D { v: c, d: [-s * self.d[0], -s * self.d[1]] })
    }
    #[inline(always)]
    fn compose_turn((s, c): (Self, Self), (sx, cx): (Self, Self), angle: Self) -> (Self, Self) {
        // the values composed in R (bit for bit the plain march's), the derivative the angle's
        // own times cos, -sin
        let (sv, cv) = R::compose_turn((s.v, c.v), (sx.v, cx.v), angle.v);
        (D { v: sv, d: [cv * angle.d[0], cv * angle.d[1]] }, D { v: cv, d: [-sv * angle.d[0], -sv * angle.d[1]] })
    }
    #[inline(always)]
    fn turn(self, small: Self) -> (Self, Self) {
        // the value part is R's own (the plain march's, bit for bit), the derivative cos, -sin
        // (past twice `small` R's rule is the sine and cosine: taken at once, no series first)
        let (s, c) = if self.v.abs() < small.v + small.v { self.v.turn(small.v) } else { self.v.sin_cos() };
        (D { v: s, d: [c * self.d[0], c * self.d[1]] }, D { v: c, d: [-s * self.d[0], -s * self.d[1]] })
    }
    fn atan2(self, x: Self) -> Self {
        let v = self.v.atan2(x.v);
        let r2 = x.v * x.v + self.v * self.v;
        if !(r2 > R::zero()) {
            return D::c(v);
        }
        let k = R::one() / r2;
        D { v, d: [(x.v * self.d[0] - self.v * x.d[0]) * k, (x.v * self.d[1] - self.v * x.d[1]) * k] }
    }
    #[inline(always)]
    fn is_finite(self) -> bool {
        self.v.is_finite() && self.d[0].is_finite() && self.d[1].is_finite()
    }
    fn exp(self) -> Self {
        let e = self.v.exp();
        D { v: e, d: [e * self.d[0], e * self.d[1]] }
    }
    fn cbrt(self) -> Self {
        let c = self.v.cbrt();
        let k = R::one() / (R::from_f64(3.0) * c * c);
        D { v: c, d: [self.d[0] * k, self.d[1] * k] }
    }
}
