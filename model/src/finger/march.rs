//! A joint's march: from a guessed guide hole, sub-element by sub-element, each one's
//! equilibrium q = C w under the loads in the deformed geometry (the paper's Eq. 7/15), to the
//! hole it arrives at. One loop (`march_subs`; `Finger::march_joint` over a float finger's
//! sub-elements) over two parts:
//! - a sub-element's equilibrium (`SubElement`) in one of three forms: `ByCompliance` (q from
//!   C in closed form, the moment about the proximal end), `ByComplianceLoaded` (the same
//!   equation from the moment about the undeflected distal end: the dual/tip-load form) and
//!   `ByStiffness` (K q = w eliminated in place, K from `JointStiffness`, march_stiffness.rs);
//! - how the loads travel to the next sub-element (`Frame`): `CableFrame` (tension alone, in
//!   each sub-element's own frame, the end's pose recovered once; with `ByCompliance` or
//!   `ByStiffness`) or `PoseFrame` (the pose carried, any scalar including dual numbers, an
//!   optional tip load; with `ByComplianceLoaded`).
//!
//! Both frames turn by one rule (`Real::turn`). Which to call (docs/model.md "Which march to
//! call"):
//!
//! | to get | call |
//! | --- | --- |
//! | one plain march, any load | `Finger::march` (joint.rs) |
//! | a converged joint under tension alone | `newton_dual` on `march_dual` (here) |
//! | one march under tension alone, by compliance or stiffness | `march_cable` (here) |
//! | the inverse's march of a joint | `Finger::joint_march` by one of `by`'s ways (joint.rs) |
//!
//! The fixed-point march (`fixed::forward`) runs `march_subs` on the Q forms of
//! `ByComplianceLoaded` and `PoseFrame`.

use super::{norm2, Finger, JointState, MarchError, Pose, TipLoad};
use crate::dual::D;
use crate::mat3::Mat3;
use crate::params::MAX_SUB;
use crate::real::Real;
use crate::solve::{self, newton::Equations, SolveOptions};
use core::ops::{Add, Mul, Sub};

/// The largest sub-element rotation (rad) whose (sin, cos) `Real::turn` takes from the Taylor series
/// to x⁵ and x⁶: their truncation errors, x⁷/5040 and x⁸/40320, stay below the scalar's
/// resolution `eps` relative (x⁶ < 5040 eps: 0.29 in f32, 0.010 in f64; the bounds below are
/// inside those).
pub(super) fn small_turn(eps: f64) -> f64 {
    if eps > 1e-10 {
        0.25
    } else {
        0.008
    }
}

/// The turn rule's (sin, cos) of one step's rotation `x` (a sub-element's, a hinge end's, a
/// link's): `Real::turn` with the scalar's series bound.
#[inline(always)]
pub(crate) fn turn<R: Real>(x: R) -> (R, R) {
    x.turn(R::from_f64(small_turn(R::EPS)))
}

/// A march's scalar: R itself, or dual numbers over R (the hole residual's exact Jacobian);
/// parameters and compliances stay in R.
pub(super) trait Scalar<R>: Real + Mul<R, Output = Self> + Add<R, Output = Self> + Sub<R, Output = Self> {}
impl<R, T: Real + Mul<R, Output = T> + Add<R, Output = T> + Sub<R, Output = T>> Scalar<R> for T {}

/// One sub-element's equilibrium in its own frame (the paper's Eq. 7/15, docs/model.md
/// "Equilibrium"): from its `Loads` (f, the force on the distal chain in the sub-element's
/// proximal frame, and the loads' moment m about the point the form names), its `Disp`: the
/// displacement q = C (f, M) with M the moment about its deformed distal end (linear in q:
/// M = m0 - f1 q0 + f0 q1, m0 the moment about the undeflected distal end). The float forms
/// take `SubLoads` and give `SubDisp`; the fixed-point form (`fixed::forward`) its Q formats.
pub(crate) trait SubElement<Loads> {
    /// What each sub-element carries (its compliance, or its hinge's stiffness).
    type Sub;
    type Disp;
    fn subs(&self) -> &[Self::Sub; MAX_SUB];
    fn equilibrium(&self, sub: &Self::Sub, loads: Loads) -> Result<Self::Disp, MarchError>;
}

/// A float sub-element's loads: f, the moment m and the sub-element's length.
pub(super) type SubLoads<R, T> = ([T; 2], T, R);
/// A float sub-element's displacement q and the moment about its deformed distal end.
pub(super) type SubDisp<T> = ([T; 3], T);

/// The compliance form from mm, the moment about the proximal end (m0 = mm - f1 L): q =
/// C (f, M) in closed form, C symmetric (`Finger::compliances` makes it so: its upper triangle
/// is read). With a = C (f, 0), M = (mm - f1 L + f0 a1 - f1 a0) / den, den = 1 + f1 C02 - f0 C12;
/// refuses a non-positive den (the tabled marches: the full model's Newton then takes it).
pub(super) struct ByCompliance<'a, R>(pub &'a [Mat3<R>; MAX_SUB]);

impl<R: Real> SubElement<SubLoads<R, R>> for ByCompliance<'_, R> {
    type Sub = Mat3<R>;
    type Disp = SubDisp<R>;
    #[inline(always)]
    fn subs(&self) -> &[Mat3<R>; MAX_SUB] {
        self.0
    }
    #[inline(always)]
    fn equilibrium(&self, cj: &Mat3<R>, (f, mm, l): SubLoads<R, R>) -> Result<SubDisp<R>, MarchError> {
        debug_assert!(cj[1][0] == cj[0][1] && cj[2][0] == cj[0][2] && cj[2][1] == cj[1][2]);
        let (c00, c01, c02, c11, c12, c22) = (cj[0][0], cj[0][1], cj[0][2], cj[1][1], cj[1][2], cj[2][2]);
        let a = [f[0] * c00 + f[1] * c01, f[0] * c01 + f[1] * c11, f[0] * c02 + f[1] * c12];
        let den = (f[1] * c02 + R::one()) - f[0] * c12;
        if !(den > R::from_f64(1e-6)) {
            return Err(MarchError::Singular);
        }
        let m = (mm + f[0] * a[1] - f[1] * (a[0] + l)) / den;
        Ok(([a[0] + m * c02, a[1] + m * c12, a[2] + m * c22], m))
    }
}

/// The compliance form from m0, the moment about the undeflected distal end (the dual/tip-load
/// form, any scalar): q0 = C (f, m0), then the moment arm's own change s = (-f1 q0_0 + f0 q0_1)
/// / den, q = q0 + s C(:, 2); refuses only |den| at or below 1e-6.
pub(super) struct ByComplianceLoaded<'a, R>(pub &'a [Mat3<R>; MAX_SUB]);

impl<R: Real, T: Scalar<R>> SubElement<SubLoads<R, T>> for ByComplianceLoaded<'_, R> {
    type Sub = Mat3<R>;
    type Disp = SubDisp<T>;
    #[inline(always)]
    fn subs(&self) -> &[Mat3<R>; MAX_SUB] {
        self.0
    }
    #[inline(always)]
    fn equilibrium(&self, cj: &Mat3<R>, (f, m0, _l): SubLoads<R, T>) -> Result<SubDisp<T>, MarchError> {
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
        Ok(([q0[0] + sm * cj[0][2], q0[1] + sm * cj[1][2], q0[2] + sm * cj[2][2]], m0 + sm))
    }
}

/// A march's end: the hinge's distal pose, the hole it arrives at, (sin, cos) of the end's
/// angle and the squared hole residual |b - hole|².
pub(super) type MarchEnd<T> = (Pose<T>, [T; 2], [T; 2], T);

/// How a march carries the loads from one sub-element to the next: `L` the loads its
/// `SubElement` form takes, `D` the displacement it gives.
pub(crate) trait Frame<L, D> {
    /// The next sub-element's loads.
    fn loads(&self) -> L;
    /// Past a sub-element displaced by `d`; its rotation turns by the turn rule (`Real::turn`:
    /// the sub-element's own (sin, cos), composed with the frame's).
    fn advance(&mut self, d: D);
}

/// The march: sub-element by sub-element, `kernel`'s equilibrium under the loads `frame`
/// carries, for as many sub-elements as `out` holds; each one's displacement goes to its slot
/// of `out` through `keep` (`()` slots keep nothing). Returns the frame at the hinge's end.
/// The one loop of every march, float and fixed point.
#[inline(always)]
pub(crate) fn march_subs<L, K: SubElement<L>, F: Frame<L, K::Disp>, O>(
    kernel: &K,
    mut frame: F,
    out: &mut [O],
    keep: impl Fn(&K::Disp) -> O,
) -> Result<F, MarchError>
where
    K::Disp: Copy,
{
    for (sub, o) in kernel.subs().iter().zip(out.iter_mut()) {
        let d = kernel.equilibrium(sub, frame.loads())?;
        *o = keep(&d);
        frame.advance(d);
    }
    Ok(frame)
}

/// Tension alone (P > 0), in each sub-element's own frame: the cable's force f turned into it,
/// the hole B held by two scalars, mm = w × f and dot = w · f with w = B - the proximal end,
/// carried by a rotation-free recurrence (no pose update); the end's pose comes back once, its
/// rotation from f = Rᵀ f_c, B - end from mm and dot.
pub(super) struct CableFrame<R> {
    f: [R; 2],
    mm: R,
    dot: R,
    theta: R,
    sub_len: R,
}

/// A `CableFrame` march's start, for its end: the hole guess and two factors of the tension.
pub(super) struct CableStart<R> {
    b: [R; 2],
    /// 1/P² and k/P² with f_c = k (B - (0, e)), k = -P/|B - (0, e)|: the end's f · f_c and
    /// f × f_c from B (a value fewer held through the march than P and f_c)
    inv_p2: R,
    k_p2: R,
}

impl<R: Real> CableFrame<R> {
    /// At hole guess `b`: f_c = -P (B - (0, e)) / |B - (0, e)|, B × f_c and B · f_c. Refuses a
    /// span below its floor and P <= 0 (`Contact`).
    #[inline(always)]
    pub(super) fn new(finger: &Finger<R>, tension: R, b: [R; 2]) -> Result<(CableStart<R>, Self), MarchError> {
        let span_v = [b[0], b[1] - finger.p.e];
        let span = norm2(span_v);
        if !(span >= finger.p.span_floor) || !(tension > R::zero()) {
            return Err(MarchError::Contact);
        }
        let k = -tension / span;
        let fc = [span_v[0] * k, span_v[1] * k];
        let (mm, dot) = (b[0] * fc[1] - b[1] * fc[0], b[0] * fc[0] + b[1] * fc[1]);
        let inv_p2 = R::one() / (tension * tension);
        Ok((CableStart { b, inv_p2, k_p2: k * inv_p2 }, CableFrame { f: fc, mm, dot, theta: R::zero(), sub_len: finger.sub_len }))
    }

    /// The end (`MarchEnd`) from the march's start, `e` the hole's offset from the hinge's
    /// axis; refuses a state that is not finite (`Singular`).
    #[inline(always)]
    pub(super) fn end(self, start: CableStart<R>, e: R) -> Result<MarchEnd<R>, MarchError> {
        let (CableStart { b, inv_p2: inv, k_p2 }, CableFrame { f, mm, dot, theta, .. }) = (start, self);
        let span_v = [b[0], b[1] - e];
        let co = (f[0] * span_v[0] + f[1] * span_v[1]) * k_p2;
        let s = (f[0] * span_v[1] - f[1] * span_v[0]) * k_p2;
        let r = [(dot * f[0] + mm * f[1]) * inv, (dot * f[1] - mm * f[0]) * inv];
        // hole - end = R (0, e): b - hole = R (r - (0, e))
        let d = [r[0], r[1] - e];
        let res2 = d[0] * d[0] + d[1] * d[1];
        let end = Pose { x: b[0] - (co * r[0] - s * r[1]), y: b[1] - (s * r[0] + co * r[1]), theta };
        let hole = [end.x - s * e, end.y + co * e];
        // one test for all four: a sum is finite only if every term is
        if !(hole[0] + hole[1] + theta + res2).is_finite() {
            return Err(MarchError::Singular);
        }
        Ok((end, hole, [s, co], res2))
    }
}

impl<R: Real> Frame<SubLoads<R, R>, SubDisp<R>> for CableFrame<R> {
    #[inline(always)]
    fn loads(&self) -> SubLoads<R, R> {
        (self.f, self.mm, self.sub_len)
    }
    #[inline(always)]
    fn advance(&mut self, (q, m_end): SubDisp<R>) {
        let (f, l) = (self.f, self.sub_len);
        self.mm = m_end;
        self.theta += q[2];
        // w - (L + q0, q1) is B - the next proximal end: its dot with f; then f into the next
        // frame (dot and cross products keep)
        self.dot = self.dot - (q[0] + l) * f[0] - q[1] * f[1];
        let (sd, cd) = turn(q[2]);
        self.f = [cd * f[0] + sd * f[1], cd * f[1] - sd * f[0]];
    }
}

/// The pose carried in the joint's proximal frame, any scalar (dual numbers for the exact
/// Jacobian), the cable's force and an optional tip load, both fixed in that frame; its
/// moment is about the sub-element's undeflected distal end (`ByComplianceLoaded`).
pub(super) struct PoseFrame<R, T> {
    b: [T; 2],
    fc: [T; 2],
    tip: Option<TipLoad<R>>,
    ftot: [T; 2],
    pose: Pose<T>,
    s: T,
    co: T,
    sub_len: R,
}

impl<R: Real, T: Scalar<R>> PoseFrame<R, T> {
    /// At hole guess `b`: the cable's force on the distal chain toward the proximal hole, and
    /// the tip load (`Finger::span_loads`). Refuses a span below its floor (`Contact`).
    #[inline(always)]
    pub(super) fn new(finger: &Finger<R>, tension: R, b: [T; 2], tip: Option<TipLoad<R>>) -> Result<Self, MarchError> {
        let loads = finger.span_loads(tension, b, tip)?;
        Ok(PoseFrame { b, fc: loads.fc, tip, ftot: loads.ftot, pose: Pose::origin(), s: T::zero(), co: T::one(), sub_len: finger.sub_len })
    }

    #[inline(always)]
    /// The end (`MarchEnd`), `e` the hole's offset from the hinge's axis; refuses a state
    /// that is not finite (`Singular`).
    pub(super) fn end(self, e: R) -> Result<(Pose<T>, [T; 2], [T; 2]), MarchError> {
        let (p, s, co) = (self.pose, self.s, self.co);
        let hole = [p.x - s * e, p.y + co * e];
        if !(hole[0].is_finite() && hole[1].is_finite() && p.theta.is_finite()) {
            return Err(MarchError::Singular);
        }
        Ok((p, hole, [s, co]))
    }
}

impl<R: Real, T: Scalar<R>> Frame<SubLoads<R, T>, SubDisp<T>> for PoseFrame<R, T> {
    #[inline(always)]
    fn loads(&self) -> SubLoads<R, T> {
        let (s, co, ft, l) = (self.s, self.co, self.ftot, self.sub_len);
        let d0 = [self.pose.x + co * l, self.pose.y + s * l];
        let mut m0 = (self.b[0] - d0[0]) * self.fc[1] - (self.b[1] - d0[1]) * self.fc[0];
        if let Some(t) = self.tip {
            m0 += (d0[1] - t.point[1]) * t.force[0] - (d0[0] - t.point[0]) * t.force[1] + t.couple;
        }
        ([co * ft[0] + s * ft[1], -s * ft[0] + co * ft[1]], m0, l)
    }
    #[inline(always)]
    fn advance(&mut self, (q, _m_end): SubDisp<T>) {
        let (p, s, co, l) = (self.pose, self.s, self.co, self.sub_len);
        let (sd, cd) = turn(q[2]);
        let ax = q[0] + l;
        self.pose = Pose { x: p.x + co * ax - s * q[1], y: p.y + s * ax + co * q[1], theta: p.theta + q[2] };
        (self.s, self.co) = T::compose_turn((s, co), (sd, cd), self.pose.theta);
    }
}

/// A joint state, its hole residual `b - hole` and the residual's Jacobian `I - ∂hole/∂b`.
pub(super) type Eval<R> = (JointState<R>, [R; 2], [[R; 2]; 2]);

impl<R: Real> Finger<R> {
    /// `march_subs` over this finger's m sub-elements, their displacements written to `q_out`
    /// as values (`val`), which keeps the fixed-capacity array out of T (no zeroing and copying
    /// of dual arrays).
    #[inline(always)]
    pub(super) fn march_joint<T: Real, K: SubElement<SubLoads<R, T>, Sub = Mat3<R>, Disp = SubDisp<T>>, F: Frame<SubLoads<R, T>, SubDisp<T>>>(
        &self,
        kernel: &K,
        frame: F,
        q_out: &mut [[R; 3]; MAX_SUB],
        val: impl Fn(T) -> R,
    ) -> Result<F, MarchError> {
        let m = self.p.m.min(MAX_SUB);
        march_subs(kernel, frame, &mut q_out[..m], |(q, _)| [val(q[0]), val(q[1]), val(q[2])])
    }

    /// The march under tension alone in the running frame (`CableFrame`), by either form that
    /// takes the moment about the proximal end: `ByCompliance` (the tabled forward's) or
    /// `ByStiffness` (the tabled inverse's, no compliance formed). Refuses what `CableFrame`
    /// refuses and a non-positive den or last pivot; the full model's Newton then takes the joint.
    #[inline(always)]
    pub(super) fn march_cable<K: SubElement<SubLoads<R, R>, Sub = Mat3<R>, Disp = SubDisp<R>>>(
        &self,
        kernel: &K,
        tension: R,
        b: [R; 2],
        q_out: &mut [[R; 3]; MAX_SUB],
    ) -> Result<MarchEnd<R>, MarchError> {
        let (start, frame) = CableFrame::new(self, tension, b)?;
        self.march_joint(kernel, frame, q_out, |x| x)?.end(start, self.p.e)
    }

    /// The march on dual numbers in `PoseFrame` (tension alone), out of line: one copy in the
    /// image for its callers (the Newton residual and `eval_dual`).
    #[inline(never)]
    fn march_dual(
        &self,
        c: &[Mat3<R>; MAX_SUB],
        tension: R,
        b: [D<R>; 2],
        tip: Option<TipLoad<R>>,
        q: &mut [[R; 3]; MAX_SUB],
    ) -> Result<(Pose<D<R>>, [D<R>; 2], [D<R>; 2]), MarchError> {
        let frame = PoseFrame::new(self, tension, b, tip)?;
        self.march_joint(&ByComplianceLoaded(c), frame, q, |x| x.v)?.end(self.p.e)
    }

    /// One dual march at hole guess `b` (tension and a fixed load `tip`): state, residual,
    /// Jacobian.
    pub(super) fn eval_dual(&self, c: &[Mat3<R>; MAX_SUB], tension: R, b: [R; 2], tip: Option<TipLoad<R>>) -> Result<Eval<R>, MarchError> {
        let mut q = [[R::zero(); 3]; MAX_SUB];
        let (end, hole, r, jac) = self.eval_dual_into(c, tension, b, tip, &mut q)?;
        Ok((JointState { q, end, hole, tangent: None }, r, jac))
    }

    /// `eval_dual` with the sub-element displacements written to `q` (its first m rows): the
    /// march in `PoseFrame` on dual numbers.
    #[inline(always)]
    fn eval_dual_into(
        &self,
        c: &[Mat3<R>; MAX_SUB],
        tension: R,
        b: [R; 2],
        tip: Option<TipLoad<R>>,
        q: &mut [[R; 3]; MAX_SUB],
    ) -> Result<(Pose<R>, [R; 2], [R; 2], [[R; 2]; 2]), MarchError> {
        let (z, o) = (R::zero(), R::one());
        let bd = [D { v: b[0], d: [o, z] }, D { v: b[1], d: [z, o] }];
        let (end_d, hole_d, _) = self.march_dual(c, tension, bd, tip, q)?;
        let end = Pose { x: end_d.x.v, y: end_d.y.v, theta: end_d.theta.v };
        let hole = [hole_d[0].v, hole_d[1].v];
        let r = [b[0] - hole[0], b[1] - hole[1]];
        let jac = [[o - hole_d[0].d[0], z - hole_d[0].d[1]], [z - hole_d[1].d[0], o - hole_d[1].d[1]]];
        Ok((end, hole, r, jac))
    }

    /// Newton at one tension from a starting hole guess: `solve::newton` on the hole residual
    /// with the exact Jacobian of each dual march. On failure returns why (contact on the way,
    /// or plain non-convergence) and the iterations. The returned state carries the residual
    /// and tangent determinant of its last march.
    pub(super) fn newton_dual(
        &self,
        c: &[Mat3<R>; MAX_SUB],
        tension: R,
        b: [R; 2],
        tip: Option<TipLoad<R>>,
        tol: R,
        max_iter: u32,
    ) -> Result<(JointState<R>, u32), (Option<MarchError>, u32)> {
        self.newton_dual_with(c, tension, b, tip, &SolveOptions::new(tol, self.resolution(), max_iter))
    }

    /// `newton_dual` with the solver's options (iterations, line-search halvings) given.
    pub(super) fn newton_dual_with(
        &self,
        c: &[Mat3<R>; MAX_SUB],
        tension: R,
        b: [R; 2],
        tip: Option<TipLoad<R>>,
        opts: &SolveOptions<R>,
    ) -> Result<(JointState<R>, u32), (Option<MarchError>, u32)> {
        let mut eq = JointHoles { f: self, c, tension, tip, q: [[[R::zero(); 3]; MAX_SUB]; 2], st: [None; 2] };
        let mut x = b;
        match solve::newton::solve(&mut eq, &mut x, opts) {
            Ok((rep, slot)) => {
                let Some((end, hole, r, jac)) = eq.st[slot] else { return Err((None, rep.iterations)) };
                let det = jac[0][0] * jac[1][1] - jac[0][1] * jac[1][0];
                Ok((JointState { q: eq.q[slot], end, hole, tangent: Some((r, det)) }, rep.iterations))
            }
            Err(fail) => Err((fail.refusal().copied(), fail.iterations())),
        }
    }
}

/// One joint's hole residual under tension alone, for `solve::newton`: each evaluation is one
/// dual march, whose state (sub-element q, end, hole, residual, Jacobian) stays in its slot.
struct JointHoles<'a, R> {
    f: &'a Finger<R>,
    c: &'a [Mat3<R>; MAX_SUB],
    tension: R,
    tip: Option<TipLoad<R>>,
    q: [[[R; 3]; MAX_SUB]; 2],
    #[allow(clippy::type_complexity)]
    st: [Option<(Pose<R>, [R; 2], [R; 2], [[R; 2]; 2])>; 2],
}

impl<R: Real> Equations<R, 2> for JointHoles<'_, R> {
    type Refusal = MarchError;
    fn residual(&mut self, x: &[R; 2], slot: usize) -> Result<[R; 2], MarchError> {
        let slot = slot.min(1);
        let ev = self.f.eval_dual_into(self.c, self.tension, *x, self.tip, &mut self.q[slot])?;
        self.st[slot] = Some(ev);
        Ok(ev.2)
    }
    fn jacobian(&mut self, _: &[R; 2], _: &[R; 2], slot: usize) -> Result<[[R; 2]; 2], MarchError> {
        // the dual march at this point gave it
        Ok(self.st[slot.min(1)].map_or([[R::one(), R::zero()], [R::zero(), R::one()]], |s| s.3))
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

    /// The plain march (`march`) and its dual run (`eval_dual`) are one march: the same
    /// displacements, end and hole as the march in `PoseFrame` run directly, in f64 and f32.
    #[test]
    fn plain_march_is_the_pose_frame_march() {
        for f in fingers() {
            let c = f.compliances(&[0.0; 3]).unwrap();
            let tips = [None, Some(TipLoad { force: [0.3, -0.7], point: [60.0, 12.0], couple: 0.0 })];
            for tension in [0.0, 0.2, 1.0, 7.0] {
                for b in [[10.0, 5.0], [9.3, 6.1], [8.0, 7.5]] {
                    for tip in tips {
                        let a = f.marched(&c.c[0], tension, b, tip).ok().unwrap();
                        let mut q = [[0.0; 3]; MAX_SUB];
                        let t = f
                            .march_joint::<f64, _, _>(&ByComplianceLoaded(&c.c[0]), PoseFrame::new(&f, tension, b, tip).ok().unwrap(), &mut q, |x| x)
                            .ok()
                            .unwrap()
                            .end(f.params().e)
                            .ok()
                            .unwrap();
                        assert_eq!(a.hole, t.1);
                        assert_eq!(a.end, t.0);
                        assert_eq!(a.q, q);
                        let d = f.eval_dual(&c.c[0], tension, b, None).ok().unwrap();
                        let plain = f.marched(&c.c[0], tension, b, None).ok().unwrap();
                        assert_eq!(d.0.hole, plain.hole, "dual value part equals the plain march");
                    }
                }
            }
        }
        // and in f32
        let f = Finger::new(Params::<f32>::default()).unwrap();
        let c = f.compliances(&[0.0; 3]).unwrap();
        let a = f.marched(&c.c[0], 1.0, [9.5, 5.5], None).ok().unwrap();
        let mut q = [[0.0; 3]; MAX_SUB];
        let t = f
            .march_joint::<f32, _, _>(&ByComplianceLoaded(&c.c[0]), PoseFrame::new(&f, 1.0, [9.5, 5.5], None).ok().unwrap(), &mut q, |x| x)
            .ok()
            .unwrap()
            .end(f.params().e)
            .ok()
            .unwrap();
        assert_eq!(a.hole, t.1);
    }

    /// The tension-alone march in the running frame (`CableFrame`) is the plain march (`PoseFrame`) to rounding:
    /// same sub-element displacements, end, hole and (sin, cos), in f64 and in f32, at the
    /// stiffest and softest stacks, the calibrated finger too, and up to joint angles past the
    /// series turn's bound (m = 1: one turn of the whole joint).
    #[test]
    fn tension_march_matches_march() {
        let cal = crate::calibration::Calibration::<f64>::model_md();
        let mut fingers = fingers().to_vec();
        fingers.push(Finger::with_calibration(Params::default(), cal).unwrap());
        fingers.push(Finger::new(Params::<f64> { m: 1, ..Params::default() }).unwrap());
        for f in &fingers {
            let v_top = 0.9 * f.voltage_ceiling();
            for volts in [0.0, v_top] {
                let c = f.compliances(&[volts; 3]).unwrap();
                // what it reads: the upper triangles of symmetric compliances
                assert!(f.params().layers > 0);
                for cj in &c.c[0] {
                    assert!(cj[1][0] == cj[0][1] && cj[2][0] == cj[0][2] && cj[2][1] == cj[1][2]);
                }
                for tension in [0.05, 1.0, 7.0, 15.0] {
                    for b in [[10.0, 5.0], [9.3, 6.1], [8.0, 7.5], [3.0, 9.0]] {
                        let Ok(a) = f.marched(&c.c[0], tension, b, None) else { continue };
                        let mut q = [[0.0; 3]; MAX_SUB];
                        let (end, hole, sc, r2) = f.march_cable(&ByCompliance(&c.c[0]), tension, b, &mut q).ok().unwrap();
                        let close = |x: f64, y: f64| (x - y).abs() <= 1e-12 * (1.0 + y.abs());
                        assert!(close(end.x, a.end.x) && close(end.y, a.end.y) && close(end.theta, a.end.theta), "{end:?} {:?}", a.end);
                        assert!(close(hole[0], a.hole[0]) && close(hole[1], a.hole[1]));
                        let (s, co) = a.end.theta.sin_cos();
                        assert!((sc[0] - s).abs() < 1e-12 && (sc[1] - co).abs() < 1e-12);
                        assert!(close(r2, (b[0] - a.hole[0]).powi(2) + (b[1] - a.hole[1]).powi(2)));
                        for j in 0..MAX_SUB {
                            for i in 0..3 {
                                assert!((q[j][i] - a.q[j][i]).abs() <= 1e-12 * (1e-3 + a.q[j][i].abs()), "q[{j}][{i}]");
                            }
                        }
                    }
                }
            }
        }
        // f32: within a few units of its resolution on a hinge length
        let f = Finger::new(Params::<f32>::default()).unwrap();
        for volts in [0.0, 5000.0, 9000.0] {
            let c = f.compliances(&[volts; 3]).unwrap();
            for tension in [0.2, 1.0, 7.0, 15.0] {
                let b = [9.0, 6.5];
                let a = f.marched(&c.c[0], tension, b, None).ok().unwrap();
                let mut q = [[0.0; 3]; MAX_SUB];
                let (end, hole, _, _) = f.march_cable(&ByCompliance(&c.c[0]), tension, b, &mut q).ok().unwrap();
                assert!((end.x - a.end.x).abs() < 2e-5 && (end.y - a.end.y).abs() < 2e-5 && (end.theta - a.end.theta).abs() < 2e-6);
                assert!((hole[0] - a.hole[0]).abs() < 2e-5 && (hole[1] - a.hole[1]).abs() < 2e-5);
            }
        }
        // what the plain march refuses, it refuses
        let f = &fingers[0];
        let c = f.compliances(&[0.0; 3]).unwrap();
        let mut q = [[0.0; 3]; MAX_SUB];
        assert!(f.march_cable(&ByCompliance(&c.c[0]), 1.0, [0.0, f.params().e], &mut q).is_err(), "span below its floor");
        assert!(f.march_cable(&ByCompliance(&c.c[0]), 0.0, [10.0, 5.0], &mut q).is_err(), "no tension: not this march's case");
    }

    /// The turn rule (series, longer series, sin/cos) is the sine and cosine to the
    /// scalar's resolution across its branches, in f64 and f32.
    #[test]
    fn turn_matches_sin_cos() {
        let small = small_turn(f64::EPSILON);
        for i in -300..=300 {
            let x = small * f64::from(i) / 100.0;
            let (s, c) = x.turn(small);
            assert!((s - x.sin()).abs() <= 2.0 * f64::EPSILON && (c - x.cos()).abs() <= 2.0 * f64::EPSILON, "{x}");
        }
        let small = small_turn(f64::from(f32::EPSILON)) as f32;
        for i in -300..=300 {
            let x = small * i as f32 / 100.0;
            let (s, c) = x.turn(small);
            let (ws, wc) = (f64::from(x).sin(), f64::from(x).cos());
            assert!((f64::from(s) - ws).abs() <= 2e-7 && (f64::from(c) - wc).abs() <= 2e-7, "{x}");
        }
    }

    #[test]
    fn dual_jacobian_matches_central_differences() {
        for f in fingers() {
            let c = f.compliances(&[0.0; 3]).unwrap();
            for tension in [0.2, 1.0, 7.0] {
                let b = [9.4, 6.0];
                let (_, r0, jac) = f.eval_dual(&c.c[0], tension, b, None).ok().unwrap();
                assert!(r0[0].is_finite());
                let h = 1e-6;
                for i in 0..2 {
                    let (mut bp, mut bm) = (b, b);
                    bp[i] += h;
                    bm[i] -= h;
                    let (_, rp, _) = f.eval_dual(&c.c[0], tension, bp, None).ok().unwrap();
                    let (_, rm, _) = f.eval_dual(&c.c[0], tension, bm, None).ok().unwrap();
                    for row in 0..2 {
                        let fd = (rp[row] - rm[row]) / (2.0 * h);
                        assert!((fd - jac[row][i]).abs() < 1e-7, "J[{row}][{i}] {} vs {fd}", jac[row][i]);
                    }
                }
            }
        }
    }
}
