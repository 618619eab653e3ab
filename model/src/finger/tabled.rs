//! The converged equilibrium under tension alone started from a guide-hole guess per joint
//! (a branch table's): one march per distinct joint, Newton only where that march is not
//! converged, the posture written in place. The same answer as `tension`'s solve.

use super::{march, norm2, tension, Compliances, Finger, JointState, Method, Pose, Solution};
use crate::error::Error;
use crate::mat3::Mat3;
use crate::params::{MAX_JOINTS, MAX_SUB};
use crate::real::Real;

/// The converged equilibrium under tension alone (docs/model.md "Equilibrium", the joints
/// decoupled) started from a guide-hole guess per joint (a branch table's,
/// `inverse::BranchTable::solve_into`), written into the caller's `sol`: Newton on the full
/// model from the guess, its first evaluation one plain march; a march whose residual is
/// within the converged solver's tolerance is the answer (Newton's own test at its first
/// evaluation), else Newton with dual marches from the guess, else the load continuation
/// of `solve`. The same tolerance and answer as `solve_with(Method::converged())`.
/// `tangent_det` is 1 for a joint answered at its first march (not evaluated). On an error
/// `sol` holds no solution.
#[inline(never)]
pub(super) fn solve_from_holes_into<R: Real>(
    f: &Finger<R>,
    c: &Compliances<R>,
    tension: R,
    holes: &[[R; 2]; MAX_JOINTS],
    sol: &mut Solution<R>,
) -> Result<(), Error> {
    f.check_load(c, tension, [R::zero(); 2])?;
    let Method::Converged { tol, max_iter } = Method::<R>::converged() else { return Err(Error::Singular { what: "method" }) };
    let tol = tol.max(f.resolution());
    fill_from_holes(f, c, tension, holes, tol, max_iter, sol)
}

/// `solve_from_holes_into`'s joints and posture, written in place in one pass: the
/// solution's scalars set, the rows it held past this finger's (n, m) cleared (only
/// those), one march per distinct joint into its rows (`march_tension`; Newton,
/// `polish_joint`, only where that march is not converged), and the posture as it goes
/// (docs/model.md "Equilibrium": node k = node k-1 ∘ hinge ∘ link; "Cable": the excursion
/// Σ (L_h - |span k|)): `chain_ends` with the node rotations composed from the marches' own
/// (sin, cos) and the link's (the same for every link under tension alone, by the series
/// turn). A span below its floor is contact.
#[inline(always)]
fn fill_from_holes<R: Real>(
    f: &Finger<R>,
    c: &Compliances<R>,
    tension: R,
    holes: &[[R; 2]; MAX_JOINTS],
    tol: R,
    max_iter: u32,
    sol: &mut Solution<R>,
) -> Result<(), Error> {
    let (n, m) = (f.p.n, f.p.m);
    // a solution's rows past its own (n, m) are zero (`Solution`): only the rows `sol`
    // held past this finger's (n, m) are cleared (none for `Solution::empty()` or a
    // solution of this finger)
    let (held_n, held_m) = (sol.n.min(MAX_JOINTS), sol.m.min(MAX_SUB));
    for k in 0..held_n {
        let from = if k < n { m } else { 0 };
        if from < held_m {
            for row in sol.q[k][from..held_m].iter_mut() {
                *row = [R::zero(); 3];
            }
        }
    }
    for k in n..held_n {
        sol.nodes[k + 1] = Pose::origin();
        sol.links[k] = [R::zero(); 3];
        sol.joint_angle[k] = R::zero();
        sol.span[k] = R::zero();
        sol.tangent_det[k] = R::one();
    }
    sol.n = n;
    sol.m = m;
    sol.tension = tension;
    sol.tip_force = [R::zero(); 2];
    sol.thickness = c.thickness;
    sol.volts = c.volts;
    let link = f.link_q(tension, None);
    // the link's rotation by the march's turn rule
    let (ls, lc) = march::turn(link[2]);
    let (lx, ly) = (f.link_len + link[0], link[1]);
    let mut node = Pose::origin();
    let (mut s, mut co) = (R::zero(), R::one());
    sol.nodes[0] = node;
    // the joint before: hinge end, (sin, cos) of its angle and squared residual (its
    // tangent determinant and span are read back from `sol`: fewer values held across a
    // march)
    let mut prev = (Pose::origin(), [R::zero(), R::one()], R::zero());
    let (mut res2, mut iters, mut excursion, mut dets) = (R::zero(), 0u32, R::zero(), R::zero());
    for k in 0..n {
        let b = holes[k];
        // a joint with the same voltage, thickness and guess as the one before has its
        // state (`compliances` makes a joint's compliances a function of its voltage; the
        // first sub-element's are compared too)
        let (end, turn, r2, det, span) =
            if k > 0 && b == holes[k - 1] && c.volts[k] == c.volts[k - 1] && c.thickness[k] == c.thickness[k - 1] && c.c[k][0] == c.c[k - 1][0] {
                // the whole row: its sub-elements past m are zero in both
                sol.q[k] = sol.q[k - 1];
                (prev.0, prev.1, prev.2, sol.tangent_det[k - 1], sol.span[k - 1])
            } else {
                let (end, turn, hole, r2, det) = match f.march_cable(&march::ByCompliance(&c.c[k]), tension, b, &mut sol.q[k]) {
                    Ok((end, hole, sc, r2)) if r2 <= tol * tol => (end, sc, hole, r2, R::one()),
                    _ => {
                        let (st, it) = polish_joint(f, k, &c.c[k], tension, b, tol, max_iter)?;
                        iters += it;
                        sol.q[k][..m].copy_from_slice(&st.q[..m]);
                        let (se, ce) = march::turn(st.end.theta);
                        let (r, det) = st.tangent.unwrap_or(([R::zero(); 2], R::one()));
                        (st.end, [se, ce], st.hole, r[0] * r[0] + r[1] * r[1], det)
                    }
                };
                // the span as the final geometry has it (not the one the loads came from)
                (end, turn, r2, det, norm2([hole[0], hole[1] - f.p.e]))
            };
        prev = (end, turn, r2);
        res2 += r2;
        dets += det;
        sol.tangent_det[k] = det;
        let [se, ce] = turn;
        let hinge = Pose { x: node.x + co * end.x - s * end.y, y: node.y + s * end.x + co * end.y, theta: node.theta + end.theta };
        let (hs, hc) = (s * ce + co * se, co * ce - s * se);
        node = Pose { x: hinge.x + hc * lx - hs * ly, y: hinge.y + hs * lx + hc * ly, theta: hinge.theta + link[2] };
        (s, co) = (hs * lc + hc * ls, hc * lc - hs * ls);
        sol.nodes[k + 1] = node;
        sol.links[k] = link;
        sol.joint_angle[k] = end.theta + link[2];
        if !(span >= f.p.span_floor) {
            return Err(Error::Contact { joint: k + 1, tension: tension.to_f64() });
        }
        sol.span[k] = span;
        excursion += f.p.hinge_len() - span;
    }
    sol.iterations = iters;
    sol.cable_excursion = excursion;
    sol.residual = res2.sqrt();
    // a non-finite node carries on to the tip; one test for all (a sum is finite only if
    // every term is)
    if !(node.x + node.y + node.theta + res2 + excursion + dets).is_finite() {
        return Err(Error::Singular { what: "solution (non-finite)" });
    }
    Ok(())
}

/// Joint k's equilibrium from the hole guess `b` (`solve_from_holes_into`) when its first march
/// is not converged: Newton from `b` (dual marches), accepted if it stays within half a
/// hinge length of the guess; else the load continuation from the straight joint.
#[inline(never)]
fn polish_joint<R: Real>(f: &Finger<R>, k: usize, c: &[Mat3<R>; MAX_SUB], tension: R, b: [R; 2], tol: R, max_iter: u32) -> Result<(JointState<R>, u32), Error> {
    match f.newton_dual(c, tension, b, f.held_at(k, R::one()), tol, max_iter) {
        Ok((st, it)) if norm2([st.hole[0] - b[0], st.hole[1] - b[1]]) <= f.p.hinge_len() / R::from_f64(2.0) => Ok((st, it)),
        _ => tension::newton_joint(f, k, c, tension, tol, max_iter, tension / R::from_f64(4096.0)),
    }
}
