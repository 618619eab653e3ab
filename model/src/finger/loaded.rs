//! The tip-loaded equilibrium (docs/model.md "Equilibrium": an external tip load couples the
//! joints): every guide hole and the tip solved together by damped Newton under load
//! continuation. Not the tension-alone solve (`tension`).

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
    states: [[JointState<R>; MAX_JOINTS]; 3],
}

impl<R: Real> Equations<R, COUPLED> for Coupled<'_, R> {
    type Refusal = MarchError;
    fn dim(&self) -> usize {
        2 * self.f.p.n + 2
    }
    fn residual(&mut self, x: &[R; COUPLED], slot: usize) -> Result<[R; COUPLED], MarchError> {
        let (r, st) = coupled_residual(self.f, self.c, self.tension, self.force, x)?;
        self.states[slot] = st;
        Ok(r)
    }
    fn jacobian(&mut self, x: &[R; COUPLED], r: &[R; COUPLED], _: usize) -> Result<[[R; COUPLED]; COUPLED], MarchError> {
        let h = R::from_f64(R::SQRT_EPS) * (self.f.p.hinge_len() + self.f.p.e);
        newton::forward_difference(self, x, r, &[h; COUPLED])
    }
}

/// Tip-loaded equilibrium, every hole and the tip together (docs/model.md "Equilibrium": an
/// external tip load couples the joints).
/// Coupled residual for the tip-loaded case. Unknowns: each joint's hole (2 per joint),
/// then the tip position (2). Returns the residual and the marched states.
pub(super) fn coupled_residual<R: Real>(
    f: &Finger<R>,
    c: &Compliances<R>,
    tension: R,
    force: [R; 2],
    x: &[R; 2 * MAX_JOINTS + 2],
) -> Result<([R; 2 * MAX_JOINTS + 2], [JointState<R>; MAX_JOINTS]), MarchError> {
    let n = f.p.n;
    let tip = [x[2 * n], x[2 * n + 1]];
    let mut states = [f.straight(); MAX_JOINTS];
    let mut r = [R::zero(); 2 * MAX_JOINTS + 2];
    let mut frame = Heading::origin();
    for k in 0..n {
        let tl = Finger::tip_in_frame(&frame, force, tip);
        let b = [x[2 * k], x[2 * k + 1]];
        let st = f.marched(&c.c[k], tension, b, Some(tl))?;
        r[2 * k] = b[0] - st.hole[0];
        r[2 * k + 1] = b[1] - st.hole[1];
        let hinge_end = frame.then(st.end.x, st.end.y, st.end.theta);
        let ql = f.link_q(tension, Some((&hinge_end, force, tip)));
        frame = hinge_end.then(f.link_len + ql[0], ql[1], ql[2]);
        states[k] = st;
    }
    r[2 * n] = tip[0] - frame.pose.x;
    r[2 * n + 1] = tip[1] - frame.pose.y;
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
    let mut x = [R::zero(); COUPLED];
    for k in 0..n {
        x[2 * k] = f.p.hinge_len();
        x[2 * k + 1] = f.p.e;
    }
    x[2 * n] = R::from_u32(n as u32) * f.p.l;
    let mut eq = Coupled { f, c, tension: R::zero(), force: [R::zero(); 2], states: [[f.straight(); MAX_JOINTS]; 3] };
    let mut iters = 0u32;
    let mut result = None;
    let opts_for = |left: u32| SolveOptions::new(tol, f.resolution() * R::from_u32(n as u32), left);
    let mut step = |_: R, to: R| -> Result<(), Step<Option<MarchError>>> {
        eq.tension = tension * to;
        eq.force = [force[0] * to, force[1] * to];
        let mut xt = x;
        let left = max_iter.saturating_sub(iters);
        match newton::solve(&mut eq, &mut xt, &opts_for(left)) {
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
