//! The coupled equilibrium (docs/model.md "Equilibrium": an external tip load or the finger's
//! weight couples the joints): every guide hole, the tip and, under gravity, each joint's
//! distal centroid solved together by damped Newton under load continuation. Not the
//! tension-alone solve (`tension`).

use super::{Compliances, Finger, Heading, JointState, MarchError, COUPLED};
use crate::error::Error;
use crate::params::MAX_JOINTS;
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
    states: [[JointState<R>; MAX_JOINTS]; 3],
}

impl<R: Real> Equations<R, COUPLED> for Coupled<'_, R> {
    type Refusal = MarchError;
    fn dim(&self) -> usize {
        coupled_dim(self.f)
    }
    fn residual(&mut self, x: &[R; COUPLED], slot: usize) -> Result<[R; COUPLED], MarchError> {
        let (r, st) = coupled_residual(self.f, self.c, self.tension, self.force, self.weight, x)?;
        self.states[slot] = st;
        Ok(r)
    }
    fn jacobian(&mut self, x: &[R; COUPLED], r: &[R; COUPLED], _: usize) -> Result<[[R; COUPLED]; COUPLED], MarchError> {
        let h = R::from_f64(R::SQRT_EPS) * (self.f.p.hinge_len() + self.f.p.e);
        newton::forward_difference(self, x, r, &[h; COUPLED])
    }
}

/// The coupled system's size: each joint's hole, the tip and, under gravity, each joint's
/// distal centroid.
pub(super) fn coupled_dim<R: Real>(f: &Finger<R>) -> usize {
    let n = f.p.n;
    2 * n + 2 + if f.weights().is_some() { 2 * n } else { 0 }
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
    let n = f.p.n;
    let tip = [x[2 * n], x[2 * n + 1]];
    let w = f.weights();
    let centroid = |k: usize| [x[2 * n + 2 + 2 * k], x[2 * n + 3 + 2 * k]];
    let grav = |k: usize| w.as_ref().map(|w| (w, weight, centroid(k.min(n - 1))));
    let tip_load = Some((force, tip));
    let mut states = [f.straight(); MAX_JOINTS];
    let mut r = [R::zero(); COUPLED];
    let mut lumps = [[[R::zero(); 2]; 3]; MAX_JOINTS];
    let mut frame = Heading::origin();
    for k in 0..n {
        let tl = f.joint_ext_load(k, tip_load, grav(k)).map(|l| Finger::load_in_frame(&frame, l));
        let b = [x[2 * k], x[2 * k + 1]];
        let st = f.marched(&c.c[k], tension, b, tl)?;
        r[2 * k] = b[0] - st.hole[0];
        r[2 * k + 1] = b[1] - st.hole[1];
        let hinge_end = frame.then(st.end.x, st.end.y, st.end.theta);
        let ql = f.link_q(tension, f.link_load(k, &hinge_end, tip_load, grav(k + 1)).map(|l| (&hinge_end, l)));
        lumps[k] = f.lumps_of(&frame, &hinge_end);
        frame = hinge_end.then(f.link_len + ql[0], ql[1], ql[2]);
        states[k] = st;
    }
    r[2 * n] = tip[0] - frame.pose.x;
    r[2 * n + 1] = tip[1] - frame.pose.y;
    if let Some(w) = &w {
        let now = w.centroids(n, &lumps);
        for k in 0..n {
            let c = centroid(k);
            r[2 * n + 2 + 2 * k] = c[0] - now[k][0];
            r[2 * n + 3 + 2 * k] = c[1] - now[k][1];
        }
    }
    Ok((r, states))
}

/// Converged equilibrium with a tip load: damped Newton (`solve::newton`, forward-difference
/// Jacobian) on all holes and the tip together, under load continuation
/// (`solve::continuation`) in the load factor λ (tension and tip force together).
pub(super) fn newton_coupled<R: Real>(
    f: &Finger<R>,
    c: &Compliances<R>,
    tension: R,
    force: [R; 2],
    tol: R,
    max_iter: u32,
) -> Result<([JointState<R>; MAX_JOINTS], [R; 2], u32), Error> {
    let n = f.p.n;
    let mut x = straight_unknowns(f);
    let mut eq = Coupled { f, c, tension: R::zero(), force: [R::zero(); 2], weight: R::zero(), states: [[f.straight(); MAX_JOINTS]; 3] };
    let mut iters = 0u32;
    let mut result = None;
    let opts_for = |left: u32| SolveOptions::new(tol, f.resolution() * R::from_u32(n as u32), left);
    let mut step = |_: R, to: R| -> Result<(), Step<Option<MarchError>>> {
        eq.tension = tension * to;
        eq.force = [force[0] * to, force[1] * to];
        eq.weight = to;
        let mut xt = x;
        let left = max_iter.saturating_sub(iters);
        match newton::solve(&mut eq, &mut xt, &opts_for(left)) {
            // each accepted step stays on the physical branch: no joint turns by more than
            // tension::same_branch's bound nor its hole jumps (past the branch's end Newton can
            // land on a coiled equilibrium of the coupled system: refused, the step halved)
            Ok((rep, slot)) if !same_branch(f, result.as_ref(), &eq.states[slot]) => {
                iters += rep.iterations;
                Err(if iters >= max_iter { Step::Stop(None) } else { Step::Retry(None) })
            }
            Ok((rep, slot)) => {
                iters += rep.iterations;
                x = xt;
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
