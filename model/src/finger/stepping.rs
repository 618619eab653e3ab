//! The paper's explicit load stepping (Eq. 29): each step's loads from the geometry of the
//! step before, first order in 1/n_inc. Not the converged solve.

use super::{Compliances, Finger, Heading, JointState, MarchError, Solution, SpanLoads, TipLoad};
use crate::error::Error;
use crate::mat3::{self, Mat3};
use crate::params::{MAX_JOINTS, MAX_SUB};
use crate::real::Real;

/// The paper's explicit load stepping (Eq. 29), `n_inc` steps.
pub(super) fn solve<R: Real>(f: &Finger<R>, c: &Compliances<R>, tension: R, tip_force: [R; 2], n_inc: u32) -> Result<Solution<R>, Error> {
    f.check_load(c, tension, tip_force)?;
    if n_inc == 0 {
        return Err(Error::Input { input: "n_inc", reason: "at least one load step" });
    }
    let states = states(f, c, tension, tip_force, n_inc)?;
    f.assemble(c, tension, tip_force, &states, None, n_inc)
}

/// The paper's load stepping (Eq. 29): P_n = n/n_inc P; each step's loads (direction of the
/// span, moment arms, tip-load point) come from the geometry of the step before, and each
/// sub-element takes `q = C w` at once.
// same parameters as `loaded::newton_coupled` (the finger's loads): the paper's stepping, another solver
fn states<R: Real>(f: &Finger<R>, c: &Compliances<R>, tension: R, force: [R; 2], n_inc: u32) -> Result<[JointState<R>; MAX_JOINTS], Error> {
    let n = f.p.n;
    let mut states = [f.straight(); MAX_JOINTS];
    let loaded = force[0] != R::zero() || force[1] != R::zero();
    for step in 1..=n_inc {
        let lam = R::from_u32(step) / R::from_u32(n_inc);
        let p = tension * lam;
        let load = [force[0] * lam, force[1] * lam];
        let (nodes, _) = f.chain(&states, p, load, None);
        let tip = [nodes[n].pose.x, nodes[n].pose.y];
        // the weight (docs/model.md "Gravity"), its share and centroids from the step before
        let weights = f.weights();
        let centroids = weights.as_ref().map_or([[R::zero(); 2]; MAX_JOINTS], |w| f.centroids_of_chain(w, &nodes, &states));
        let mut next = states;
        for k in 0..n {
            let tl = f
                .joint_ext_load(k, if loaded { Some((load, tip)) } else { None }, weights.as_ref().map(|w| (w, lam, centroids[k])))
                .map(|l| Finger::load_in_frame(&nodes[k], l));
            next[k] = explicit_step(f, &c.c[k], p, &states[k], tl).map_err(|_| Error::Contact { joint: k + 1, tension: p.to_f64() })?;
        }
        states = next;
    }
    Ok(states)
}

/// One explicit step for a joint: loads from the previous geometry `prev`.
fn explicit_step<R: Real>(
    f: &Finger<R>,
    c: &[Mat3<R>; MAX_SUB],
    tension: R,
    prev: &JointState<R>,
    tip: Option<TipLoad<R>>,
) -> Result<JointState<R>, MarchError> {
    let e = f.p.e;
    let b = prev.hole;
    let SpanLoads { fc, ft, tp, tc, ftot } = f.span_loads(tension, b, tip)?;
    let mut frame = Heading::origin();
    let mut q = [[R::zero(); 3]; MAX_SUB];
    for j in 0..f.p.m {
        let (s, co) = (frame.s, frame.c);
        let qp = prev.q[j];
        // previous distal end of this sub-element
        let d = frame.point(f.sub_len + qp[0], qp[1]);
        let mut mo = (b[0] - d[0]) * fc[1] - (b[1] - d[1]) * fc[0];
        if tip.is_some() {
            mo += (tp[0] - d[0]) * ft[1] - (tp[1] - d[1]) * ft[0] + tc;
        }
        let fj = [co * ftot[0] + s * ftot[1], -s * ftot[0] + co * ftot[1]];
        q[j] = mat3::mul_vec(&c[j], &[fj[0], fj[1], mo]);
        frame = frame.then(f.sub_len + qp[0], qp[1], qp[2]);
    }
    // new geometry from the new q
    let end = f.walk(&q);
    let hole = end.point(R::zero(), e);
    if !(hole[0].is_finite() && hole[1].is_finite()) {
        return Err(MarchError::Singular);
    }
    Ok(JointState { q, end: end.pose, hole, tangent: None })
}
