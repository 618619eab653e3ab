//! The finger's value types: a planar pose, the solver choice, the per-voltage compliances,
//! a solved posture, how the equilibrium branch ends, one joint's equilibrium and march.
//! No solving here (see the solvers in `finger`'s other modules).

use crate::mat3::{self, Mat3};
use crate::params::{MAX_JOINTS, MAX_SUB};
use crate::real::Real;

/// A planar pose: position (mm) and angle (rad, positive toward +y).
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct Pose<R> {
    pub x: R,
    pub y: R,
    pub theta: R,
}

impl<R: Real> Pose<R> {
    pub fn origin() -> Self {
        Pose { x: R::zero(), y: R::zero(), theta: R::zero() }
    }
    /// `self ∘ (dx, dy, dθ)`: move by (dx, dy) in this pose's frame, then turn by dθ. One
    /// step from a pose known by its angle; a chain of steps carries a `Heading`.
    pub fn then(&self, dx: R, dy: R, dtheta: R) -> Self {
        let (s, c) = self.theta.sin_cos();
        Pose { x: self.x + c * dx - s * dy, y: self.y + s * dx + c * dy, theta: self.theta + dtheta }
    }
    /// A point given in this pose's frame, in the parent frame.
    pub fn point(&self, px: R, py: R) -> [R; 2] {
        let (s, c) = self.theta.sin_cos();
        [self.x + c * px - s * py, self.y + s * px + c * py]
    }
}

/// A pose with its angle's (sin, cos), carried along a chain (a joint's sub-elements, the
/// finger's nodes): each step turns it by the turn rule, the march frames' own (`Real::turn`
/// of the step's rotation, composed by `Real::compose_turn`), so no chain takes the sine and
/// cosine of a summed angle (docs/model.md "The turn rule").
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Heading<R> {
    pub pose: Pose<R>,
    pub s: R,
    pub c: R,
}

impl<R: Real> Heading<R> {
    pub fn origin() -> Self {
        Heading { pose: Pose::origin(), s: R::zero(), c: R::one() }
    }

    /// `self ∘ (dx, dy, dθ)`: move by (dx, dy) in this frame, then turn by dθ.
    #[inline(always)]
    pub fn then(&self, dx: R, dy: R, dtheta: R) -> Self {
        let (p, s, c) = (self.pose, self.s, self.c);
        let pose = Pose { x: p.x + c * dx - s * dy, y: p.y + s * dx + c * dy, theta: p.theta + dtheta };
        let (s, c) = R::compose_turn((s, c), super::march::turn(dtheta), pose.theta);
        Heading { pose, s, c }
    }

    /// A point given in this frame, in the parent frame.
    pub fn point(&self, px: R, py: R) -> [R; 2] {
        [self.pose.x + self.c * px - self.s * py, self.pose.y + self.s * px + self.c * py]
    }

    /// The poses of a chain of headings.
    pub fn poses<const N: usize>(h: &[Heading<R>; N]) -> [Pose<R>; N] {
        h.map(|h| h.pose)
    }
}

/// Which solver.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Method<R> {
    /// The converged equilibrium: Newton to `tol` (mm, on the guide-hole position), at most
    /// `max_iter` iterations in all. A `tol` below the type's resolution is raised to it.
    Converged { tol: R, max_iter: u32 },
    /// The paper's load stepping (Eq. 29): `n_inc` increments, the load direction taken from
    /// the geometry of the step before. First order in 1/n_inc.
    Stepping { n_inc: u32 },
}

impl<R: Real> Method<R> {
    /// The converged solver at its default tolerance (1e-9 mm, or the type's resolution).
    pub fn converged() -> Self {
        Method::Converged { tol: R::from_f64(1e-9), max_iter: 200 }
    }
}

/// Compliance of every sub-element of every joint, for one set of channel voltages.
#[derive(Clone, Copy, Debug)]
pub struct Compliances<R> {
    pub n: usize,
    pub m: usize,
    /// C of sub-element j of joint k: `c[k][j]`.
    pub c: [[Mat3<R>; MAX_SUB]; MAX_JOINTS],
    /// Whole-stack thickness per joint, mm (0 without stacks).
    pub thickness: [R; MAX_JOINTS],
    /// The channel voltages these compliances are for, V.
    pub volts: [R; MAX_JOINTS],
}

pub(super) fn cast_mat<R: Real, S: Real>(m: &Mat3<R>) -> Mat3<S> {
    let mut o = mat3::zero();
    for i in 0..3 {
        for j in 0..3 {
            o[i][j] = S::from_f64(m[i][j].to_f64());
        }
    }
    o
}

impl<R: Real> Compliances<R> {
    /// The same compliances in another scalar type (computed once in f32/f64, used in fixed
    /// point).
    pub fn cast<S: Real>(&self) -> Compliances<S> {
        let mut c = [[mat3::zero(); MAX_SUB]; MAX_JOINTS];
        for k in 0..MAX_JOINTS {
            for j in 0..MAX_SUB {
                c[k][j] = cast_mat(&self.c[k][j]);
            }
        }
        Compliances { n: self.n, m: self.m, c, thickness: self.thickness.map(|x| S::from_f64(x.to_f64())), volts: self.volts.map(|x| S::from_f64(x.to_f64())) }
    }
}

/// A solved posture.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Solution<R> {
    pub n: usize,
    pub m: usize,
    /// Cable tension, N.
    pub tension: R,
    /// External tip force (base frame), N.
    pub tip_force: [R; 2],
    /// Sub-element displacements q = (δax, δtr, Δθ), `q[k][j]`. Every solver leaves the rows
    /// past (n, m) zero, as `empty()` has them (and the per-joint arrays past n as `empty()`
    /// has them); the `_into` solves rely on it and clear only rows a solution held past
    /// another finger's (n, m).
    pub q: [[[R; 3]; MAX_SUB]; MAX_JOINTS],
    /// Link deflections (δax, δtr, Δθ) in each link's proximal frame (zero for rigid links).
    pub links: [[R; 3]; MAX_JOINTS],
    /// Joint angles Δθ_k: the rotation of element k (its hinge's sub-elements, and its link
    /// when links are flexible), rad.
    pub joint_angle: [R; MAX_JOINTS],
    /// Node poses 0..=n; node n is the tip (centreline, distal end of the last link).
    pub nodes: [Pose<R>; MAX_JOINTS + 1],
    /// Length of cable span k, mm.
    pub span: [R; MAX_JOINTS],
    /// Stack thickness per joint, mm.
    pub thickness: [R; MAX_JOINTS],
    /// Channel voltages, V.
    pub volts: [R; MAX_JOINTS],
    /// Cable the servo must pull in: Σ (L_h - |span k|), mm.
    pub cable_excursion: R,
    /// Newton iterations (converged) or load steps (stepping).
    pub iterations: u32,
    /// Final equilibrium residual: guide-hole mismatch, mm.
    pub residual: R,
    /// Determinant of each joint's equilibrium tangent (2x2, dimensionless; 1 unloaded; 1 where
    /// not evaluated: a joint the tabled forward answered at its first march).
    /// It falls to zero at a limit point of the equilibrium branch.
    pub tangent_det: [R; MAX_JOINTS],
}

impl<R: Real> Solution<R> {
    /// An empty solution (every field zero, no joints): storage for the `_into` solves.
    pub fn empty() -> Self {
        Solution {
            n: 0,
            m: 0,
            tension: R::zero(),
            tip_force: [R::zero(); 2],
            q: [[[R::zero(); 3]; MAX_SUB]; MAX_JOINTS],
            links: [[R::zero(); 3]; MAX_JOINTS],
            joint_angle: [R::zero(); MAX_JOINTS],
            nodes: [Pose::origin(); MAX_JOINTS + 1],
            span: [R::zero(); MAX_JOINTS],
            thickness: [R::zero(); MAX_JOINTS],
            volts: [R::zero(); MAX_JOINTS],
            cable_excursion: R::zero(),
            iterations: 0,
            residual: R::zero(),
            tangent_det: [R::one(); MAX_JOINTS],
        }
    }
    /// Tip pose (node n).
    pub fn tip(&self) -> Pose<R> {
        self.nodes[self.n]
    }
    pub fn joint_angles(&self) -> &[R] {
        &self.joint_angle[..self.n]
    }
}

/// How the equilibrium branch ends (see `Finger::fmax`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BranchEnd {
    /// A cable span closed to its floor: the links touch.
    Contact,
    /// The equilibrium tangent turned singular: the branch turns back.
    LimitPoint,
    /// Neither below the search bound.
    SearchBound,
}

/// The tension at which the equilibrium branch ends, and where and how.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BranchLimit<R> {
    /// N.
    pub tension: R,
    /// 1-based joint where it ends first.
    pub joint: usize,
    pub kind: BranchEnd,
}

/// One joint's equilibrium under tension alone (`Finger::joint_equilibrium`; for the inverse).
#[derive(Clone, Copy, Debug)]
pub struct JointEquilibrium<R> {
    /// Sub-element displacements q = (δax, δtr, Δθ).
    pub q: [[R; 3]; MAX_SUB],
    /// The hinge's distal-end pose in the joint's proximal frame.
    pub end: Pose<R>,
    /// Link k's proximal guide hole (joint's proximal frame), mm.
    pub hole: [R; 2],
    /// The link's deflection (zero for rigid links).
    pub link: [R; 3],
    /// The joint angle as `Solution::joint_angle` has it: end.theta + the link's rotation, rad.
    pub angle: R,
    /// Newton iterations.
    pub iterations: u32,
}

/// One march of a joint without Newton (`Finger::joint_march`): where it arrives.
#[derive(Clone, Copy, Debug)]
pub(crate) struct JointMarch<R> {
    pub end: Pose<R>,
    /// The hole the march arrives at (the residual is the guess minus this), mm.
    pub hole: [R; 2],
    pub link: [R; 3],
    /// end.theta + the link's rotation, rad.
    pub angle: R,
}

impl<R: Real> JointMarch<R> {
    /// The state a march arrived at: its hinge end, hole and link deflection, and the joint
    /// angle end.theta + the link's rotation.
    #[inline(always)]
    pub(super) fn arrived(end: Pose<R>, hole: [R; 2], link: [R; 3]) -> Self {
        JointMarch { end, hole, link, angle: end.theta + link[2] }
    }

    /// The state of a solved equilibrium (`Finger::joint_equilibrium`'s).
    pub(crate) fn of_equilibrium(eq: &JointEquilibrium<R>) -> Self {
        JointMarch { end: eq.end, hole: eq.hole, link: eq.link, angle: eq.angle }
    }
}
