//! The m = 1 rigid-link fast path of the inverse (docs/inverse.md "Module notes: the m = 1 fast
//! path"): each joint held at its target angle by closed Newton solves of `K q - P ŵ(q) = 0`,
//! for the tension at a thickness and for the thickness at a tension. What it is not: the
//! general path (`general`, any m and flexible links) or the steps both share (`inverse`).

use super::{choose_tension, one_tension, thickness_slack, Options, PoseSolution};
use crate::de;
use crate::error::Error;
use crate::finger::{Finger, JointStiffness};
use crate::mat3::{self, Mat3};
use crate::params::{Params, MAX_JOINTS};
use crate::real::Real;
use crate::solve::{newton, Failure};

/// One joint held at its angle: the Newton result.
#[derive(Clone, Copy, Debug)]
struct Hold<R> {
    delta: [R; 2],
    tension: R,
    thickness: R,
    /// Moment per newton of tension at the solution, N·mm/N.
    wm: R,
    /// dP/dθ at fixed t (only from `hold_tension`), N/rad.
    dp_dtheta: R,
    iters: u32,
}

/// What the solver needs of the finger, prepared once per solve.
struct Ctx<'a, R> {
    f: &'a Finger<R>,
    p: &'a Params<R>,
    stack: de::StackStiffness<R>,
    lh: R,
    max_iter: u32,
    rel: R,
}

/// The joint's target angle with its sine and cosine.
#[derive(Clone, Copy)]
struct Angle<R> {
    theta: R,
    s: R,
    c: R,
}

/// ŵ, its derivatives by δax, δtr, θ (columns), and the span length.
struct Wrench<R> {
    w: [R; 3],
    d: [[R; 3]; 3],
}

impl<'a, R: Real> Ctx<'a, R> {
    fn new(f: &'a Finger<R>, opts: &Options<R>) -> Result<Self, Error> {
        let p = f.params();
        let rel = R::from_f64(1e-11_f64.max(64.0 * R::EPS));
        Ok(Ctx { f, p, stack: f.stack(), lh: p.hinge_len(), max_iter: opts.max_iter.max(1), rel })
    }

    /// The joint's stiffness K(t) = K_hinge + K_de(t) and dK/dt (`Finger::joint_stiffness`; m = 1:
    /// its one sub-element; K_hinge alone without stacks).
    fn stiffness(&self, t: R) -> JointStiffness<'a, R> {
        JointStiffness::new(self.f, &self.stack, t)
    }

    /// ŵ at (δax, δtr, θ) and its derivatives. v = B - A (A = (0, e) the hole at node k-1,
    /// B = D + e (-sin θ, cos θ) link k's proximal hole, D = (L_h + δax, δtr) the hinge's
    /// distal end); the force per newton is f = -v/|v|, the moment about D is
    /// M = (B - D) × f = -e (sin θ f_y + cos θ f_x).
    fn wrench(&self, ang: &Angle<R>, d: [R; 2], joint: usize, tension: R) -> Result<Wrench<R>, Error> {
        let e = self.p.e;
        let v = [self.lh + d[0] - e * ang.s, d[1] + e * ang.c - e];
        let rho = (v[0] * v[0] + v[1] * v[1]).sqrt();
        if !(rho >= self.p.span_floor) {
            return Err(Error::Contact { joint, tension: tension.to_f64() });
        }
        let u = [v[0] / rho, v[1] / rho];
        let f = [-u[0], -u[1]];
        let m = -e * (ang.s * f[1] + ang.c * f[0]);
        // df/dv = -(I - u uᵀ)/rho
        let j00 = -(R::one() - u[0] * u[0]) / rho;
        let j01 = u[0] * u[1] / rho;
        let j11 = -(R::one() - u[1] * u[1]) / rho;
        let dmdf = |df0: R, df1: R| -e * (ang.s * df1 + ang.c * df0);
        // by δax (v0), δtr (v1)
        let col0 = [j00, j01, dmdf(j00, j01)];
        let col1 = [j01, j11, dmdf(j01, j11)];
        // by θ: dv/dθ = e (-cos θ, -sin θ), plus the explicit dependence of M on θ
        let dv = [-e * ang.c, -e * ang.s];
        let df = [j00 * dv[0] + j01 * dv[1], j01 * dv[0] + j11 * dv[1]];
        let col2 = [df[0], df[1], -e * (ang.c * f[1] - ang.s * f[0]) + dmdf(df[0], df[1])];
        Ok(Wrench { w: [f[0], f[1], m], d: [col0, col1, col2] })
    }

    /// Joint `joint` (1-based) held at `ang` with stack thickness t: Newton on (δax, δtr, P) of
    /// `K q - P ŵ(q) = 0` (`solve::newton::full_steps`). Also the implicit dP/dθ at fixed t.
    /// Not the march's `SubElement`: with θ given and P (or t) unknown the residual is solved for
    /// the load, where the march solves q for a given load; K is the same `JointStiffness`.
    fn hold_tension(&self, joint: usize, ang: &Angle<R>, t: R, guess: [R; 2]) -> Result<Hold<R>, Error> {
        let k = self.stiffness(t).matrix(0);
        // first tension from the moment row with the guessed δ
        let w0 = self.wrench(ang, guess, joint, R::zero())?;
        let p0 = (k[2][0] * guess[0] + k[2][1] * guess[1] + k[2][2] * ang.theta) / w0.w[2];
        let mut eq = HoldTension { ctx: self, joint, ang, k, w: w0 };
        let mut x = [guess[0], guess[1], p0];
        let (c, inv) = newton::full_steps(&mut eq, &mut x, self.max_iter).map_err(|e| match e {
            Failure::Singular { .. } => Error::LimitPoint { joint, tension: x[2].to_f64() },
            e => hold_error(e),
        })?;
        let (p, w) = (x[2], &eq.w);
        // implicit derivative: J (dδ, dP) = -(K[:,2] - P dŵ/dθ)
        let rhs = [-(k[0][2] - p * w.d[2][0]), -(k[1][2] - p * w.d[2][1]), -(k[2][2] - p * w.d[2][2])];
        let dp = newton::mul_vec(&inv, &rhs)[2];
        Ok(Hold { delta: [x[0], x[1]], tension: p, thickness: t, wm: w.w[2], dp_dtheta: dp, iters: c.iterations })
    }

    /// Joint held at `ang` under tension P: Newton on (δax, δtr, t) of `K(t) q - P ŵ(q) = 0`
    /// (`solve::newton::full_steps`).
    fn hold_thickness(&self, joint: usize, ang: &Angle<R>, p: R, guess: Hold<R>) -> Result<Hold<R>, Error> {
        let w0 = Wrench { w: [R::zero(); 3], d: [[R::zero(); 3]; 3] };
        let mut eq = HoldThickness { ctx: self, joint, ang, p, w: w0, slack: R::one() };
        let mut x = [guess.delta[0], guess.delta[1], guess.thickness];
        let mut r = newton::full_steps(&mut eq, &mut x, self.max_iter);
        if let Err(Failure::MaxIter { .. }) = r {
            // At a low tension the stack's thickness moves the joint little: in f32 the steps
            // can wander at the residual's rounding above `rel`. Once more from there, the
            // steps' tolerance 64 x looser (a thickness error that moves the joint by less).
            eq.slack = R::from_f64(64.0);
            r = newton::full_steps(&mut eq, &mut x, self.max_iter);
        }
        let (c, _) = r.map_err(|e| match e {
            Failure::Singular { .. } => Error::Singular { what: "inverse joint Jacobian" },
            e => hold_error(e),
        })?;
        Ok(Hold { delta: [x[0], x[1]], tension: p, thickness: x[2], wm: eq.w.w[2], dp_dtheta: R::zero(), iters: c.iterations })
    }

    /// The joint's effective compliance θ/M at its target posture when held with tension P
    /// (moment per newton `wm`), or its linear limit (C(t) ŵ)_θ / ŵ_M when P M vanishes.
    fn compliance(&self, ang: &Angle<R>, p: R, wm: R, t: R) -> f64 {
        let m = p * wm;
        if m.abs() > R::from_f64(1e-30_f64.max(R::EPS * 1e-20)) {
            return (ang.theta / m).to_f64();
        }
        let Ok(c) = self.stiffness(t).compliance(0) else { return 0.0 };
        let Ok(w) = self.wrench(ang, [R::zero(); 2], 0, R::zero()) else { return 0.0 };
        let cw = mat3::mul_vec(&c, &w.w);
        (cw[2] / w.w[2]).to_f64()
    }
}

/// `K q - P ŵ(q) = 0` in (δax, δtr, P) at a fixed stiffness K; `w` the last wrench evaluated.
struct HoldTension<'c, 'a, R> {
    ctx: &'c Ctx<'a, R>,
    joint: usize,
    ang: &'c Angle<R>,
    k: Mat3<R>,
    w: Wrench<R>,
}

impl<R: Real> newton::Linearized<R, 3> for HoldTension<'_, '_, R> {
    type Refusal = Error;
    #[inline]
    fn linearize(&mut self, x: &[R; 3]) -> Result<([R; 3], Mat3<R>), Error> {
        let (k, p) = (&self.k, x[2]);
        self.w = self.ctx.wrench(self.ang, [x[0], x[1]], self.joint, p)?;
        let w = &self.w;
        let mut r = [R::zero(); 3];
        let mut jm: Mat3<R> = mat3::zero();
        for row in 0..3 {
            r[row] = k[row][0] * x[0] + k[row][1] * x[1] + k[row][2] * self.ang.theta - p * w.w[row];
            jm[row][0] = k[row][0] - p * w.d[0][row];
            jm[row][1] = k[row][1] - p * w.d[1][row];
            jm[row][2] = -w.w[row];
        }
        Ok((r, jm))
    }
    #[inline]
    fn step_converged(&self, x: &[R; 3], dx: &[R; 3]) -> bool {
        let (rel, tol_len) = (self.ctx.rel, self.ctx.rel * self.ctx.lh);
        dx[0].abs() <= tol_len && dx[1].abs() <= tol_len && dx[2].abs() <= rel * (x[2].abs() + rel)
    }
}

/// `K(t) q - P ŵ(q) = 0` in (δax, δtr, t) at a fixed tension P; `w` the last wrench evaluated.
struct HoldThickness<'c, 'a, R> {
    ctx: &'c Ctx<'a, R>,
    joint: usize,
    ang: &'c Angle<R>,
    p: R,
    w: Wrench<R>,
    /// The steps' tolerance in units of `rel` (1; 64 on the retry).
    slack: R,
}

impl<R: Real> newton::Linearized<R, 3> for HoldThickness<'_, '_, R> {
    type Refusal = Error;
    #[inline]
    fn linearize(&mut self, x: &[R; 3]) -> Result<([R; 3], Mat3<R>), Error> {
        let (ctx, p) = (self.ctx, self.p);
        let kj = ctx.stiffness(x[2]);
        let (k, kd) = (kj.matrix(0), kj.dt(&ctx.stack));
        self.w = ctx.wrench(self.ang, [x[0], x[1]], self.joint, p)?;
        let w = &self.w;
        let q = [x[0], x[1], self.ang.theta];
        let kq = mat3::mul_vec(&k, &q);
        let kdq = mat3::mul_vec(&kd, &q);
        let mut r = [R::zero(); 3];
        let mut jm: Mat3<R> = mat3::zero();
        for row in 0..3 {
            r[row] = kq[row] - p * w.w[row];
            jm[row][0] = k[row][0] - p * w.d[0][row];
            jm[row][1] = k[row][1] - p * w.d[1][row];
            jm[row][2] = kdq[row];
        }
        Ok((r, jm))
    }
    #[inline]
    fn step_converged(&self, x: &[R; 3], dx: &[R; 3]) -> bool {
        let rel = self.ctx.rel * self.slack;
        let tol_len = rel * self.ctx.lh;
        dx[0].abs() <= tol_len && dx[1].abs() <= tol_len && dx[2].abs() <= rel * x[2]
    }
    #[inline]
    fn admissible(&self, x: &[R; 3]) -> bool {
        x.iter().all(|v| v.is_finite()) && x[2] > R::zero()
    }
}

/// A joint hold's failure as the model's error (the wrench's refusal as it is).
fn hold_error(e: Failure<Error>) -> Error {
    match e {
        Failure::Domain(e) | Failure::Stalled { last: Some(e), .. } => e,
        Failure::Singular { iterations } => Error::NotConverged { iterations, residual: f64::INFINITY },
        Failure::Stalled { iterations, .. } | Failure::MaxIter { iterations, .. } => Error::NotConverged { iterations, residual: f64::INFINITY },
    }
}

/// The m = 1, rigid-link solve (docs/inverse.md "Module notes: the m = 1 fast path"): each
/// joint held at its angle by Newton, with stacks (`with_stacks`) or without (`no_stacks`).
pub(super) fn solve<R: Real>(f: &Finger<R>, angles: &[R], tension: Option<R>, opts: &Options<R>, out: PoseSolution<R>) -> Result<PoseSolution<R>, Error> {
    let n = out.n;
    let ctx = Ctx::new(f, opts)?;
    let mut ang = [Angle { theta: R::zero(), s: R::zero(), c: R::one() }; MAX_JOINTS];
    for k in 0..n {
        let (s, c) = crate::finger::turn(angles[k]);
        ang[k] = Angle { theta: angles[k], s, c };
    }
    let out = if f.params().layers == 0 { no_stacks(&ctx, &ang, tension, opts, out)? } else { with_stacks(&ctx, &ang, tension, opts, out)? };
    // a posture held only by a pushing cable is no answer (a cable cannot push)
    if !(out.tension >= R::zero()) {
        return Err(Error::Input { input: "angles", reason: "the posture needs a pushing cable (tension < 0)" });
    }
    Ok(fill_sub(out))
}

/// The m = 1 fast path: the sub-element q is the hinge's q.
fn fill_sub<R: Real>(mut out: PoseSolution<R>) -> PoseSolution<R> {
    for k in 0..out.n {
        out.sub_q[k][0] = out.q[k];
    }
    out
}

/// The m = 1, rigid-link solve with stacks (docs/inverse.md "Module notes: the m = 1 fast path", steps 1-4).
fn with_stacks<R: Real>(
    ctx: &Ctx<'_, R>,
    ang: &[Angle<R>; MAX_JOINTS],
    tension: Option<R>,
    opts: &Options<R>,
    mut out: PoseSolution<R>,
) -> Result<PoseSolution<R>, Error> {
    let p = ctx.p;
    let n = out.n;

    // 1. every joint's tension range: stiffest stack (0 V) and softest (top voltage)
    let t0 = R::from_u32(p.layers) * p.z0;
    let v_top = ctx.f.ceiling_in_force(opts.hv_fs) * opts.top;
    let t_top = if v_top > R::zero() { de::stack_thickness(p, 1, v_top)? } else { t0 };
    let mut hi = [ctx.hold_tension(1, &ang[0], t0, [R::zero(); 2])?; MAX_JOINTS];
    let mut lo = hi;
    for k in 0..n {
        // a joint at the same angle as the one before holds it the same way (no work)
        if k > 0 && ang[k].theta == ang[k - 1].theta {
            hi[k] = hi[k - 1];
            lo[k] = lo[k - 1];
            continue;
        }
        if k > 0 {
            // first guess: the previous joint's deflection scaled by the angle ratio
            let g = if ang[k - 1].theta != R::zero() { ang[k].theta / ang[k - 1].theta } else { R::zero() };
            let guess = [hi[k - 1].delta[0] * g, hi[k - 1].delta[1] * g];
            hi[k] = ctx.hold_tension(k + 1, &ang[k], t0, guess)?;
        }
        lo[k] = ctx.hold_tension(k + 1, &ang[k], t_top, hi[k].delta)?;
        out.iterations += hi[k].iters + lo[k].iters;
        for h in [&hi[k], &lo[k]] {
            if !(h.dp_dtheta > R::zero()) && ang[k].theta != R::zero() {
                return Err(Error::LimitPoint { joint: k + 1, tension: h.tension.to_f64() });
            }
        }
    }
    // 2-3. the feasible interval and the tension (`choose_tension`)
    let mut ends = [[R::zero(); 2]; MAX_JOINTS];
    for k in 0..n {
        ends[k] = [lo[k].tension, hi[k].tension];
    }
    let (interval, pt, worst) = choose_tension(&ends[..n], tension, None, ctx.rel);
    out.interval = interval;
    if let Some(k) = worst {
        // the range the ceiling allows, whichever end is the more compliant
        let (c_hi, c_lo) = (ctx.compliance(&ang[k], hi[k].tension, hi[k].wm, t0), ctx.compliance(&ang[k], lo[k].tension, lo[k].wm, t_top));
        return Err(Error::Unreachable { joint: k + 1, needed: ctx.compliance(&ang[k], pt, hi[k].wm, t0), min: c_hi.min(c_lo), max: c_hi.max(c_lo) });
    }
    out.tension = pt;
    // 4. every joint's thickness at that tension, then its voltage. At zero tension (every
    //    angle zero, or the check above refused it) any voltage holds the straight finger: 0 V.
    for k in 0..n {
        if pt == R::zero() {
            out.thickness[k] = t0;
            out.q[k] = [hi[k].delta[0], hi[k].delta[1], ang[k].theta];
            continue;
        }
        if k > 0 && ang[k].theta == ang[k - 1].theta {
            out.thickness[k] = out.thickness[k - 1];
            out.volts[k] = out.volts[k - 1];
            out.q[k] = out.q[k - 1];
            continue;
        }
        let span = hi[k].tension - lo[k].tension;
        let frac = if span != R::zero() { ((pt - lo[k].tension) / span).max(R::zero()).min(R::one()) } else { R::one() };
        let lerp = |a: R, b: R| a + (b - a) * frac;
        let guess = Hold { delta: [lerp(lo[k].delta[0], hi[k].delta[0]), lerp(lo[k].delta[1], hi[k].delta[1])], thickness: lerp(t_top, t0), ..hi[k] };
        let h = ctx.hold_thickness(k + 1, &ang[k], pt, guess)?;
        out.iterations += h.iters;
        // a thickness the stack cannot take (past either end of its range by more than
        // rounding): Newton found a root outside it, and the clamped thickness would not hold
        // the angle
        let slack = thickness_slack(t0);
        if !(h.thickness >= t_top - slack && h.thickness <= t0 + slack) {
            return Err(Error::NotConverged { iterations: out.iterations, residual: f64::INFINITY });
        }
        let t = h.thickness.max(t_top).min(t0);
        out.thickness[k] = t;
        out.volts[k] = if t >= t0 { R::zero() } else { de::voltage_for_thickness(p, k + 1, t)?.min(v_top) };
        out.q[k] = [h.delta[0], h.delta[1], ang[k].theta];
    }
    Ok(out)
}

/// The finger without stacks: only the tension is free.
fn no_stacks<R: Real>(
    ctx: &Ctx<'_, R>,
    ang: &[Angle<R>; MAX_JOINTS],
    tension: Option<R>,
    opts: &Options<R>,
    mut out: PoseSolution<R>,
) -> Result<PoseSolution<R>, Error> {
    let n = out.n;
    let z = R::zero();
    let mut h = [ctx.hold_tension(1, &ang[0], z, [z; 2])?; MAX_JOINTS];
    // weights dθ/dP
    let mut wt = [z; MAX_JOINTS];
    for k in 0..n {
        if k > 0 {
            h[k] = ctx.hold_tension(k + 1, &ang[k], z, [z; 2])?;
        }
        out.iterations += h[k].iters;
        if !(h[k].dp_dtheta > z) {
            return Err(Error::LimitPoint { joint: k + 1, tension: h[k].tension.to_f64() });
        }
        wt[k] = R::one() / h[k].dp_dtheta;
        out.q[k] = [h[k].delta[0], h[k].delta[1], ang[k].theta];
    }
    let mut tensions = [z; MAX_JOINTS];
    for k in 0..n {
        tensions[k] = h[k].tension;
    }
    let (interval, pt, worst) = one_tension(&tensions[..n], &wt[..n], tension, opts.angle_tol);
    out.interval = interval;
    if let Some(k) = worst {
        let c = ctx.compliance(&ang[k], h[k].tension, h[k].wm, z);
        return Err(Error::Unreachable { joint: k + 1, needed: ctx.compliance(&ang[k], pt, h[k].wm, z), min: c, max: c });
    }
    out.tension = pt;
    Ok(out)
}
