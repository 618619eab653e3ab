//! A joint's march: from a guessed guide hole, each sub-element's q = C w under the loads in the
//! deformed geometry (the paper's Eq. 7/15), to the hole it arrives at. Two recurrences here:
//! `march_t` (any scalar, an optional tip load; on dual numbers it gives the hole residual's
//! exact Jacobian for Newton, `eval_dual`, `newton_dual`) and `march_tension_by` (tension
//! alone, carried in each sub-element's frame). `march_t_matches_march` and
//! `tension_march_matches_march` hold them equal. Which to call:
//!
//! | to get                                        | call                                       |
//! | a converged joint (forward solve)             | `newton_dual`                              |
//! | one plain march, any load                     | `march`, `march_into` (joint.rs)           |
//! | the tabled forward's march                    | `march_tension`                            |
//! | a march from stiffnesses (tabled inverse)     | `march_stiffness` (march_stiffness.rs)     |
//! | the inverse's evaluation, confirming marches  | `joint_march`, `joint_march_tension`, `joint_march_stiffness` (joint.rs) |
//! | the paper's Eq. 29 load stepping              | `explicit_step` (stepping.rs)              |
//! | fixed point (the Cortex-M3)                   | `fixed::forward`'s march                   |
//!
//! docs/model.md "Which march to call" has the full table and the small-angle turn rule.

use super::{norm2, Finger, JointState, MarchError, Pose, TipLoad};
use crate::dual::D;
use crate::mat3::Mat3;
use crate::params::MAX_SUB;
use crate::real::Real;
use crate::solve::{self, newton::Equations, SolveOptions};
use core::ops::{Add, Mul, Sub};

/// Whether the march turns (sin, cos) by the series (below): not on a soft-float core, where
/// the series' code in the plain and the dual march costs flash the M3 image's 64 KiB does not
/// have (`scripts/fw-size m3`); there each sub-element takes its angle's sin/cos.
const SERIES_TURN: bool = !cfg!(target_abi = "eabi");

/// The largest sub-element rotation (rad) whose (sin, cos) the march takes from the Taylor
/// series to x⁵ and x⁶: their truncation errors, x⁷/5040 and x⁸/40320, stay below the scalar's
/// resolution `eps` relative (x⁶ < 5040 eps: 0.29 in f32, 0.010 in f64; the bounds below are
/// inside those).
pub(super) fn small_turn(eps: f64) -> f64 {
    if eps > 1e-10 {
        0.25
    } else {
        0.008
    }
}

/// (sin x, cos x) of a sub-element's rotation: the series (`Real::sin_cos_small`'s) below
/// `small` (`small_turn`), the series one term longer (to x⁷ and x⁸, exact to the scalar's
/// resolution up to 0.6 in f32, 0.07 in f64) below 2 `small` (the stiffest scenes' middle
/// sub-elements), else the scalar's sin/cos. The bounds are tested on x², which the series
/// needs anyway.
#[inline(always)]
fn turn<R: Real>(x: R, small: R) -> (R, R) {
    let z = x * x;
    let small2 = small * small;
    if z < small2 {
        series_turn(x, z)
    } else if z < small2 * R::from_f64(4.0) {
        let s = x * (R::one() - z * (R::from_f64(1.0 / 6.0) - z * (R::from_f64(1.0 / 120.0) - z * R::from_f64(1.0 / 5040.0))));
        let c = R::one()
            - z * (R::from_f64(0.5) - z * (R::from_f64(1.0 / 24.0) - z * (R::from_f64(1.0 / 720.0) - z * R::from_f64(1.0 / 40320.0))));
        (s, c)
    } else {
        x.sin_cos()
    }
}

/// `Real::sin_cos_small` with x² given.
#[inline(always)]
fn series_turn<R: Real>(x: R, z: R) -> (R, R) {
    let s = x * (R::one() - z * (R::from_f64(1.0 / 6.0) - z * R::from_f64(1.0 / 120.0)));
    let c = R::one() - z * (R::from_f64(0.5) - z * (R::from_f64(1.0 / 24.0) - z * R::from_f64(1.0 / 720.0)));
    (s, c)
}

/// A joint state, its hole residual `b - hole` and the residual's Jacobian `I - ∂hole/∂b`.
pub(super) type Eval<R> = (JointState<R>, [R; 2], [[R; 2]; 2]);

impl<R: Real> Finger<R> {
    /// Joint equilibrium march, `q_j = C_j w_j` sub-element by sub-element (the paper's Eq. 7
    /// and 15, loads in the deformed geometry: docs/model.md "Equilibrium").
    /// `Finger::march` in the scalar `T` (R itself, or dual numbers over R); parameters and
    /// compliances stay in R. Same operations in the same order as `march`. Returns the hinge
    /// end and the hole in T; the sub-element displacements go to `q_out` as values (`val`),
    /// which keeps the fixed-capacity array out of T (no zeroing and copying of dual arrays).
    /// The third value is (sin, cos) of the end's angle (the posture chain reuses it).
    pub(super) fn march_t<T>(
        &self,
        c: &[Mat3<R>; MAX_SUB],
        tension: R,
        b_hole: [T; 2],
        tip: Option<TipLoad<R>>,
        q_out: &mut [[R; 3]; MAX_SUB],
        val: impl Fn(T) -> R,
    ) -> Result<(Pose<T>, [T; 2], [T; 2]), MarchError>
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
        let small = T::from_f64(small_turn(T::EPS));
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
            // (sin, cos) of the new angle: the old one turned by this sub-element's rotation
            // (`Real::sin_cos_small`, below `small_turn`'s bound exact to the scalar's
            // resolution), else the angle's own sin/cos
            let dth = qj[2];
            if SERIES_TURN && dth.abs() < small {
                let (sd, cd) = dth.sin_cos_small();
                (s, co) = (s * cd + co * sd, co * cd - s * sd);
            } else {
                (s, co) = pose.theta.sin_cos();
            }
        }
        let hole = [pose.x - s * e, pose.y + co * e];
        if !(hole[0].is_finite() && hole[1].is_finite() && pose.theta.is_finite()) {
            return Err(MarchError::Singular);
        }
        Ok((pose, hole, [s, co]))
    }

    /// The plain march under tension alone (P > 0), carried in each sub-element's own frame:
    /// the same equations as `march_t` (docs/model.md "Equilibrium", the paper's Eq. 7 and 15), with
    /// the cable force f turned into each sub-element's frame and the hole B held by two
    /// scalars, the moment about the sub-element's proximal end and the dot product of
    /// (B - that end) with f, each carried to the next sub-element by a rotation-free
    /// recurrence: a sub-element costs its closed-form 3x3 equilibrium and one turn of f (no
    /// pose update, no moment arm rebuilt from the pose). The end's pose comes back once: its
    /// rotation from f = R^T f_c, B - end from the two scalars. The compliances are symmetric
    /// (`Finger::compliances` makes them so: `mat3::inverse_spd`), and their upper triangles
    /// are read. Same answer as `march_into` to the scalar's rounding (test
    /// `tension_march_matches_march`); the branch table's forward marches with it
    /// (`Finger::fill_from_holes`), and refuses what it refuses (and a non-positive `den`,
    /// which the full model's Newton then takes). Returns the hinge end, the hole, (sin, cos)
    /// of the end's angle, and the squared hole residual |b - hole|².
    #[inline(always)]
    pub(super) fn march_tension(
        &self,
        c: &[Mat3<R>; MAX_SUB],
        tension: R,
        b: [R; 2],
        q_out: &mut [[R; 3]; MAX_SUB],
    ) -> Result<(Pose<R>, [R; 2], [R; 2], R), MarchError> {
        let l = self.sub_len;
        let eps_den = R::from_f64(1e-6);
        self.march_tension_by(c, tension, b, q_out, |cj, f, mm| {
            debug_assert!(cj[1][0] == cj[0][1] && cj[2][0] == cj[0][2] && cj[2][1] == cj[1][2]);
            // q = C (f, M), M the moment about the deformed distal end: M = m0 + f0 q1 - f1 q0
            // with m0 = mm - L f1 the moment about the undeformed one, linear in q, so with
            // a = C (f, 0) it is (mm + f0 a1 - f1 (a0 + L)) / den (`march_t`'s closed form, its
            // terms regrouped)
            let (c00, c01, c02, c11, c12, c22) = (cj[0][0], cj[0][1], cj[0][2], cj[1][1], cj[1][2], cj[2][2]);
            let a = [f[0] * c00 + f[1] * c01, f[0] * c01 + f[1] * c11, f[0] * c02 + f[1] * c12];
            let den = (f[1] * c02 + R::one()) - f[0] * c12;
            if !(den > eps_den) {
                return Err(MarchError::Singular);
            }
            let mm = (mm + f[0] * a[1] - f[1] * (a[0] + l)) / den;
            Ok(([a[0] + mm * c02, a[1] + mm * c12, a[2] + mm * c22], mm))
        })
    }

    /// The tension-alone march's recurrences (`march_tension`'s), with sub-element j's
    /// equilibrium `sub(&per_sub[j], f, mm)`: its q and the moment about its deformed distal
    /// end from f, the cable's force in its frame, and mm, the moment about its proximal end.
    /// f is turned by each q's rotation and (B - the proximal end) · f carried along; the end's
    /// pose, hole, (sin, cos) and |b - hole|² come back once (`tension_end`).
    #[inline(always)]
    pub(super) fn march_tension_by<T, S>(
        &self,
        per_sub: &[T; MAX_SUB],
        tension: R,
        b: [R; 2],
        q_out: &mut [[R; 3]; MAX_SUB],
        mut sub: S,
    ) -> Result<(Pose<R>, [R; 2], [R; 2], R), MarchError>
    where
        S: FnMut(&T, [R; 2], R) -> Result<([R; 3], R), MarchError>,
    {
        let l = self.sub_len;
        // in sub-element j's proximal frame: f the cable's force on the distal chain; with w =
        // B - the sub-element's proximal end, mm = w × f (the moment about that end) and
        // dot = w · f
        let (fc, mut mm, mut dot) = self.tension_start(tension, b)?;
        let mut f = fc;
        let mut theta = R::zero();
        let small = R::from_f64(small_turn(R::EPS));
        let m = self.p.m.min(MAX_SUB);
        for (pj, qo) in per_sub[..m].iter().zip(q_out[..m].iter_mut()) {
            let (q, m_end) = sub(pj, f, mm)?;
            mm = m_end;
            *qo = q;
            theta = theta + q[2];
            // B - the deformed distal end (the next proximal end) is w - (L + q0, q1): its dot
            // with f; then f into the next frame (turned by q[2]; dot and cross products keep)
            dot = dot - (q[0] + l) * f[0] - q[1] * f[1];
            let (sd, cd) = turn(q[2], small);
            f = [cd * f[0] + sd * f[1], cd * f[1] - sd * f[0]];
        }
        self.tension_end(tension, b, fc, f, dot, mm, theta)
    }

    /// A tension-alone march's start at hole guess `b`: the cable's force f_c = -P (B - (0, e)) / |B - (0, e)|
    /// on the distal chain, the moment B × f_c and the dot product B · f_c (refuses a span below
    /// its floor and P <= 0: `Contact`).
    #[inline(always)]
    pub(super) fn tension_start(&self, tension: R, b: [R; 2]) -> Result<([R; 2], R, R), MarchError> {
        let span_v = [b[0], b[1] - self.p.e];
        let span = norm2(span_v);
        if !(span >= self.p.span_floor) || !(tension > R::zero()) {
            return Err(MarchError::Contact);
        }
        let k = -tension / span;
        let fc = [span_v[0] * k, span_v[1] * k];
        Ok((fc, b[0] * fc[1] - b[1] * fc[0], b[0] * fc[0] + b[1] * fc[1]))
    }

    /// A tension-alone march's end from the force f in the last frame, the running dot product
    /// and moment, and the summed rotation: the end's rotation R from f = Rᵀ f_c, r = B - end in
    /// its frame from r · f and r × f, the hole B - R (r - (0, e)). Returns the hinge end, the
    /// hole, (sin, cos) of the end's angle and |b - hole|²; refuses a state that is not finite.
    #[inline(always)]
    #[allow(clippy::too_many_arguments)]
    pub(super) fn tension_end(
        &self,
        tension: R,
        b: [R; 2],
        fc: [R; 2],
        f: [R; 2],
        dot: R,
        mm: R,
        theta: R,
    ) -> Result<(Pose<R>, [R; 2], [R; 2], R), MarchError> {
        let e = self.p.e;
        let inv = R::one() / (tension * tension);
        let co = (f[0] * fc[0] + f[1] * fc[1]) * inv;
        let s = (f[0] * fc[1] - f[1] * fc[0]) * inv;
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
        let (end_d, hole_d, _) = self.march_t::<D<R>>(c, tension, bd, None, q, |x| x.v)?;
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
        tol: R,
        max_iter: u32,
    ) -> Result<(JointState<R>, u32), (Option<MarchError>, u32)> {
        self.newton_dual_with(c, tension, b, &SolveOptions::new(tol, self.resolution(), max_iter))
    }

    /// `newton_dual` with the solver's options (iterations, line-search halvings) given.
    pub(super) fn newton_dual_with(
        &self,
        c: &[Mat3<R>; MAX_SUB],
        tension: R,
        b: [R; 2],
        opts: &SolveOptions<R>,
    ) -> Result<(JointState<R>, u32), (Option<MarchError>, u32)> {
        let mut eq = JointHoles { f: self, c, tension, q: [[[R::zero(); 3]; MAX_SUB]; 2], st: [None; 2] };
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
    q: [[[R; 3]; MAX_SUB]; 2],
    #[allow(clippy::type_complexity)]
    st: [Option<(Pose<R>, [R; 2], [R; 2], [[R; 2]; 2])>; 2],
}

impl<R: Real> Equations<R, 2> for JointHoles<'_, R> {
    type Refusal = MarchError;
    fn residual(&mut self, x: &[R; 2], slot: usize) -> Result<[R; 2], MarchError> {
        let slot = slot.min(1);
        let ev = self.f.eval_dual_into(self.c, self.tension, *x, &mut self.q[slot])?;
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

    /// The tension-alone march in the running frame is the plain march (`march_t`) to rounding:
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
                        let Ok(a) = f.march(&c.c[0], tension, b, None) else { continue };
                        let mut q = [[0.0; 3]; MAX_SUB];
                        let (end, hole, sc, r2) = f.march_tension(&c.c[0], tension, b, &mut q).ok().unwrap();
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
                let a = f.march(&c.c[0], tension, b, None).ok().unwrap();
                let mut q = [[0.0; 3]; MAX_SUB];
                let (end, hole, _, _) = f.march_tension(&c.c[0], tension, b, &mut q).ok().unwrap();
                assert!((end.x - a.end.x).abs() < 2e-5 && (end.y - a.end.y).abs() < 2e-5 && (end.theta - a.end.theta).abs() < 2e-6);
                assert!((hole[0] - a.hole[0]).abs() < 2e-5 && (hole[1] - a.hole[1]).abs() < 2e-5);
            }
        }
        // what the plain march refuses, it refuses
        let f = &fingers[0];
        let c = f.compliances(&[0.0; 3]).unwrap();
        let mut q = [[0.0; 3]; MAX_SUB];
        assert!(f.march_tension(&c.c[0], 1.0, [0.0, f.params().e], &mut q).is_err(), "span below its floor");
        assert!(f.march_tension(&c.c[0], 0.0, [10.0, 5.0], &mut q).is_err(), "no tension: not this march's case");
    }

    /// The series turn is the sine and cosine to the scalar's resolution over its whole range.
    #[test]
    fn series_turn_matches_sin_cos() {
        let lim = small_turn(f64::EPSILON);
        for i in -100..=100 {
            let x = lim * f64::from(i) / 100.0;
            let (s, c) = x.sin_cos_small();
            assert!((s - x.sin()).abs() <= 2.0 * f64::EPSILON && (c - x.cos()).abs() <= 2.0 * f64::EPSILON, "{x}");
        }
        let lim = small_turn(f64::from(f32::EPSILON)) as f32;
        for i in -100..=100 {
            let x = lim * i as f32 / 100.0;
            let (s, c) = x.sin_cos_small();
            let (ws, wc) = (f64::from(x).sin(), f64::from(x).cos());
            assert!((f64::from(s) - ws).abs() <= 2e-7 && (f64::from(c) - wc).abs() <= 2e-7, "{x}");
        }
    }

    /// The tension march's turn (series, longer series, sin/cos) is the sine and cosine to the
    /// scalar's resolution across its branches, in f64 and f32.
    #[test]
    fn turn_matches_sin_cos() {
        let small = small_turn(f64::EPSILON);
        for i in -300..=300 {
            let x = small * f64::from(i) / 100.0;
            let (s, c) = turn(x, small);
            assert!((s - x.sin()).abs() <= 2.0 * f64::EPSILON && (c - x.cos()).abs() <= 2.0 * f64::EPSILON, "{x}");
        }
        let small = small_turn(f64::from(f32::EPSILON)) as f32;
        for i in -300..=300 {
            let x = small * i as f32 / 100.0;
            let (s, c) = turn(x, small);
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
