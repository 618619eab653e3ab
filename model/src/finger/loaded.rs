//! The coupled equilibrium (docs/model.md "Equilibrium": an external tip load or the finger's
//! weight couples the joints): every guide hole, the tip and, under gravity, each joint's
//! distal centroid solved together by damped Newton under load continuation. Not the
//! tension-alone solve (`tension`).

use super::gravity::Weights;
use super::{Compliances, Finger, Heading, JointState, MarchError, COUPLED};
use crate::error::Error;
use crate::params::{MAX_JOINTS, MAX_SUB};
use crate::real::Real;
use crate::solve::continuation::{self, Step};
use crate::solve::newton::{self, Equations};
use crate::solve::SolveOptions;

/// The coupled residual (`coupled_residual`) for `solve::newton`, each slot's marched
/// joint states kept.
struct Coupled<'a, R> {
    f: &'a Finger<R>,
    c: &'a Compliances<R>,
    tension: R,
    force: [R; 2],
    /// The weight's share of its full value (the load continuation's factor).
    weight: R,
    /// The finger's weight (`Finger::weights`, once per solve).
    w: Option<Weights<R>>,
    /// Each slot's marched states and its evaluation (`Trace`: where a forward difference resumes).
    states: [[JointState<R>; MAX_JOINTS]; 3],
    traces: [Trace<R>; 3],
    /// The Jacobian estimate (kept where the caller keeps it: `CoupledStart`).
    est: &'a mut Estimate<R>,
}

/// The coupled system's Jacobian estimate: forward differences once, then Broyden's rank-one
/// update at each Newton iterate (and carried across the continuation's steps, tensions and
/// voltages: `carry`).
#[derive(Clone, Copy)]
pub(super) struct Estimate<R> {
    jac: [[R; COUPLED]; COUPLED],
    /// Whether `jac` holds an estimate; false: forward differences at the next call.
    formed: bool,
    /// The point (x, r) of this system `jac` was last formed or updated at (the next update's
    /// base); None: `jac` as it is at the next call.
    at: Option<([R; COUPLED], [R; COUPLED])>,
}

impl<R: Real> Estimate<R> {
    /// None yet: forward differences at the first call.
    pub(super) fn new() -> Self {
        Estimate { jac: [[R::zero(); COUPLED]; COUPLED], formed: false, at: None }
    }

    /// The system changes (another load factor, tension or compliances): the estimate is kept
    /// as it is, but its last point is not one of the new system's (a residual there would
    /// make the next update take the change of system for a slope).
    fn carry(&mut self) {
        self.at = None;
    }

    /// Forward differences at the next call.
    fn drop(&mut self) {
        (self.formed, self.at) = (false, None);
    }
}

impl<R: Real> Equations<R, COUPLED> for Coupled<'_, R> {
    type Refusal = MarchError;
    fn dim(&self) -> usize {
        coupled_dim(self.f) - if self.tipless() { 2 } else { 0 }
    }
    fn residual(&mut self, x: &[R; COUPLED], slot: usize) -> Result<[R; COUPLED], MarchError> {
        let full = self.unpack(x);
        let (t, st) = (&mut self.traces[slot], &mut self.states[slot]);
        let r = coupled_eval(self.f, self.c, self.tension, self.force, (self.w.as_ref(), self.weight), &full, (0, false), t, Some(st))?;
        Ok(self.pack(&r))
    }
    fn jacobian(&mut self, x: &[R; COUPLED], r: &[R; COUPLED], slot: usize) -> Result<[[R; COUPLED]; COUPLED], MarchError> {
        let mut jac = [[R::zero(); COUPLED]; COUPLED];
        self.jacobian_into(x, r, slot, &mut jac)?;
        Ok(jac)
    }
    fn jacobian_into(&mut self, x: &[R; COUPLED], r: &[R; COUPLED], slot: usize, out: &mut [[R; COUPLED]; COUPLED]) -> Result<(), MarchError> {
        let dim = self.dim();
        let est = &mut *self.est;
        match &est.at {
            // carried into this system: J as it is
            None if est.formed => {}
            // Broyden's good update from the last point: J += (Δr - J Δx) Δxᵀ / |Δx|²
            Some((x0, r0)) => broyden_rank_one(&mut est.jac, dim, x, r, x0, r0),
            None => {
                self.forward_difference(x, r, slot)?;
                self.est.formed = true;
            }
        }
        self.est.at = Some((*x, *r));
        // the leading block only: Newton factors it in place, the estimate stays here
        for (o, j) in out[..dim].iter_mut().zip(&self.est.jac[..dim]) {
            o[..dim].copy_from_slice(&j[..dim]);
        }
        Ok(())
    }
}

impl<R: Real> Coupled<'_, R> {
    /// Without a tip force the tip loads nothing: Newton's unknowns and residual leave it out
    /// (the holes, then the centroids; `pack`, `unpack`), and the answer's tip is the chain's.
    fn tipless(&self) -> bool {
        self.force == [R::zero(); 2]
    }

    /// The coupled unknowns (or residual) as Newton's: without the tip's two when `tipless`.
    fn pack(&self, v: &[R; COUPLED]) -> [R; COUPLED] {
        let n = self.f.p.n;
        if !self.tipless() {
            return *v;
        }
        core::array::from_fn(|i| if i < 2 * n { v[i] } else { v.get(i + 2).copied().unwrap_or(R::zero()) })
    }

    /// Newton's unknowns as the coupled ones (`pack`'s inverse; the tip 0: it loads nothing).
    fn unpack(&self, v: &[R; COUPLED]) -> [R; COUPLED] {
        let n = self.f.p.n;
        if !self.tipless() {
            return *v;
        }
        core::array::from_fn(|i| {
            if i < 2 * n {
                v[i]
            } else if i < 2 * n + 2 {
                R::zero()
            } else {
                v[i - 2]
            }
        })
    }

    /// Forward differences of the residual at Newton's `x` (evaluated into `slot`) into `jac`,
    /// each column's evaluation resumed where its unknown enters the chain (`enters_at`).
    fn forward_difference(&mut self, x: &[R; COUPLED], r: &[R; COUPLED], slot: usize) -> Result<(), MarchError> {
        let (n, dim) = (self.f.p.n, self.dim());
        let h = R::from_f64(R::SQRT_EPS) * (self.f.p.hinge_len() + self.f.p.e);
        let mut xp = self.unpack(x);
        // the evaluation each column resumes (copied once; a column's changes undone after it)
        let mut t = self.traces[slot];
        for i in 0..dim {
            // the unknown's index among the coupled ones
            let at = if self.tipless() && i >= 2 * n { i + 2 } else { i };
            let from = enters_at(n, at);
            let x_at = xp[at];
            xp[at] += h;
            let rp = coupled_eval(self.f, self.c, self.tension, self.force, (self.w.as_ref(), self.weight), &xp, from, &mut t, None);
            xp[at] = x_at;
            t.restore(&self.traces[slot], from.0, n);
            let rp = self.pack(&rp?);
            for row in 0..dim {
                self.est.jac[row][i] = (rp[row] - r[row]) / h;
            }
        }
        Ok(())
    }
}

/// Broyden's good update of `jac` (its leading `dim` block) from (x0, r0) to (x, r):
/// J += (Δr - J Δx) Δxᵀ / |Δx|² (none where x = x0).
fn broyden_rank_one<R: Real>(jac: &mut [[R; COUPLED]; COUPLED], dim: usize, x: &[R; COUPLED], r: &[R; COUPLED], x0: &[R; COUPLED], r0: &[R; COUPLED]) {
    let dx: [R; COUPLED] = core::array::from_fn(|i| x[i] - x0[i]);
    let dx2 = dx[..dim].iter().fold(R::zero(), |a, &v| a + v * v);
    if dx2 > R::zero() {
        for row in 0..dim {
            let jd = (0..dim).fold(R::zero(), |a, c| a + jac[row][c] * dx[c]);
            let u = (r[row] - r0[row] - jd) / dx2;
            for col in 0..dim {
                jac[row][col] += u * dx[col];
            }
        }
    }
}

/// [`broyden_rank_one`] on the whole coupled system (the pinned solve's).
pub(super) fn broyden_update<R: Real>(
    jac: &mut [[R; COUPLED]; COUPLED],
    f: &Finger<R>,
    x: &[R; COUPLED],
    r: &[R; COUPLED],
    x0: &[R; COUPLED],
    r0: &[R; COUPLED],
) {
    broyden_rank_one(jac, coupled_dim(f), x, r, x0, r0);
}

/// The coupled system's size: each joint's hole, the tip and, under gravity, each joint's
/// distal centroid.
pub(super) fn coupled_dim<R: Real>(f: &Finger<R>) -> usize {
    let n = f.p.n;
    2 * n + 2 + if f.p.has_gravity() { 2 * n } else { 0 }
}

/// The coupled system's start at the straight finger (holes, tip, centroids).
pub(super) fn straight_unknowns<R: Real>(f: &Finger<R>) -> [R; COUPLED] {
    let n = f.p.n;
    let mut x = [R::zero(); COUPLED];
    let mut states = [f.straight(); MAX_JOINTS];
    for k in 0..n {
        x[2 * k] = f.p.hinge_len();
        x[2 * k + 1] = f.p.e;
        states[k] = f.straight();
    }
    x[2 * n] = R::from_u32(n as u32) * f.p.l;
    f.put_centroids(&states, &mut x);
    x
}

impl<R: Real> Finger<R> {
    /// Under gravity, the distal centroids of the posture `states` give (rigid links: the
    /// coupled unknowns' start) into `x` after the holes and the tip.
    pub(super) fn put_centroids(&self, states: &[JointState<R>; MAX_JOINTS], x: &mut [R; COUPLED]) {
        let n = self.p.n;
        if let Some(w) = self.weights() {
            let mut lumps = [[[R::zero(); 2]; 3]; MAX_JOINTS];
            let mut node = Heading::origin();
            for k in 0..n {
                let e = states[k].end;
                let hinge_end = node.then(e.x, e.y, e.theta);
                lumps[k] = self.lumps_of(&node, &hinge_end);
                node = hinge_end.then(self.link_len, R::zero(), R::zero());
            }
            let c = w.centroids(n, &lumps);
            for k in 0..n {
                x[2 * n + 2 + 2 * k] = c[k][0];
                x[2 * n + 3 + 2 * k] = c[k][1];
            }
        }
    }
}

/// The coupled residual (docs/model.md "Equilibrium", "Gravity"). Unknowns: each joint's hole
/// (2 per joint), the tip position (2) and, under gravity, each joint's distal centroid (2 per
/// joint, base frame), whose weight (times `weight`) loads that joint and the link before it.
/// Residual: each hole's mismatch, the tip's with the chain, each centroid's with the chain's.
/// Returns the residual and the marched states.
pub(super) fn coupled_residual<R: Real>(
    f: &Finger<R>,
    c: &Compliances<R>,
    tension: R,
    force: [R; 2],
    weight: R,
    x: &[R; COUPLED],
) -> Result<([R; COUPLED], [JointState<R>; MAX_JOINTS]), MarchError> {
    let mut states = [f.straight(); MAX_JOINTS];
    let r = coupled_eval(f, c, tension, force, (f.weights().as_ref(), weight), x, (0, false), &mut Trace::new(), Some(&mut states))?;
    Ok((r, states))
}

/// An evaluation of the coupled residual, kept per joint so that another can resume from a
/// joint (`coupled_eval`): each joint's proximal frame and hinge end (base frame), its lumps
/// and hole residual.
#[derive(Clone, Copy)]
struct Trace<R> {
    frames: [Heading<R>; MAX_JOINTS + 1],
    ends: [Heading<R>; MAX_JOINTS],
    lumps: [[[R; 2]; 3]; MAX_JOINTS],
    holes: [[R; 2]; MAX_JOINTS],
}

impl<R: Real> Trace<R> {
    fn new() -> Self {
        let o = Heading::origin();
        Trace { frames: [o; MAX_JOINTS + 1], ends: [o; MAX_JOINTS], lumps: [[[R::zero(); 2]; 3]; MAX_JOINTS], holes: [[R::zero(); 2]; MAX_JOINTS] }
    }

    /// What an evaluation resumed at joint `k` of `n` wrote, back as `src` holds it.
    fn restore(&mut self, src: &Self, k: usize, n: usize) {
        self.frames[k + 1..=n].copy_from_slice(&src.frames[k + 1..=n]);
        self.ends[k..n].copy_from_slice(&src.ends[k..n]);
        self.lumps[k..n].copy_from_slice(&src.lumps[k..n]);
        self.holes[k..n].copy_from_slice(&src.holes[k..n]);
    }
}

/// The coupled residual into `t` (and the marched states into `states`, if given), resuming at
/// `from` = (joint, past its march): the joints before it (and that joint's march, if past it)
/// as `t` holds them, from an evaluation whose unknowns differ from `x` only in what loads the
/// chain from there on (a forward-difference column: the same arithmetic as the whole
/// evaluation, bit for bit).
#[allow(clippy::too_many_arguments)]
fn coupled_eval<R: Real>(
    f: &Finger<R>,
    c: &Compliances<R>,
    tension: R,
    force: [R; 2],
    (w, weight): (Option<&Weights<R>>, R),
    x: &[R; COUPLED],
    from: (usize, bool),
    t: &mut Trace<R>,
    mut states: Option<&mut [JointState<R>; MAX_JOINTS]>,
) -> Result<[R; COUPLED], MarchError> {
    let n = f.p.n;
    let tip = [x[2 * n], x[2 * n + 1]];
    let centroid = |k: usize| [x[2 * n + 2 + 2 * k], x[2 * n + 3 + 2 * k]];
    let grav = |k: usize| w.map(|w| (w, weight, centroid(k.min(n - 1))));
    let tip_load = if force == [R::zero(); 2] { None } else { Some((force, tip)) };
    // the sub-element displacements where no state is kept
    let mut scratch = [[R::zero(); 3]; MAX_SUB];
    for k in from.0..n {
        let frame = t.frames[k];
        if !(k == from.0 && from.1) {
            let tl = f.joint_ext_load(k, tip_load, grav(k)).map(|l| Finger::load_in_frame(&frame, l));
            let b = [x[2 * k], x[2 * k + 1]];
            let (end, hole, _) = match states.as_deref_mut() {
                Some(st) => f.march(&c.c[k], tension, b, tl, &mut st[k].q)?,
                None => f.march(&c.c[k], tension, b, tl, &mut scratch)?,
            };
            if let Some(st) = states.as_deref_mut() {
                (st[k].end, st[k].hole, st[k].tangent) = (end, hole, None);
            }
            t.holes[k] = [b[0] - hole[0], b[1] - hole[1]];
            t.ends[k] = frame.then(end.x, end.y, end.theta);
            t.lumps[k] = f.lumps_of(&frame, &t.ends[k]);
        }
        let hinge_end = t.ends[k];
        let ql = f.link_q(tension, f.link_load(k, &hinge_end, tip_load, grav(k + 1)).map(|l| (&hinge_end, l)));
        t.frames[k + 1] = hinge_end.then(f.link_len + ql[0], ql[1], ql[2]);
    }
    let mut r = [R::zero(); COUPLED];
    for k in 0..n {
        r[2 * k] = t.holes[k][0];
        r[2 * k + 1] = t.holes[k][1];
    }
    let end = t.frames[n];
    r[2 * n] = tip[0] - end.pose.x;
    r[2 * n + 1] = tip[1] - end.pose.y;
    if let Some(w) = w {
        let now = w.centroids(n, &t.lumps);
        for k in 0..n {
            let c = centroid(k);
            r[2 * n + 2 + 2 * k] = c[0] - now[k][0];
            r[2 * n + 3 + 2 * k] = c[1] - now[k][1];
        }
    }
    Ok(r)
}

/// Where a change in unknown `i` first enters the coupled chain (`coupled_eval`'s `from`): a
/// hole at its joint's march, the tip at the first joint's, a centroid at the link before its
/// joint (joint 1's at its march).
fn enters_at(n: usize, i: usize) -> (usize, bool) {
    if i < 2 * n {
        (i / 2, false)
    } else if i < 2 * n + 2 {
        (0, false)
    } else {
        match (i - 2 * n - 2) / 2 {
            0 => (0, false),
            j => (j - 1, true),
        }
    }
}

/// Converged equilibrium with a tip load: damped Newton (`solve::newton`; the Jacobian by
/// forward differences once, then Broyden's update, forward differences again where a step
/// fails on it) on all holes and the tip together, under load continuation
/// (`solve::continuation`) in the load factor λ (tension and tip force together).
pub(super) fn newton_coupled<R: Real>(
    f: &Finger<R>,
    c: &Compliances<R>,
    tension: R,
    force: [R; 2],
    tol: R,
    max_iter: u32,
) -> Result<([JointState<R>; MAX_JOINTS], [R; 2], u32), Error> {
    let mut x = straight_unknowns(f);
    let mut est = Estimate::new();
    let mut eq = Coupled::new(f, c, &mut est);
    continued(&mut eq, &mut x, tension, force, tol, max_iter)
}

impl<'a, R: Real> Coupled<'a, R> {
    #[inline(always)]
    fn new(f: &'a Finger<R>, c: &'a Compliances<R>, est: &'a mut Estimate<R>) -> Self {
        Coupled {
            f,
            c,
            tension: R::zero(),
            force: [R::zero(); 2],
            weight: R::zero(),
            w: f.weights(),
            states: [[f.straight(); MAX_JOINTS]; 3],
            traces: [Trace::new(); 3],
            est,
        }
    }
}

/// `newton_coupled` from the coupled unknowns `x` (updated: on success, the answer's) with
/// `eq` (its Jacobian estimate kept for a later solve).
fn continued<R: Real>(
    eq: &mut Coupled<'_, R>,
    x: &mut [R; COUPLED],
    tension: R,
    force: [R; 2],
    tol: R,
    max_iter: u32,
) -> Result<([JointState<R>; MAX_JOINTS], [R; 2], u32), Error> {
    let f = eq.f;
    let n = f.p.n;
    let mut iters = 0u32;
    let mut result = None;
    let opts_for = |left: u32| SolveOptions::new(tol, f.resolution() * R::from_u32(n as u32), left);
    let mut step = |_: R, to: R| -> Result<(), Step<Option<MarchError>>> {
        eq.tension = tension * to;
        eq.force = [force[0] * to, force[1] * to];
        eq.weight = to;
        let mut xt = eq.pack(x);
        let left = max_iter.saturating_sub(iters);
        // (the estimate's last point is the step before's: the first update mixes the two
        // load factors, which reaches further near a limit point than the estimate as it is)
        let carried = eq.est.formed;
        let mut run = newton::solve(eq, &mut xt, &opts_for(left));
        if run.is_err() && carried {
            // Broyden's estimate may be what failed: once more from the step's start on forward
            // differences
            iters += run.as_ref().err().map_or(0, |f| f.iterations());
            eq.est.drop();
            xt = eq.pack(x);
            run = newton::solve(eq, &mut xt, &opts_for(max_iter.saturating_sub(iters)));
        }
        match run {
            // each accepted step stays on the physical branch: no joint turns by more than
            // tension::same_branch's bound nor its hole jumps (past the branch's end Newton can
            // land on a coiled equilibrium of the coupled system: refused, the step halved)
            Ok((rep, slot)) if !same_branch(f, result.as_ref(), &eq.states[slot]) => {
                iters += rep.iterations;
                Err(if iters >= max_iter { Step::Stop(None) } else { Step::Retry(None) })
            }
            Ok((rep, slot)) => {
                iters += rep.iterations;
                *x = eq.unpack(&xt);
                if eq.tipless() {
                    // the chain's tip
                    let end = eq.traces[slot].frames[n].pose;
                    (x[2 * n], x[2 * n + 1]) = (end.x, end.y);
                }
                result = Some(eq.states[slot]);
                Ok(())
            }
            Err(fail) => {
                iters += fail.iterations();
                let why = fail.refusal().copied();
                if iters >= max_iter {
                    Err(Step::Stop(why))
                } else {
                    Err(Step::Retry(why))
                }
            }
        }
    };
    match continuation::run(R::one(), R::from_f64(1.0 / 4096.0), None, &mut step) {
        Ok(_) => match result {
            Some(states) => Ok((states, [x[2 * n], x[2 * n + 1]], iters)),
            None => Err(Error::NotConverged { iterations: iters, residual: f64::INFINITY }),
        },
        Err((lam, why)) => Err(match why {
            Some(MarchError::Contact) => Error::Contact { joint: 0, tension: (tension * lam).to_f64() },
            _ => Error::NotConverged { iterations: iters, residual: f64::INFINITY },
        }),
    }
}

/// A coupled step's joints against the last accepted ones (the straight finger before the first):
/// every joint turns by at most 0.8 rad and its hole moves at most half a hinge length, and no
/// joint passes half a turn.
pub(super) fn same_branch<R: Real>(f: &Finger<R>, last: Option<&[JointState<R>; MAX_JOINTS]>, next: &[JointState<R>; MAX_JOINTS]) -> bool {
    let straight = f.straight();
    (0..f.p.n).all(|k| {
        let before = last.map_or(&straight, |l| &l[k]);
        let dtheta = (next[k].end.theta - before.end.theta).abs();
        let dhole = super::norm2([next[k].hole[0] - before.hole[0], next[k].hole[1] - before.hole[1]]);
        dtheta <= R::from_f64(0.8) && dhole <= R::from_f64(0.5) * f.p.hinge_len() && next[k].end.theta.abs() < R::from_f64(core::f64::consts::PI)
    })
}

/// A coupled answer kept to start a later solve from (`Finger::solve_from`: the board's last
/// posture; fmax's walk up the branch): the coupled unknowns, tension and joints, and the
/// Jacobian estimate there.
#[derive(Clone, Copy)]
pub struct CoupledStart<R> {
    x: [R; COUPLED],
    tension: R,
    states: [JointState<R>; MAX_JOINTS],
    est: Estimate<R>,
}

impl<R: Real> CoupledStart<R> {
    /// The answer's tension, N.
    pub fn tension(&self) -> R {
        self.tension
    }

    /// The answer's joints.
    pub(super) fn states(&self) -> &[JointState<R>; MAX_JOINTS] {
        &self.states
    }

    /// The answer's tip (the chain's), base frame, mm.
    pub(super) fn tip(&self, n: usize) -> [R; 2] {
        [self.x[2 * n], self.x[2 * n + 1]]
    }

    /// The coupled equilibrium at `tension` as `newton_coupled` finds it (from the straight
    /// finger, under load continuation; at the finger's full weight, no tip force), and its
    /// iterations.
    pub(super) fn solve(f: &Finger<R>, c: &Compliances<R>, tension: R, tol: R, max_iter: u32) -> Result<(Self, u32), Error> {
        let tol = tol.max(f.resolution());
        let mut x = straight_unknowns(f);
        let mut est = Estimate::new();
        let mut eq = Coupled::new(f, c, &mut est);
        let (states, _, iters) = continued(&mut eq, &mut x, tension, [R::zero(); 2], tol, max_iter)?;
        Ok((CoupledStart { x, tension, states, est }, iters))
    }

    /// A step to tension `p` (at `c`'s compliances) from this answer, written over it: damped
    /// Newton on the carried estimate (at most `max_iter` iterations, `CARRIED_HALVINGS` line
    /// search halvings), once more on forward differences at the start if that fails; taken if it
    /// converges on the same branch (`same_branch`): its iterations. Refused: the answer stays
    /// (its estimate may not), and the march's refusal, if one, is returned.
    pub(super) fn step(&mut self, f: &Finger<R>, c: &Compliances<R>, p: R, tol: R, max_iter: u32) -> Result<u32, Option<MarchError>> {
        let n = f.p.n;
        let CoupledStart { x, tension, states, est } = self;
        let mut eq = Coupled::new(f, c, est);
        (eq.tension, eq.weight) = (p, R::one());
        let mut opts = SolveOptions::new(tol.max(f.resolution()), f.resolution() * R::from_u32(n as u32), max_iter);
        let (mut why, mut iters) = (None, 0);
        eq.est.carry();
        for fresh in [false, true] {
            if fresh {
                eq.est.drop();
                opts.max_halvings = SolveOptions::<R>::new(tol, tol, 0).max_halvings;
            } else if !eq.est.formed {
                continue;
            } else {
                opts.max_halvings = CARRIED_HALVINGS;
            }
            let mut xt = eq.pack(x);
            match newton::solve(&mut eq, &mut xt, &opts) {
                Ok((rep, slot)) if same_branch(f, Some(states), &eq.states[slot]) => {
                    *x = eq.unpack(&xt);
                    // the chain's tip
                    let end = eq.traces[slot].frames[n].pose;
                    (x[2 * n], x[2 * n + 1]) = (end.x, end.y);
                    *tension = p;
                    *states = eq.states[slot];
                    return Ok(iters + rep.iterations);
                }
                Ok((rep, _)) => iters += rep.iterations,
                Err(fail) => {
                    iters += fail.iterations();
                    why = fail.refusal().copied().or(why);
                }
            }
        }
        Err(why)
    }
}

/// Line-search halvings a step from a carried estimate may take before it is retried on
/// forward differences (an estimate carried from another tension or voltage can point
/// nowhere downhill: cheaper to form it again than to halve twelve times).
const CARRIED_HALVINGS: u32 = 2;
