//! The inverse for every parameter set the forward model accepts: hinges split into m
//! sub-elements (`Params::m` > 1) and flexible links (`Params::flex_links`), with either
//! modulus (`Params::plate`). One forward march of a joint from a guessed guide hole
//! (`Finger::joint_march`) is the function evaluation; each joint solve is a quasi-Newton
//! solve on (hole, P) at a fixed stack thickness (step 1) or on (hole, t) at a fixed tension
//! (step 4), with a bracketed root behind it. docs/inverse.md "The general path" has the
//! design; steps 2-3 (the interval, the tension rule) are the parent's.
//!
//! - `prepare`: what the solves need, prepared once (`Gen`);
//! - `hold`: a joint held at its target angle (tension or thickness);
//! - `qn`: the quasi-Newton joint solve;
//! - `tabled`: the path from the branch table (`solve_pose_tabled`).
//!
//! Here: the general solve (`solve`) and the finger without stacks.

use super::table::{BranchTable, TableEnd, TABLE_BAND};
use super::{choose_tension, feasible_interval, one_tension, thickness_slack, Options, PoseSolution};
use crate::de;
use crate::error::Error;
use crate::finger::{by, uniform_beam_compliance, By, Finger, JointEquilibrium, JointMarch, JointStiffness, Method, Pose};
use crate::mat3::{self, Mat3};
use crate::params::{Params, MAX_JOINTS, MAX_SUB};
use crate::real::Real;
use crate::solve::{bracket, broyden};

mod build_table;
mod hold;
mod prepare;
mod qn;
mod tabled;

use hold::level_guess;
pub(super) use tabled::solve_tabled;

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
    /// The stack's stiffness as a function of its thickness.
    stack: de::StackStiffness<R>,
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

/// Each joint's two tension ends (softest, stiffest stack), as `choose_tension` takes them.
fn tension_ends<R: Real>(lo: &[Held<R>; MAX_JOINTS], hi: &[Held<R>; MAX_JOINTS], n: usize) -> [[R; 2]; MAX_JOINTS] {
    let mut ends = [[R::zero(); 2]; MAX_JOINTS];
    for k in 0..n {
        ends[k] = [lo[k].tension, hi[k].tension];
    }
    ends
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
        // the same angle (and held load), the same end
        for j in 0..n {
            if angles[j] == angles[k] && f.same_held(j, k) {
                if e == 0 {
                    lo[j] = solved;
                } else {
                    hi[j] = solved;
                }
            }
        }
    }
    // 2-3. the feasible interval and the tension (`choose_tension`); a negative angle is
    //      outside every tension's reach (unless a held load, the weight, bends it back)
    let negative =
        (0..n).filter(|&k| angles[k] < R::zero() && !f.has_held()).min_by(|&a, &b| angles[a].partial_cmp(&angles[b]).unwrap_or(core::cmp::Ordering::Equal));
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
        if k > 0 && angles[k] == angles[k - 1] && f.same_held(k, k - 1) {
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
        // the root find ends at an end of the stack's range when no thickness inside it holds
        // the angle at this tension: refused, not clamped
        let slack = thickness_slack(t0);
        let at_end = held.thickness <= t_top + slack || held.thickness >= t0 - slack;
        if at_end && (held.st.angle - angles[k]).abs() > R::from_f64(16.0) * g.angle_atol(angles[k]) {
            return Err(Error::NotConverged { iterations: g.iters, residual: f64::INFINITY });
        }
        let t = held.thickness.max(t_top).min(t0);
        out.thickness[k] = t;
        out.volts[k] = if t >= t0 { R::zero() } else { de::voltage_for_thickness(p, k + 1, t)?.min(v_top) };
        record(out, k, lh, &held);
    }
    out.iterations = g.iters;
    Ok(())
}

/// The finger without stacks: only the tension is free (the parent's rule).
#[inline(never)]
fn no_stacks<R: Real>(g: &mut Gen<'_, R>, angles: &[R], tension: Option<R>, opts: &Options<R>, out: &mut PoseSolution<R>) -> Result<(), Error> {
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
        if k > 0 && angles[k] == angles[k - 1] && g.f.same_held(k, k - 1) {
            h[k] = h[k - 1];
            out.sub_q[k] = out.sub_q[k - 1];
        } else {
            let hint = (0..k).rev().find(|&j| h[j].tension > z).map(|j| (angles[k] * h[j].tension / angles[j], h[j].st.hole));
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
        return Err(Error::Unreachable { joint: k + 1, needed: g.compliance(angles[k], pt, &h[k].st, cl).to_f64(), min: have, max: have });
    }
    out.tension = pt;
    // the states at the chosen tension: the forward model's posture there (0 V: the hinges
    // alone)
    if pt > z {
        let sol = g.f.solve(pt, &[z; MAX_JOINTS][..n], Method::converged())?;
        g.iters += sol.iterations;
        for k in 0..n {
            let end = g.f.walk(&sol.q[k]).pose;
            out.q[k] = [end.x - lh, end.y, end.theta];
            out.sub_q[k] = sol.q[k];
            out.links[k] = sol.links[k];
        }
    }
    out.iterations = g.iters;
    Ok(())
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
        let mut ev = |x: [f64; 3], q: &mut [[f64; 3]; MAX_SUB]| f.joint_march(1, by::Compliance(&c0), x[2], [x[0], x[1]], q);
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
            f.joint_march(1, by::Compliance(&c), pt, [x[0], x[1]], qb)
        };
        let (r, _) = g.broyden(&mut ev, [q.x[0], q.x[1], t0 * 0.995], [lh, lh, t0], q.jac.unwrap(), [false, false, true], theta, &mut qb);
        let r = r.expect("Broyden converges for the thickness");
        assert!(r.x[2] < t0);
        let eq = f.joint_equilibrium(1, &g.comp(r.x[2]).unwrap(), pt, None, 1e-12).unwrap();
        assert!((eq.angle - theta).abs() < 1e-10, "{} vs {theta}", eq.angle);
    }
}
