//! The stiffness form of a sub-element's equilibrium (`ByStiffness`): K_j q = (f, M) with
//! K_j = K_hinge,j + K_de(t) (`JointStiffness`), solved by Gaussian elimination in place of multiplying by a
//! compliance computed beforehand. For the tabled inverse, whose thickness is new at every
//! solve: no compliance array is formed. The march around it is `Finger::march_cable`.

use super::march::{SubDisp, SubElement, SubLoads};
use super::{JointStiffness, MarchError};
use crate::mat3::Mat3;
use crate::params::MAX_SUB;
use crate::real::Real;

/// Sub-element j's q from K_j q = (f0, f1, M), M = mm - f1 (L + q0) + f0 q1 the moment about its
/// deformed distal end (linear in q: the third row carries it), K_j from the joint's
/// `JointStiffness`. Refuses (`Singular`) a non-positive last pivot (the compliance form's
/// non-positive den).
pub(super) struct ByStiffness<'a, R>(pub JointStiffness<'a, R>);

impl<R: Real> SubElement<SubLoads<R, R>> for ByStiffness<'_, R> {
    type Sub = Mat3<R>;
    type Disp = SubDisp<R>;
    #[inline(always)]
    fn subs(&self) -> &[Mat3<R>; MAX_SUB] {
        self.0.hinges()
    }
    #[inline(always)]
    fn equilibrium(&self, kh: &Mat3<R>, (f, mm, l): SubLoads<R, R>) -> Result<SubDisp<R>, MarchError> {
        let zr = R::zero();
        let [k00, k01, k02, k11, k12, k22] = self.0.add_to(kh);
        // rows: K q = (f0, f1, g + f0 q1 - f1 q0), g = mm - f1 L; eliminate below k00, then
        // below u11 (not `mat3::inverse_spd`: the moment's load terms make the rows unsymmetric)
        let g = mm - f[1] * l;
        let i0 = R::one() / k00;
        let l1 = k01 * i0;
        let l2 = (k02 + f[1]) * i0;
        let u11 = k11 - l1 * k01;
        let u12 = k12 - l1 * k02;
        let i1 = R::one() / u11;
        let l3 = ((k12 - f[0]) - l2 * k01) * i1;
        let u22 = (k22 - l2 * k02) - l3 * u12;
        let y1 = f[1] - l1 * f[0];
        let y2 = (g - l2 * f[0]) - l3 * y1;
        // (k00 and u11 are pivots of the positive definite K: positive; u22 is K's last
        // pivot less the load's term, the compliance form's den times K's own)
        if !(u22 > zr) {
            return Err(MarchError::Singular);
        }
        let q2 = y2 / u22;
        let q1 = (y1 - u12 * q2) * i1;
        let q0 = (f[0] - k01 * q1 - k02 * q2) * i0;
        Ok(([q0, q1, q2], g + f[0] * q1 - f[1] * q0))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::calibration::Calibration;
    use crate::finger::march::ByCompliance;
    use crate::finger::Finger;
    use crate::mat3;
    use crate::params::Params;

    /// The joint's stiffness and every sub-element's compliance (K_hinge,j + K_de)⁻¹ at
    /// thickness t, the inverse taken here by `mat3::inverse_spd` of the matrices.
    fn at<R: Real>(f: &Finger<R>, t: R) -> (JointStiffness<'_, R>, [mat3::Mat3<R>; MAX_SUB]) {
        let k = f.joint_stiffness(t);
        let mut c = [mat3::zero(); MAX_SUB];
        for j in 0..f.params().m {
            c[j] = mat3::inverse_spd(&mat3::add(&mat3::inverse_spd(&f.hinge_compliance(j)).unwrap(), &f.stack_stiffness(t))).unwrap();
            assert_eq!(c[j], k.compliance(j).unwrap(), "the joint stiffness's compliance");
        }
        (k, c)
    }

    /// The stack's upper triangle (`Finger::stack`) is the matrix `Finger::stack_stiffness`
    /// gives to rounding, with and without the calibration, over the thicknesses the stacks
    /// reach and past them.
    #[test]
    fn stack_upper_is_the_stack_stiffness() {
        for cal in [Calibration::<f64>::none(), Calibration::model_md()] {
            for p in [Params::<f64>::default(), Params { m: 1, ..Params::default() }] {
                let f = Finger::with_calibration(p, cal).unwrap();
                let su = f.stack();
                let t0 = f.stack_thickness(0.0).unwrap();
                for i in 0..=20 {
                    let t = t0 * (0.3 + 0.04 * f64::from(i));
                    let k = f.stack_stiffness(t);
                    let want = [k[0][0], k[0][1], k[0][2], k[1][1], k[1][2], k[2][2]];
                    let got = su.upper(t);
                    let scale = want.iter().fold(0.0f64, |a, x| a.max(x.abs()));
                    for (g, w) in got.iter().zip(want) {
                        assert!((g - w).abs() <= 1e-14 * scale, "{got:?} vs {want:?} at t = {t}");
                    }
                }
            }
        }
    }

    /// The stiffness march is the compliance march (`march_tension`) to rounding: q, end, hole,
    /// (sin, cos) and residual, in f64 (1e-12) and f32, over the stack's range, tensions to
    /// 15 N and holes around the branch, for the default, the calibrated and m = 1 fingers.
    #[test]
    fn stiffness_march_is_the_compliance_march() {
        let fingers = [
            Finger::new(Params::<f64>::default()).unwrap(),
            Finger::with_calibration(Params::default(), Calibration::<f64>::model_md()).unwrap(),
            Finger::new(Params::<f64> { m: 1, ..Params::default() }).unwrap(),
        ];
        let mut compared = 0;
        for f in &fingers {
            let t0 = f.stack_thickness(0.0).unwrap();
            let t_top = f.stack_thickness(0.99 * f.voltage_ceiling()).unwrap();
            for t in [t0, 0.5 * (t0 + t_top), t_top] {
                let (kd, c) = at(f, t);
                for tension in [0.05, 1.0, 7.0, 15.0] {
                    for b in [[10.0, 5.0], [9.3, 6.1], [8.0, 7.5], [3.0, 9.0]] {
                        let mut qa = [[0.0; 3]; MAX_SUB];
                        let Ok(a) = f.march_cable(&ByCompliance(&c), tension, b, &mut qa) else { continue };
                        let mut qb = [[0.0; 3]; MAX_SUB];
                        let s = f.march_cable(&ByStiffness(kd), tension, b, &mut qb).ok().unwrap();
                        let close = |x: f64, y: f64| (x - y).abs() <= 1e-12 * (1.0 + y.abs());
                        assert!(close(s.0.x, a.0.x) && close(s.0.y, a.0.y) && close(s.0.theta, a.0.theta), "{:?} {:?}", s.0, a.0);
                        assert!(close(s.1[0], a.1[0]) && close(s.1[1], a.1[1]));
                        assert!(close(s.2[0], a.2[0]) && close(s.2[1], a.2[1]) && close(s.3, a.3));
                        for j in 0..MAX_SUB {
                            for i in 0..3 {
                                assert!((qa[j][i] - qb[j][i]).abs() <= 1e-12 * (1e-3 + qa[j][i].abs()), "q[{j}][{i}]");
                            }
                        }
                        compared += 1;
                    }
                }
            }
        }
        assert!(compared > 100, "{compared} marches compared");
        // f32: within a few units of its resolution on a hinge length
        let f = Finger::with_calibration(Params::<f32>::default(), Calibration::<f32>::model_md()).unwrap();
        for volts in [0.0f32, 5000.0, 9000.0] {
            let (kd, c) = at(&f, f.stack_thickness(volts).unwrap());
            for tension in [0.2f32, 1.0, 7.0, 15.0] {
                let b = [9.0, 6.5];
                let mut q = [[0.0; 3]; MAX_SUB];
                let a = f.march_cable(&ByCompliance(&c), tension, b, &mut q).ok().unwrap();
                let s = f.march_cable(&ByStiffness(kd), tension, b, &mut q).ok().unwrap();
                assert!((s.0.x - a.0.x).abs() < 2e-5 && (s.0.y - a.0.y).abs() < 2e-5 && (s.0.theta - a.0.theta).abs() < 2e-6);
                assert!((s.1[0] - a.1[0]).abs() < 2e-5 && (s.1[1] - a.1[1]).abs() < 2e-5);
            }
        }
        // what the compliance march refuses for its span and tension, it refuses
        let f = &fingers[0];
        let (kd, _) = at(f, f.stack_thickness(0.0).unwrap());
        let mut q = [[0.0; 3]; MAX_SUB];
        assert!(f.march_cable(&ByStiffness(kd), 1.0, [0.0, f.params().e], &mut q).is_err(), "span below its floor");
        assert!(f.march_cable(&ByStiffness(kd), 0.0, [10.0, 5.0], &mut q).is_err(), "no tension");
        // a stiffness that is not positive definite: refused, not a NaN state
        let bad = JointStiffness::with_upper(f, [0.0, 0.0, 0.0, 0.0, 0.0, -1e9]);
        assert!(f.march_cable(&ByStiffness(bad), 1.0, [10.0, 5.0], &mut q).is_err(), "negative pivot");
        assert!(bad.compliance(0).is_err(), "and no compliance");
        let nan = JointStiffness::with_upper(f, [f64::NAN, 0.0, 0.0, 0.0, 0.0, 0.0]);
        assert!(f.march_cable(&ByStiffness(nan), 1.0, [10.0, 5.0], &mut q).is_err(), "not finite");
        assert!(nan.compliance(0).is_err(), "and no compliance");
    }
}
