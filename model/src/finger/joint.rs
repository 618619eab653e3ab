//! One joint's march entry points under a guessed guide hole: the cable's loads on the distal
//! chain, the plain march, its hole residual and tangent, and the crate-visible marches the
//! inverse calls (`joint_march`). The march's loop and forms are in `march` and
//! `march_stiffness`.

use super::{march, march_stiffness, norm2, Finger, JointMarch, JointState, JointStiffness, MarchError, Pose, SpanLoads, TipLoad};
use crate::error::Error;
use crate::mat3::Mat3;
use crate::params::MAX_SUB;
use crate::real::Real;

impl<R: Real> Finger<R> {
    /// Cable statics, `f = -P (B - A)/|B - A|` along span k (docs/model.md "Cable", "Equilibrium").
    /// The loads on a joint's distal chain for a guide-hole position `b_hole` (the joint's
    /// proximal frame): the cable's force P along the span toward the hole at the proximal node,
    /// the tip load if any, and their sum. A span at its floor is contact.
    /// Any march scalar (R, or dual numbers for the exact Jacobian: `march::PoseFrame`).
    #[inline(always)]
    pub(super) fn span_loads<T: march::Scalar<R>>(&self, tension: R, b_hole: [T; 2], tip: Option<TipLoad<R>>) -> Result<SpanLoads<R, T>, MarchError> {
        let span_v = [b_hole[0], b_hole[1] - self.p.e];
        let span = norm2(span_v);
        if !(span >= T::zero() + self.p.span_floor) {
            return Err(MarchError::Contact);
        }
        let fc = [span_v[0] * -tension / span, span_v[1] * -tension / span];
        let (ft, tp, tc) = match tip {
            Some(t) => (t.force, t.point, t.couple),
            None => ([R::zero(); 2], [R::zero(); 2], R::zero()),
        };
        Ok(SpanLoads { fc, ft, tp, tc, ftot: [fc[0] + ft[0], fc[1] + ft[1]] })
    }

    /// The plain march of joint k's sub-elements for a guessed guide-hole position `b_hole` (the
    /// joint's proximal frame), any load: cable force P along the span from `b_hole` to the
    /// hole at the proximal node, plus an optional tip load (`ByComplianceLoaded` in
    /// `PoseFrame`: each sub-element's `q = C (f, M0 + s)` in closed form, `s = -f_y δax + f_x
    /// δtr` the moment arm's own change). Returns the hinge's end, the hole it arrives at and
    /// the end's (sin, cos); the displacements go to `q`. Out of line: the one copy in the
    /// image (flash).
    #[inline(never)]
    pub(super) fn march(
        &self,
        c: &[Mat3<R>; MAX_SUB],
        tension: R,
        b_hole: [R; 2],
        tip: Option<TipLoad<R>>,
        q: &mut [[R; 3]; MAX_SUB],
    ) -> Result<(Pose<R>, [R; 2], [R; 2]), MarchError> {
        let frame = march::PoseFrame::new(self, tension, b_hole, tip)?;
        self.march_joint(&march::ByComplianceLoaded(c), frame, q, |x| x)?.end(self.p.e)
    }

    /// `march`'s state (a fresh displacement array).
    pub(super) fn marched(&self, c: &[Mat3<R>; MAX_SUB], tension: R, b_hole: [R; 2], tip: Option<TipLoad<R>>) -> Result<JointState<R>, MarchError> {
        let mut q = [[R::zero(); 3]; MAX_SUB];
        let (end, hole, _) = self.march(c, tension, b_hole, tip, &mut q)?;
        Ok(JointState { q, end, hole, tangent: None })
    }

    /// Residual of the hole guess: guess - arrived.
    pub(super) fn hole_residual(&self, c: &[Mat3<R>; MAX_SUB], tension: R, b: [R; 2], tip: Option<TipLoad<R>>) -> Result<([R; 2], JointState<R>), MarchError> {
        let st = self.marched(c, tension, b, tip)?;
        Ok(([b[0] - st.hole[0], b[1] - st.hole[1]], st))
    }

    /// The exact 2x2 tangent of a joint's hole residual (tension and a fixed load `tip`), from
    /// one march on dual numbers (see `dual`).
    pub(super) fn joint_tangent(&self, c: &[Mat3<R>; MAX_SUB], tension: R, b: [R; 2], tip: Option<TipLoad<R>>) -> Result<[[R; 2]; 2], MarchError> {
        self.eval_dual(c, tension, b, tip).map(|(_, _, jac)| jac)
    }

    /// Joint k's (0-based) fixed load (`held`), times `s`.
    pub(super) fn held_at(&self, k: usize, s: R) -> Option<TipLoad<R>> {
        self.held.get(k).copied().flatten().map(|l| l.scaled(s))
    }

    /// Link k's (0-based) deflection under tension with its fixed load (`held_link`).
    pub(super) fn held_link_q(&self, k: usize, tension: R) -> [R; 3] {
        if !self.p.flex_links {
            return [R::zero(); 3];
        }
        let mut w = self.link_wrench(tension, None);
        let h = self.held_link.get(k).copied().unwrap_or([R::zero(); 3]);
        for i in 0..3 {
            w[i] += h[i];
        }
        crate::mat3::mul_vec(&self.link_c, &w)
    }

    /// One march of joint `joint` (1-based) under tension alone from the hole guess `b` (no
    /// Newton), `by` one of the three ways (`by`'s types): the state it arrives at, with `hole`
    /// the hole it arrives at (the residual is `b - hole`) and `angle` the joint angle (hinge
    /// and flexible link). For the inverse's quasi-Newton solves and the tabled inverse's
    /// confirming marches; `iterations` is 0. The sub-element displacements go to `q`.
    #[inline(always)]
    pub(crate) fn joint_march<B: By<R>>(&self, joint: usize, by: B, tension: R, b: [R; 2], q: &mut [[R; 3]; MAX_SUB]) -> Result<JointMarch<R>, Error> {
        let (end, hole, link) = by.arrive(self, joint.max(1) - 1, tension, b, q).map_err(|e| match e {
            MarchError::Contact => Error::Contact { joint, tension: tension.to_f64() },
            MarchError::Singular => Error::Singular { what: "joint march" },
        })?;
        Ok(JointMarch::arrived(end, hole, link))
    }

    /// A link's deflection under tension alone, the same for every joint (`link_q` without a
    /// tip load).
    pub(crate) fn tension_link_q(&self, tension: R) -> [R; 3] {
        self.link_q(tension, None)
    }
}

/// A way `Finger::joint_march` marches a joint under tension alone (`by`'s types): the hinge's
/// end, the hole it arrives at and the link's deflection. One type per way, so each caller's
/// march is built for its way, with no choice made at run time.
/// Joint `k` (0-based) carries its fixed load (`Finger::held`) in every way: the ways in the
/// running frame, which carry none, take the compliance way then or refuse.
pub(crate) trait By<R: Real> {
    fn arrive(self, f: &Finger<R>, k: usize, tension: R, b: [R; 2], q: &mut [[R; 3]; MAX_SUB]) -> Result<(Pose<R>, [R; 2], [R; 3]), MarchError>;
}

/// The ways of `Finger::joint_march`.
pub(crate) mod by {
    use super::{march, march_stiffness, By, Finger, JointStiffness, MarchError, Pose};
    use crate::de::StackStiffness;
    use crate::mat3::Mat3;
    use crate::params::MAX_SUB;
    use crate::real::Real;

    /// By compliances in `PoseFrame` (`Finger::march`).
    #[derive(Clone, Copy)]
    pub(crate) struct Compliance<'a, R>(pub &'a [Mat3<R>; MAX_SUB]);

    /// By compliances in the running frame (`march_cable` by `ByCompliance`) where that march
    /// applies, else as `Compliance`.
    #[derive(Clone, Copy)]
    pub(crate) struct Cable<'a, R>(pub &'a [Mat3<R>; MAX_SUB]);

    /// By the joint's stiffness with its stack at thickness `.1` (mm; the stack's constants
    /// `.0`), no compliance formed, the link's deflection at that tension given (`.2`); refused
    /// where its last pivot is not positive (the caller takes the compliance path).
    #[derive(Clone, Copy)]
    pub(crate) struct Stiffness<'a, R>(pub &'a StackStiffness<R>, pub R, pub [R; 3]);

    impl<R: Real> By<R> for Compliance<'_, R> {
        #[inline(always)]
        fn arrive(self, f: &Finger<R>, k: usize, tension: R, b: [R; 2], q: &mut [[R; 3]; MAX_SUB]) -> Result<(Pose<R>, [R; 2], [R; 3]), MarchError> {
            let (end, hole, _) = f.march(self.0, tension, b, f.held_at(k, R::one()), q)?;
            Ok((end, hole, f.held_link_q(k, tension)))
        }
    }

    impl<R: Real> By<R> for Cable<'_, R> {
        #[inline(always)]
        fn arrive(self, f: &Finger<R>, k: usize, tension: R, b: [R; 2], q: &mut [[R; 3]; MAX_SUB]) -> Result<(Pose<R>, [R; 2], [R; 3]), MarchError> {
            if f.held_at(k, R::one()).is_some() {
                return Compliance(self.0).arrive(f, k, tension, b, q);
            }
            match f.march_cable(&march::ByCompliance(self.0), tension, b, q) {
                Ok((end, hole, _, _)) => Ok((end, hole, f.link_q(tension, None))),
                Err(_) => Compliance(self.0).arrive(f, k, tension, b, q),
            }
        }
    }

    impl<R: Real> By<R> for Stiffness<'_, R> {
        #[inline(always)]
        fn arrive(self, f: &Finger<R>, k: usize, tension: R, b: [R; 2], q: &mut [[R; 3]; MAX_SUB]) -> Result<(Pose<R>, [R; 2], [R; 3]), MarchError> {
            if f.held_at(k, R::one()).is_some() {
                return Err(MarchError::Singular);
            }
            let k = JointStiffness::new(f, self.0, self.1);
            let (end, hole, _, _) = f.march_cable(&march_stiffness::ByStiffness(k), tension, b, q)?;
            Ok((end, hole, self.2))
        }
    }
}
