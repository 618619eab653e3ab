//! The inverse for every parameter set the forward model accepts: hinges split into m
//! sub-elements (`Params::m` > 1) and flexible links (`Params::flex_links`), with either
//! modulus (`Params::plate`). The m = 1 rigid-link fast path (the parent module) fixes the
//! hinge angle and solves the closed joint equilibrium for P or t; with m > 1 the angle is
//! split among the sub-elements and does not fix the hinge's geometry, and with flexible links
//! the hinge's share of the joint angle depends on P. So here the forward per-joint solve
//! (`Finger::joint_equilibrium`, the same Newton as `Finger::solve_with`, warm-started) is
//! the function evaluation, and the inverse is 1-D root finding on it:
//!
//! - at fixed stack thickness t, the joint angle θ_k(P, t) rises monotonically with the
//!   tension along the equilibrium branch (root in P: the tension range ends, steps 1);
//! - at fixed tension it falls monotonically with t (thinner stack, softer joint; root in t
//!   on [t_top, t0], then the voltage in closed form from t, step 4).
//!
//! Each root: secant steps kept inside a bracket, bisection when a step leaves it or when one
//! end has been kept three times (the Illinois failure mode), converged when the joint angle
//! is within `angle tolerance` of the target or the bracket has shrunk to the scalar's
//! resolution. A forward failure (contact, limit point) at a trial tension marks it as beyond
//! the branch end; a target past the end is refused with that error. The flexible link's
//! rotation (P e L/(E I), independent of the voltage) is part of θ_k.
//!
//! Steps 2-3 (the interval, the tension rule, the unreachable report) are the parent's, with
//! the same meaning for every m.

use super::{choose_tension, Options, PoseSolution};
use crate::de;
use crate::error::Error;
use crate::finger::{uniform_beam_compliance, Finger, JointEquilibrium, JointMarch, Pose};
use crate::mat3::{self, Mat3};
use crate::params::{Params, MAX_JOINTS, MAX_SUB};
use crate::real::Real;

/// One evaluated point of a root find: the parameter x (P or t), h = sign (θ - θ*), the state.
#[derive(Clone, Copy)]
struct Pt<R> {
    x: R,
    h: R,
    eq: JointEquilibrium<R>,
}

/// A joint held at its target angle.
#[derive(Clone, Copy)]
struct Held<R> {
    tension: R,
    thickness: R,
    eq: JointEquilibrium<R>,
    /// dθ/dP at the solution (secant estimate), rad/N.
    slope: R,
    /// The quasi-Newton solve's last Jacobian in (b, P) or (b, t), when it converged.
    jac: Option<Mat3<R>>,
}

/// What the root finds need, prepared once per solve.
struct Gen<'a, R> {
    f: &'a Finger<R>,
    p: &'a Params<R>,
    hinge_k: [Mat3<R>; MAX_SUB],
    sub_len: R,
    /// The link's linear rotation per newton of tension (0 for rigid links), rad/N.
    link_rot: R,
    /// Hole tolerance of the per-joint Newton, mm.
    tol_hole: R,
    /// Relative angle tolerance of a root.
    tol_angle: R,
    /// Relative bracket width at which a root stops.
    rel: R,
    max_iter: u32,
    /// Newton iterations spent in all.
    iters: u32,
}

impl<'a, R: Real> Gen<'a, R> {
    fn new(f: &'a Finger<R>, opts: &Options<R>) -> Result<Self, Error> {
        let p = f.params();
        let mut hinge_k = [mat3::zero(); MAX_SUB];
        for (j, k) in hinge_k.iter_mut().enumerate().take(p.m) {
            *k = mat3::inverse_spd(&f.hinge_compliance(j)).ok_or(Error::Singular { what: "hinge compliance" })?;
        }
        let lh = p.hinge_len();
        let link_rot = if p.flex_links {
            let lc = uniform_beam_compliance(p.hinge_modulus(), p.w, p.b, p.l - lh);
            lc[2][2] * p.e - lc[2][0]
        } else {
            R::zero()
        };
        Ok(Gen {
            f,
            p,
            hinge_k,
            sub_len: lh / R::from_u32(p.m as u32),
            link_rot,
            tol_hole: R::from_f64(1e-12) * (lh + p.e),
            tol_angle: R::from_f64(1e-12_f64.max(32.0 * R::EPS)),
            rel: R::from_f64(4.0 * R::EPS),
            max_iter: 2 * opts.max_iter.max(8),
            iters: 0,
        })
    }

    /// Sub-element compliances at stack thickness t, as `Finger::compliances` computes them.
    fn comp(&self, t: R) -> Result<[Mat3<R>; MAX_SUB], Error> {
        let mut c = [mat3::zero(); MAX_SUB];
        self.comp_into(t, &mut c)?;
        Ok(c)
    }

    /// `comp` into `c` (its first m entries; no array returned by value in the hot loop).
    fn comp_into(&self, t: R, c: &mut [Mat3<R>; MAX_SUB]) -> Result<(), Error> {
        let k_de = if self.p.layers == 0 { mat3::zero() } else { de::stack_stiffness(self.p, self.sub_len, t) };
        for (j, cj) in c.iter_mut().enumerate().take(self.p.m) {
            *cj = if self.p.layers == 0 {
                self.f.hinge_compliance(j)
            } else {
                mat3::inverse_spd(&mat3::add(&self.hinge_k[j], &k_de)).ok_or(Error::Singular { what: "joint stiffness" })?
            };
        }
        Ok(())
    }

    /// dθ/dP at P = 0 (straight joint: every sub-element sees the axial force -P and the
    /// moment P e), rad/N.
    fn slope0(&self, c: &[Mat3<R>; MAX_SUB]) -> R {
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

    /// Root of h(x) = sign (θ(x) - θ*), increasing in x, on [lo, hi] (hi = None: unbounded).
    /// `left`: a known point at lo; `x0`, `guess`: the first trial and its hole guess;
    /// `slope`: an estimate of dh/dx > 0. With `beyond_ok`, a forward failure marks the trial
    /// as past the branch end. Returns the point and dh/dx there (secant estimate).
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
    ) -> Result<(Pt<R>, R), Error>
    {
        let atol = self.tol_angle * (theta.abs() + R::from_f64(0.1));
        let two = R::from_f64(2.0);
        let (mut l_x, mut l_pt) = (lo, left);
        let (mut r_x, mut r_pt): (Option<R>, Option<Pt<R>>) = (hi, None);
        let (mut prev, mut last): (Option<Pt<R>>, Option<Pt<R>>) = (left, None);
        let mut beyond: Option<Error> = None;
        let (mut run_side, mut run) = (0i8, 0u32);
        let mut x = x0;
        let mut hole = guess;
        let slope_of = |a: Option<Pt<R>>, b: &Pt<R>| match a {
            Some(a) if a.x != b.x => {
                let s = (b.h - a.h) / (b.x - a.x);
                if s.is_finite() && s > R::zero() {
                    s
                } else {
                    slope
                }
            }
            _ => slope,
        };
        for _ in 0..self.max_iter {
            let side;
            match ev(x, hole) {
                Ok(eq) => {
                    *iters += eq.iterations;
                    let pt = Pt { x, h: sign * (eq.angle - theta), eq };
                    if !pt.h.is_finite() {
                        return Err(Error::NotConverged { iterations: *iters, residual: f64::INFINITY });
                    }
                    if pt.h.abs() <= atol {
                        let s = slope_of(last.or(prev), &pt);
                        return Ok((pt, s));
                    }
                    if pt.h < R::zero() {
                        l_x = x;
                        l_pt = Some(pt);
                        side = -1;
                    } else {
                        r_x = Some(x);
                        r_pt = Some(pt);
                        side = 1;
                    }
                    if last.is_some() {
                        prev = last;
                    }
                    last = Some(pt);
                }
                Err(e @ (Error::Contact { .. } | Error::LimitPoint { .. } | Error::NotConverged { .. })) if beyond_ok => {
                    r_x = Some(x);
                    r_pt = None;
                    beyond = Some(e);
                    side = 1;
                }
                Err(e) => return Err(e),
            }
            if side == run_side {
                run += 1;
            } else {
                run_side = side;
                run = 1;
            }
            // the target lies past the branch end: the tension where it ends is known to 1e-6
            if let (Some(rx), None, Some(e)) = (r_x, r_pt, beyond) {
                if rx - l_x <= R::from_f64(1e-6) * rx {
                    return Err(e);
                }
            }
            // the bracket has shrunk to the resolution: the best point, or the branch end
            if let Some(rx) = r_x {
                if rx - l_x <= self.rel * rx.abs().max(l_x.abs()) {
                    if r_pt.is_none() {
                        if let Some(e) = beyond {
                            return Err(e);
                        }
                    }
                    let best = match (l_pt, r_pt) {
                        (Some(a), Some(b)) => Some(if a.h.abs() <= b.h.abs() { a } else { b }),
                        (a, b) => a.or(b),
                    };
                    let Some(pt) = best else {
                        return Err(Error::NotConverged { iterations: *iters, residual: f64::INFINITY });
                    };
                    let s = slope_of(if last.map(|z| z.x) == Some(pt.x) { prev } else { last }, &pt);
                    return Ok((pt, s));
                }
            }
            // next trial: secant through the last two points, else the slope estimate
            let mut xn = match (prev, last) {
                (Some(a), Some(b)) if b.h != a.h => b.x - b.h * (b.x - a.x) / (b.h - a.h),
                (_, Some(b)) => b.x - b.h / slope,
                _ => (l_x + x) / two,
            };
            let inside = xn.is_finite() && xn > l_x && r_x.map_or(true, |rx| xn < rx);
            match r_x {
                None => {
                    // unbounded: grow at most fourfold per step
                    let cap = R::from_f64(4.0) * l_x.max(x);
                    if !inside || run >= 3 {
                        xn = two * l_x.max(x);
                    }
                    xn = xn.min(cap);
                }
                Some(rx) => {
                    if run >= 3 {
                        xn = (l_x + rx) / two;
                    } else if !inside {
                        // an end of the range not yet evaluated is tried first
                        xn = if xn >= rx && r_pt.is_none() && beyond.is_none() {
                            rx
                        } else if xn <= l_x && l_pt.is_none() {
                            l_x
                        } else {
                            (l_x + rx) / two
                        };
                    }
                }
            }
            // hole guess: interpolated between the bracket's states, else the nearest state
            hole = match (l_pt, r_pt) {
                (Some(a), Some(b)) if b.x != a.x => {
                    let fr = (xn - a.x) / (b.x - a.x);
                    Some([
                        a.eq.hole[0] + (b.eq.hole[0] - a.eq.hole[0]) * fr,
                        a.eq.hole[1] + (b.eq.hole[1] - a.eq.hole[1]) * fr,
                    ])
                }
                _ => last.or(l_pt).map(|z| z.eq.hole).or(hole),
            };
            x = xn;
        }
        Err(Error::NotConverged { iterations: *iters, residual: f64::INFINITY })
    }

    /// Joint `joint` held at θ* with compliances `c` (thickness t): the tension, by a root in P
    /// from the straight joint at P = 0. `hint`: a first tension and hole to try.
    fn hold_tension(
        &mut self,
        joint: usize,
        theta: R,
        c: &[Mat3<R>; MAX_SUB],
        t: R,
        s_lin: R,
        hint: Option<(R, [R; 2])>,
        jac_hint: Option<Mat3<R>>,
    ) -> Result<Held<R>, Error> {
        if !(theta > R::zero()) {
            // the straight joint (θ* = 0) at P = 0; a negative angle is refused by the caller
            return Ok(Held { tension: R::zero(), thickness: t, eq: self.straight(), slope: s_lin, jac: None });
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
            let (q, n) = self.broyden(&mut ev, [b0[0], b0[1], x0], scale, jac, fd, theta);
            self.iters += n;
            if let Some(q) = q {
                let slope = Self::slope_of(&q.jac);
                if q.x[2] > R::zero() && slope > R::zero() && slope.is_finite() {
                    return Ok(Held { tension: q.x[2], thickness: t, eq: q.eq, slope, jac: Some(q.jac) });
                }
            }
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
        Ok(Held { tension: pt.x, thickness: t, eq: pt.eq, slope: s, jac: None })
    }

    /// Joint held at θ* under tension `pt`: the stack thickness in [t_top, t0], by a root in t.
    #[inline(never)]
    fn hold_thickness(&mut self, joint: usize, theta: R, pt: R, lo: &Held<R>, hi: &Held<R>) -> Result<Held<R>, Error> {
        let (t_top, t0) = (lo.thickness, hi.thickness);
        if pt == lo.tension {
            return Ok(*lo);
        }
        if pt == hi.tension {
            return Ok(*hi);
        }
        let span = hi.tension - lo.tension;
        let frac = if span != R::zero() { ((pt - lo.tension) / span).max(R::zero()).min(R::one()) } else { R::one() };
        let x0 = t_top + (t0 - t_top) * frac;
        let guess = [
            lo.eq.hole[0] + (hi.eq.hole[0] - lo.eq.hole[0]) * frac,
            lo.eq.hole[1] + (hi.eq.hole[1] - lo.eq.hole[1]) * frac,
        ];
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
            let mut ev = |x: [R; 3], q: &mut [[R; 3]; MAX_SUB]| {
                if !(x[2] > R::zero()) {
                    return Err(Error::Input { input: "thickness", reason: "trial below zero" });
                }
                me.comp_into(x[2], &mut c)?;
                me.f.joint_march(joint, &c, pt, [x[0], x[1]], q)
            };
            let (q, n) = self.broyden(&mut ev, [guess[0], guess[1], x0], [lh, lh, t0], jac, fd, theta);
            self.iters += n;
            if let Some(q) = q {
                // inside the stack's range (a root outside it is the bracket's to refuse)
                let slack = R::from_f64(1e-6) * t0;
                if q.x[2] >= t_top - slack && q.x[2] <= t0 + slack {
                    return Ok(Held { tension: pt, thickness: q.x[2], eq: q.eq, slope: hi.slope, jac: Some(q.jac) });
                }
            }
        }
        let me: &Self = self;
        let mut ev = |x: R, g: Option<[R; 2]>| f_eval(me, joint, x, pt, g);
        let mut it = 0;
        let res = self.root(&mut it, theta, sign, &mut ev, t_top, Some(t0), None, x0, Some(guess), slope, false);
        self.iters += it;
        let (p1, _) = res?;
        Ok(Held { tension: pt, thickness: p1.x, eq: p1.eq, slope: hi.slope, jac: None })
    }

    /// The joint's effective compliance θ/M (M the cable's moment about the hinge's distal
    /// end) when held with tension P in state `eq`, or its linear limit when P M vanishes.
    fn compliance(&self, theta: R, p: R, eq: &JointEquilibrium<R>, c_lin: R) -> f64 {
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
            return (theta / m).to_f64();
        }
        if theta < R::zero() {
            -c_lin.to_f64()
        } else {
            c_lin.to_f64()
        }
    }
}

/// A converged quasi-Newton solve: the unknowns x = (b0, b1, s), the state, and the last
/// Jacobian of F in the unknowns x (reused as the next solve's first Jacobian).
#[derive(Clone, Copy)]
struct Qn<R> {
    x: [R; 3],
    eq: JointEquilibrium<R>,
    jac: Mat3<R>,
}

impl<'a, R: Real> Gen<'a, R> {
    /// The hole of a joint bent to θ as a circular arc (the first guess of a quasi-Newton
    /// solve): hinge end (L_h sin θ/θ, L_h (1 - cos θ)/θ), link k's proximal hole e above it.
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
    fn broyden(&self, ev: &mut dyn FnMut([R; 3], &mut [[R; 3]; MAX_SUB]) -> Result<JointMarch<R>, Error>, x0: [R; 3], scale: [R; 3], jac_x: Mat3<R>, fd: [bool; 3], theta: R) -> (Option<Qn<R>>, u32) {
        let mut evals = 0u32;
        let mut ev = |x: [R; 3], q: &mut [[R; 3]; MAX_SUB]| {
            evals += 1;
            ev(x, q)
        };
        let r = self.broyden_steps(&mut ev, x0, scale, jac_x, fd, theta);
        let r = r.map(|mut q| {
            q.eq.iterations = evals;
            q
        });
        (r, evals)
    }

    #[allow(clippy::too_many_arguments)]
    #[inline(never)]
    fn broyden_steps<F>(&self, ev: &mut F, x0: [R; 3], scale: [R; 3], jac_x: Mat3<R>, fd: [bool; 3], theta: R) -> Option<Qn<R>>
    where
        F: FnMut([R; 3], &mut [[R; 3]; MAX_SUB]) -> Result<JointMarch<R>, Error>,
    {
        let atol = self.tol_angle * (theta.abs() + R::from_f64(0.1));
        let htol = self.tol_hole.max(self.f.hole_resolution());
        let resid = |x: &[R; 3], st: &JointMarch<R>| [x[0] - st.hole[0], x[1] - st.hole[1], st.angle - theta];
        // the sub-element displacements of the current and the trial march, swapped by index
        let mut qs = [[[R::zero(); 3]; MAX_SUB]; 2];
        let mut cur = 0usize;
        let mut x = x0;
        let mut st = ev(x, &mut qs[0]).ok()?;
        let mut fx = resid(&x, &st);
        let done = |x: [R; 3], st: &JointMarch<R>, q: &[[R; 3]; MAX_SUB], j: &Mat3<R>| {
            let mut jx = *j;
            for row in 0..3 {
                for col in 0..3 {
                    jx[row][col] = j[row][col] / scale[col];
                }
            }
            let eq = JointEquilibrium { q: *q, end: st.end, hole: st.hole, link: st.link, angle: st.angle, iterations: 0 };
            Qn { x, eq, jac: jx }
        };
        // the Jacobian in the scaled unknowns; columns marked `fd` by forward differences
        let mut j = jac_x;
        for col in 0..3 {
            if fd[col] {
                let h = R::from_f64(R::SQRT_EPS);
                let mut xp = x;
                xp[col] += h * scale[col];
                let sp = ev(xp, &mut qs[1]).ok()?;
                let fp = resid(&xp, &sp);
                for row in 0..3 {
                    j[row][col] = (fp[row] - fx[row]) / h;
                }
            } else {
                for row in 0..3 {
                    j[row][col] = jac_x[row][col] * scale[col];
                }
            }
        }
        let converged = |f: &[R; 3], k: R| f[0].abs() <= k * htol && f[1].abs() <= k * htol && f[2].abs() <= k * atol;
        for _ in 0..16 {
            if converged(&fx, R::one()) {
                return Some(done(x, &st, &qs[cur], &j));
            }
            let inv = mat3::inverse_unscaled(&j)?;
            let dy = mat3::mul_vec(&inv, &fx);
            let dy = [-dy[0], -dy[1], -dy[2]];
            let xn = [x[0] + dy[0] * scale[0], x[1] + dy[1] * scale[1], x[2] + dy[2] * scale[2]];
            // a step below the scalar's resolution: converged as far as it can be
            let tiny = (0..3).all(|i| (xn[i] - x[i]).abs() <= R::from_f64(4.0 * R::EPS) * x[i].abs().max(scale[i]));
            let sn = ev(xn, &mut qs[1 - cur]).ok()?;
            let fnew = resid(&xn, &sn);
            if !(fnew[0].is_finite() && fnew[1].is_finite() && fnew[2].is_finite()) {
                return None;
            }
            // J += (Δf - J Δy) Δyᵀ / |Δy|²
            let dy2 = dy[0] * dy[0] + dy[1] * dy[1] + dy[2] * dy[2];
            if dy2 > R::zero() {
                let jdy = mat3::mul_vec(&j, &dy);
                for row in 0..3 {
                    let u = (fnew[row] - fx[row] - jdy[row]) / dy2;
                    for col in 0..3 {
                        j[row][col] += u * dy[col];
                    }
                }
            }
            x = xn;
            st = sn;
            fx = fnew;
            cur = 1 - cur;
            if tiny {
                return if converged(&fx, R::from_f64(16.0)) { Some(done(x, &st, &qs[cur], &j)) } else { None };
            }
        }
        None
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

/// The joint's equilibrium at tension `p` with the stack at thickness `t`.
fn f_eval<R: Real>(g: &Gen<'_, R>, joint: usize, t: R, p: R, guess: Option<[R; 2]>) -> Result<JointEquilibrium<R>, Error> {
    let c = g.comp(t)?;
    g.f.joint_equilibrium(joint, &c, p, guess, g.tol_hole)
}

fn record<R: Real>(out: &mut PoseSolution<R>, k: usize, lh: R, h: &Held<R>) {
    let eq = &h.eq;
    out.q[k] = [eq.end.x - lh, eq.end.y, eq.end.theta];
    out.sub_q[k] = eq.q;
    out.links[k] = eq.link;
}

/// `solve_pose_with` for m > 1 or flexible links (module documentation).
#[inline(never)]
pub(super) fn solve<R: Real>(
    f: &Finger<R>,
    angles: &[R],
    tension: Option<R>,
    opts: &Options<R>,
    mut out: PoseSolution<R>,
) -> Result<PoseSolution<R>, Error> {
    let mut g = Gen::new(f, opts)?;
    let p = f.params();
    let n = p.n;
    let lh = p.hinge_len();
    if p.layers == 0 {
        return no_stacks(&mut g, angles, tension, opts, out);
    }
    // 1. every joint's tension range: stiffest stack (0 V) and softest (top voltage)
    let t0 = R::from_u32(p.layers as u32) * p.z0;
    let v_top = f.voltage_ceiling() * opts.top;
    let t_top = if v_top > R::zero() { de::stack_thickness(p, 1, v_top)? } else { t0 };
    let c0 = g.comp(t0)?;
    let c_top = g.comp(t_top)?;
    let (s0, s_top) = (g.slope0(&c0), g.slope0(&c_top));
    let straight = Held { tension: R::zero(), thickness: t0, eq: g.straight(), slope: s0, jac: None };
    let mut hi = [straight; MAX_JOINTS];
    let mut lo = [straight; MAX_JOINTS];
    for k in 0..n {
        if k > 0 && angles[k] == angles[k - 1] {
            hi[k] = hi[k - 1];
            lo[k] = lo[k - 1];
            continue;
        }
        // first trial: the previous joint's chord θ/P (the same nonlinearity at a similar angle)
        let hint = (0..k)
            .rev()
            .find(|&j| hi[j].tension > R::zero())
            .map(|j| (angles[k] * hi[j].tension / angles[j], hi[j].eq.hole));
        // the previous joint's Jacobian (a similar state) spares the first forward differences
        let jac = (0..k).rev().find_map(|j| hi[j].jac);
        hi[k] = g.hold_tension(k + 1, angles[k], &c0, t0, s0, hint, jac)?;
        let hint = Some((hi[k].tension * s0 / s_top, hi[k].eq.hole));
        lo[k] = g.hold_tension(k + 1, angles[k], &c_top, t_top, s_top, hint, hi[k].jac)?;
    }
    // 2-3. the feasible interval and the tension (`choose_tension`); a negative angle is
    //      outside every tension's reach
    let negative = (0..n).filter(|&k| angles[k] < R::zero()).min_by(|&a, &b| {
        angles[a].partial_cmp(&angles[b]).unwrap_or(core::cmp::Ordering::Equal)
    });
    let mut ends = [[R::zero(); 2]; MAX_JOINTS];
    for k in 0..n {
        ends[k] = [lo[k].tension, hi[k].tension];
    }
    let (interval, pt, worst) = choose_tension(&ends[..n], tension, negative, g.rel);
    out.interval = interval;
    if let Some(k) = worst {
        let (cl0, cl_top) = (s0 / p.e, s_top / p.e);
        // the range the ceiling allows, whichever end is the more compliant
        let (c_hi, c_lo) = (g.compliance(angles[k], hi[k].tension, &hi[k].eq, cl0), g.compliance(angles[k], lo[k].tension, &lo[k].eq, cl_top));
        return Err(Error::Unreachable {
            joint: k + 1,
            needed: g.compliance(angles[k], pt, &hi[k].eq, cl0),
            min: if c_hi <= c_lo { c_hi } else { c_lo },
            max: if c_hi <= c_lo { c_lo } else { c_hi },
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
        let held = if pt == R::zero() {
            straight
        } else if t0 - t_top <= g.rel * t0 {
            hi[k]
        } else {
            g.hold_thickness(k + 1, angles[k], pt, &lo[k], &hi[k])?
        };
        let t = held.thickness.max(t_top).min(t0);
        out.thickness[k] = t;
        out.volts[k] = if t >= t0 { R::zero() } else { de::voltage_for_thickness(p, k + 1, t)?.min(v_top) };
        record(&mut out, k, lh, &held);
    }
    out.iterations = g.iters;
    Ok(out)
}

/// The finger without stacks: only the tension is free (the parent's rule).
#[inline(never)]
fn no_stacks<R: Real>(
    g: &mut Gen<'_, R>,
    angles: &[R],
    tension: Option<R>,
    opts: &Options<R>,
    mut out: PoseSolution<R>,
) -> Result<PoseSolution<R>, Error> {
    let n = out.n;
    let z = R::zero();
    let lh = g.p.hinge_len();
    let c = g.comp(z)?;
    let s_lin = g.slope0(&c);
    let mut h = [Held { tension: z, thickness: z, eq: g.straight(), slope: s_lin, jac: None }; MAX_JOINTS];
    for k in 0..n {
        if angles[k] < z {
            let cl = s_lin / g.p.e;
            return Err(Error::Unreachable { joint: k + 1, needed: -cl.to_f64(), min: cl.to_f64(), max: cl.to_f64() });
        }
        if k > 0 && angles[k] == angles[k - 1] {
            h[k] = h[k - 1];
        } else {
            let hint = (0..k)
                .rev()
                .find(|&j| h[j].tension > z)
                .map(|j| (angles[k] * h[j].tension / angles[j], h[j].eq.hole));
            let jac = (0..k).rev().find_map(|j| h[j].jac);
            h[k] = g.hold_tension(k + 1, angles[k], &c, z, s_lin, hint, jac)?;
        }
        record(&mut out, k, lh, &h[k]);
    }
    // the tensions within the tolerance for every joint (dP/dθ = 1/slope)
    let tol = opts.angle_tol;
    let dp = |k: usize| R::one() / h[k].slope;
    let mut lo = h[0].tension - tol * dp(0);
    let mut hi = h[0].tension + tol * dp(0);
    for k in 1..n {
        lo = lo.max(h[k].tension - tol * dp(k));
        hi = hi.min(h[k].tension + tol * dp(k));
    }
    out.interval = [lo.max(z), hi.max(z)];
    let pt = match tension {
        Some(t) => t,
        None => {
            let mut best = (h[0].tension, R::from_f64(-1.0));
            for i in 0..n {
                for j in i + 1..n {
                    let (wi, wj) = (h[i].slope, h[j].slope);
                    let e = wi * wj * (h[i].tension - h[j].tension).abs() / (wi + wj);
                    if e > best.1 {
                        best = ((wi * h[i].tension + wj * h[j].tension) / (wi + wj), e);
                    }
                }
            }
            best.0.max(z)
        }
    };
    let mut worst: Option<(usize, R)> = None;
    for k in 0..n {
        let err = (pt - h[k].tension).abs() * h[k].slope;
        if err > tol * R::from_f64(1.001) && worst.map_or(true, |(_, w)| err > w) {
            worst = Some((k, err));
        }
    }
    if let Some((k, _)) = worst {
        let cl = s_lin / g.p.e;
        let have = g.compliance(angles[k], h[k].tension, &h[k].eq, cl);
        return Err(Error::Unreachable {
            joint: k + 1,
            needed: g.compliance(angles[k], pt, &h[k].eq, cl),
            min: have,
            max: have,
        });
    }
    out.tension = pt;
    // the states at the chosen tension (the posture the forward model gives there)
    if pt > z {
        for k in 0..n {
            if k > 0 && angles[k] == angles[k - 1] {
                out.q[k] = out.q[k - 1];
                out.sub_q[k] = out.sub_q[k - 1];
                out.links[k] = out.links[k - 1];
                continue;
            }
            let eq = g.f.joint_equilibrium(k + 1, &c, pt, Some(h[k].eq.hole), g.tol_hole)?;
            g.iters += eq.iterations;
            record(&mut out, k, lh, &Held { eq, ..h[k] });
        }
    }
    out.iterations = g.iters;
    Ok(out)
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
        let (q, n) = g.broyden(&mut ev, [b0[0], b0[1], p_lin], [lh, lh, p_lin], mat3::zero(), [true; 3], theta);
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
        let (r, _) = g.broyden(&mut ev, [q.x[0], q.x[1], t0 * 0.995], [lh, lh, t0], q.jac, [false, false, true], theta);
        let r = r.expect("Broyden converges for the thickness");
        assert!(r.x[2] < t0);
        let eq = f.joint_equilibrium(1, &g.comp(r.x[2]).unwrap(), pt, None, 1e-12).unwrap();
        assert!((eq.angle - theta).abs() < 1e-10, "{} vs {theta}", eq.angle);
    }
}
