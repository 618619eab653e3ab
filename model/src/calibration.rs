//! Calibration of the sub-element compliances against a finite-element solution (issue 18):
//! a few factors per parameter set, produced by `tools/calculix` (`fe-calibrate`), that make the
//! model's small-load element compliance equal the FE's. The large-deflection behaviour then
//! follows from the subdivision.
//!
//! What it is: factors on each hinge sub-element's four compliance integrals, and on the
//! stack's axial (EA) and bending (EI) stiffness, each linear in the stack thickness. What it
//! is not: a change of any equation; `Calibration::none()` is the uncalibrated model.

use crate::error::Error;
use crate::mat3::Mat3;
use crate::params::Params;
use crate::real::Real;

/// Correction factors (dimensionless; 1 = none).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Calibration<R> {
    /// Factors on every hinge sub-element's C_x-Fx, C_y-Fy, C_y-M (= C_θ-Fy), C_θ-M.
    pub hinge: [R; 4],
    /// The stack's EA factor `g = g0 + g1 t` (t the stack thickness, mm): [g0, g1].
    pub stack_axial: [R; 2],
    /// The stack's EI factor `g = g0 + g1 t`: [g0, g1].
    pub stack_bending: [R; 2],
}

impl<R: Real> Default for Calibration<R> {
    fn default() -> Self {
        Self::none()
    }
}

impl<R: Real> Calibration<R> {
    /// No correction: the model as MODEL.md states it.
    pub fn none() -> Self {
        let (o, z) = (R::one(), R::zero());
        Calibration { hinge: [o; 4], stack_axial: [o, z], stack_bending: [o, z] }
    }

    /// Every factor finite, and the factors at every stack thickness the parameters allow
    /// (2/3 N_L z0 .. N_L z0) within [0.1, 10].
    pub fn validate(&self, p: &Params<R>) -> Result<(), Error> {
        let ok = |g: R| g.is_finite() && g >= R::from_f64(0.1) && g <= R::from_f64(10.0);
        let bad = Error::Param { name: "cal", range: "factors finite, 0.1..10" };
        if !self.hinge.iter().all(|&g| ok(g)) {
            return Err(bad);
        }
        let t0 = R::from_u32(p.layers) * p.z0;
        for t in [t0, t0 * R::from_f64(2.0 / 3.0)] {
            for c in [self.stack_axial, self.stack_bending] {
                if !(c[0].is_finite() && c[1].is_finite() && ok(c[0] + c[1] * t)) {
                    return Err(bad);
                }
            }
        }
        Ok(())
    }

    /// A hinge sub-element's compliance with the factors applied entry by entry.
    pub fn hinge_compliance(&self, c: &Mat3<R>) -> Mat3<R> {
        let f = &self.hinge;
        let mut o = *c;
        o[0][0] = c[0][0] * f[0];
        o[1][1] = c[1][1] * f[1];
        o[1][2] = c[1][2] * f[2];
        o[2][1] = c[2][1] * f[2];
        o[2][2] = c[2][2] * f[3];
        o
    }

    /// The stack stiffness `Tᵀ C_de⁻¹ T` (`de::stack_stiffness`, MODEL.md) with EA scaled by the
    /// axial factor and EI by the bending factor at thickness `t`: `g_b K + (g_a - g_b) K_a`,
    /// K_a = EA/L (1, 0, d)ᵀ(1, 0, d) the transformed axial part.
    pub fn stack_stiffness(&self, p: &Params<R>, k: &Mat3<R>, len: R, t: R) -> Mat3<R> {
        let ga = self.stack_axial[0] + self.stack_axial[1] * t;
        let gb = self.stack_bending[0] + self.stack_bending[1] * t;
        let ka = p.e_de() * p.w * t / len;
        let d = (p.t_min + t) / R::from_f64(2.0);
        let v = [R::one(), R::zero(), d];
        let mut o = *k;
        for i in 0..3 {
            for j in 0..3 {
                o[i][j] = gb * k[i][j] + (ga - gb) * ka * v[i] * v[j];
            }
        }
        o
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::finger::Finger;

    #[test]
    fn none_is_the_uncalibrated_model() {
        let p = Params::<f64>::default();
        let (a, b) = (Finger::new(p).unwrap(), Finger::with_calibration(p, Calibration::none()).unwrap());
        let v = [3000.0, 0.0, 8000.0];
        let (ca, cb) = (a.compliances(&v).unwrap(), b.compliances(&v).unwrap());
        assert_eq!(ca.c, cb.c);
    }

    #[test]
    fn factors_scale_their_entries() {
        let p = Params::<f64>::default();
        let cal = Calibration { hinge: [1.5, 2.0, 1.1, 1.25], ..Calibration::none() };
        let (a, b) = (Finger::new(p).unwrap(), Finger::with_calibration(p, cal).unwrap());
        for j in 0..p.m {
            let (x, y) = (a.hinge_compliance(j), b.hinge_compliance(j));
            for (r, c, f) in [(0, 0, 1.5), (1, 1, 2.0), (1, 2, 1.1), (2, 1, 1.1), (2, 2, 1.25)] {
                assert!((y[r][c] - f * x[r][c]).abs() <= 1e-15 * x[r][c].abs());
            }
        }
        // the stack: EI factor 2 and EA factor 1 double the bending stiffness, keep the axial
        let t = 2.0;
        let cal = Calibration { stack_bending: [2.0, 0.0], ..Calibration::none() };
        let f = Finger::with_calibration(p, cal).unwrap();
        let (k0, k1) = (a.stack_stiffness(t), f.stack_stiffness(t));
        let ea = p.e_de() * p.w * t / (p.hinge_len() / p.m as f64);
        assert!((k1[0][0] - k0[0][0]).abs() < 1e-9 * ea && (k1[1][1] - 2.0 * k0[1][1]).abs() < 1e-9 * k0[1][1]);
    }

    #[test]
    fn bad_factors_are_refused() {
        let p = Params::<f64>::default();
        for cal in [
            Calibration { hinge: [f64::NAN, 1.0, 1.0, 1.0], ..Calibration::none() },
            Calibration { hinge: [1.0, 1.0, 1.0, 0.05], ..Calibration::none() },
            // fine at 2 mm, below 0.1 at the pull-in thickness 4/3 mm
            Calibration { stack_bending: [-6.0, 4.0], ..Calibration::none() },
        ] {
            assert!(matches!(Finger::with_calibration(p, cal), Err(Error::Param { name: "cal", .. })));
        }
    }
}
