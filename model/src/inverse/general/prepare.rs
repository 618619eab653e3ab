//! What the general path's solves need, prepared once per solve (`Gen`): the tolerances, the
//! sub-element compliances at a stack thickness, the stack's range, straight-joint states and
//! the joint's effective compliance. No solving here.

use super::*;

impl<'a, R: Real> Gen<'a, R> {
    #[inline(never)]
    pub(in crate::inverse) fn new(f: &'a Finger<R>, opts: &Options<R>) -> Result<Self, Error> {
        let p = f.params();
        let lh = p.hinge_len();
        let link_rot = if p.flex_links {
            let lc = uniform_beam_compliance(p.hinge_modulus(), p.w, p.b, p.l - lh);
            lc[2][2] * p.e - lc[2][0]
        } else {
            R::zero()
        };
        Ok(Self::with_link_rot(f, opts, link_rot))
    }

    /// `new` with the link's rotation per newton given (zero where `slope0` is not used: the
    /// tabled path, whose slopes the table holds).
    #[inline(always)]
    pub(super) fn with_link_rot(f: &'a Finger<R>, opts: &Options<R>, link_rot: R) -> Self {
        let p = f.params();
        let lh = p.hinge_len();
        let tol_hole = R::from_f64(1e-12) * (lh + p.e);
        Gen {
            f,
            p,
            stack: f.stack(),
            link_rot,
            tol_hole,
            htol: tol_hole.max(f.hole_resolution()),
            tol_angle: R::from_f64(1e-12_f64.max(32.0 * R::EPS)),
            rel: R::from_f64(4.0 * R::EPS),
            max_iter: 2 * opts.max_iter.max(8),
            iters: 0,
        }
    }

    /// Sub-element compliances at stack thickness t, as `Finger::compliances` computes them.
    #[inline(never)]
    pub(in crate::inverse) fn comp(&self, t: R) -> Result<[Mat3<R>; MAX_SUB], Error> {
        let mut c = [mat3::zero(); MAX_SUB];
        self.comp_into(t, &mut c)?;
        Ok(c)
    }

    /// `comp` into `c` (its first m entries; no array returned by value in the hot loop):
    /// `Finger::joint_stiffness`'s compliances; refuses a thickness that is not positive and
    /// finite (K_de ∝ t axially, t³ in bending: positive semi-definite for t > 0).
    #[inline(never)]
    pub(super) fn comp_into(&self, t: R, c: &mut [Mat3<R>; MAX_SUB]) -> Result<(), Error> {
        if self.p.layers != 0 && !(t > R::zero() && t.is_finite()) {
            return Err(Error::Singular { what: "joint stiffness" });
        }
        self.stiffness(t).compliances_into(c)
    }

    /// The joint's stiffness at thickness t (the stack's constants taken once, in `new`).
    #[inline(always)]
    pub(super) fn stiffness(&self, t: R) -> JointStiffness<'a, R> {
        JointStiffness::new(self.f, &self.stack, t)
    }

    /// A joint angle's tolerance at a root (rad): `tol_angle` relative, 0.1 rad added so that
    /// a small angle keeps an absolute floor.
    #[inline(always)]
    pub(super) fn angle_atol(&self, theta: R) -> R {
        self.tol_angle * (theta.abs() + R::from_f64(0.1))
    }

    /// Scale the angle tolerance of the solves (the branch table's samples).
    pub(in crate::inverse) fn tighten(&mut self, k: R) {
        self.tol_angle *= k;
    }

    /// The stack's range: (t0 at 0 V, t_top at `top` x the ceiling, the top voltage).
    #[inline(never)]
    pub(in crate::inverse) fn stack_ends(&self, opts: &Options<R>) -> Result<(R, R, R), Error> {
        let p = self.p;
        let t0 = R::from_u32(p.layers) * p.z0;
        let v_top = self.f.ceiling_in_force(opts.hv_fs) * opts.top;
        let t_top = if v_top > R::zero() { de::stack_thickness(p, 1, v_top)? } else { t0 };
        Ok((t0, t_top, v_top))
    }

    /// The state of a held end: its own if solved, else one march at its tension and hole.
    #[inline(never)]
    pub(super) fn state(&self, joint: usize, c: &[Mat3<R>; MAX_SUB], h: &Held<R>) -> Result<JointMarch<R>, Error> {
        if h.exact || h.tension == R::zero() {
            return Ok(h.st);
        }
        let mut q = [[R::zero(); 3]; MAX_SUB];
        self.f.joint_march(joint, by::Compliance(c), h.tension, h.st.hole, &mut q)
    }

    /// The unloaded joint's state.
    pub(super) fn straight_st(&self) -> JointMarch<R> {
        JointMarch::of_equilibrium(&self.straight())
    }

    /// dθ/dP at P = 0 (straight joint: every sub-element sees the axial force -P and the
    /// moment P e), rad/N.
    #[inline(never)]
    pub(in crate::inverse) fn slope0(&self, c: &[Mat3<R>; MAX_SUB]) -> R {
        let e = self.p.e;
        c.iter().take(self.p.m).fold(self.link_rot, |a, cj| a + cj[2][2] * e - cj[2][0])
    }

    pub(super) fn straight(&self) -> JointEquilibrium<R> {
        let lh = self.p.hinge_len();
        JointEquilibrium {
            q: [[R::zero(); 3]; MAX_SUB],
            end: Pose { x: lh, y: R::zero(), theta: R::zero() },
            hole: [lh, self.p.e],
            link: [R::zero(); 3],
            angle: R::zero(),
            iterations: 0,
        }
    }

    /// The joint's effective compliance θ/M (M the cable's moment about the hinge's distal
    /// end) when held with tension P in state `eq`, or its linear limit when P M vanishes.
    #[inline(never)]
    pub(super) fn compliance(&self, theta: R, p: R, eq: &JointMarch<R>, c_lin: R) -> R {
        let e = self.p.e;
        let v = [eq.hole[0], eq.hole[1] - e];
        let rho = (v[0].sq() + v[1].sq()).sqrt();
        let wm = if rho > R::zero() {
            let fc = [-v[0] / rho, -v[1] / rho];
            (eq.hole[0] - eq.end.x) * fc[1] - (eq.hole[1] - eq.end.y) * fc[0]
        } else {
            e
        };
        let m = p * wm;
        if theta > R::zero() && m.abs() > R::from_f64(1e-30_f64.max(R::EPS * 1e-20)) {
            return theta / m;
        }
        if theta < R::zero() {
            -c_lin
        } else {
            c_lin
        }
    }
}
