//! A joint held at its target angle (steps 1 and 4 of the inverse, docs/inverse.md): the
//! tension at a stack thickness (`hold_tension`) or the thickness at a tension
//! (`hold_thickness`), each by the quasi-Newton solve (`qn`) and, behind it (feature
//! `inverse-fallback`), a bracketed root on the warm-started forward equilibrium.

use super::*;

impl<'a, R: Real> Gen<'a, R> {
    /// Root of h(x) = sign (θ(x) - θ*), increasing in x, on [lo, hi] (hi = None: unbounded),
    /// on the solve layer's bracket (`solve::bracket::increasing_root`). `left`: a known point
    /// at lo; `x0`, `guess`: the first trial and its hole guess; `slope`: an estimate of dh/dx
    /// > 0. With `beyond_ok`, a forward failure (contact, limit point, no convergence) marks the
    /// >    trial as past the branch end, and a target past it is refused with that error. Each
    /// >    trial's hole guess is interpolated between the bracket's states, else the last state's.
    /// >    Returns the point and dh/dx there (secant estimate).
    #[allow(clippy::too_many_arguments)]
    #[inline(never)]
    pub(super) fn root(
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
        let opts = bracket::RootOptions { atol: self.angle_atol(theta), rel: self.rel, beyond_rel: R::from_f64(1e-6), max_iter: self.max_iter };
        let left = left.map(|p| bracket::Point { x: p.x, h: p.h, state: p.eq });
        let (mut hole, mut first) = (guess, true);
        let mut trial = |x: R, at: &bracket::Around<'_, R, JointEquilibrium<R>>| {
            if !first {
                hole = match (at.left, at.right) {
                    (Some(a), Some(b)) if b.x != a.x => {
                        let fr = (x - a.x) / (b.x - a.x);
                        Some([a.state.hole[0] + (b.state.hole[0] - a.state.hole[0]) * fr, a.state.hole[1] + (b.state.hole[1] - a.state.hole[1]) * fr])
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
                Err(e @ (Error::Contact { .. } | Error::LimitPoint { .. } | Error::NotConverged { .. })) if beyond_ok => Ok(bracket::Trial::Beyond(e)),
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
    pub(in crate::inverse) fn hold_tension(
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
        // the joint's own turn under its held load (the weight: docs/model.md "Gravity"), linear
        let theta_held = self.f.held_turn(joint.max(1) - 1, c);
        if !(theta > R::zero()) && theta_held == R::zero() {
            // the straight joint (θ* = 0) at P = 0; a negative angle is refused by the caller
            *q_out = [[R::zero(); 3]; MAX_SUB];
            return Ok(Held { tension: R::zero(), thickness: t, st: self.straight_st(), slope: s_lin, jac: None, exact: true });
        }
        if !(s_lin > R::zero() && s_lin.is_finite()) {
            return Err(Error::Singular { what: "joint compliance" });
        }
        let (x0, guess) = match hint {
            Some((p, h)) if p > R::zero() && p.is_finite() => (p, Some(h)),
            // past the held turn (a cable cannot push): the least tension the solve tries
            _ => (((theta - theta_held) / s_lin).max(R::from_f64(1e-3) * theta.abs() / s_lin), None),
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
                f.joint_march(joint, by::Compliance(c), x[2], [x[0], x[1]], q)
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
        // under a held load (the weight) the joint at P = 0 is not straight: where the load
        // alone bends it to θ* or past, no tension holds it there (a cable cannot push)
        if theta_held != R::zero() {
            let eq0 = f.joint_equilibrium(joint, c, R::zero(), None, self.tol_hole)?;
            self.iters += eq0.iterations;
            if eq0.angle >= theta {
                let cl = s_lin / self.p.e;
                return Err(Error::Unreachable { joint, needed: -cl.to_f64(), min: cl.to_f64(), max: cl.to_f64() });
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
        Ok(Held { tension: pt.x, thickness: t, st: JointMarch::of_equilibrium(&pt.eq), slope: s, jac: None, exact: true })
    }

    /// Joint held at θ* under tension `pt`: the stack thickness in [t_top, t0], by a root in t.
    /// `mid`: a third point (P, t, hole) of the joint held at θ* between the two, if known.
    /// The sub-element displacements go to `q_out`.
    #[inline(never)]
    #[allow(clippy::too_many_arguments)]
    pub(super) fn hold_thickness(
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
                me.f.joint_march(joint, by::Compliance(&c), pt, [x[0], x[1]], q)
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
        Ok(Held { tension: pt, thickness: p1.x, st: JointMarch::of_equilibrium(&p1.eq), slope: hi.slope, jac: None, exact: true })
    }
}

/// The first guess of a thickness solve at tension `pt` along the level curve θ(P, t) = θ*
/// through the joint's two ends `lo`, `hi` (tension, thickness, hole): linear between them, or
/// quadratic through a third point `mid` of it (the branch table's middle thickness), which
/// takes the guess inside the solve's tolerance for the default stacks. Returns (t, hole).
#[inline(always)]
pub(super) fn level_guess<R: Real>(lo: (R, R, [R; 2]), hi: (R, R, [R; 2]), mid: Option<(R, R, [R; 2])>, pt: R) -> (R, [R; 2]) {
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
pub(super) fn f_eval<R: Real>(g: &Gen<'_, R>, joint: usize, t: R, p: R, guess: Option<[R; 2]>) -> Result<JointEquilibrium<R>, Error> {
    let c = g.comp(t)?;
    g.f.joint_equilibrium(joint, &c, p, guess, g.tol_hole)
}
