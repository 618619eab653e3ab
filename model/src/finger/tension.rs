//! The converged equilibrium under tension alone (docs/model.md "Equilibrium": the joints
//! decouple): each joint by Newton on its guide hole under load continuation, then the posture.
//! Not the tabled start (`tabled`) nor the tip-loaded solve (`loaded`).

use super::{norm2, Compliances, Finger, Heading, JointEquilibrium, JointState, MarchError, Pose, Solution};
use crate::error::Error;
use crate::mat3::Mat3;
use crate::params::{MAX_JOINTS, MAX_SUB};
use crate::real::Real;
use crate::solve::continuation::{self, Step};

/// The converged solve under tension alone: the joints decouple, each solved by Newton on
/// its own; the solution is written in place (no joint-state arrays, no second march for
/// the residual and tangent: Newton's last dual march gives them).
pub(super) fn solve<R: Real>(f: &Finger<R>, c: &Compliances<R>, tension: R, tol: R, max_iter: u32) -> Result<Solution<R>, Error> {
    let mut out = Ok(Solution { n: f.p.n, m: f.p.m, tension, thickness: c.thickness, volts: c.volts, ..Solution::empty() });
    if let Ok(sol) = &mut out {
        if let Err(e) = solve_into(f, c, tension, tol, max_iter, sol) {
            out = Err(e);
        }
    }
    out
}

/// `solve` into `sol`: each distinct joint by `newton_joint`, then `posture_into`.
fn solve_into<R: Real>(f: &Finger<R>, c: &Compliances<R>, tension: R, tol: R, max_iter: u32, sol: &mut Solution<R>) -> Result<(), Error> {
    let (n, m) = (f.p.n, f.p.m);
    let mut ends = [Pose::origin(); MAX_JOINTS];
    let mut holes = [[R::zero(); 2]; MAX_JOINTS];
    let mut res2 = R::zero();
    let mut r2_prev = R::zero();
    let mut iters = 0;
    for k in 0..n {
        // a joint with the same compliance as the one before has the same state (no work)
        if k > 0 && c.c[k][..m] == c.c[k - 1][..m] && f.same_held(k, k - 1) {
            let (done, rest) = sol.q.split_at_mut(k);
            rest[0][..m].copy_from_slice(&done[k - 1][..m]);
            ends[k] = ends[k - 1];
            holes[k] = holes[k - 1];
            sol.tangent_det[k] = sol.tangent_det[k - 1];
            res2 += r2_prev;
            continue;
        }
        let min_step = tension / R::from_f64(4096.0);
        let (st, it) = newton_joint(f, k, &c.c[k], tension, tol, max_iter, min_step)?;
        iters += it;
        sol.q[k][..m].copy_from_slice(&st.q[..m]);
        ends[k] = st.end;
        holes[k] = st.hole;
        let tangent = match st.tangent {
            Some(t) => Some(t),
            None => f.eval_dual(&c.c[k], tension, st.hole, f.held_at(k, R::one())).ok().map(|(_, r, j)| (r, j[0][0] * j[1][1] - j[0][1] * j[1][0])),
        };
        let r2 = match tangent {
            Some((r, det)) => {
                sol.tangent_det[k] = det;
                r[0] * r[0] + r[1] * r[1]
            }
            None => match f.hole_residual(&c.c[k], tension, st.hole, f.held_at(k, R::one())) {
                Ok((r, _)) => r[0] * r[0] + r[1] * r[1],
                Err(_) => return Err(Error::Contact { joint: k + 1, tension: tension.to_f64() }),
            },
        };
        r2_prev = r2;
        res2 += r2;
    }
    posture_into(f, tension, &ends, &holes, res2, iters, sol)
}

/// The posture of a solve under tension alone from each joint's hinge end and guide hole
/// (docs/model.md "Equilibrium": node k = node k-1 ∘ hinge ∘ link; "Cable": the excursion
/// Σ (L_h - |span k|)), into `sol`; a span below its floor is contact.
#[inline(never)]
fn posture_into<R: Real>(
    f: &Finger<R>,
    tension: R,
    ends: &[Pose<R>; MAX_JOINTS],
    holes: &[[R; 2]; MAX_JOINTS],
    res2: R,
    iters: u32,
    sol: &mut Solution<R>,
) -> Result<(), Error> {
    let n = f.p.n;
    let (heads, links) = f.chain_ends(ends, tension, [R::zero(); 2], None);
    let nodes = Heading::poses(&heads);
    sol.nodes = nodes;
    sol.links = links;
    sol.iterations = iters;
    for k in 0..n {
        sol.joint_angle[k] = ends[k].theta + links[k][2];
        // the span as the final geometry has it (not the one the loads came from)
        let span = norm2([holes[k][0], holes[k][1] - f.p.e]);
        if !(span >= f.p.span_floor) {
            return Err(Error::Contact { joint: k + 1, tension: tension.to_f64() });
        }
        sol.span[k] = span;
        sol.cable_excursion += f.p.hinge_len() - span;
    }
    sol.residual = res2.sqrt();
    Finger::check_finite(&nodes, sol)
}

/// Converged equilibrium of joint k under tension alone: Newton on the hole position
/// (`newton_dual`, on `solve::newton`) under load continuation (`solve::continuation`: the
/// increment doubles on success, halves on failure, down to `min_step`), from a secant
/// predictor; each accepted step stays on the physical branch (`same_branch`).
pub(super) fn newton_joint<R: Real>(
    f: &Finger<R>,
    k: usize,
    c: &[Mat3<R>; MAX_SUB],
    tension: R,
    tol: R,
    max_iter: u32,
    min_step: R,
) -> Result<(JointState<R>, u32), Error> {
    // a fixed load (`held`) grows with the tension along the continuation, from the straight
    // joint; without tension it is the continuation's only load
    let held = f.held_at(k, R::one());
    if tension == R::zero() && held.is_none() {
        let st = f.marched(c, tension, [f.p.hinge_len(), f.p.e], None).map_err(|_| Error::Singular { what: "joint" })?;
        return Ok((st, 0));
    }
    let unit = if tension == R::zero() { R::one() } else { tension };
    // the unloaded joint is straight (the march at zero tension gives exactly this)
    let mut last = f.straight();
    let mut b = last.hole;
    let mut iters = 0u32;
    let mut attempts = 0u32;
    // secant predictor: the hole's rate of change with tension over the last accepted step
    let mut rate = [R::zero(); 2];
    let mut failed_at = tension;
    let mut step = |from: R, to: R| -> Result<(), Step<Option<MarchError>>> {
        let (done, target) = (unit * from, unit * to);
        let dp = target - done;
        let guess = [b[0] + rate[0] * dp, b[1] + rate[1] * dp];
        let (p_to, load) = (tension * to, f.held_at(k, to));
        let attempt = match f.newton_dual(c, p_to, guess, load, tol, max_iter.saturating_sub(iters)) {
            Err((_, it)) if done > R::zero() => {
                // the predictor overshot: retry from the last solution itself
                iters += it;
                f.newton_dual(c, p_to, b, load, tol, max_iter.saturating_sub(iters))
            }
            other => other,
        };
        let (it, outcome) = match attempt {
            Ok((st, it)) => (it, if same_branch(f, &last, &st, held.is_some()) { Ok(st) } else { Err(None) }),
            Err((why, it)) => (it, Err(why)),
        };
        iters += it;
        match outcome {
            Ok(st) => {
                rate = [(st.hole[0] - b[0]) / dp, (st.hole[1] - b[1]) / dp];
                b = st.hole;
                last = st;
                Ok(())
            }
            Err(why) => {
                failed_at = target;
                attempts += 1;
                if iters >= max_iter || attempts > 4 * max_iter {
                    Err(Step::Stop(why))
                } else {
                    Err(Step::Retry(why))
                }
            }
        }
    };
    let mut why_failed = None;
    let mut track = |from: R, to: R| -> Result<(), Step<Option<MarchError>>> {
        step(from, to).inspect_err(|&e| {
            let (Step::Retry(w) | Step::Stop(w)) = e;
            if w.is_some() {
                why_failed = w;
            }
        })
    };
    match continuation::run(R::one(), min_step / unit, None, &mut track) {
        Ok(_) => Ok((last, iters)),
        Err((lam, _)) => {
            let done = tension * lam;
            Err(match why_failed {
                Some(MarchError::Contact) => Error::Contact { joint: k + 1, tension: failed_at.to_f64() },
                _ if done > R::zero() && near_limit_point(f, c, done, &last, f.held_at(k, lam)) => Error::LimitPoint { joint: k + 1, tension: done.to_f64() },
                _ => Error::NotConverged { iterations: iters, residual: f64::INFINITY },
            })
        }
    }
}

/// Load continuation stays on the physical branch: under a growing tension a joint flexes
/// further (its angle grows) by a bounded amount per step. A Newton solution that fails
/// this (a jump to another branch, far from the last one) is rejected and the step halved.
/// With a fixed load growing beside the tension (`loaded`) the joint may turn either way: only
/// the bound holds.
pub(super) fn same_branch<R: Real>(f: &Finger<R>, last: &JointState<R>, next: &JointState<R>, loaded: bool) -> bool {
    let dtheta = next.end.theta - last.end.theta;
    let dhole = norm2([next.hole[0] - last.hole[0], next.hole[1] - last.hole[1]]);
    let turn_ok = if loaded { dtheta.abs() <= R::from_f64(0.8) } else { dtheta >= -R::from_f64(1e-9) && dtheta <= R::from_f64(0.8) };
    turn_ok && dhole <= R::from_f64(0.5) * f.p.hinge_len()
}

/// Whether the equilibrium tangent at a solved state is (nearly) singular: the branch
/// turns back there (a limit point), so no solution exists just beyond it.
fn near_limit_point<R: Real>(f: &Finger<R>, c: &[Mat3<R>; MAX_SUB], tension: R, st: &JointState<R>, held: Option<super::TipLoad<R>>) -> bool {
    if f.hole_residual(c, tension, st.hole, held).is_err() {
        return false;
    }
    match f.joint_tangent(c, tension, st.hole, held) {
        Ok(j) => (j[0][0] * j[1][1] - j[0][1] * j[1][0]).abs() < R::from_f64(0.2),
        Err(_) => false,
    }
}

/// `Finger::joint_equilibrium`: Newton from the guess, else load continuation.
pub(super) fn joint_equilibrium<R: Real>(
    f: &Finger<R>,
    joint: usize,
    c: &[Mat3<R>; MAX_SUB],
    tension: R,
    guess: Option<[R; 2]>,
    tol: R,
) -> Result<JointEquilibrium<R>, Error> {
    if !tension.is_finite() || tension < R::zero() {
        return Err(Error::Input { input: "tension", reason: "a cable cannot push: tension must be >= 0" });
    }
    let tol = tol.max(f.resolution());
    let k = joint.max(1) - 1;
    let warm = guess.and_then(|b| match f.newton_dual(c, tension, b, f.held_at(k, R::one()), tol, 40) {
        Ok((st, it)) if norm2([st.hole[0] - b[0], st.hole[1] - b[1]]) <= f.p.hinge_len() / R::from_f64(2.0) => Some((st, it)),
        _ => None,
    });
    let (st, iterations) = match warm {
        Some(v) => v,
        None => newton_joint(f, k, c, tension, tol, 200, tension / R::from_f64(4096.0))?,
    };
    let link = f.held_link_q(k, tension);
    Ok(JointEquilibrium { q: st.q, end: st.end, hole: st.hole, link, angle: st.end.theta + link[2], iterations })
}
