//! Preparing a finger: validation, the hinge compliances (once per parameter set), the stack's
//! stiffness and the sub-element compliances for a set of channel voltages (docs/model.md
//! "Joint compliance with the stack"). No solving here.

use super::types::cast_mat;
use super::{Compliances, Finger, HELD};
use crate::calibration::Calibration;
use crate::error::Error;
use crate::mat3::{self, Mat3};
use crate::material::Hold;
use crate::params::{Params, MAX_JOINTS, MAX_SUB};
use crate::real::Real;
use crate::{de, hinge};

impl<R: Real> Finger<R> {
    /// Validate the parameters and compute the hinge compliances (once per parameter set).
    pub fn new(p: Params<R>) -> Result<Self, Error> {
        Self::with_calibration(p, Calibration::none())
    }

    /// `new` with an FE calibration of the sub-element compliances (`calibration`).
    pub fn with_calibration(p: Params<R>, cal: Calibration<R>) -> Result<Self, Error> {
        p.validate()?;
        cal.validate(&p)?;
        #[cfg(not(feature = "de"))]
        if p.layers > 0 {
            return Err(Error::Param { name: "layers", range: "0 (this build has no DE support)" });
        }
        let mut hinge_c = [mat3::zero(); MAX_SUB];
        let mut hinge_k = [mat3::zero(); MAX_SUB];
        let e = p.hinge_modulus();
        for j in 0..p.m {
            let (x0, x1) = hinge::sub_element_bounds(p.a, p.m, j);
            hinge_c[j] = cal.hinge_compliance(&hinge::stretch_compliance(p.b, p.t_min, p.a, e, p.w, x0, x1));
            hinge_k[j] = mat3::inverse_spd(&hinge_c[j]).ok_or(Error::Singular { what: "hinge compliance" })?;
            if !hinge_c[j].iter().flatten().all(|x| x.is_finite()) {
                return Err(Error::Singular { what: "hinge compliance" });
            }
        }
        let sub_len = p.hinge_len() / R::from_u32(p.m as u32);
        let link_len = p.l - p.hinge_len();
        let link_c = if p.flex_links { uniform_beam_compliance(e, p.w, p.b, link_len) } else { mat3::zero() };
        Ok(Finger { p, hinge_c, hinge_k, sub_len, link_len, link_c, cal, held: [None; HELD], held_link: [[R::zero(); 3]; HELD] })
    }

    pub fn params(&self) -> &Params<R> {
        &self.p
    }

    /// The same prepared finger in another scalar type: the parameters and the hinge
    /// compliances computed once in `R` and cast (fixed point cannot hold the quadrature's
    /// intermediate products).
    pub fn cast<S: Real>(&self) -> Finger<S> {
        let mut hinge_c = [mat3::zero(); MAX_SUB];
        let mut hinge_k = [mat3::zero(); MAX_SUB];
        for j in 0..MAX_SUB {
            hinge_c[j] = cast_mat(&self.hinge_c[j]);
            hinge_k[j] = cast_mat(&self.hinge_k[j]);
        }
        Finger {
            p: self.p.cast(),
            hinge_c,
            hinge_k,
            sub_len: S::from_f64(self.sub_len.to_f64()),
            link_len: S::from_f64(self.link_len.to_f64()),
            link_c: cast_mat(&self.link_c),
            held: self.held.map(|h| h.map(|l| l.cast())),
            held_link: self.held_link.map(|w| w.map(|x| S::from_f64(x.to_f64()))),
            cal: Calibration {
                hinge: self.cal.hinge.map(|x| S::from_f64(x.to_f64())),
                stack_axial: self.cal.stack_axial.map(|x| S::from_f64(x.to_f64())),
                stack_bending: self.cal.stack_bending.map(|x| S::from_f64(x.to_f64())),
            },
        }
    }

    /// The FE calibration this finger was prepared with.
    pub fn calibration(&self) -> &Calibration<R> {
        &self.cal
    }

    /// Stiffness of a stack stretch of one sub-element at stack thickness t (mm), calibrated
    /// (`de::StackStiffness`).
    pub fn stack_stiffness(&self, t: R) -> Mat3<R> {
        self.stack().matrix(t)
    }

    /// The stack's stiffness on one sub-element as a function of the thickness, calibrated
    /// (`de::StackStiffness`, its constants taken once).
    pub fn stack(&self) -> de::StackStiffness<R> {
        de::StackStiffness::new(&self.p, self.sub_len, &self.cal)
    }

    /// The stack's kernel under `hold` (`de::StackStiffness::with_hold`): `Hold::FreeFilm` is
    /// `stack`, what the solves take; `Hold::Laminate` the bonded stack held across its width.
    pub fn stack_held(&self, hold: Hold) -> Result<de::StackStiffness<R>, Error> {
        de::StackStiffness::with_hold(&self.p, self.sub_len, &self.cal, hold)
    }

    /// A joint's rotation under its voltage alone with its stack at state `t` (the free film's
    /// thickness, mm) by the kernel `stack`, rad (+: toward the cable): each sub-element's
    /// `C_j w_act` (`StackStiffness::active`), the rotation summed. No external load, so the
    /// loads' geometry does not enter and the link carries nothing: the unimorph's bending
    /// (docs/materials.md "Free film and bonded stack"). 0 for the free film and without stacks.
    pub fn voltage_rotation(&self, stack: &de::StackStiffness<R>, t: R) -> Result<R, Error> {
        if self.p.layers == 0 || cfg!(not(feature = "de")) {
            return Ok(R::zero());
        }
        let w = stack.active(t);
        let mut c = [mat3::zero(); MAX_SUB];
        super::JointStiffness::new(self, stack, t).compliances_into(&mut c)?;
        let mut th = R::zero();
        for cj in c.iter().take(self.p.m) {
            th += cj[2][0] * w[0] + cj[2][1] * w[1] + cj[2][2] * w[2];
        }
        Ok(th)
    }

    /// Hinge compliance of sub-element j (no stack): the Castigliano integrals of docs/model.md
    /// "Hinge compliance".
    pub fn hinge_compliance(&self, j: usize) -> Mat3<R> {
        self.hinge_c[j.min(MAX_SUB - 1)]
    }

    /// Pull-in voltage V_pi of a layer, V (0 without stacks).
    pub fn pull_in_voltage(&self) -> R {
        de::pull_in_voltage(&self.p)
    }

    /// The ceiling every channel stays below: min(margin x V_pi, supply), V.
    pub fn voltage_ceiling(&self) -> R {
        de::voltage_ceiling(&self.p)
    }

    /// The ceiling in force: min(margin x V_pi, v_supply, hv_fs), V (`de::ceiling_in_force`).
    pub fn ceiling_in_force(&self, hv_fs: Option<R>) -> R {
        de::ceiling_in_force(&self.p, hv_fs)
    }

    /// Whole-stack thickness at `volts`, mm (refuses a voltage at or past the ceiling).
    pub fn stack_thickness(&self, volts: R) -> Result<R, Error> {
        de::stack_thickness(&self.p, 1, volts)
    }

    /// The compliance of every sub-element for these channel voltages (one per joint):
    /// `C = (C_hinge⁻¹ + Tᵀ C_de(t_k)⁻¹ T)⁻¹`, or C_hinge alone without stacks.
    pub fn compliances(&self, volts: &[R]) -> Result<Compliances<R>, Error> {
        let p = &self.p;
        if volts.len() != p.n {
            return Err(Error::Input { input: "voltages", reason: "one voltage per joint is required" });
        }
        let mut out =
            Compliances { n: p.n, m: p.m, c: [[mat3::zero(); MAX_SUB]; MAX_JOINTS], thickness: [R::zero(); MAX_JOINTS], volts: [R::zero(); MAX_JOINTS] };
        out.volts[..p.n].copy_from_slice(volts);
        // the ceiling and the film's law once for every joint
        let stack = de::Stack::new(p);
        for (k, &v) in volts.iter().enumerate() {
            stack.check(k + 1, v)?;
            // a build without the `de` feature refuses stacks in `new`, and leaves the stack's
            // code (thinning, stack stiffness) out of the image
            if p.layers == 0 || cfg!(not(feature = "de")) {
                out.c[k][..p.m].copy_from_slice(&self.hinge_c[..p.m]);
                continue;
            }
            let t = stack.thickness(k + 1, v)?;
            self.stack_into(&mut out, k, t)?;
        }
        Ok(out)
    }

    /// As [`Finger::compliances`], the stacks at the thicknesses `thickness_mm` (mm, one per
    /// joint) instead of the ones the voltages relax to: a film still creeping toward its
    /// voltage (the board's `status`). The voltages are checked and kept in the answer; a
    /// thickness outside (the 33 % limit, N_L z0] is refused. Without stacks, the hinges alone.
    pub fn compliances_at_thickness(&self, volts: &[R], thickness_mm: &[R]) -> Result<Compliances<R>, Error> {
        let p = &self.p;
        if thickness_mm.len() != p.n {
            return Err(Error::Input { input: "thickness", reason: "one thickness per joint is required" });
        }
        let mut out = self.compliances(&[R::zero(); MAX_JOINTS][..p.n])?;
        if volts.len() != p.n {
            return Err(Error::Input { input: "voltages", reason: "one voltage per joint is required" });
        }
        out.volts[..p.n].copy_from_slice(volts);
        let t0 = R::from_u32(p.layers) * p.z0;
        let stack = de::Stack::new(p);
        for (k, (&v, &t)) in volts.iter().zip(thickness_mm).enumerate() {
            stack.check(k + 1, v)?;
            if p.layers == 0 || cfg!(not(feature = "de")) {
                continue;
            }
            if !t.is_finite() {
                return Err(Error::NonFinite { input: "thickness" });
            }
            if !(t <= t0 && t > t0 * R::from_f64(crate::material::LIMIT_RATIO)) {
                return Err(Error::Input { input: "thickness", reason: "must lie in (the 33 % limit, N_L z0]" });
            }
            self.stack_into(&mut out, k, t)?;
        }
        Ok(out)
    }

    /// Joint `k`'s sub-element compliances with its stack at thickness `t`, mm.
    fn stack_into(&self, out: &mut Compliances<R>, k: usize, t: R) -> Result<(), Error> {
        out.thickness[k] = t;
        self.joint_stiffness(t).compliances_into(&mut out.c[k])
    }
}

/// Compliance of a uniform beam (modulus e, width w, thickness t, length len), clamped at its
/// proximal end, loads at its distal end: [[L/EA,0,0],[0,L³/3EI,L²/2EI],[0,L²/2EI,L/EI]].
pub fn uniform_beam_compliance<R: Real>(e: R, w: R, t: R, len: R) -> Mat3<R> {
    let ea = e * w * t;
    let ei = e * w * t * t * t / R::from_f64(12.0);
    let z = R::zero();
    [[len / ea, z, z], [z, len * len * len / (R::from_f64(3.0) * ei), len * len / (R::from_f64(2.0) * ei)], [z, len * len / (R::from_f64(2.0) * ei), len / ei]]
}
