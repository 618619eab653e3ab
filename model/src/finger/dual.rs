//! The hot path of the converged solver: the joint march in any scalar (`march_t`), run on
//! dual numbers to get a joint's hole residual and its exact 2x2 Jacobian in one pass, and
//! Newton on that (`newton_dual`). Replaces the forward-difference Jacobian (two extra
//! marches per iteration and a step size that limits the Jacobian to half the digits): one
//! march per Newton iteration, quadratic convergence to the scalar's resolution (issue 5).
//!
//! `Finger::march` is `march_t::<R>` (one copy of the march in the image); the test
//! `march_t_matches_march` checks that the dual march's value part is the plain march, bit
//! for bit.

use super::{norm2, Finger, JointState, MarchError, Pose, TipLoad};
use crate::mat3::Mat3;
use crate::params::MAX_SUB;
use crate::real::Real;
use core::cmp::Ordering;
use core::ops::{Add, AddAssign, Div, DivAssign, Mul, MulAssign, Neg, Sub, SubAssign};

/// A dual number: value and its derivatives with respect to the two hole coordinates.
#[derive(Clone, Copy, Debug)]
pub(super) struct D<R> {
    pub v: R,
    pub d: [R; 2],
}

impl<R: Real> D<R> {
    #[inline(always)]
    fn c(v: R) -> Self {
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
        D {
            v: self.v * o.v,
            d: [self.v * o.d[0] + self.d[0] * o.v, self.v * o.d[1] + self.d[1] * o.v],
        }
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
impl<R: Real> AddAssign for D<R> {
    #[inline(always)]
    fn add_assign(&mut self, o: Self) {
        *self = *self + o;
    }
}
impl<R: Real> SubAssign for D<R> {
    #[inline(always)]
    fn sub_assign(&mut self, o: Self) {
        *self = *self - o;
    }
}
impl<R: Real> MulAssign for D<R> {
    #[inline(always)]
    fn mul_assign(&mut self, o: Self) {
        *self = *self * o;
    }
}
impl<R: Real> DivAssign for D<R> {
    #[inline(always)]
    fn div_assign(&mut self, o: Self) {
        *self = *self / o;
    }
}

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
    fn sin(self) -> Self {
        self.sin_cos().0
    }
    #[inline(always)]
    fn cos(self) -> Self {
        self.sin_cos().1
    }
    #[inline(always)]
    fn sin_cos(self) -> (Self, Self) {
        let (s, c) = self.v.sin_cos();
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
}

/// A joint state, its hole residual `b - hole` and the residual's Jacobian `I - ∂hole/∂b`.
pub(super) type Eval<R> = (JointState<R>, [R; 2], [[R; 2]; 2]);

impl<R: Real> Finger<R> {
    /// `Finger::march` in the scalar `T` (R itself, or dual numbers over R); parameters and
    /// compliances stay in R. Same operations in the same order as `march`. Returns the hinge
    /// end and the hole in T; the sub-element displacements go to `q_out` as values (`val`),
    /// which keeps the fixed-capacity array out of T (no zeroing and copying of dual arrays).
    pub(super) fn march_t<T>(
        &self,
        c: &[Mat3<R>; MAX_SUB],
        tension: R,
        b_hole: [T; 2],
        tip: Option<TipLoad<R>>,
        q_out: &mut [[R; 3]; MAX_SUB],
        val: impl Fn(T) -> R,
    ) -> Result<(Pose<T>, [T; 2]), MarchError>
    where
        T: Real + Mul<R, Output = T> + Add<R, Output = T> + Sub<R, Output = T>,
    {
        let e = self.p.e;
        let span_v = [b_hole[0], b_hole[1] - e];
        let span = norm2(span_v);
        if !(span >= T::zero() + self.p.span_floor) {
            return Err(MarchError::Contact);
        }
        // force of the cable on the distal chain, toward the proximal hole
        let fc = [span_v[0] * -tension / span, span_v[1] * -tension / span];
        let (ft, tp) = match tip {
            Some(t) => (t.force, t.point),
            None => ([R::zero(); 2], [R::zero(); 2]),
        };
        let ftot = [fc[0] + ft[0], fc[1] + ft[1]];
        let mut pose: Pose<T> = Pose::origin();
        let (mut s, mut co) = (T::zero(), T::one());
        for j in 0..self.p.m {
            let cj = &c[j];
            let d0 = [pose.x + co * self.sub_len, pose.y + s * self.sub_len];
            let mut m0 = (b_hole[0] - d0[0]) * fc[1] - (b_hole[1] - d0[1]) * fc[0];
            if tip.is_some() {
                m0 += (d0[1] - tp[1]) * ft[0] - (d0[0] - tp[0]) * ft[1];
            }
            let f = [co * ftot[0] + s * ftot[1], -s * ftot[0] + co * ftot[1]];
            let q0 = [
                f[0] * cj[0][0] + f[1] * cj[0][1] + m0 * cj[0][2],
                f[0] * cj[1][0] + f[1] * cj[1][1] + m0 * cj[1][2],
                f[0] * cj[2][0] + f[1] * cj[2][1] + m0 * cj[2][2],
            ];
            let den = (f[1] * cj[0][2] + R::one()) - f[0] * cj[1][2];
            if !(den.abs() > T::from_f64(1e-6)) {
                return Err(MarchError::Singular);
            }
            let sm = (-f[1] * q0[0] + f[0] * q0[1]) / den;
            let qj = [q0[0] + sm * cj[0][2], q0[1] + sm * cj[1][2], q0[2] + sm * cj[2][2]];
            q_out[j] = [val(qj[0]), val(qj[1]), val(qj[2])];
            pose = Pose {
                x: pose.x + co * (qj[0] + self.sub_len) - s * qj[1],
                y: pose.y + s * (qj[0] + self.sub_len) + co * qj[1],
                theta: pose.theta + qj[2],
            };
            let sc = pose.theta.sin_cos();
            s = sc.0;
            co = sc.1;
        }
        let hole = [pose.x - s * e, pose.y + co * e];
        if !(hole[0].is_finite() && hole[1].is_finite() && pose.theta.is_finite()) {
            return Err(MarchError::Singular);
        }
        Ok((pose, hole))
    }

    /// One dual march at hole guess `b` (tension alone): state, residual, Jacobian.
    pub(super) fn eval_dual(&self, c: &[Mat3<R>; MAX_SUB], tension: R, b: [R; 2]) -> Result<Eval<R>, MarchError> {
        let mut q = [[R::zero(); 3]; MAX_SUB];
        let (end, hole, r, jac) = self.eval_dual_into(c, tension, b, &mut q)?;
        Ok((JointState { q, end, hole, tangent: None }, r, jac))
    }

    /// `eval_dual` with the sub-element displacements written to `q` (its first m rows).
    #[inline(always)]
    fn eval_dual_into(
        &self,
        c: &[Mat3<R>; MAX_SUB],
        tension: R,
        b: [R; 2],
        q: &mut [[R; 3]; MAX_SUB],
    ) -> Result<(Pose<R>, [R; 2], [R; 2], [[R; 2]; 2]), MarchError> {
        let (z, o) = (R::zero(), R::one());
        let bd = [D { v: b[0], d: [o, z] }, D { v: b[1], d: [z, o] }];
        let (end_d, hole_d) = self.march_t::<D<R>>(c, tension, bd, None, q, |x| x.v)?;
        let end = Pose { x: end_d.x.v, y: end_d.y.v, theta: end_d.theta.v };
        let hole = [hole_d[0].v, hole_d[1].v];
        let r = [b[0] - hole[0], b[1] - hole[1]];
        let jac = [[o - hole_d[0].d[0], z - hole_d[0].d[1]], [z - hole_d[1].d[0], o - hole_d[1].d[1]]];
        Ok((end, hole, r, jac))
    }

    /// Newton at one tension from a starting hole guess, with the exact Jacobian of each
    /// dual march and backtracking (accept the first halving that lowers the residual). On
    /// failure returns why (contact on the way, or plain non-convergence) and the iterations.
    /// The returned state carries the residual and tangent determinant of its last march.
    /// Norms are compared squared (no square root per iteration); the sub-element
    /// displacements of the accepted and the trial march live in two buffers, swapped by index.
    pub(super) fn newton_dual(
        &self,
        c: &[Mat3<R>; MAX_SUB],
        tension: R,
        mut b: [R; 2],
        tol: R,
        max_iter: u32,
    ) -> Result<(JointState<R>, u32), (Option<MarchError>, u32)> {
        let mut qs = [[[R::zero(); 3]; MAX_SUB]; 2];
        let mut cur = 0usize;
        let (mut end, mut hole, mut r, mut jac) =
            self.eval_dual_into(c, tension, b, &mut qs[0]).map_err(|e| (Some(e), 0))?;
        // squared norms where the type resolves the square of its resolution (floats); fixed
        // point would lose the small residuals to its quantum, so it keeps the root
        let squared = R::from_f64(R::EPS * R::EPS) > R::zero();
        let metric = |r: [R; 2]| if squared { r[0] * r[0] + r[1] * r[1] } else { norm2(r) };
        let mut rn2 = metric(r);
        let floor = self.resolution();
        let (tol2, floor2) = if squared { (tol * tol, floor * floor) } else { (tol, floor) };
        let done = |qs: &[[[R; 3]; MAX_SUB]; 2], cur: usize, end, hole, r: [R; 2], jac: [[R; 2]; 2]| {
            let det = jac[0][0] * jac[1][1] - jac[0][1] * jac[1][0];
            JointState { q: qs[cur], end, hole, tangent: Some((r, det)) }
        };
        for it in 0..max_iter {
            if rn2 <= tol2 {
                return Ok((done(&qs, cur, end, hole, r, jac), it));
            }
            let det = jac[0][0] * jac[1][1] - jac[0][1] * jac[1][0];
            if !(det.abs() > R::from_f64(1e-12)) {
                return Err((None, it));
            }
            let inv = R::one() / det;
            let db = [(jac[0][1] * r[1] - jac[1][1] * r[0]) * inv, (jac[1][0] * r[0] - jac[0][0] * r[1]) * inv];
            let mut lambda = R::one();
            let mut accepted = false;
            let mut last_err = None;
            for _ in 0..12 {
                let bt = [b[0] + lambda * db[0], b[1] + lambda * db[1]];
                match self.eval_dual_into(c, tension, bt, &mut qs[1 - cur]) {
                    Ok((et, ht, rt, jt)) => {
                        let rtn2 = metric(rt);
                        if rtn2 < rn2 {
                            b = bt;
                            r = rt;
                            rn2 = rtn2;
                            cur = 1 - cur;
                            end = et;
                            hole = ht;
                            jac = jt;
                            accepted = true;
                            break;
                        }
                    }
                    Err(e) => last_err = Some(e),
                }
                lambda = lambda / R::from_f64(2.0);
            }
            if !accepted {
                // at the scalar's resolution the residual stops falling: that is convergence
                if rn2 <= floor2 {
                    return Ok((done(&qs, cur, end, hole, r, jac), it + 1));
                }
                return Err((last_err, it + 1));
            }
        }
        if rn2 <= tol2 {
            Ok((done(&qs, cur, end, hole, r, jac), max_iter))
        } else {
            Err((None, max_iter))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::params::Params;

    fn fingers() -> [Finger<f64>; 2] {
        let p1 = Params::<f64>::default();
        let p3 = Params::<f64> { m: 3, ..Params::default() };
        [Finger::new(p1).unwrap(), Finger::new(p3).unwrap()]
    }

    #[test]
    fn march_t_matches_march() {
        for f in fingers() {
            let c = f.compliances(&[0.0; 3]).unwrap();
            let tips = [None, Some(TipLoad { force: [0.3, -0.7], point: [60.0, 12.0] })];
            for tension in [0.0, 0.2, 1.0, 7.0] {
                for b in [[10.0, 5.0], [9.3, 6.1], [8.0, 7.5]] {
                    for tip in tips {
                        let a = f.march(&c.c[0], tension, b, tip).ok().unwrap();
                        let mut q = [[0.0; 3]; MAX_SUB];
                        let t = f.march_t::<f64>(&c.c[0], tension, b, tip, &mut q, |x| x).ok().unwrap();
                        assert_eq!(a.hole, t.1);
                        assert_eq!(a.end, t.0);
                        assert_eq!(a.q, q);
                        let d = f.eval_dual(&c.c[0], tension, b).ok().unwrap();
                        let plain = f.march(&c.c[0], tension, b, None).ok().unwrap();
                        assert_eq!(d.0.hole, plain.hole, "dual value part equals the plain march");
                    }
                }
            }
        }
        // and in f32
        let f = Finger::new(Params::<f32>::default()).unwrap();
        let c = f.compliances(&[0.0; 3]).unwrap();
        let a = f.march(&c.c[0], 1.0, [9.5, 5.5], None).ok().unwrap();
        let mut q = [[0.0; 3]; MAX_SUB];
        let t = f.march_t::<f32>(&c.c[0], 1.0, [9.5, 5.5], None, &mut q, |x| x).ok().unwrap();
        assert_eq!(a.hole, t.1);
    }

    #[test]
    fn dual_jacobian_matches_central_differences() {
        for f in fingers() {
            let c = f.compliances(&[0.0; 3]).unwrap();
            for tension in [0.2, 1.0, 7.0] {
                let b = [9.4, 6.0];
                let (_, r0, jac) = f.eval_dual(&c.c[0], tension, b).ok().unwrap();
                assert!(r0[0].is_finite());
                let h = 1e-6;
                for i in 0..2 {
                    let (mut bp, mut bm) = (b, b);
                    bp[i] += h;
                    bm[i] -= h;
                    let (_, rp, _) = f.eval_dual(&c.c[0], tension, bp).ok().unwrap();
                    let (_, rm, _) = f.eval_dual(&c.c[0], tension, bm).ok().unwrap();
                    for row in 0..2 {
                        let fd = (rp[row] - rm[row]) / (2.0 * h);
                        assert!((fd - jac[row][i]).abs() < 1e-7, "J[{row}][{i}] {} vs {fd}", jac[row][i]);
                    }
                }
            }
        }
    }
}
