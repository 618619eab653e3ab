//! A joint's stiffness at one stack thickness: per sub-element K_j = K_hinge,j + K_de(t), its
//! inverse C_j (the compliance the marches take) and dK/dt (docs/model.md "Joint compliance
//! with the stack"). Built once per thickness (`Finger::joint_stiffness`); every solve that
//! needs the sum takes it here, the forward's compliances, the fixed point's, the general and
//! m = 1 inverses' and the stiffness march alike. What it is not: the stack's beam itself
//! (`de::StackStiffness`), or a march.

use super::Finger;
use crate::de::StackStiffness;
use crate::error::Error;
use crate::mat3::{self, Mat3};
use crate::params::MAX_SUB;
use crate::real::Real;

/// K_hinge,j + K_de(t) for every sub-element j of one joint, at stack thickness `t` (mm).
#[derive(Clone, Copy, Debug)]
pub struct JointStiffness<'a, R> {
    f: &'a Finger<R>,
    /// K_de(t)'s upper triangle (k01 = 0); zeros with no stacks (in the set or the build).
    upper: [R; 6],
    /// The set has stacks: without them C_j is the hinge's own compliance.
    stacks: bool,
    t: R,
}

impl<'a, R: Real> JointStiffness<'a, R> {
    /// Finger `f`'s joint with its stack at thickness `t`, mm, the stack's constants `stack`
    /// (`Finger::stack`, taken once by a caller that builds many).
    #[inline(always)]
    pub fn new(f: &'a Finger<R>, stack: &StackStiffness<R>, t: R) -> Self {
        // a build without the `de` feature refuses stacks in `Finger::new` and leaves the
        // stack's code out of the image
        let stacks = f.p.layers > 0 && cfg!(feature = "de");
        let upper = if stacks { stack.upper(t) } else { [R::zero(); 6] };
        JointStiffness { f, upper, stacks, t }
    }

    /// Only the tests' stiffness from a given stack triangle (a bad one, say).
    #[cfg(test)]
    pub(crate) fn with_upper(f: &'a Finger<R>, upper: [R; 6]) -> Self {
        JointStiffness { f, upper, stacks: true, t: R::zero() }
    }

    /// The stack thickness it was built at, mm.
    pub fn thickness(&self) -> R {
        self.t
    }

    /// The sub-element count m and the hinges' stiffnesses (K_hinge,j), for a march over them.
    pub(crate) fn hinges(&self) -> &'a [Mat3<R>; MAX_SUB] {
        &self.f.hinge_k
    }

    /// `kh` + K_de's upper triangle (k00, k01, k02, k11, k12, k22): the one place the two add.
    /// The stack couples no shear to the axial force (its k01 is zero), so k01 is the hinge's.
    /// Without stacks the zeros add (a test per sub-element costs more than five adds).
    #[inline(always)]
    pub(crate) fn add_to(&self, kh: &Mat3<R>) -> [R; 6] {
        let [d00, _, d02, d11, d12, d22] = self.upper;
        [kh[0][0] + d00, kh[0][1], kh[0][2] + d02, kh[1][1] + d11, kh[1][2] + d12, kh[2][2] + d22]
    }

    /// K_j's upper triangle.
    #[inline(always)]
    pub fn upper(&self, j: usize) -> [R; 6] {
        self.add_to(&self.f.hinge_k[j.min(MAX_SUB - 1)])
    }

    /// K_j.
    pub fn matrix(&self, j: usize) -> Mat3<R> {
        mat3::from_upper(self.upper(j))
    }

    /// dK_j/dt, the same for every sub-element (zero without stacks); `stack` the stack's
    /// constants it was built with.
    pub fn dt(&self, stack: &StackStiffness<R>) -> Mat3<R> {
        if self.stacks {
            mat3::from_upper(stack.upper_dt(self.t))
        } else {
            mat3::zero()
        }
    }

    /// C_j = K_j⁻¹ with `mat3::inverse_spd_upper`'s check value; without stacks the hinge's
    /// own compliance (the Castigliano integrals, not an inverted inverse) and check 0.
    #[inline(always)]
    fn compliance_checked(&self, j: usize) -> (Mat3<R>, R) {
        if !self.stacks {
            return (self.f.hinge_c[j.min(MAX_SUB - 1)], R::zero());
        }
        let (o, check) = mat3::inverse_spd_upper(self.upper(j));
        (mat3::from_upper(o), check)
    }

    /// C_j; refuses a sum that is not positive definite (`Singular`, "joint stiffness"). By
    /// `mat3::inverse_spd` out of line: the set-up's one copy (flash; `compliances_into` is
    /// the solves' inline one, the same arithmetic).
    pub fn compliance(&self, j: usize) -> Result<Mat3<R>, Error> {
        if !self.stacks {
            return Ok(self.f.hinge_c[j.min(MAX_SUB - 1)]);
        }
        mat3::inverse_spd(&self.matrix(j)).ok_or(Error::Singular { what: "joint stiffness" })
    }

    /// Every sub-element's C_j into `c` (its first m entries), one test for all of them.
    #[inline(always)]
    pub fn compliances_into(&self, c: &mut [Mat3<R>; MAX_SUB]) -> Result<(), Error> {
        let mut check = R::zero();
        for (j, cj) in c.iter_mut().enumerate().take(self.f.p.m) {
            let (m, ck) = self.compliance_checked(j);
            *cj = m;
            check += ck;
        }
        checked(check)
    }
}

/// A finite sum of checks: every sum positive definite.
fn checked<R: Real>(check: R) -> Result<(), Error> {
    if check.is_finite() {
        Ok(())
    } else {
        Err(Error::Singular { what: "joint stiffness" })
    }
}

impl<R: Real> Finger<R> {
    /// The joint's stiffness with its stack at thickness `t`, mm (`JointStiffness`). Out of
    /// line (flash): the set-ups call it; the inverses' loops keep the stack's constants
    /// (`JointStiffness::new`).
    #[inline(never)]
    pub fn joint_stiffness(&self, t: R) -> JointStiffness<'_, R> {
        JointStiffness::new(self, &self.stack(), t)
    }
}
