//! The posture chain (docs/model.md "Equilibrium": node k = node k-1 ∘ hinge ∘ link): link
//! deflections, node poses, the tip load in a joint's frame, and the assembled `Solution`.
//! No solving here.

use super::{norm2, Compliances, Finger, Heading, JointState, Pose, Solution, TipLoad};
use crate::error::Error;
use crate::mat3;
use crate::params::{MAX_JOINTS, MAX_SUB};
use crate::real::Real;

impl<R: Real> Finger<R> {
    /// Link compliance, `q = C_link w` (a uniform beam; the model's `flex_links`, docs/model.md).
    /// Deflection of a link (proximal frame `hinge_end`, base frame) when `flex_links` is set:
    /// the cable inside the link compresses it with P at the offset e (moment P·e about its
    /// axis), plus the tip load if any; linear, loads in the undeformed link frame.
    /// `tip`: the hinge's end (the link's proximal frame), the tip force and its point.
    pub(super) fn link_q(&self, tension: R, tip: Option<(&Heading<R>, TipLoad<R>)>) -> [R; 3] {
        if !self.p.flex_links {
            return [R::zero(); 3];
        }
        mat3::mul_vec(&self.link_c, &self.link_wrench(tension, tip))
    }

    /// `link_q`'s wrench (Fx, Fy, M) on a link's distal end, in its undeformed frame.
    pub(super) fn link_wrench(&self, tension: R, tip: Option<(&Heading<R>, TipLoad<R>)>) -> [R; 3] {
        let mut w = [-tension, R::zero(), tension * self.p.e];
        if let Some((hinge_end, load)) = tip {
            let end = hinge_end.then(self.link_len, R::zero(), R::zero());
            let tl = Self::load_in_frame(&end, load);
            let (s, c) = (hinge_end.s, hinge_end.c);
            let force = load.force;
            w[0] += c * force[0] + s * force[1];
            w[1] += -s * force[0] + c * force[1];
            w[2] += tl.point[0] * tl.force[1] - tl.point[1] * tl.force[0] + tl.couple;
        }
        w
    }

    /// A joint's hinge end from its sub-elements' displacements `q` (its first m rows), in the
    /// joint's proximal frame.
    pub(crate) fn walk(&self, q: &[[R; 3]; MAX_SUB]) -> Heading<R> {
        q.iter().take(self.p.m).fold(Heading::origin(), |h, q| h.then(self.sub_len + q[0], q[1], q[2]))
    }

    /// Nodes 0..=n (node k-1 is joint k's proximal frame; node n the tip) for given joint
    /// states, and each link's deflection.
    pub(super) fn chain(
        &self,
        states: &[JointState<R>; MAX_JOINTS],
        tension: R,
        tip_force: [R; 2],
        tip_point: Option<[R; 2]>,
    ) -> ([Heading<R>; MAX_JOINTS + 1], [[R; 3]; MAX_JOINTS]) {
        let mut ends = [Pose::origin(); MAX_JOINTS];
        for k in 0..self.p.n {
            ends[k] = states[k].end;
        }
        self.chain_ends(&ends, tension, tip_force, tip_point)
    }

    /// `chain` from each joint's hinge end pose alone.
    // same parameters as `chain`, which only gathers the ends and calls this
    pub(super) fn chain_ends(
        &self,
        ends: &[Pose<R>; MAX_JOINTS],
        tension: R,
        tip_force: [R; 2],
        tip_point: Option<[R; 2]>,
    ) -> ([Heading<R>; MAX_JOINTS + 1], [[R; 3]; MAX_JOINTS]) {
        let loaded = tip_force[0] != R::zero() || tip_force[1] != R::zero();
        let mut nodes = [Heading::origin(); MAX_JOINTS + 1];
        let mut links = [[R::zero(); 3]; MAX_JOINTS];
        // with a tip load on flexible links the tip point enters the links' loads: the solved
        // tip when the caller has it (the coupled and pinned solves carry it as an unknown),
        // else a fixed point on the tip from the rigid-link tip (the load stepping); the
        // weight beyond each link (docs/model.md "Gravity") likewise, from the chain before
        let n = self.p.n;
        let weights = if self.p.flex_links { self.weights() } else { None };
        let given = tip_point.is_some();
        let passes = if self.p.flex_links && ((loaded && !given) || weights.is_some()) { 8 } else { 1 };
        let mut tip_point = if loaded && self.p.flex_links { tip_point } else { None };
        let mut centroids: Option<[[R; 2]; MAX_JOINTS]> = None;
        let mut lumps = [[[R::zero(); 2]; 3]; MAX_JOINTS];
        for _ in 0..passes {
            let tip = if loaded { tip_point.map(|t| (tip_force, t)) } else { None };
            for k in 0..n {
                let e = ends[k];
                let hinge_end = nodes[k].then(e.x, e.y, e.theta);
                let grav = match (&weights, centroids) {
                    (Some(w), Some(c)) => Some((w, R::one(), c[(k + 1).min(n - 1)])),
                    _ => None,
                };
                links[k] = if loaded && tip.is_none() {
                    [R::zero(); 3]
                } else {
                    self.link_q(tension, self.link_load(k, &hinge_end, tip, grav).map(|l| (&hinge_end, l)))
                };
                lumps[k] = self.lumps_of(&nodes[k], &hinge_end);
                let q = links[k];
                nodes[k + 1] = hinge_end.then(self.link_len + q[0], q[1], q[2]);
            }
            let new_tip = [nodes[n].pose.x, nodes[n].pose.y];
            let mut settled = given || !(loaded && self.p.flex_links);
            if let Some(t) = tip_point {
                settled |= (new_tip[0] - t[0]).abs() + (new_tip[1] - t[1]).abs() <= self.resolution();
            }
            if let Some(w) = &weights {
                let now = w.centroids(n, &lumps);
                if let Some(before) = centroids {
                    let moved = (0..n).map(|k| (now[k][0] - before[k][0]).abs() + (now[k][1] - before[k][1]).abs()).fold(R::zero(), |a, b| a.max(b));
                    settled &= moved <= self.resolution();
                } else {
                    settled = false;
                }
                centroids = Some(now);
            }
            if settled {
                break;
            }
            if !given {
                tip_point = Some(new_tip);
            }
        }
        (nodes, links)
    }

    /// A base-frame load as a frame sees it (the couple is the same in every frame).
    pub(super) fn load_in_frame(frame: &Heading<R>, l: TipLoad<R>) -> TipLoad<R> {
        let (s, c) = (frame.s, frame.c);
        let (force, point) = (l.force, l.point);
        let dx = point[0] - frame.pose.x;
        let dy = point[1] - frame.pose.y;
        TipLoad { force: [c * force[0] + s * force[1], -s * force[0] + c * force[1]], point: [c * dx + s * dy, -s * dx + c * dy], couple: l.couple }
    }

    /// Collect the solution: nodes, joint angles, spans, excursion, residual, tangents.
    pub(super) fn assemble(
        &self,
        c: &Compliances<R>,
        tension: R,
        tip_force: [R; 2],
        states: &[JointState<R>; MAX_JOINTS],
        tip_point: Option<[R; 2]>,
        iterations: u32,
    ) -> Result<Solution<R>, Error> {
        let n = self.p.n;
        let (heads, links) = self.chain(states, tension, tip_force, tip_point);
        let nodes = Heading::poses(&heads);
        let mut sol = Solution { n, m: self.p.m, tension, tip_force, nodes, thickness: c.thickness, volts: c.volts, iterations, ..Solution::empty() };
        let loaded = tip_force[0] != R::zero() || tip_force[1] != R::zero();
        // the solved tip (the load's point in the joints' residuals), and its mismatch with
        // the chain's tip in the residual
        let chain_tip = [nodes[n].x, nodes[n].y];
        let tip = tip_point.unwrap_or(chain_tip);
        let mut res2 = (tip[0] - chain_tip[0]).sq() + (tip[1] - chain_tip[1]).sq();
        // under gravity each joint's distal weight at the centroid the chain puts it
        // (docs/model.md "Gravity"): the joints are coupled, as under a tip load
        let weights = self.weights();
        let centroids = weights.as_ref().map_or([[R::zero(); 2]; MAX_JOINTS], |w| self.centroids_of_chain(w, &heads, states));
        let coupled = loaded || weights.is_some();
        // residual and tangent determinant of the joint before (tension alone)
        let mut prev: Option<([R; 2], R)> = None;
        for k in 0..n {
            let st = &states[k];
            sol.q[k] = st.q;
            sol.links[k] = links[k];
            sol.joint_angle[k] = st.end.theta + links[k][2];
            // the span as the final geometry has it (not the one the loads came from)
            let span = norm2([st.hole[0], st.hole[1] - self.p.e]);
            if !(span >= self.p.span_floor) {
                return Err(Error::Contact { joint: k + 1, tension: tension.to_f64() });
            }
            sol.span[k] = span;
            sol.cable_excursion += self.p.hinge_len() - span;
            let tl = self
                .joint_ext_load(k, if loaded { Some((tip_force, tip)) } else { None }, weights.as_ref().map(|w| (w, R::one(), centroids[k])))
                .map(|l| Self::load_in_frame(&heads[k], l))
                .or(self.held_at(k, R::one()));
            // tension alone: one dual march gives the residual and the exact tangent; a joint
            // equal to the one before (same compliance, same hole) has the same ones
            let same = k > 0 && c.c[k][..self.p.m] == c.c[k - 1][..self.p.m] && st.hole == states[k - 1].hole && self.same_held(k, k - 1);
            let dual = match (coupled || self.held_at(k, R::one()).is_some(), same, prev) {
                (true, _, _) => None,
                (false, true, Some(p)) => Some(p),
                (false, _, _) => self.eval_dual(&c.c[k], tension, st.hole, None).ok().map(|(_, r, j)| (r, j[0][0] * j[1][1] - j[0][1] * j[1][0])),
            };
            prev = dual;
            if let Some((r, det)) = dual {
                res2 += r[0] * r[0] + r[1] * r[1];
                sol.tangent_det[k] = det;
                continue;
            }
            // its residual and tangent from one dual march (its value part is the plain march's),
            // else the residual from the plain march
            match self.eval_dual(&c.c[k], tension, st.hole, tl) {
                Ok((_, r, jac)) => {
                    res2 += r[0] * r[0] + r[1] * r[1];
                    sol.tangent_det[k] = jac[0][0] * jac[1][1] - jac[0][1] * jac[1][0];
                }
                Err(_) => match self.hole_residual(&c.c[k], tension, st.hole, tl) {
                    Ok((r, _)) => res2 += r[0] * r[0] + r[1] * r[1],
                    Err(_) => return Err(Error::Contact { joint: k + 1, tension: tension.to_f64() }),
                },
            }
        }
        sol.residual = res2.sqrt();
        Self::check_finite(&nodes, &sol)?;
        Ok(sol)
    }

    /// A solution's nodes 0..=n, residual, excursion and tangent determinants are finite (no
    /// `Ok` result carries a NaN or an infinity).
    pub(super) fn check_finite(nodes: &[Pose<R>; MAX_JOINTS + 1], sol: &Solution<R>) -> Result<(), Error> {
        let n = sol.n;
        let all_finite = nodes.iter().take(n + 1).all(|p| p.x.is_finite() && p.y.is_finite() && p.theta.is_finite())
            && sol.residual.is_finite()
            && sol.cable_excursion.is_finite()
            && sol.tangent_det[..n].iter().all(|d| d.is_finite());
        if !all_finite {
            return Err(Error::Singular { what: "solution (non-finite)" });
        }
        Ok(())
    }
}
