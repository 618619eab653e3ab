//! Tip stiffness at a solved posture (docs/model.md "Tip stiffness"): the linearised tip
//! compliance Σ J C Jᵀ and its inverse, and the equilibrium residual as an independent check
//! of any solve.

use super::{loaded, Compliances, Finger, Heading, Solution, COUPLED};
use crate::error::Error;
use crate::mat3::{self, Mat3};
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

    /// The forward equilibrium residual of a solved posture under its own tension, voltages
    /// and tip load (docs/model.md "Equilibrium": each guide hole where its joint's march puts it,
    /// the tip where the chain ends), mm: the coupled system's residual, evaluated afresh from
    /// the solution's holes and tip. An independent check of any solve (forward, pinned).
    pub fn equilibrium_residual(&self, sol: &Solution<R>) -> Result<R, Error> {
        let n = self.p.n;
        if sol.n != n || sol.m != self.p.m {
            return Err(Error::Input { input: "solution", reason: "solved for other parameters" });
        }
        let c = self.compliances(&sol.volts[..n])?;
        let mut x = [R::zero(); COUPLED];
        for k in 0..n {
            let hole = self.walk(&sol.q[k]).point(R::zero(), self.p.e);
            x[2 * k] = hole[0];
            x[2 * k + 1] = hole[1];
        }
        x[2 * n] = sol.tip().x;
        x[2 * n + 1] = sol.tip().y;
        let (r, _) =
            loaded::coupled_residual(self, &c, sol.tension, sol.tip_force, &x).map_err(|_| Error::Contact { joint: 0, tension: sol.tension.to_f64() })?;
        Ok(r[..2 * n + 2].iter().fold(R::zero(), |a, &v| a + v * v).sqrt())
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
