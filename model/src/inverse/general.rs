//! The inverse for every parameter set the forward model accepts: hinges split into m
//! sub-elements (`Params::m` > 1) and flexible links (`Params::flex_links`), with either
//! modulus (`Params::plate`). The m = 1 rigid-link fast path (the parent module) fixes the
//! hinge angle and solves the closed joint equilibrium for P or t; with m > 1 the angle is
//! split among the sub-elements and does not fix the hinge's geometry, and with flexible links
//! the hinge's share of the joint angle depends on P. So here one forward march of a joint
//! (`Finger::joint_march`, from a guessed guide-hole position) is the function evaluation,
//! and each joint solve is Broyden's method on (hole, P) at fixed stack thickness t (the
//! tension range ends, step 1: `hold_tension`) or on (hole, t) at fixed tension (step 4:
//! `hold_thickness`, then the voltage in closed form from t):
//!
//! - at fixed t the joint angle θ_k(P, t) rises with the tension along the equilibrium branch;
//! - at fixed tension it falls with t where thinning softens the joint, rises where the
//!   stack's axial-bending coupling makes thinning stiffen it.
//!
//! With the branch table (table.rs, `solve_tabled`) step 1 reads the range ends off the table
//! and confirms (one march) only those the answer rests on (the interval's bounds when the
//! tension is free); step 4 starts from a quadratic through the table's three branches, one
//! compliance evaluation and one march where that is within the tolerance. Behind the quasi-Newton solves (model feature `inverse-fallback`), a
//! bracketed root on the warm-started forward equilibrium (`Finger::joint_equilibrium`), the
//! solve layer's `bracket::increasing_root`: secant steps kept inside a bracket, bisection when
//! a step leaves it or when one end has been kept three times (the Illinois failure mode),
//! converged when the joint angle is within the angle tolerance or the bracket has shrunk to
//! the scalar's resolution. A forward failure
//! (contact, limit point) at a trial tension marks it as beyond the branch end; a target past
//! the end is refused with that error. The flexible link's rotation (P e L/(E I), independent
//! of the voltage) is part of θ_k.
//!
//! Steps 2-3 (the interval, the tension rule, the unreachable report) are the parent's, with
//! the same meaning for every m.

use super::table::{BranchTable, TableEnd, TABLE_BAND, TABLE_LEN, TABLE_STEP_DEG};
use super::{choose_tension, feasible_interval, one_tension, Options, PoseSolution};
use crate::de;
use crate::error::Error;
use crate::finger::{uniform_beam_compliance, Finger, JointEquilibrium, JointMarch, Method, Pose};
use crate::mat3::{self, Mat3};
use crate::params::{Params, MAX_JOINTS, MAX_SUB};
use crate::real::Real;
use crate::solve::{bracket, broyden};

/// One evaluated point of a root find: the parameter x (P or t), h = sign (θ - θ*), the state.
#[derive(Clone, Copy)]
struct Pt<R> {
    x: R,
    h: R,
    eq: JointEquilibrium<R>,
}

/// A joint held at its target angle.
#[derive(Clone, Copy)]
pub(super) struct Held<R> {
    pub(super) tension: R,
    thickness: R,
    /// The joint's state (the sub-element displacements go to the caller's buffer).
    pub(super) st: JointMarch<R>,
    /// dθ/dP at the solution (secant estimate), rad/N.
    pub(super) slope: R,
    /// The quasi-Newton solve's last Jacobian in (b, P) or (b, t), when it converged.
    pub(super) jac: Option<Mat3<R>>,
    /// Whether `st` is a solved state; a tension end read off the `BranchTable` has only its
    /// hole (and `tension`, `slope`) until it is verified.
    exact: bool,
}

/// What the root finds need, prepared once per solve.
pub(super) struct Gen<'a, R> {
    f: &'a Finger<R>,
    p: &'a Params<R>,
    /// The link's linear rotation per newton of tension (0 for rigid links), rad/N.
    link_rot: R,
    /// Hole tolerance of the per-joint Newton, mm.
    tol_hole: R,
    /// Hole tolerance of a converged march (`tol_hole`, or the march's resolution if coarser), mm.
    htol: R,
    /// Relative angle tolerance of a root.
    tol_angle: R,
    /// Relative bracket width at which a root stops.
    rel: R,
    max_iter: u32,
    /// Newton iterations spent in all.
    iters: u32,
}

impl<'a, R: Real> Gen<'a, R> {
    #[inline(never)]
    pub(super) fn new(f: &'a Finger<R>, opts: &Options<R>) -> Result<Self, Error> {
        let p = f.params();
        let lh = p.hinge_len();
        let link_rot = if p.flex_links {
            let lc = uniform_beam_compliance(p.hinge_modulus(), p.w, p.b, p.l - lh);
            lc[2][2] * p.e - lc[2][0]
        } else {
            R::zero()
        };
        Ok(Self::with_link_rot(f, opts, link_rot))
    }

    /// `new` with the link's rotation per newton given (zero where `slope0` is not used: the
    /// tabled path, whose slopes the table holds).
    #[inline(always)]
    fn with_link_rot(f: &'a Finger<R>, opts: &Options<R>, link_rot: R) -> Self {
        let p = f.params();
        let lh = p.hinge_len();
        let tol_hole = R::from_f64(1e-12) * (lh + p.e);
        Gen {
            f,
            p,
            link_rot,
            tol_hole,
            htol: tol_hole.max(f.hole_resolution()),
            tol_angle: R::from_f64(1e-12_f64.max(32.0 * R::EPS)),
            rel: R::from_f64(4.0 * R::EPS),
            max_iter: 2 * opts.max_iter.max(8),
            iters: 0,
        }
    }

    /// Sub-element compliances at stack thickness t, as `Finger::compliances` computes them.
    #[inline(never)]
    pub(super) fn comp(&self, t: R) -> Result<[Mat3<R>; MAX_SUB], Error> {
        let mut c = [mat3::zero(); MAX_SUB];
        self.comp_into(t, &mut c)?;
        Ok(c)
    }

    /// `comp` into `c` (its first m entries; no array returned by value in the hot loop).
    #[inline(never)]
    fn comp_into(&self, t: R, c: &mut [Mat3<R>; MAX_SUB]) -> Result<(), Error> {
        if self.p.layers == 0 {
            for (j, cj) in c.iter_mut().enumerate().take(self.p.m) {
                *cj = self.f.hinge_compliance(j);
            }
            return Ok(());
        }
        let kd = self.stack_upper(t)?;
        let mut check = R::zero();
        for (j, cj) in c.iter_mut().enumerate().take(self.p.m) {
            let (m, ck) = self.sub_compliance(j, &kd);
            *cj = m;
            check += ck;
        }
        Self::checked(check)
    }

    /// The upper triangle of the stack's stiffness at thickness t (K_de ∝ t axially, t³ in
    /// bending: positive semi-definite for t > 0, so each sum with the positive definite
    /// hinge has a positive diagonal). It depends on t alone: once per compliance evaluation.
    #[inline(always)]
    fn stack_upper(&self, t: R) -> Result<[R; 6], Error> {
        if !(t > R::zero() && t.is_finite()) {
            return Err(Error::Singular { what: "joint stiffness" });
        }
        let kd = self.f.stack_stiffness(t);
        Ok([kd[0][0], kd[0][1], kd[0][2], kd[1][1], kd[1][2], kd[2][2]])
    }

    /// Sub-element j's compliance C_j = (K_hinge,j + K_de)⁻¹ (`kd` the stack's upper triangle):
    /// the upper triangle's sum and its cofactor inverse, `mat3::inverse_spd_of_sum`'s
    /// arithmetic (the same numbers). With a check value: finite (the determinant plus the
    /// entries) when the sum is positive definite to working precision, else NaN; one
    /// finiteness test of the checks' sum then stands for every entry's.
    #[inline(always)]
    fn sub_compliance(&self, j: usize, kd: &[R; 6]) -> (Mat3<R>, R) {
        let kh = self.f.hinge_stiffness(j);
        let (a, b, c, d, e, f) = (kh[0][0] + kd[0], kh[0][1] + kd[1], kh[0][2] + kd[2], kh[1][1] + kd[3], kh[1][2] + kd[4], kh[2][2] + kd[5]);
        let ca = d * f - e * e;
        let cb = c * e - b * f;
        let cc = b * e - c * d;
        let det = a * ca + b * cb + c * cc;
        let ok = det > a * d * f * R::from_f64(64.0 * R::EPS);
        let inv = R::one() / det;
        let (cd, ce, cf) = (a * f - c * c, b * c - a * e, a * d - b * b);
        let o = [ca * inv, cb * inv, cc * inv, cd * inv, ce * inv, cf * inv];
        let check = if ok { det + o[0] + o[1] + o[2] + o[3] + o[4] + o[5] } else { R::from_f64(f64::NAN) };
        ([[o[0], o[1], o[2]], [o[1], o[3], o[4]], [o[2], o[4], o[5]]], check)
    }

    fn checked(check: R) -> Result<(), Error> {
        if check.is_finite() {
            Ok(())
        } else {
            Err(Error::Singular { what: "joint stiffness" })
        }
    }

    /// Scale the angle tolerance of the solves (the branch table's samples).
    pub(super) fn tighten(&mut self, k: R) {
        self.tol_angle = self.tol_angle * k;
    }

    /// The stack's range: (t0 at 0 V, t_top at `top` x the ceiling, the top voltage).
    #[inline(never)]
    pub(super) fn stack_ends(&self, opts: &Options<R>) -> Result<(R, R, R), Error> {
        let p = self.p;
        let t0 = R::from_u32(p.layers as u32) * p.z0;
        let v_top = self.f.ceiling_in_force(opts.hv_fs) * opts.top;
        let t_top = if v_top > R::zero() { de::stack_thickness(p, 1, v_top)? } else { t0 };
        Ok((t0, t_top, v_top))
    }

    /// The state of a held end: its own if solved, else one march at its tension and hole.
    #[inline(never)]
    fn state(&self, joint: usize, c: &[Mat3<R>; MAX_SUB], h: &Held<R>) -> Result<JointMarch<R>, Error> {
        if h.exact || h.tension == R::zero() {
            return Ok(h.st);
        }
        let mut q = [[R::zero(); 3]; MAX_SUB];
        self.f.joint_march(joint, c, h.tension, h.st.hole, &mut q)
    }

    /// The unloaded joint's state.
    fn straight_st(&self) -> JointMarch<R> {
        march_of(&self.straight())
    }

    /// dθ/dP at P = 0 (straight joint: every sub-element sees the axial force -P and the
    /// moment P e), rad/N.
    #[inline(never)]
    pub(super) fn slope0(&self, c: &[Mat3<R>; MAX_SUB]) -> R {
        let e = self.p.e;
        c.iter().take(self.p.m).fold(self.link_rot, |a, cj| a + cj[2][2] * e - cj[2][0])
    }

    fn straight(&self) -> JointEquilibrium<R> {
        let lh = self.p.hinge_len();
        JointEquilibrium {
            q: [[R::zero(); 3]; MAX_SUB],
            end: Pose { x: lh, y: R::zero(), theta: R::zero() },
            hole: [lh, self.p.e],
            link: [R::zero(); 3],
            angle: R::zero(),
            iterations: 0,
        }
    }

    /// Root of h(x) = sign (θ(x) - θ*), increasing in x, on [lo, hi] (hi = None: unbounded),
    /// on the solve layer's bracket (`solve::bracket::increasing_root`). `left`: a known point
    /// at lo; `x0`, `guess`: the first trial and its hole guess; `slope`: an estimate of dh/dx
    /// > 0. With `beyond_ok`, a forward failure (contact, limit point, no convergence) marks the
    /// trial as past the branch end, and a target past it is refused with that error. Each
    /// trial's hole guess is interpolated between the bracket's states, else the last state's.
    /// Returns the point and dh/dx there (secant estimate).
    #[allow(clippy::too_many_arguments)]
    #[inline(never)]
    fn root(
        &self,
        iters: &mut u32,
        theta: R,
        sign: R,
        ev: &mut dyn FnMut(R, Option<[R; 2]>) -> Result<JointEquilibrium<R>, Error>,
        lo: R,
        hi: Option<R>,
        left: Option<Pt<R>>,
        x0: R,
        guess: Option<[R; 2]>,
        slope: R,
        beyond_ok: bool,
    ) -> Result<(Pt<R>, R), Error> {
        let opts = bracket::RootOptions {
            atol: self.tol_angle * (theta.abs() + R::from_f64(0.1)),
            rel: self.rel,
            beyond_rel: R::from_f64(1e-6),
            max_iter: self.max_iter,
        };
        let left = left.map(|p| bracket::Point { x: p.x, h: p.h, state: p.eq });
        let (mut hole, mut first) = (guess, true);
        let mut trial = |x: R, at: &bracket::Around<'_, R, JointEquilibrium<R>>| {
            if !first {
                hole = match (at.left, at.right) {
                    (Some(a), Some(b)) if b.x != a.x => {
                        let fr = (x - a.x) / (b.x - a.x);
                        Some([
                            a.state.hole[0] + (b.state.hole[0] - a.state.hole[0]) * fr,
                            a.state.hole[1] + (b.state.hole[1] - a.state.hole[1]) * fr,
                        ])
                    }
                    _ => at.last.or(at.left).map(|z| z.state.hole).or(hole),
                };
            }
            first = false;
            match ev(x, hole) {
                Ok(eq) => {
                    *iters += eq.iterations;
                    Ok(bracket::Trial::Value(sign * (eq.angle - theta), eq))
                }
                Err(e @ (Error::Contact { .. } | Error::LimitPoint { .. } | Error::NotConverged { .. })) if beyond_ok => {
                    Ok(bracket::Trial::Beyond(e))
                }
                Err(e) => Err(e),
            }
        };
        match bracket::increasing_root(&mut trial, lo, hi, left, x0, slope, &opts) {
            Ok((p, s)) => Ok((Pt { x: p.x, h: p.h, eq: p.state }, s)),
            Err(bracket::RootError::Beyond(e) | bracket::RootError::Refused(e)) => Err(e),
            Err(bracket::RootError::NotConverged) => Err(Error::NotConverged { iterations: *iters, residual: f64::INFINITY }),
        }
    }

    /// Joint `joint` held at θ* with compliances `c` (thickness t): the tension, by a root in P
    /// from the straight joint at P = 0. `hint`: a first tension and hole to try; `jac_hint` a
    /// Jacobian in (b, P) to start from; `slope_hint` dθ/dP there (used when the hint itself
    /// is converged and no Jacobian was formed).
    #[allow(clippy::too_many_arguments)]
    pub(super) fn hold_tension(
        &mut self,
        joint: usize,
        theta: R,
        c: &[Mat3<R>; MAX_SUB],
        t: R,
        s_lin: R,
        hint: Option<(R, [R; 2])>,
        jac_hint: Option<Mat3<R>>,
        slope_hint: Option<R>,
        q_out: &mut [[R; 3]; MAX_SUB],
    ) -> Result<Held<R>, Error> {
        if !(theta > R::zero()) {
            // the straight joint (θ* = 0) at P = 0; a negative angle is refused by the caller
            *q_out = [[R::zero(); 3]; MAX_SUB];
            return Ok(Held { tension: R::zero(), thickness: t, st: self.straight_st(), slope: s_lin, jac: None, exact: true });
        }
        if !(s_lin > R::zero() && s_lin.is_finite()) {
            return Err(Error::Singular { what: "joint compliance" });
        }
        let (x0, guess) = match hint {
            Some((p, h)) if p > R::zero() && p.is_finite() => (p, Some(h)),
            _ => (theta / s_lin, None),
        };
        let f = self.f;
        // quasi-Newton on (b, P) first: one march per step
        {
            let lh = self.p.hinge_len();
            let b0 = guess.unwrap_or_else(|| self.arc_hole(theta));
            let scale = [lh, lh, x0];
            let (jac, fd) = match jac_hint {
                Some(j) => (j, [false; 3]),
                None => (mat3::zero(), [true; 3]),
            };
            let mut ev = |x: [R; 3], q: &mut [[R; 3]; MAX_SUB]| {
                if !(x[2] > R::zero()) {
                    return Err(Error::Input { input: "tension", reason: "trial below zero" });
                }
                f.joint_march(joint, c, x[2], [x[0], x[1]], q)
            };
            let (q, n) = self.broyden(&mut ev, [b0[0], b0[1], x0], scale, jac, fd, theta, q_out);
            self.iters += n;
            if let Some(q) = q {
                // converged at the first march (a guess from the table): the guess's slope
                let slope = match q.jac {
                    Some(j) => Self::slope_of(&j),
                    None => slope_hint.unwrap_or(R::zero()),
                };
                if q.x[2] > R::zero() && slope > R::zero() && slope.is_finite() {
                    return Ok(Held { tension: q.x[2], thickness: t, st: q.st, slope, jac: q.jac, exact: true });
                }
            }
        }
        if !cfg!(feature = "inverse-fallback") {
            return Err(Error::NotConverged { iterations: self.iters, residual: f64::INFINITY });
        }
        let left = Pt { x: R::zero(), h: -theta, eq: self.straight() };
        let tol = self.tol_hole;
        let mut ev = |x: R, g: Option<[R; 2]>| f.joint_equilibrium(joint, c, x, g, tol);
        let mut it = 0;
        let res = self.root(&mut it, theta, R::one(), &mut ev, R::zero(), None, Some(left), x0, guess, s_lin, true);
        self.iters += it;
        let (pt, s) = res?;
        if !(s > R::zero()) {
            return Err(Error::LimitPoint { joint, tension: pt.x.to_f64() });
        }
        *q_out = pt.eq.q;
        Ok(Held { tension: pt.x, thickness: t, st: march_of(&pt.eq), slope: s, jac: None, exact: true })
    }

    /// Joint held at θ* under tension `pt`: the stack thickness in [t_top, t0], by a root in t.
    /// `mid`: a third point (P, t, hole) of the joint held at θ* between the two, if known.
    /// The sub-element displacements go to `q_out`.
    #[inline(never)]
    #[allow(clippy::too_many_arguments)]
    fn hold_thickness(
        &mut self,
        joint: usize,
        theta: R,
        pt: R,
        lo: &Held<R>,
        hi: &Held<R>,
        mid: Option<(R, R, [R; 2])>,
        q_out: &mut [[R; 3]; MAX_SUB],
    ) -> Result<Held<R>, Error> {
        let (t_top, t0) = (lo.thickness, hi.thickness);
        let span = hi.tension - lo.tension;
        let (x0, guess) = level_guess((lo.tension, t_top, lo.st.hole), (hi.tension, t0, hi.st.hole), mid, pt);
        let dt = t0 - t_top;
        // dh/dt, h = θ* - θ: dθ/dP times the tension the range of t trades for
        let mut slope = ((lo.slope + hi.slope) / R::from_f64(2.0) * span / dt).abs();
        if !(slope > R::zero() && slope.is_finite()) {
            slope = theta * R::from_f64(0.01) / t0;
        }
        // θ falls with t where thinning softens the joint (the 0 V end needs the most
        // tension), rises where it stiffens it
        let sign = if hi.tension >= lo.tension { -R::one() } else { R::one() };
        // quasi-Newton on (b, t) first: the hole columns of the tension solve's Jacobian,
        // the thickness column by a forward difference
        {
            let lh = self.p.hinge_len();
            let (jac, fd) = match hi.jac.or(lo.jac) {
                Some(j) => (j, [false, false, true]),
                None => (mat3::zero(), [true; 3]),
            };
            let me: &Self = self;
            let mut c = [mat3::zero(); MAX_SUB];
            // the compliances of the last thickness tried (the hole columns' differences
            // keep t)
            let mut c_at: Option<R> = None;
            let mut ev = |x: [R; 3], q: &mut [[R; 3]; MAX_SUB]| {
                if !(x[2] > R::zero()) {
                    return Err(Error::Input { input: "thickness", reason: "trial below zero" });
                }
                if c_at != Some(x[2]) {
                    c_at = None;
                    me.comp_into(x[2], &mut c)?;
                    c_at = Some(x[2]);
                }
                me.f.joint_march(joint, &c, pt, [x[0], x[1]], q)
            };
            let (q, n) = self.broyden(&mut ev, [guess[0], guess[1], x0], [lh, lh, t0], jac, fd, theta, q_out);
            self.iters += n;
            if let Some(q) = q {
                // inside the stack's range (a root outside it is the bracket's to refuse)
                let slack = R::from_f64(1e-6) * t0;
                if q.x[2] >= t_top - slack && q.x[2] <= t0 + slack {
                    return Ok(Held { tension: pt, thickness: q.x[2], st: q.st, slope: hi.slope, jac: q.jac, exact: true });
                }
            }
        }
        if !cfg!(feature = "inverse-fallback") {
            return Err(Error::NotConverged { iterations: self.iters, residual: f64::INFINITY });
        }
        let me: &Self = self;
        let mut ev = |x: R, g: Option<[R; 2]>| f_eval(me, joint, x, pt, g);
        let mut it = 0;
        let res = self.root(&mut it, theta, sign, &mut ev, t_top, Some(t0), None, x0, Some(guess), slope, false);
        self.iters += it;
        let (p1, _) = res?;
        *q_out = p1.eq.q;
        Ok(Held { tension: pt, thickness: p1.x, st: march_of(&p1.eq), slope: hi.slope, jac: None, exact: true })
    }

    /// The joint's effective compliance θ/M (M the cable's moment about the hinge's distal
    /// end) when held with tension P in state `eq`, or its linear limit when P M vanishes.
    #[inline(never)]
    fn compliance(&self, theta: R, p: R, eq: &JointMarch<R>, c_lin: R) -> R {
        let e = self.p.e;
        let v = [eq.hole[0], eq.hole[1] - e];
        let rho = (v[0].sq() + v[1].sq()).sqrt();
        let wm = if rho > R::zero() {
            let fc = [-v[0] / rho, -v[1] / rho];
            (eq.hole[0] - eq.end.x) * fc[1] - (eq.hole[1] - eq.end.y) * fc[0]
        } else {
            e
        };
        let m = p * wm;
        if theta > R::zero() && m.abs() > R::from_f64(1e-30_f64.max(R::EPS * 1e-20)) {
            return theta / m;
        }
        if theta < R::zero() {
            -c_lin
        } else {
            c_lin
        }
    }
}

/// A converged quasi-Newton solve: the unknowns x = (b0, b1, s), the state, and the last
/// Jacobian of F in the unknowns x (reused as the next solve's first Jacobian).
#[derive(Clone, Copy)]
struct Qn<R> {
    x: [R; 3],
    st: JointMarch<R>,
    /// None when the first guess was converged and no Jacobian was given.
    jac: Option<Mat3<R>>,
}

impl<'a, R: Real> Gen<'a, R> {
    /// The hole of a joint bent to θ as a circular arc (the first guess of a quasi-Newton
    /// solve): hinge end (L_h sin θ/θ, L_h (1 - cos θ)/θ), link k's proximal hole e above it.
    #[inline(never)]
    fn arc_hole(&self, theta: R) -> [R; 2] {
        let lh = self.p.hinge_len();
        let (s, c) = theta.sin_cos();
        let (ex, ey) = if theta.abs() > R::from_f64(1e-6) { (lh * s / theta, lh * (R::one() - c) / theta) } else { (lh, R::zero()) };
        [ex - self.p.e * s, ey + self.p.e * c]
    }

    /// Broyden's method ("good" update, scaled unknowns y = x / scale) on the joint's three
    /// equations F(x) = (b - hole(b, s), θ(b, s) - θ*) = 0, x = (b0, b1, s), s the tension
    /// (`hold_tension`) or the stack thickness (`hold_thickness`); `ev(x)` is one plain march.
    /// The first Jacobian is `jac` (a previous solve's) or forward differences (3 marches).
    /// Converged when the hole residual is within the march's resolution and the angle
    /// within the root tolerance. `None` when it does not converge in 16 steps, or a march
    /// fails: the caller falls back to the bracketed root (robust, 3-5x the marches).
    /// Each step costs one march and no derivatives: cheaper than the dual-number Newton
    /// nested in a secant (issue 4: the inverse's instruction count).
    /// Returns the solve (if it converged) and the marches it took.
    /// (One instance for both solves: `ev` is a trait object, which keeps the firmware image
    /// small.)
    #[allow(clippy::too_many_arguments)]
    fn broyden(
        &self,
        ev: &mut dyn FnMut([R; 3], &mut [[R; 3]; MAX_SUB]) -> Result<JointMarch<R>, Error>,
        x0: [R; 3],
        scale: [R; 3],
        jac_x: Mat3<R>,
        fd: [bool; 3],
        theta: R,
        q_out: &mut [[R; 3]; MAX_SUB],
    ) -> (Option<Qn<R>>, u32) {
        let mut evals = 0u32;
        let mut ev = |x: [R; 3], q: &mut [[R; 3]; MAX_SUB]| {
            evals += 1;
            ev(x, q)
        };
        let r = self.broyden_steps(&mut ev, x0, scale, jac_x, fd, theta, q_out);
        (r, evals)
    }

    /// The iteration of `broyden`. The iterates' marches write their sub-element displacements
    /// to `q_out` (the converged state is always the last iterate marched), the forward
    /// differences to a scratch buffer.
    #[allow(clippy::too_many_arguments)]
    #[inline(never)]
    fn broyden_steps<F>(
        &self,
        ev: &mut F,
        x0: [R; 3],
        scale: [R; 3],
        jac_x: Mat3<R>,
        fd: [bool; 3],
        theta: R,
        q_out: &mut [[R; 3]; MAX_SUB],
    ) -> Option<Qn<R>>
    where
        F: FnMut([R; 3], &mut [[R; 3]; MAX_SUB]) -> Result<JointMarch<R>, Error>,
    {
        let atol = self.tol_angle * (theta.abs() + R::from_f64(0.1));
        let htol = self.htol;
        let resid = |x: &[R; 3], st: &JointMarch<R>| [x[0] - st.hole[0], x[1] - st.hole[1], st.angle - theta];
        let mut x = x0;
        let st = ev(x, q_out).ok()?;
        let mut fx = resid(&x, &st);
        let unscaled = |j: &Mat3<R>| {
            let mut jx = *j;
            for row in 0..3 {
                for col in 0..3 {
                    jx[row][col] = j[row][col] / scale[col];
                }
            }
            jx
        };
        let converged = |f: &[R; 3], k: R| f[0].abs() <= k * htol && f[1].abs() <= k * htol && f[2].abs() <= k * atol;
        // a first guess already converged (from the branch table) needs no Jacobian
        if converged(&fx, R::one()) {
            let jac = if fd.iter().any(|&d| d) { None } else { Some(jac_x) };
            return Some(Qn { x, st, jac });
        }
        // the Jacobian in the scaled unknowns; columns marked `fd` by forward differences
        let mut j = jac_x;
        if fd.iter().any(|&d| d) {
            let mut scratch = [[R::zero(); 3]; MAX_SUB];
            for col in 0..3 {
                if fd[col] {
                    let h = R::from_f64(R::SQRT_EPS);
                    let mut xp = x;
                    xp[col] += h * scale[col];
                    let sp = ev(xp, &mut scratch).ok()?;
                    let fp = resid(&xp, &sp);
                    for row in 0..3 {
                        j[row][col] = (fp[row] - fx[row]) / h;
                    }
                }
            }
        }
        for col in 0..3 {
            if !fd[col] {
                for row in 0..3 {
                    j[row][col] = jac_x[row][col] * scale[col];
                }
            }
        }
        // Broyden (`solve::broyden`) in the scaled unknowns y = x / scale; the marches write
        // the iterate's displacements to `q_out` (no line search: the last one is the answer's)
        let mut y = [x[0] / scale[0], x[1] / scale[1], x[2] / scale[2]];
        let mut last = st;
        let mut eval = |y: &[R; 3]| -> Result<[R; 3], Error> {
            let xn = [y[0] * scale[0], y[1] * scale[1], y[2] * scale[2]];
            let sn = ev(xn, q_out)?;
            last = sn;
            Ok(resid(&xn, &sn))
        };
        let done = broyden::solve(&mut eval, &mut y, &mut fx, &mut j, 3, &converged, 16);
        done.ok()?;
        x = [y[0] * scale[0], y[1] * scale[1], y[2] * scale[2]];
        Some(Qn { x, st: last, jac: Some(unscaled(&j)) })
    }

    /// dθ/dP along the equilibrium at fixed t from a solve's Jacobian (unknowns (b, P)):
    /// J dx = (0, 0, dθ*) gives dP/dθ* = (J⁻¹)[2][2].
    fn slope_of(jac: &Mat3<R>) -> R {
        match mat3::inverse_unscaled(jac) {
            Some(inv) if inv[2][2] != R::zero() => R::one() / inv[2][2],
            _ => R::zero(),
        }
    }
}

/// The first guess of a thickness solve at tension `pt` along the level curve θ(P, t) = θ*
/// through the joint's two ends `lo`, `hi` (tension, thickness, hole): linear between them, or
/// quadratic through a third point `mid` of it (the branch table's middle thickness), which
/// takes the guess inside the solve's tolerance for the default stacks. Returns (t, hole).
#[inline(always)]
fn level_guess<R: Real>(lo: (R, R, [R; 2]), hi: (R, R, [R; 2]), mid: Option<(R, R, [R; 2])>, pt: R) -> (R, [R; 2]) {
    let ((p0, t_top, b0), (p2, t0, b2)) = (lo, hi);
    if let Some((p1, tm, b1)) = mid {
        let (d01, d02, d12) = (p0 - p1, p0 - p2, p1 - p2);
        if d01 != R::zero() && d02 != R::zero() && d12 != R::zero() {
            let w = [(pt - p1) * (pt - p2) / (d01 * d02), -(pt - p0) * (pt - p2) / (d01 * d12), (pt - p0) * (pt - p1) / (d02 * d12)];
            let q = w[0] * t_top + w[1] * tm + w[2] * t0;
            if q.is_finite() {
                let b = [w[0] * b0[0] + w[1] * b1[0] + w[2] * b2[0], w[0] * b0[1] + w[1] * b1[1] + w[2] * b2[1]];
                return (q.max(t_top).min(t0), b);
            }
        }
    }
    let span = p2 - p0;
    let frac = if span != R::zero() { ((pt - p0) / span).max(R::zero()).min(R::one()) } else { R::one() };
    (t_top + (t0 - t_top) * frac, [b0[0] + (b2[0] - b0[0]) * frac, b0[1] + (b2[1] - b0[1]) * frac])
}

/// The joint's equilibrium at tension `p` with the stack at thickness `t`.
fn f_eval<R: Real>(g: &Gen<'_, R>, joint: usize, t: R, p: R, guess: Option<[R; 2]>) -> Result<JointEquilibrium<R>, Error> {
    let c = g.comp(t)?;
    g.f.joint_equilibrium(joint, &c, p, guess, g.tol_hole)
}

/// Each joint's two tension ends (softest, stiffest stack), as `choose_tension` takes them.
fn tension_ends<R: Real>(lo: &[Held<R>; MAX_JOINTS], hi: &[Held<R>; MAX_JOINTS], n: usize) -> [[R; 2]; MAX_JOINTS] {
    let mut ends = [[R::zero(); 2]; MAX_JOINTS];
    for k in 0..n {
        ends[k] = [lo[k].tension, hi[k].tension];
    }
    ends
}

/// A march's state of a solved equilibrium.
fn march_of<R: Real>(eq: &JointEquilibrium<R>) -> JointMarch<R> {
    JointMarch { end: eq.end, hole: eq.hole, link: eq.link, angle: eq.angle }
}

/// The hinge end and link deflection of joint k (its sub-element displacements are written
/// to `out.sub_q[k]` by the solve itself).
fn record<R: Real>(out: &mut PoseSolution<R>, k: usize, lh: R, h: &Held<R>) {
    let st = &h.st;
    out.q[k] = [st.end.x - lh, st.end.y, st.end.theta];
    out.links[k] = st.link;
}

/// `solve_pose_with` for m > 1 or flexible links (module documentation), with the branch
/// table when one is given (table.rs). Fills `out` (zeroed by the caller).
#[inline(never)]
pub(super) fn solve<R: Real>(
    f: &Finger<R>,
    table: Option<&BranchTable<R>>,
    angles: &[R],
    tension: Option<R>,
    opts: &Options<R>,
    out: &mut PoseSolution<R>,
) -> Result<(), Error> {
    let mut g = Gen::new(f, opts)?;
    let p = f.params();
    let n = p.n;
    let lh = p.hinge_len();
    if p.layers == 0 {
        return no_stacks(&mut g, angles, tension, opts, out);
    }
    // 1. every joint's tension range: stiffest stack (0 V) and softest (top voltage)
    let (t0, t_top, v_top) = match table {
        Some(tb) => (tb.thickness[1], tb.thickness[0], tb.v_top),
        None => g.stack_ends(opts)?,
    };
    let own;
    let cs: &[[Mat3<R>; MAX_SUB]; 2] = match table {
        Some(tb) => &tb.comp,
        None => {
            own = [g.comp(t_top)?, g.comp(t0)?];
            &own
        }
    };
    let (c_top, c0) = (&cs[0], &cs[1]);
    let (s0, s_top) = match table {
        Some(tb) => (tb.slope0[1], tb.slope0[0]),
        None => (g.slope0(c0), g.slope0(c_top)),
    };
    let straight = Held { tension: R::zero(), thickness: t0, st: g.straight_st(), slope: s0, jac: None, exact: true };
    let mut hi = [straight; MAX_JOINTS];
    let mut lo = [straight; MAX_JOINTS];
    // the middle branch at each joint's angle (step 4's third point)
    let mut mid: [Option<(R, R, [R; 2])>; MAX_JOINTS] = [None; MAX_JOINTS];
    // ends the table did not give (no table, or the angle outside it)
    let mut unknown = [false; MAX_JOINTS];
    for k in 0..n {
        let th = angles[k];
        let ends = table.and_then(|tb| tb.ends(th));
        let read = |e: Option<&TableEnd<R>>, t: R, s: R| {
            // without the table: the linear guess (hold_tension's own first trial)
            let (tension, hole) = match e {
                Some(e) => (e.tension, e.hole),
                None => (th / s, g.arc_hole(th)),
            };
            let st = JointMarch { hole, angle: th, ..straight.st };
            Held { tension, thickness: t, st, slope: th / tension, jac: None, exact: false }
        };
        lo[k] = read(ends.as_ref().map(|e| &e[0]), t_top, s_top);
        hi[k] = read(ends.as_ref().map(|e| &e[1]), t0, s0);
        unknown[k] = ends.is_none();
        if let (Some(tb), Some(e)) = (table, ends) {
            mid[k] = Some((e[2].tension, tb.thickness[2], e[2].hole));
        }
    }
    // step 1's states are not kept: their sub-element displacements go here
    let mut scratch = [[R::zero(); 3]; MAX_SUB];
    // 1b. solve the ends the table did not give, the ends that bound the feasible interval,
    //     and any within `TABLE_BAND` of those bounds (they might bound it instead)
    loop {
        // the interval's two bounds: the largest low end and the smallest high end
        let bound = feasible_interval(n, |k| [lo[k].tension, hi[k].tension]);
        let band = R::from_f64(TABLE_BAND);
        let mut next = None;
        'find: for k in 0..n {
            for e in 0..2 {
                let h = if e == 0 { &lo[k] } else { &hi[k] };
                let near = (h.tension - bound[0]).abs() <= band * bound[0] || (h.tension - bound[1]).abs() <= band * bound[1];
                if !h.exact && (unknown[k] || near) {
                    next = Some((k, e));
                    break 'find;
                }
            }
        }
        let Some((k, e)) = next else { break };
        let (h, c, t, s) = if e == 0 { (lo[k], c_top, t_top, s_top) } else { (hi[k], c0, t0, s0) };
        // a solved end's Jacobian (a similar state) spares the forward differences
        let mut jac = None;
        for j in 0..n {
            jac = jac.or(hi[j].jac).or(lo[j].jac);
        }
        let hint = if unknown[k] { None } else { Some((h.tension, h.st.hole)) };
        let solved = g.hold_tension(k + 1, angles[k], c, t, s, hint, jac, Some(h.slope), &mut scratch)?;
        // the same angle, the same end
        for j in 0..n {
            if angles[j] == angles[k] {
                if e == 0 {
                    lo[j] = solved;
                } else {
                    hi[j] = solved;
                }
            }
        }
    }
    // 2-3. the feasible interval and the tension (`choose_tension`); a negative angle is
    //      outside every tension's reach
    let negative = (0..n).filter(|&k| angles[k] < R::zero()).min_by(|&a, &b| {
        angles[a].partial_cmp(&angles[b]).unwrap_or(core::cmp::Ordering::Equal)
    });
    let (interval, pt, worst) = choose_tension(&tension_ends(&lo, &hi, n)[..n], tension, negative, g.rel);
    out.interval = interval;
    if let Some(k) = worst {
        let (cl0, cl_top) = (s0 / p.e, s_top / p.e);
        // the states of ends read off the table (one march each)
        let (h_hi, h_lo) = (g.state(k + 1, c0, &hi[k])?, g.state(k + 1, c_top, &lo[k])?);
        // the range the ceiling allows, whichever end is the more compliant
        let (c_hi, c_lo) = (g.compliance(angles[k], hi[k].tension, &h_hi, cl0), g.compliance(angles[k], lo[k].tension, &h_lo, cl_top));
        return Err(Error::Unreachable {
            joint: k + 1,
            needed: g.compliance(angles[k], pt, &h_hi, cl0).to_f64(),
            min: c_hi.min(c_lo).to_f64(),
            max: c_hi.max(c_lo).to_f64(),
        });
    }
    out.tension = pt;
    // 4. every joint's thickness at that tension, then its voltage (0 V for the straight
    //    finger at zero tension)
    for k in 0..n {
        if k > 0 && angles[k] == angles[k - 1] {
            // the joint before, recorded already: the same state
            out.thickness[k] = out.thickness[k - 1];
            out.volts[k] = out.volts[k - 1];
            out.q[k] = out.q[k - 1];
            out.sub_q[k] = out.sub_q[k - 1];
            out.links[k] = out.links[k - 1];
            continue;
        }
        let q_out = &mut out.sub_q[k];
        let held = if pt == R::zero() {
            straight
        } else if t0 - t_top <= g.rel * t0 {
            // no stack range: the 0 V end's state
            g.hold_tension(k + 1, angles[k], c0, t0, s0, Some((hi[k].tension, hi[k].st.hole)), hi[k].jac, Some(hi[k].slope), q_out)?
        } else {
            g.hold_thickness(k + 1, angles[k], pt, &lo[k], &hi[k], mid[k], q_out)?
        };
        let t = held.thickness.max(t_top).min(t0);
        out.thickness[k] = t;
        out.volts[k] = if t >= t0 { R::zero() } else { de::voltage_for_thickness(p, k + 1, t)?.min(v_top) };
        record(out, k, lh, &held);
    }
    out.iterations = g.iters;
    Ok(())
}

impl<'a, R: Real> Gen<'a, R> {
    /// One march of joint `joint` at tension `p` from hole `b` with compliances `c`: its state
    /// when that is already an equilibrium of the full model to the quasi-Newton solves' own
    /// tolerance (`broyden_steps`: hole residual and joint angle), else None (also when the
    /// march fails). The march is `march_tension` where it applies (`Finger::joint_march_tension`).
    /// The sub-element displacements go to `q`.
    #[inline(never)]
    fn march_converged(&self, joint: usize, c: &[Mat3<R>; MAX_SUB], p: R, b: [R; 2], theta: R, q: &mut [[R; 3]; MAX_SUB]) -> Option<JointMarch<R>> {
        let st = self.f.joint_march_tension(joint, c, p, b, q).ok()?;
        self.converged(st, b, theta)
    }

    /// `march_converged` from the stiffnesses at the stack's upper triangle `kd`
    /// (`Finger::joint_march_stiffness`: no compliance formed).
    #[inline(never)]
    fn march_converged_stiff(&self, kd: &[R; 6], p: R, link: [R; 3], b: [R; 2], theta: R, q: &mut [[R; 3]; MAX_SUB]) -> Option<JointMarch<R>> {
        let st = self.f.joint_march_stiffness(kd, p, link, b, q)?;
        self.converged(st, b, theta)
    }

    /// `st` if its hole is `b` and its angle `theta` within the quasi-Newton solves' tolerance.
    #[inline(always)]
    fn converged(&self, st: JointMarch<R>, b: [R; 2], theta: R) -> Option<JointMarch<R>> {
        let atol = self.tol_angle * (theta.abs() + R::from_f64(0.1));
        let htol = self.htol;
        let ok = (b[0] - st.hole[0]).abs() <= htol && (b[1] - st.hole[1]).abs() <= htol && (st.angle - theta).abs() <= atol;
        ok.then_some(st)
    }
}

/// Joint `k`'s (0-based) range end `e` (0 softest, 1 stiffest stack) held at `theta`,
/// confirmed in place from the table's reading `r`: kept where one march there is within the
/// solver's tolerance, else the quasi-Newton solve from it. Returns whether the tension moved.
/// The march's sub-element displacements go to `q` (the joint's own rows: step 4 writes them
/// again).
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn confirm_end<R: Real>(g: &mut Gen<'_, R>, tb: &BranchTable<R>, k: usize, e: usize, r: &mut TableEnd<R>, theta: R, q: &mut [[R; 3]; MAX_SUB]) -> Result<bool, Error> {
    let c = &tb.comp[e];
    if g.march_converged(k + 1, c, r.tension, r.hole, theta, q).is_some() {
        return Ok(false);
    }
    let h = g.hold_tension(k + 1, theta, c, tb.thickness[e], tb.slope0[e], Some((r.tension, r.hole)), None, Some(theta / r.tension), q)?;
    let moved = h.tension != r.tension;
    *r = TableEnd { tension: h.tension, hole: h.st.hole };
    Ok(moved)
}

/// Step 1b of `solve_tabled` with the tension free: confirm (`confirm_end`) the ends the
/// midpoint rule rests on, the feasible interval's bounds and any end within `TABLE_BAND` of
/// them, in the readings `rd` (per joint: softest, stiffest, middle); `interval` the readings'
/// bounds, updated when a confirmed tension moves them (then the scan starts again). The
/// marches' sub-element displacements go to each joint's rows of `sub_q`.
#[inline(never)]
fn confirm_bounds<R: Real>(
    g: &mut Gen<'_, R>,
    tb: &BranchTable<R>,
    angles: &[R],
    rd: &mut [[TableEnd<R>; 3]; MAX_JOINTS],
    interval: &mut [R; 2],
    sub_q: &mut [[[R; 3]; MAX_SUB]; MAX_JOINTS],
) -> Result<(), Error> {
    let n = angles.len().min(MAX_JOINTS);
    let band = R::from_f64(TABLE_BAND);
    // (bit 2k + e: end e of joint k)
    let mut exact = 0u32;
    loop {
        // the ends near a bound, not yet confirmed, in the order of the bits
        let [lo, hi] = *interval;
        let (near_lo, near_hi) = (band * lo, band * hi);
        let mut todo = 0u32;
        for (k, rk) in rd.iter().enumerate().take(n) {
            for (e, end) in rk.iter().take(2).enumerate() {
                let x = end.tension;
                if (x - lo).abs() <= near_lo || (x - hi).abs() <= near_hi {
                    todo |= 1 << (2 * k + e);
                }
            }
        }
        todo &= !exact;
        let mut moved = false;
        while todo != 0 && !moved {
            let i = todo.trailing_zeros() as usize;
            let (k, e) = (i / 2, i % 2);
            moved = confirm_end(g, tb, k, e, &mut rd[k][e], angles[k], &mut sub_q[k])?;
            g.iters += 1;
            exact |= 1 << i;
            todo &= !(1 << i);
            // the same angle, the same end (a joint before at this angle has the same reading:
            // it was confirmed first)
            let solved = rd[k][e];
            for j in k + 1..n {
                if angles[j] == angles[k] {
                    rd[j][e] = solved;
                    exact |= 1 << (2 * j + e);
                    todo &= !(1 << (2 * j + e));
                }
            }
        }
        if !moved {
            return Ok(());
        }
        *interval = feasible_interval(n, |k| [rd[k][0].tension, rd[k][1].tension]);
    }
}

/// Step 4's march of joint `k` (0-based) from compliances at thickness `t`: the table's at either
/// end of the stack's range, else evaluated (after a stiffness march that was not converged: a
/// march more). `Gen::march_converged`'s answer.
#[inline(never)]
#[allow(clippy::too_many_arguments)]
fn compliance_march<R: Real>(
    g: &mut Gen<'_, R>,
    tb: &BranchTable<R>,
    k: usize,
    t: R,
    p: R,
    b: [R; 2],
    theta: R,
    q: &mut [[R; 3]; MAX_SUB],
) -> Result<Option<JointMarch<R>>, Error> {
    let [t_top, t0, _] = tb.thickness;
    let mut c = [tb.comp[1][0]; MAX_SUB];
    let ck = if t >= t0 {
        &tb.comp[1]
    } else if t <= t_top {
        &tb.comp[0]
    } else {
        g.iters += 1;
        g.comp_into(t, &mut c)?;
        &c
    };
    Ok(g.march_converged(k + 1, ck, p, b, theta, q))
}

/// `solve_pose_tabled`'s path (docs/inverse.md, "The tabled inverse"): every joint's range
/// ends and step 4's start read off the table; each read confirmed by one march of the full
/// model where the answer depends on it, the quasi-Newton solve from there only where that
/// march is not within the solver's tolerance. Writes `out` in place (every field). Returns
/// false, leaving the answer to `solve`, where the table does not hold a target (outside its
/// angles, zero or negative angles) and on a refusal (the error's report is `solve`'s).
#[inline(never)]
pub(super) fn solve_tabled<R: Real>(tb: &BranchTable<R>, angles: &[R], tension: Option<R>, out: &mut PoseSolution<R>) -> Result<bool, Error> {
    let f = &tb.finger;
    let p = f.params();
    let n = p.n;
    let [t_top, t0, tm] = tb.thickness;
    if p.layers == 0 || !(t0 - t_top > R::from_f64(4.0 * R::EPS) * t0) {
        return Ok(false);
    }
    // (the table holds the straight joint's slopes: no link rotation needed)
    let mut g = Gen::with_link_rot(f, &tb.opts, R::zero());
    // per joint: the softest end, the stiffest end, the middle branch (tension, hole); joint k
    // repeats joint k-1 where their angles are equal (filled with the first joint's reading:
    // no zeroed array written twice)
    let len = tb.covered();
    let Some(e0) = tb.read(angles[0], len).filter(|_| angles[0] > R::zero()) else { return Ok(false) };
    let mut rd = [e0; MAX_JOINTS];
    for k in 1..n {
        if angles[k] == angles[k - 1] {
            rd[k] = rd[k - 1];
            continue;
        }
        match tb.read(angles[k], len) {
            Some(e) if angles[k] > R::zero() => rd[k] = e,
            _ => return Ok(false),
        }
    }
    let band = R::from_f64(TABLE_BAND);
    let mut interval = feasible_interval(n, |k| [rd[k][0].tension, rd[k][1].tension]);
    // a target the readings refuse (the interval empty; a given tension outside a joint's
    // range by more than the band) is `solve`'s to refuse and report, before any march here
    let pt = match tension {
        Some(pg) => {
            // (some joint's range starts above pg + tol or ends below pg - tol: the interval
            // does, its bounds the largest start and the smallest end)
            let tol = band * pg;
            if interval[0] - pg > tol || pg - interval[1] > tol {
                return Ok(false);
            }
            // (no end confirmed: step 4's converged solve inside [t_top, t0] is what shows the
            // tension within a joint's range; near an end whose solve does not converge,
            // `solve` decides)
            pg
        }
        None => {
            if !(interval[0] <= interval[1]) {
                return Ok(false);
            }
            // 1b. confirm the ends the midpoint rule rests on
            confirm_bounds(&mut g, tb, angles, &mut rd, &mut interval, &mut out.sub_q)?;
            // 2-3. the midpoint of the interval (`choose_tension`'s rule); a refusal is
            //      `solve`'s to report
            if !(interval[0] <= interval[1]) {
                return Ok(false);
            }
            (interval[0] + interval[1]) / R::from_f64(2.0)
        }
    };
    // (the midpoint of a non-empty interval lies in every joint's range; a given tension was
    // checked against the readings above, and step 4 shows it inside or hands it to `solve`)
    if !(pt > R::zero()) {
        return Ok(false);
    }
    // the answer's scalars, and zeros past the n joints and m sub-elements (written in place)
    let zr = R::zero();
    out.n = n;
    out.m = p.m;
    out.tension_given = tension.is_some();
    out.interval = interval;
    out.tension = pt;
    for k in 0..n {
        out.angles[k] = angles[k];
    }
    for k in n..MAX_JOINTS {
        out.angles[k] = zr;
        out.volts[k] = zr;
        out.thickness[k] = zr;
        out.q[k] = [zr; 3];
        out.links[k] = [zr; 3];
    }
    out.sub_q[n..].as_flattened_mut().as_flattened_mut().fill(zr);
    if p.m < MAX_SUB {
        for row in out.sub_q.iter_mut().take(n) {
            for qj in row.iter_mut().skip(p.m) {
                *qj = [zr; 3];
            }
        }
    }
    // 4. every joint's thickness at that tension: one compliance evaluation and one march at
    //    the table's start along the level curve, the quasi-Newton solve only if that march is
    //    not within the tolerance; then the voltage
    let lh = p.hinge_len();
    let (v_top, volts) = (tb.v_top, &tb.volts);
    let (stack, link) = (f.stack_upper(), f.tension_link_q(pt));
    for k in 0..n {
        if k > 0 && angles[k] == angles[k - 1] {
            out.thickness[k] = out.thickness[k - 1];
            out.volts[k] = out.volts[k - 1];
            out.q[k] = out.q[k - 1];
            // (row by row, strided: no call to a byte-wise memcpy)
            for jj in 0..p.m {
                out.sub_q[k][jj] = out.sub_q[k - 1][jj];
            }
            out.links[k] = out.links[k - 1];
            continue;
        }
        let [lo, hi, md] = &rd[k];
        let (t_guess, b) = level_guess((lo.tension, t_top, lo.hole), (hi.tension, t0, hi.hole), Some((md.tension, tm, md.hole)), pt);
        // inside the stack's range one march from the stiffnesses (no compliance formed); the
        // compliance march at either end, and inside it only where that one is not converged
        let inside = t_guess < t0 && t_guess > t_top;
        let quick = if inside { g.march_converged_stiff(&stack.at(t_guess), pt, link, b, angles[k], &mut out.sub_q[k]) } else { None };
        g.iters += 1;
        let marched = match quick {
            Some(st) => Some(st),
            None => compliance_march(&mut g, tb, k, t_guess, pt, b, angles[k], &mut out.sub_q[k])?,
        };
        let (t, st) = match marched {
            Some(st) => (t_guess, st),
            None if tension.is_some() && (0..2).any(|e| (rd[k][e].tension - pt).abs() <= band * pt) => {
                // a given tension near an unconfirmed end: `solve` confirms the range
                return Ok(false);
            }
            None => {
                let held = |e: &TableEnd<R>, t: R| Held {
                    tension: e.tension,
                    thickness: t,
                    st: JointMarch { hole: e.hole, angle: angles[k], ..g.straight_st() },
                    slope: angles[k] / e.tension,
                    jac: None,
                    exact: false,
                };
                let (l, h) = (held(&lo, t_top), held(&hi, t0));
                let r = g.hold_thickness(k + 1, angles[k], pt, &l, &h, Some((md.tension, tm, md.hole)), &mut out.sub_q[k])?;
                (r.thickness, r.st)
            }
        };
        let t = t.max(t_top).min(t0);
        out.thickness[k] = t;
        out.volts[k] = if t >= t0 { R::zero() } else { volts.voltage(k + 1, t)?.min(v_top) };
        out.q[k] = [st.end.x - lh, st.end.y, st.end.theta];
        out.links[k] = st.link;
    }
    out.iterations = g.iters;
    Ok(true)
}

/// The finger without stacks: only the tension is free (the parent's rule).
#[inline(never)]
fn no_stacks<R: Real>(
    g: &mut Gen<'_, R>,
    angles: &[R],
    tension: Option<R>,
    opts: &Options<R>,
    out: &mut PoseSolution<R>,
) -> Result<(), Error> {
    let n = out.n;
    let z = R::zero();
    let lh = g.p.hinge_len();
    let c = g.comp(z)?;
    let s_lin = g.slope0(&c);
    let mut h = [Held { tension: z, thickness: z, st: g.straight_st(), slope: s_lin, jac: None, exact: true }; MAX_JOINTS];
    for k in 0..n {
        if angles[k] < z {
            let cl = s_lin / g.p.e;
            return Err(Error::Unreachable { joint: k + 1, needed: -cl.to_f64(), min: cl.to_f64(), max: cl.to_f64() });
        }
        if k > 0 && angles[k] == angles[k - 1] {
            h[k] = h[k - 1];
            out.sub_q[k] = out.sub_q[k - 1];
        } else {
            let hint = (0..k)
                .rev()
                .find(|&j| h[j].tension > z)
                .map(|j| (angles[k] * h[j].tension / angles[j], h[j].st.hole));
            let jac = (0..k).rev().find_map(|j| h[j].jac);
            h[k] = g.hold_tension(k + 1, angles[k], &c, z, s_lin, hint, jac, None, &mut out.sub_q[k])?;
        }
        record(out, k, lh, &h[k]);
    }
    // the rule (the parent's `one_tension`), dθ/dP = slope
    let mut tensions = [z; MAX_JOINTS];
    let mut slopes = [z; MAX_JOINTS];
    for k in 0..n {
        tensions[k] = h[k].tension;
        slopes[k] = h[k].slope;
    }
    let (interval, pt, worst) = one_tension(&tensions[..n], &slopes[..n], tension, opts.angle_tol);
    out.interval = interval;
    if let Some(k) = worst {
        let cl = s_lin / g.p.e;
        let have = g.compliance(angles[k], h[k].tension, &h[k].st, cl).to_f64();
        return Err(Error::Unreachable {
            joint: k + 1,
            needed: g.compliance(angles[k], pt, &h[k].st, cl).to_f64(),
            min: have,
            max: have,
        });
    }
    out.tension = pt;
    // the states at the chosen tension: the forward model's posture there (0 V: the hinges
    // alone)
    if pt > z {
        let sol = g.f.solve(pt, &[z; MAX_JOINTS][..n], Method::converged())?;
        g.iters += sol.iterations;
        let sub_len = lh / R::from_u32(g.p.m as u32);
        for k in 0..n {
            let mut end = Pose::origin();
            for q in sol.q[k].iter().take(g.p.m) {
                end = end.then(sub_len + q[0], q[1], q[2]);
            }
            out.q[k] = [end.x - lh, end.y, end.theta];
            out.sub_q[k] = sol.q[k];
            out.links[k] = sol.links[k];
        }
    }
    out.iterations = g.iters;
    Ok(())
}

impl<R: Real> BranchTable<R> {
    /// Build the table for finger `f` and the inverse options `opts` (their `top` sets the
    /// softest end). Fails for a finger without stacks (nothing to tabulate: its inverse is
    /// one root per joint) and for options the inverse refuses.
    #[inline(never)]
    pub fn new(f: &Finger<R>, opts: &Options<R>) -> Result<Self, Error> {
        super::check_options(opts)?;
        let p = f.params();
        if p.layers == 0 {
            return Err(Error::Input { input: "table", reason: "a finger without stacks has no branch table" });
        }
        let mut g = Gen::new(f, opts)?;
        // samples eight times tighter than a solve's tolerance: the ends read off the table
        // start step 4, whose first march then lands inside that tolerance
        g.tighten(R::from_f64(0.125));
        let (t0, t_top, v_top) = g.stack_ends(opts)?;
        let comp = [g.comp(t_top)?, g.comp(t0)?];
        let t_mid = (t_top + t0) / R::from_f64(2.0);
        let c_mid = g.comp(t_mid)?;
        let slope0 = [g.slope0(&comp[0]), g.slope0(&comp[1])];
        let step = R::from_f64(TABLE_STEP_DEG.to_radians());
        let lh = p.hinge_len();
        let mut t = BranchTable {
            finger: *f,
            opts: *opts,
            thickness: [t_top, t0, t_mid],
            v_top,
            volts: de::ThicknessVoltage::new(p),
            comp,
            slope0,
            step,
            len: [1; 3],
            x: [[[R::zero(), lh, p.e]; TABLE_LEN]; 3],
            angle_cubics: [[[[R::zero(); 4]; 3]; 3]; TABLE_LEN],
            grid: super::table::zero_grid(),
            dp: R::zero(),
            inv_dp: R::zero(),
            grid_len: 0,
            grid_top: R::zero(),
        };
        let mut scratch = [[R::zero(); 3]; MAX_SUB];
        for e in 0..3 {
            let th = t.thickness[e];
            let (c, s_lin) = if e < 2 { (&t.comp[e], t.slope0[e]) } else { (&c_mid, g.slope0(&c_mid)) };
            let mut jac: Option<Mat3<R>> = None;
            let mut slope = s_lin;
            for i in 1..TABLE_LEN {
                let theta = step * R::from_u32(i as u32);
                let xs = &t.x[e];
                // linear extrapolation from the two samples before (none for the first)
                let ex = |c: usize| xs[i - 1][c] + xs[i - 1][c] - xs[i - 2][c];
                let hint = if i > 1 { Some((ex(0), [ex(1), ex(2)])) } else { None };
                let Ok(h) = g.hold_tension(1, theta, c, th, s_lin, hint, jac, Some(slope), &mut scratch) else {
                    break;
                };
                if !(h.tension > t.x[e][i - 1][0]) {
                    // past a limit point the branch turns back: the table ends before it
                    break;
                }
                t.x[e][i] = [h.tension, h.st.hole[0], h.st.hole[1]];
                t.len[e] = i + 1;
                jac = h.jac.or(jac);
                slope = h.slope;
            }
        }
        t.build_angle_cubics();
        t.build_tension_grid();
        Ok(t)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::params::Params;

    /// Broyden on one march per step converges for both kinds of solve (P at fixed t, t at
    /// fixed P) at the default model (m = 8, plate, flexible links), from the first guesses
    /// the general path uses, and its answer is the forward model's equilibrium.
    #[test]
    fn broyden_solves_a_joint_and_agrees_with_the_forward_equilibrium() {
        let f = Finger::new(Params::<f64>::default()).unwrap();
        let g = Gen::new(&f, &Options::default()).unwrap();
        let p = f.params();
        let lh = p.hinge_len();
        let t0 = f64::from(p.layers) * p.z0;
        let c0 = g.comp(t0).unwrap();
        let theta = 10f64.to_radians();
        // P at fixed t (step 1), forward-difference Jacobian
        let p_lin = theta / g.slope0(&c0);
        let b0 = g.arc_hole(theta);
        let mut ev = |x: [f64; 3], q: &mut [[f64; 3]; MAX_SUB]| f.joint_march(1, &c0, x[2], [x[0], x[1]], q);
        let mut qb = [[0.0; 3]; MAX_SUB];
        let (q, n) = g.broyden(&mut ev, [b0[0], b0[1], p_lin], [lh, lh, p_lin], mat3::zero(), [true; 3], theta, &mut qb);
        let q = q.expect("Broyden converges for the tension");
        assert!(n <= 12, "{n} marches");
        let eq = f.joint_equilibrium(1, &c0, q.x[2], None, 1e-12).unwrap();
        assert!((eq.angle - theta).abs() < 1e-10, "{} vs {theta}", eq.angle);
        assert!((eq.hole[0] - q.x[0]).abs() < 1e-9 && (eq.hole[1] - q.x[1]).abs() < 1e-9);
        // t at fixed P (step 4) from the tension solve's Jacobian, t column differenced
        let pt = q.x[2] * 0.995;
        let mut ev = |x: [f64; 3], qb: &mut [[f64; 3]; MAX_SUB]| {
            let c = g.comp(x[2])?;
            f.joint_march(1, &c, pt, [x[0], x[1]], qb)
        };
        let (r, _) = g.broyden(&mut ev, [q.x[0], q.x[1], t0 * 0.995], [lh, lh, t0], q.jac.unwrap(), [false, false, true], theta, &mut qb);
        let r = r.expect("Broyden converges for the thickness");
        assert!(r.x[2] < t0);
        let eq = f.joint_equilibrium(1, &g.comp(r.x[2]).unwrap(), pt, None, 1e-12).unwrap();
        assert!((eq.angle - theta).abs() < 1e-10, "{} vs {theta}", eq.angle);
    }
}
