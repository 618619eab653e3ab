//! The equilibrium with the tip pinned at a point (docs/model.md "Contact"; the paper's second
//! conclusion): unknowns each joint's guide hole and the tip load F that holds the tip there,
//! residual the coupled hole mismatches and the tip's distance from the point (the tip-loaded
//! system of `loaded::coupled_residual` with the tip fixed and F unknown). Reached by
//! continuation from the free posture at (P0, V0), where F = 0, to (P, V): tension and
//! voltages move together along λ, damped Newton (`solve::newton`, forward-difference
//! Jacobian) at each step, steps doubled on success and halved on failure
//! (`solve::continuation`).

use super::{loaded, Compliances, Finger, JointState, MarchError, Solution, COUPLED};
use crate::error::Error;
use crate::params::MAX_JOINTS;
use crate::real::Real;
use crate::solve::continuation::{self, Step};
use crate::solve::newton::{self, Equations};
use crate::solve::SolveOptions;

/// Newton iterations per continuation step.
const STEP_ITER: u32 = 30;
/// Smallest continuation step.
const MIN_STEP: f64 = 1.0 / 65536.0;

/// A pinned-tip answer: the loaded equilibrium, the force on the tip and the iterations.
pub(crate) struct Pinned<R> {
    pub solution: Solution<R>,
    pub force: [R; 2],
    pub iterations: u32,
}

// same shape as `loaded`'s `Coupled` (an `Equations` on the coupled residual): the tip pinned, not loaded
struct PinnedTip<'a, R> {
    f: &'a Finger<R>,
    c: Compliances<R>,
    tension: R,
    point: [R; 2],
    states: [[JointState<R>; MAX_JOINTS]; 3],
}

impl<R: Real> Equations<R, COUPLED> for PinnedTip<'_, R> {
    type Refusal = MarchError;
    fn dim(&self) -> usize {
        loaded::coupled_dim(self.f)
    }
    fn residual(&mut self, x: &[R; COUPLED], slot: usize) -> Result<[R; COUPLED], MarchError> {
        let n = self.f.p.n;
        let mut xx = *x;
        xx[2 * n] = self.point[0];
        xx[2 * n + 1] = self.point[1];
        let (r, st) = loaded::coupled_residual(self.f, &self.c, self.tension, [x[2 * n], x[2 * n + 1]], R::one(), &xx)?;
        self.states[slot] = st;
        Ok(r)
    }
    fn jacobian(&mut self, x: &[R; COUPLED], r: &[R; COUPLED], _: usize) -> Result<[[R; COUPLED]; COUPLED], MarchError> {
        let n = self.f.p.n;
        let mut h = [R::from_f64(R::SQRT_EPS) * (self.f.p.hinge_len() + self.f.p.e); COUPLED];
        let fs = R::from_f64(R::SQRT_EPS) * (self.tension + x[2 * n].abs() + x[2 * n + 1].abs() + R::one());
        h[2 * n] = fs;
        h[2 * n + 1] = fs;
        newton::forward_difference(self, x, r, &h)
    }
}

/// The tip pinned at the free tip of (`p0`, `volts0`) (`free0`, solved by the caller), at
/// tension `p` and `volts`: the force the point exerts on the tip. Refusals: `Contact`
/// (the links touch on the way), `LimitPoint` (the pinned equilibrium's tangent turns
/// singular: the stop cannot be held), else `NotConverged`.
pub(super) fn solve<R: Real>(f: &Finger<R>, free0: &Solution<R>, p: R, volts: &[R]) -> Result<Pinned<R>, Error> {
    let n = f.p.n;
    let p0 = free0.tension;
    let v0 = free0.volts;
    let point = [free0.tip().x, free0.tip().y];
    let mut x = [R::zero(); COUPLED];
    for k in 0..n {
        let hole = f.walk(&free0.q[k]).point(R::zero(), f.p.e);
        x[2 * k] = hole[0];
        x[2 * k + 1] = hole[1];
    }
    let mut free_states = [f.straight(); MAX_JOINTS];
    for k in 0..n {
        free_states[k].end = f.walk(&free0.q[k]).pose;
    }
    f.put_centroids(&free_states, &mut x);
    let dim = loaded::coupled_dim(f);
    let scale = f.p.l * R::from_u32(n as u32);
    // tight: a re-march amplifies the hole residual by the march's gain (hundreds near fmax)
    let tol = R::from_f64(1e-11_f64.max(R::EPS * 256.0)) * scale;
    let opts = SolveOptions::new(tol, f.resolution() * R::from_u32(n as u32), STEP_ITER);
    let c_at = |lam: R| -> Result<Compliances<R>, Error> {
        let mut v = [R::zero(); MAX_JOINTS];
        for k in 0..n {
            v[k] = v0[k] + lam * (volts[k] - v0[k]);
        }
        f.compliances(&v[..n])
    };
    let mut eq = PinnedTip { f, c: c_at(R::zero())?, tension: p0, point, states: [[f.straight(); MAX_JOINTS]; 3] };
    let mut iters = 0u32;
    let mut last: Option<(R, [R; COUPLED])> = None;
    let mut at = (R::zero(), x);
    let mut answer = None;
    let mut step = |from: R, to: R| -> Result<(), Step<Result<Option<MarchError>, Error>>> {
        eq.c = c_at(to).map_err(|e| Step::Stop(Err(e)))?;
        eq.tension = p0 + to * (p - p0);
        // secant predictor from the last two accepted points
        let mut xt = at.1;
        if let Some((l0, x0)) = last {
            if from > l0 {
                let s = (to - from) / (from - l0);
                for i in 0..dim {
                    xt[i] += s * (at.1[i] - x0[i]);
                }
            }
        }
        let run = |xt: &mut [R; COUPLED], eq: &mut PinnedTip<'_, R>| newton::solve(eq, xt, &opts);
        let mut outcome = run(&mut xt, &mut eq);
        if outcome.is_err() && last.is_some() {
            iters += outcome.as_ref().err().map_or(0, |f| f.iterations());
            xt = at.1;
            outcome = run(&mut xt, &mut eq);
        }
        match outcome {
            Ok((rep, slot)) => {
                iters += rep.iterations;
                last = Some(at);
                at = (to, xt);
                answer = Some(eq.states[slot]);
                Ok(())
            }
            Err(fail) => {
                iters += fail.iterations();
                Err(Step::Retry(Ok(fail.refusal().copied())))
            }
        }
    };
    match continuation::run(R::one(), R::from_f64(MIN_STEP), Ok(None), &mut step) {
        Ok(_) => {
            let Some(states) = answer else { return Err(Error::NotConverged { iterations: iters, residual: f64::INFINITY }) };
            let force = [at.1[2 * n], at.1[2 * n + 1]];
            let c = f.compliances(volts)?;
            let solution = f.assemble(&c, p, force, &states, Some(point), iters)?;
            Ok(Pinned { solution, force, iterations: iters })
        }
        Err((_, Err(e))) => Err(e),
        Err((lam, Ok(why))) => {
            let reached = (p0 + lam * (p - p0)).to_f64();
            Err(match why {
                Some(MarchError::Contact) => Error::Contact { joint: 0, tension: reached },
                _ => Error::LimitPoint { joint: 0, tension: reached },
            })
        }
    }
}
