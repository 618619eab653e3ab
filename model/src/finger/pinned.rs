//! The equilibrium with the tip pinned at a point (docs/model.md "Contact"; the paper's second
//! conclusion): unknowns each joint's guide hole and the tip load F that holds the tip there,
//! residual the coupled hole mismatches and the tip's distance from the point (the tip-loaded
//! system of `loaded::coupled_residual` with the tip fixed and F unknown). Reached by
//! continuation from the free posture at (P0, V0), where F = 0, to (P, V): tension and
//! voltages move together along λ, damped Newton (`solve::newton`, forward-difference
//! Jacobian) at each step, steps doubled on success and halved on failure
//! (`solve::continuation`). Each accepted step stays on the branch the finger reaches (the
//! coupled solve's `loaded::same_branch`; a step that lands elsewhere is halved) and its stop
//! only pushes (the force along the approach, the free tip's rate at the start: else
//! `PullingStop`). Refused as a limit point when a failed step ends past the fold that the
//! tangent determinants of the last two accepted points place (det²'s secant through zero,
//! close to the fold only: [`NEAR_FOLD`], [`FOLD_SPAN`]), when a step falls below [`MIN_STEP`]
//! or the residual evaluations pass [`MAX_EVALS`] (docs/inverse.md "Contact force": what
//! bounds the cost). Newton's Jacobian is formed by forward differences once, at the free
//! posture, then carried by Broyden's update across iterates and steps; a step that fails on it
//! is tried once more from the last accepted point on forward differences.

use super::{loaded, Compliances, Finger, JointState, MarchError, Solution, COUPLED};
use crate::error::Error;
use crate::params::MAX_JOINTS;
use crate::real::Real;
use crate::solve::continuation::{self, Step};
use crate::solve::lu::Lu;
use crate::solve::newton::{self, Equations};
use crate::solve::SolveOptions;

/// |det| below this fraction of the free posture's, falling by half or more in a step: near
/// enough to a fold for det²'s secant through zero to place it.
const NEAR_FOLD: f64 = 0.2;
/// The longest step between the two points det²'s secant is taken over (det² is linear in λ
/// near a fold only).
const FOLD_SPAN: f64 = 1.0 / 256.0;
/// Newton iterations per continuation step.
const STEP_ITER: u32 = 30;
/// Smallest continuation step: a step halved below it is the limit point. Every contact the
/// model answers on the fuzz corpora (466) and the default and paper fingers' grids needs steps
/// of 1/8,192 at the least; the refusals went on halving to 1/65,536 (the floor before) at up
/// to 30 Newton iterations a try, twice (docs/inverse.md "Contact force"; since issue 55 the
/// one answer that needed 1/8,192, below P0, is a pulling stop).
const MIN_STEP: f64 = 1.0 / 8192.0;
/// The continuation's residual evaluations, all steps together (its cost: the Newton iterates,
/// their line searches and forward differences): past them the step is refused as the limit
/// point too. The answers of the fuzz corpora and the two fingers' grids (`contact_dump`) take at
/// most 7,636 (f32) and 25,584 (f64).
const MAX_EVALS: u32 = 32768;

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
    /// The Jacobian estimate: forward differences at a step's start (or where a step is
    /// retried), then Broyden's rank-one update at each Newton iterate.
    jac: [[R; COUPLED]; COUPLED],
    /// The point (x, r) `jac` was last formed or updated at; None: forward differences at the
    /// next call.
    jac_at: Option<([R; COUPLED], [R; COUPLED])>,
    /// The next call takes `jac` as it is at its point (a new step's start: the parameters
    /// moved, so the last point's residual is not on this step's system).
    rebase: bool,
    /// Residual evaluations so far (the cost: the budget counts them).
    evals: u32,
}

impl<R: Real> Equations<R, COUPLED> for PinnedTip<'_, R> {
    type Refusal = MarchError;
    fn dim(&self) -> usize {
        loaded::coupled_dim(self.f)
    }
    fn residual(&mut self, x: &[R; COUPLED], slot: usize) -> Result<[R; COUPLED], MarchError> {
        let n = self.f.p.n;
        self.evals += 1;
        let mut xx = *x;
        xx[2 * n] = self.point[0];
        xx[2 * n + 1] = self.point[1];
        let (r, st) = loaded::coupled_residual(self.f, &self.c, self.tension, [x[2 * n], x[2 * n + 1]], R::one(), &xx)?;
        self.states[slot] = st;
        Ok(r)
    }
    fn jacobian(&mut self, x: &[R; COUPLED], r: &[R; COUPLED], _: usize) -> Result<[[R; COUPLED]; COUPLED], MarchError> {
        match self.jac_at {
            // Broyden's good update from the last point: J += (Δr - J Δx) Δxᵀ / |Δx|²
            Some((x0, r0)) if !self.rebase => loaded::broyden_update(&mut self.jac, self.f, x, r, &x0, &r0),
            Some(_) => {}
            None => self.jac = self.forward_difference(x, r)?,
        }
        self.rebase = false;
        self.jac_at = Some((*x, *r));
        Ok(self.jac)
    }
}

impl<R: Real> PinnedTip<'_, R> {
    /// Forward differences of the residual at `x` (`r` there).
    fn forward_difference(&mut self, x: &[R; COUPLED], r: &[R; COUPLED]) -> Result<[[R; COUPLED]; COUPLED], MarchError> {
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
    solve_counted(f, free0, p, volts).0
}

/// [`solve`] and the residual evaluations it spent, refused or not.
fn solve_counted<R: Real>(f: &Finger<R>, free0: &Solution<R>, p: R, volts: &[R]) -> (Result<Pinned<R>, Error>, u32) {
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
    let c0 = match c_at(R::zero()) {
        Ok(c) => c,
        Err(e) => return (Err(e), 0),
    };
    let zero = [[R::zero(); COUPLED]; COUPLED];
    let mut eq = PinnedTip { f, c: c0, tension: p0, point, states: [[f.straight(); MAX_JOINTS]; 3], jac: zero, jac_at: None, rebase: false, evals: 0 };
    let refused_at = |lam: R, why: Option<MarchError>| {
        let reached = (p0 + lam * (p - p0)).to_f64();
        match why {
            Some(MarchError::Contact) => Error::Contact { joint: 0, tension: reached },
            _ => Error::LimitPoint { joint: 0, tension: reached },
        }
    };
    // the free posture's tangent: the scale of the determinants that place a fold, and the
    // approach
    let (r0, jac0) = match eq.residual(&x, 0).and_then(|r| eq.jacobian(&x, &r, 0).map(|j| (r, j))) {
        Ok(rj) => rj,
        Err(why) => return (Err(refused_at(R::zero(), Some(why))), 0),
    };
    let det_of = |jac: &[[R; COUPLED]; COUPLED]| Lu::new(jac, dim).map_or(R::zero(), |lu| lu.determinant());
    let det0 = det_of(&jac0);
    if !(det0 != R::zero()) {
        return (Err(refused_at(R::zero(), None)), 0);
    }
    let mut last_states = free_states;
    for k in 0..n {
        last_states[k].hole = [x[2 * k], x[2 * k + 1]];
    }
    // the approach's unit direction: a force with a positive component along it pulls
    let approach = approach(&mut eq, &x, &r0, &jac0, dim);
    let pull_tol = R::from_f64(R::SQRT_EPS) * (R::one() + p0 + p);
    let mut iters = 0u32;
    let mut last: Option<(R, [R; COUPLED])> = None;
    // the last two accepted points' (λ, det): where det² reaches zero on their secant
    let mut dets: [Option<(R, R)>; 2] = [None, None];
    let mut at = (R::zero(), x);
    // the Jacobian estimate at the last accepted point: each step's start
    let mut at_jac = jac0;
    let mut answer = None;
    let mut step = |from: R, to: R| -> Result<(), Step<Result<Option<MarchError>, Error>>> {
        // the budget spent: a step of at most STEP_ITER (twice) more, then the limit point
        if eq.evals >= MAX_EVALS {
            return Err(Step::Stop(Ok(None)));
        }
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
        // from the last accepted point's estimate (Broyden's updates from there), then, failing,
        // once more from that point on forward differences
        eq.jac = at_jac;
        eq.jac_at = Some((at.1, [R::zero(); COUPLED]));
        eq.rebase = true;
        let mut outcome = newton::solve(&mut eq, &mut xt, &opts);
        if outcome.is_err() {
            iters += outcome.as_ref().err().map_or(0, |f| f.iterations());
            xt = at.1;
            eq.jac_at = None;
            outcome = newton::solve(&mut eq, &mut xt, &opts);
        }
        // a failed step whose end lies past the fold the determinants point to: the limit point
        // (a shorter step cannot pass it)
        let fold_within = |dets: &[Option<(R, R)>; 2]| match *dets {
            [Some((la, da)), Some((lb, db))]
                if R::from_f64(4.0) * db * db <= da * da
                    && db.abs() <= R::from_f64(NEAR_FOLD) * det0.abs()
                    && da * det0 > R::zero()
                    && db * det0 > R::zero()
                    && lb > la
                    && lb - la <= R::from_f64(FOLD_SPAN) =>
            {
                lb + db * db * (lb - la) / (da * da - db * db) <= to
            }
            _ => false,
        };
        let failed = |why: Option<MarchError>, dets: &[Option<(R, R)>; 2]| {
            if fold_within(dets) {
                Step::Stop(Ok(None))
            } else {
                Step::Retry(Ok(why))
            }
        };
        match outcome {
            Ok((rep, slot)) => {
                iters += rep.iterations;
                // the determinant at the answer: the last Jacobian estimate's (Broyden's; a fresh
                // forward difference here does worse in f32, whose differences are noisier)
                let det = det_of(&eq.jac);
                // on the branch reached from the free posture: no joint turns by more than the
                // coupled solve's bound (`loaded::same_branch`) in a step; a step that lands
                // elsewhere (past a fold, on another equilibrium) is halved
                if !loaded::same_branch(f, Some(&last_states), &eq.states[slot]) {
                    return Err(failed(None, &dets));
                }
                if let Some(d) = approach {
                    let along = d[0] * xt[2 * n] + d[1] * xt[2 * n + 1];
                    if along > pull_tol {
                        return Err(Step::Stop(Err(Error::PullingStop { tension: eq.tension.to_f64(), force: along.to_f64() })));
                    }
                }
                last = Some(at);
                at = (to, xt);
                last_states = eq.states[slot];
                dets = [dets[1], Some((to, det))];
                at_jac = eq.jac;
                answer = Some(eq.states[slot]);
                Ok(())
            }
            Err(fail) => {
                iters += fail.iterations();
                Err(failed(fail.refusal().copied(), &dets))
            }
        }
    };
    let outcome = continuation::run(R::one(), R::from_f64(MIN_STEP), Ok(None), &mut step);
    let answer = match outcome {
        Ok(_) => match answer {
            None => Err(Error::NotConverged { iterations: iters, residual: f64::INFINITY }),
            Some(states) => {
                let force = [at.1[2 * n], at.1[2 * n + 1]];
                f.compliances(volts).and_then(|c| f.assemble(&c, p, force, &states, Some(point), iters)).map(|solution| Pinned {
                    solution,
                    force,
                    iterations: iters,
                })
            }
        },
        Err((_, Err(e))) => Err(e),
        Err((lam, Ok(why))) => Err(refused_at(lam, why)),
    };
    (answer, eq.evals)
}

/// The direction the free tip moves in as the tension rises at the start (unit, base frame):
/// the stop's normal. From the pinned system's Jacobian there (`jac0`, residual `r0` at `x`):
/// the holes' (and centroids') rates with the tip load held at 0, ∂r/∂P by one forward
/// difference, the tip's rate from its rows (r_tip = point - tip). None where that system is
/// singular or the tip does not move.
fn approach<R: Real>(eq: &mut PinnedTip<'_, R>, x: &[R; COUPLED], r0: &[R; COUPLED], jac0: &[[R; COUPLED]; COUPLED], dim: usize) -> Option<[R; 2]> {
    let n = eq.f.p.n;
    let p0 = eq.tension;
    let dp = R::from_f64(R::SQRT_EPS) * (R::one() + p0);
    eq.tension = p0 + dp;
    let r1 = eq.residual(x, newton::SCRATCH);
    eq.tension = p0;
    let r1 = r1.ok()?;
    let mut dr = [R::zero(); COUPLED];
    for i in 0..dim {
        dr[i] = (r1[i] - r0[i]) / dp;
    }
    // every unknown but the tip load, every row but the tip's
    let mut idx = [0usize; COUPLED];
    let mut m = 0;
    for i in (0..dim).filter(|&i| i != 2 * n && i != 2 * n + 1) {
        idx[m] = i;
        m += 1;
    }
    let mut a = [[R::zero(); COUPLED]; COUPLED];
    let mut b = [R::zero(); COUPLED];
    for i in 0..m {
        for j in 0..m {
            a[i][j] = jac0[idx[i]][idx[j]];
        }
        b[i] = -dr[idx[i]];
    }
    let dx = Lu::new(&a, m)?.solve(&b);
    let mut d = [R::zero(); 2];
    for (c, dc) in d.iter_mut().enumerate() {
        let row = 2 * n + c;
        *dc = -(0..m).fold(dr[row], |s, j| s + jac0[row][idx[j]] * dx[j]);
    }
    let len = (d[0].sq() + d[1].sq()).sqrt();
    (len > R::zero()).then(|| [d[0] / len, d[1] / len])
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Method, Params};

    /// One step's most residual evaluations: two tries of STEP_ITER iterations, each a forward
    /// difference and a line search.
    const STEP_EVALS: u32 = 2 * STEP_ITER * (COUPLED as u32 + 1 + 12);

    /// A stop the continuation cannot hold (the fuzz corpus's model_contact/6fc70630: the paper's
    /// model with a 0.023 mm hinge and the cable 0.65 mm off the centreline) is refused as the
    /// limit point within the budget, MAX_EVALS and one step's two tries. With the floor at
    /// 1/65,536 it took 7,982 Newton iterations (42-150 ms here).
    #[test]
    fn a_refused_contact_stays_within_its_budget() {
        let p = Params::<f64> { t_min: 0.0234375, a: 8.705505632961241, e: 0.6470405774008609, ..Params::paper() };
        let f = Finger::new(p).unwrap();
        let free0 = f.solve(8.909440657448953e-2, &[0.0; 3], Method::converged()).unwrap();
        let (r, evals) = solve_counted(&f, &free0, 13.408160566953532, &[0.0, 8150.0, 0.0]);
        assert!(matches!(r, Err(Error::LimitPoint { .. })), "{:?}", r.err());
        assert!(evals <= MAX_EVALS + STEP_EVALS, "{evals} residual evaluations");
    }

    /// The corpus's model_contact/f22fbf2e, the answer that took steps of 1/8,192 (the floor's
    /// evidence, docs/inverse.md "Contact force"): its tension falls below P0 (0.0169 -> 0.0082
    /// N), so the stop would pull: now refused as that (issue 55) at the first step it accepts,
    /// where it answered 8.7459e-3 N.
    #[test]
    fn a_tension_below_p0_is_refused_as_a_pulling_stop() {
        let p = Params::<f64> {
            n: 1,
            t_min: 0.0234375,
            a: 0.078125,
            e: 0.078125,
            layers: 0,
            z0: 0.0078125,
            g: 0.009375,
            m: 1,
            plate: false,
            flex_links: false,
            ..Params::default()
        };
        let f = Finger::new(p).unwrap();
        let free0 = f.solve(1.691105422117015e-2, &[0.0], Method::converged()).unwrap();
        let (r, evals) = solve_counted(&f, &free0, 8.167500816323055e-3, &[0.0]);
        assert!(matches!(r, Err(Error::PullingStop { .. })), "{:?}", r.map(|c| c.force));
        assert!(evals <= MAX_EVALS + STEP_EVALS, "{evals} residual evaluations");
    }
}
