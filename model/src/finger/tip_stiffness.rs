//! Tip stiffness at a solved posture (docs/model.md "Tip stiffness"): the linearised tip
//! compliance Σ J C Jᵀ and its inverse, and the equilibrium residual as an independent check
//! of any solve.

use super::{norm2, Compliances, Finger, Heading, Solution};
use crate::error::Error;
use crate::mat3::{self, Mat3, Vec3};
use crate::params::MAX_JOINTS;
use crate::real::Real;

impl<R: Real> Finger<R> {
    /// Linearised tip compliance (docs/model.md "Tip stiffness"): `C_tip = Σ J C Jᵀ` over every
    /// sub-element and flexible link, J mapping a segment's distal-end displacement (its
    /// proximal frame, rotation about its distal end) to the tip's (x, y, θ) in the base frame;
    /// under gravity with the weight's posture-dependent term, `C_tip = J (C⁻¹ - G)⁻¹ Jᵀ`, G the
    /// Hessian of the lumped weights' work (`weight_terms`), solved by one sweep from the base to
    /// the tip (without weight the sweep is Σ J C Jᵀ: G = 0).
    pub fn tip_compliance(&self, c: &Compliances<R>, sol: &Solution<R>) -> Mat3<R> {
        let n = sol.n;
        let tip = sol.nodes[n];
        let terms = self.weight_terms(sol);
        // G couples every pair of DOFs (u upstream of d) by ω_u g_d, ω 1 for a rotation: segment
        // s's equations (C_s⁻¹ - g_θ e3 e3ᵀ) dq_s = Jᵀ dF + A g_s + B e3, A the rotation of the
        // segments before it, B = Σ g·dq over the segments after it; B at the first segment is
        // the sweep's one unknown X, each quantity affine in it (value, coefficient of X), and
        // B after the last is 0. One sweep for the three unit loads (Fx, Fy, M) at once.
        let z = R::zero();
        let mut rot = [[z; 2]; 3];
        let mut after = [[z, R::one()]; 3];
        let mut du = [[[z; 2]; 3]; 3];
        let mut node = Heading::origin();
        let mut segment = |pose: &Heading<R>, next: &Heading<R>, cs: &Mat3<R>, load: ([R; 2], R)| {
            let (s, co) = (pose.s, pose.c);
            let d = [next.pose.x, next.pose.y];
            let (dx, dy) = (tip.x - d[0], tip.y - d[1]);
            let jm: Mat3<R> = [[co, -s, -dy], [s, co, dx], [z, z, R::one()]];
            // g: the weight beyond (force f, Σ p·f) against this segment's three motions
            let (f, pf) = load;
            let g = [co * f[1] - s * f[0], -s * f[1] - co * f[0], d[0] * f[0] + d[1] * f[1] - pf];
            // (C⁻¹ - g_θ e3 e3ᵀ)⁻¹ v = C v + γ c3 (c3 · v) (Sherman-Morrison), c3 = C e3
            let c3 = [cs[0][2], cs[1][2], cs[2][2]];
            let gamma = g[2] / (R::one() - g[2] * c3[2]);
            let solve = |v: [R; 3]| {
                let cv = mat3::mul_vec(cs, &v);
                let k = gamma * (c3[0] * v[0] + c3[1] * v[1] + c3[2] * v[2]);
                [cv[0] + k * c3[0], cv[1] + k * c3[1], cv[2] + k * c3[2]]
            };
            let (q, w) = (solve(g), solve([z, z, R::one()]));
            let (gq, gw) = (g[0] * q[0] + g[1] * q[1] + g[2] * q[2], g[0] * w[0] + g[1] * w[1] + g[2] * w[2]);
            for r in 0..3 {
                // the load's generalized force on this segment, Jᵀ e_r
                let p = solve([jm[r][0], jm[r][1], jm[r][2]]);
                let gp = g[0] * p[0] + g[1] * p[1] + g[2] * p[2];
                let mut dq = [[z; 2]; 3];
                let mut b = [z; 2];
                for a in 0..2 {
                    let base = if a == 0 { gp } else { z };
                    b[a] = (after[r][a] - base - rot[r][a] * gq) / (R::one() + gw);
                    for i in 0..3 {
                        dq[i][a] = (if a == 0 { p[i] } else { z }) + rot[r][a] * q[i] + b[a] * w[i];
                    }
                }
                for a in 0..2 {
                    after[r][a] = b[a];
                    rot[r][a] += dq[2][a];
                    for i in 0..3 {
                        du[r][i][a] += jm[i][0] * dq[0][a] + jm[i][1] * dq[1][a] + jm[i][2] * dq[2][a];
                    }
                }
            }
        };
        for k in 0..n {
            let mut pose = node;
            for j in 0..sol.m {
                let qj = sol.q[k][j];
                let next = pose.then(self.sub_len + qj[0], qj[1], qj[2]);
                segment(&pose, &next, &c.c[k][j], terms[k].0);
                pose = next;
            }
            let l = sol.links[k];
            let end = pose.then(self.link_len + l[0], l[1], l[2]);
            if self.p.flex_links {
                segment(&pose, &end, &self.link_c, terms[k].1);
            }
            node = end;
        }
        // B after the last segment is 0: X from each load's coefficient
        let mut ct = mat3::zero();
        for r in 0..3 {
            let x = if after[r][1] != z { -after[r][0] / after[r][1] } else { z };
            for i in 0..3 {
                ct[i][r] = du[r][i][0] + x * du[r][i][1];
            }
        }
        ct
    }

    /// Under gravity, the lumped weight beyond each joint's sub-elements and beyond each link
    /// (its force, N, and Σ p·f over its lumps, N·mm, base frame, at the posture `sol`): the
    /// weight's term in the tip compliance. Zero without gravity.
    fn weight_terms(&self, sol: &Solution<R>) -> [(([R; 2], R), ([R; 2], R)); MAX_JOINTS] {
        let n = sol.n;
        let z = R::zero();
        let mut out = [(([z; 2], z), ([z; 2], z)); MAX_JOINTS];
        let Some(w) = self.weights() else { return out };
        let (half, link) = (w.force(w.half_hinge_g), w.force(w.link_g));
        let dot = |p: [R; 2], f: [R; 2]| p[0] * f[0] + p[1] * f[1];
        let (_, _, lumps) = self.chain_at_posture(&sol.q, &sol.links);
        // from the tip back: beyond link k, every lump of the elements after it; beyond joint
        // k's sub-elements, its hinge's distal half, its link's midpoint and those
        let (mut f, mut pf) = ([z; 2], z);
        for k in (0..n).rev() {
            let [prox, end, mid] = lumps[k];
            out[k].1 = (f, pf);
            f = [f[0] + half[0] + link[0], f[1] + half[1] + link[1]];
            pf += dot(end, half) + dot(mid, link);
            out[k].0 = (f, pf);
            f = [f[0] + half[0], f[1] + half[1]];
            pf += dot(prox, half);
        }
        out
    }

    /// The equilibrium residual of a solved posture under its own tension, voltages and tip
    /// load (docs/model.md "Equilibrium": `q = C · w(q)` for every sub-element, `q = C_link w`
    /// for each flexible link, the tip where the chain ends), relative: the largest wrench
    /// imbalance `|C⁻¹ q - w|` over the largest wrench `|w|` (moments over the hinge's length),
    /// w from the posture itself (the cable's pull along each span at its hole, the tip load at
    /// the tip, moments about each deformed distal end), or the tip's mismatch over the
    /// finger's length if larger. A backward error: no re-march, so neither a march's gain nor a
    /// compliance's size enters it. An independent check of any solve (forward, loaded,
    /// pinned); 0 for the unloaded straight finger.
    pub fn equilibrium_residual(&self, sol: &Solution<R>) -> Result<R, Error> {
        let (n, m) = (self.p.n, self.p.m);
        if sol.n != n || sol.m != m {
            return Err(Error::Input { input: "solution", reason: "solved for other parameters" });
        }
        let c = self.compliances(&sol.volts[..n])?;
        let (lh, e, p) = (self.p.hinge_len(), self.p.e, sol.tension);
        let ft = sol.tip_force;
        let loaded = ft[0] != R::zero() || ft[1] != R::zero();
        let tip = [sol.tip().x, sol.tip().y];
        let size = |w: Vec3<R>| (w[0] * w[0] + w[1] * w[1] + (w[2] / lh) * (w[2] / lh)).sqrt();
        let (mut worst_imbalance, mut worst_load) = (R::zero(), R::zero());
        let mut compare = |q: &Vec3<R>, w: Vec3<R>, cm: &Mat3<R>| -> Result<(), Error> {
            let held = mat3::mul_vec(&mat3::inverse_spd(cm).ok_or(Error::Singular { what: "compliance" })?, q);
            worst_imbalance = worst_imbalance.max(size([held[0] - w[0], held[1] - w[1], held[2] - w[2]]));
            worst_load = worst_load.max(size(w)).max(size(held));
            Ok(())
        };
        let cross = |r: [R; 2], f: [R; 2]| r[0] * f[1] - r[1] * f[0];
        // under gravity, the distal centroids where the posture puts the lumps (docs/model.md
        // "Gravity")
        let weights = self.weights();
        let mut centroids = [[R::zero(); 2]; MAX_JOINTS];
        if let Some(w) = &weights {
            centroids = w.centroids(n, &self.chain_at_posture(&sol.q, &sol.links).2);
        }
        let grav = |k: usize| weights.as_ref().map(|w| (w, R::one(), centroids[k.min(n - 1)]));
        let tip_load = if loaded { Some((ft, tip)) } else { None };
        let mut node = Heading::origin();
        for k in 0..n {
            // in the joint's own frame (node k-1), as its march: no rounding of far-off positions
            // enters a short span's direction
            let (ftl, tpl, tcl) = match self.joint_ext_load(k, tip_load, grav(k)) {
                Some(l) => {
                    let t = Self::load_in_frame(&node, l);
                    (t.force, t.point, t.couple)
                }
                None => ([R::zero(); 2], [R::zero(); 2], R::zero()),
            };
            let hinge_end = self.walk(&sol.q[k]);
            // the cable's pull on joint k's distal chain: P along span k at its hole B, toward
            // the proximal node's hole A = (0, e)
            let b = hinge_end.point(R::zero(), e);
            let span_v = [b[0], b[1] - e];
            let span = norm2(span_v);
            if !(span >= self.p.span_floor) {
                return Err(Error::Contact { joint: k + 1, tension: p.to_f64() });
            }
            let fc = [-p * span_v[0] / span, -p * span_v[1] / span];
            let f = [fc[0] + ftl[0], fc[1] + ftl[1]];
            let mut pose = Heading::origin();
            for (q, cj) in sol.q[k][..m].iter().zip(&c.c[k][..m]) {
                let d = pose.then(self.sub_len + q[0], q[1], q[2]);
                let at = [d.pose.x, d.pose.y];
                let moment = cross([b[0] - at[0], b[1] - at[1]], fc) + cross([tpl[0] - at[0], tpl[1] - at[1]], ftl) + tcl;
                compare(q, [pose.c * f[0] + pose.s * f[1], -pose.s * f[0] + pose.c * f[1], moment], cj)?;
                pose = d;
            }
            let end = pose.pose;
            let hinge_end = node.then(end.x, end.y, end.theta);
            let link = sol.links[k];
            if self.p.flex_links {
                compare(&link, self.link_wrench(p, self.link_load(k, &hinge_end, tip_load, grav(k + 1)).map(|l| (&hinge_end, l))), &self.link_c)?;
            }
            node = hinge_end.then(self.link_len + link[0], link[1], link[2]);
        }
        let len = R::from_u32(n as u32) * self.p.l;
        let tip_off = norm2([node.pose.x - tip[0], node.pose.y - tip[1]]) / len;
        let of_loads = if worst_load > R::zero() { worst_imbalance / worst_load } else { R::zero() };
        Ok(of_loads.max(tip_off))
    }

    /// Linearised tip stiffness K_tip = C_tip⁻¹ (rows/columns x mm, y mm, θ rad; N/mm and
    /// N·mm/rad) at a solved posture (with the channel voltages it was solved with).
    pub fn tip_stiffness(&self, sol: &Solution<R>) -> Result<Mat3<R>, Error> {
        let c = self.compliances(&sol.volts[..sol.n])?;
        let ct = self.tip_compliance(&c, sol);
        // C_tip is symmetric positive definite (Σ J C Jᵀ): the cofactor inverse with a
        // scale-free singularity test
        mat3::inverse_spd(&ct).ok_or(Error::Singular { what: "tip compliance" })
    }
}
