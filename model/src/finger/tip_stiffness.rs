//! Tip stiffness at a solved posture (docs/model.md "Tip stiffness"): the linearised tip
//! compliance Σ J C Jᵀ and its inverse, and the equilibrium residual as an independent check
//! of any solve.

use super::{norm2, Compliances, Finger, Heading, Solution};
use crate::error::Error;
use crate::mat3::{self, Mat3, Vec3};
use crate::params::MAX_JOINTS;
use crate::real::Real;

impl<R: Real> Finger<R> {
    /// Linearised tip compliance `C_tip = Σ J C Jᵀ` over every sub-element (docs/model.md "Tip
    /// stiffness"), J mapping a sub-element's distal-end displacement (its proximal frame,
    /// rotation about its distal end) to the tip's (x, y, θ) in the base frame.
    pub fn tip_compliance(&self, c: &Compliances<R>, sol: &Solution<R>) -> Mat3<R> {
        let n = sol.n;
        let tip = sol.nodes[n];
        let mut ct = mat3::zero();
        let mut node = Heading::origin();
        for k in 0..n {
            let mut pose = node;
            for j in 0..sol.m {
                let qj = sol.q[k][j];
                let (s, co) = (pose.s, pose.c);
                let next = pose.then(self.sub_len + qj[0], qj[1], qj[2]);
                let (dx, dy) = (tip.x - next.pose.x, tip.y - next.pose.y);
                let jm: Mat3<R> = [[co, -s, -dy], [s, co, dx], [R::zero(), R::zero(), R::one()]];
                let jc = mat3::mul(&jm, &c.c[k][j]);
                ct = mat3::add(&ct, &mat3::mul(&jc, &mat3::transpose(&jm)));
                pose = next;
            }
            if self.p.flex_links {
                let (s, co) = (pose.s, pose.c);
                let end = sol.nodes[k + 1];
                let (dx, dy) = (tip.x - end.x, tip.y - end.y);
                let jm: Mat3<R> = [[co, -s, -dy], [s, co, dx], [R::zero(), R::zero(), R::one()]];
                let jc = mat3::mul(&jm, &self.link_c);
                ct = mat3::add(&ct, &mat3::mul(&jc, &mat3::transpose(&jm)));
            }
            let l = sol.links[k];
            node = pose.then(self.link_len + l[0], l[1], l[2]);
        }
        ct
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
            let mut lumps = [[[R::zero(); 2]; 3]; MAX_JOINTS];
            let mut node = Heading::origin();
            for k in 0..n {
                let end = self.walk(&sol.q[k]).pose;
                let hinge_end = node.then(end.x, end.y, end.theta);
                lumps[k] = self.lumps_of(&node, &hinge_end);
                let l = sol.links[k];
                node = hinge_end.then(self.link_len + l[0], l[1], l[2]);
            }
            centroids = w.centroids(n, &lumps);
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
