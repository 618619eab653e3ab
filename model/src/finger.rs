//! The finger: joint equilibrium under cable tension (and an optional tip load), posture,
//! cable excursion and tip stiffness (docs/model.md "Cable", "Equilibrium"; the paper's
//! n-FEM-NI, sections II-C/D).
//!
//! What it is: a prepared finger (`Finger::new`) and its solvers. What it is not: the inverse
//! (`inverse`) or anything that drives hardware. One idea per submodule:
//! - `types`: the value types (pose, method, compliances, solution, branch end);
//! - `prepare`: validation, hinge compliances, the compliances for a set of voltages;
//! - `stiffness`: a joint's K_hinge + K_de at a thickness, its inverse and derivative;
//! - `joint`: one joint's march entry points; `march`, `march_stiffness`: the marches;
//! - `tension`: the converged solve under tension alone; `tabled`: it from a table's guesses;
//! - `loaded`: the tip-loaded coupled solve; `stepping`: the paper's Eq. 29 load stepping;
//! - `posture`: nodes, links and the assembled solution; `tip_stiffness`: C_tip and K_tip;
//! - `pinned`: the tip pinned at a point; `branch_end`: the end of the branch (fmax).
//!
//! The solvers (`tension`, `tabled`, `loaded`, `stepping`, `pinned`, `branch_end`) are functions
//! over `&Finger`; `Finger`'s solving methods below delegate to them.
//!
//! The sub-element state and the solver's unknowns: docs/model.md "Finger solver layout".

use crate::calibration::Calibration;
use crate::error::Error;
use crate::mat3::Mat3;
use crate::params::{Params, MAX_JOINTS, MAX_SUB};
use crate::real::Real;

mod branch_end;
mod gravity;
mod joint;
mod loaded;
mod march;
pub(crate) use march::turn;
#[cfg(feature = "fixed")]
pub(crate) use march::{march_subs, Frame, SubElement};
mod march_stiffness;
mod pinned;
mod posture;
mod prepare;
mod stepping;
mod stiffness;
mod tabled;
mod tension;
mod tip_stiffness;
mod types;

pub(crate) use joint::{by, By};
pub use loaded::CoupledStart;
pub use prepare::uniform_beam_compliance;
pub use stiffness::JointStiffness;
pub use types::{BranchEnd, BranchLimit, Compliances, JointEquilibrium, Method, Pose, Solution};
pub(crate) use types::{Heading, JointMarch};

/// Unknowns of the coupled (tip-loaded or weighted) solve: each joint's hole, the tip position,
/// then under gravity each joint's distal centroid.
const COUPLED: usize = 4 * MAX_JOINTS + 2;
/// Newton iterations a solve started from an earlier answer (`Finger::solve_from`) may take
/// before it falls back to the solve from the straight finger.
const WARM_ITER: u32 = 8;

/// A prepared finger: validated parameters and the hinge compliances, computed once.
#[derive(Clone, Copy, Debug)]
pub struct Finger<R> {
    p: Params<R>,
    /// Hinge (no stack) compliance of sub-element j.
    hinge_c: [Mat3<R>; MAX_SUB],
    /// Its inverse (stiffness), for adding the stack in parallel.
    hinge_k: [Mat3<R>; MAX_SUB],
    /// Sub-element length, mm (L_h / m).
    sub_len: R,
    /// Link length l - L_h, mm.
    link_len: R,
    /// Link compliance (a uniform beam of the body, thickness b), when `flex_links` is set.
    link_c: Mat3<R>,
    /// FE calibration of the sub-element compliances (`Calibration::none()`: docs/model.md as is).
    cal: Calibration<R>,
    /// A fixed load on each joint's distal chain besides the cable (its proximal frame), and
    /// the wrench it adds on its link (the link's frame): the inverse's distal weight at a
    /// posture (docs/model.md "Gravity"); none on a finger `new` prepares.
    held: [Option<TipLoad<R>>; HELD],
    held_link: [[R; 3]; HELD],
}

/// Joints with a held load: every joint with the gravity feature, none without (the fields
/// and their code leave the image).
const HELD: usize = if cfg!(feature = "gravity") { MAX_JOINTS } else { 0 };

/// The loads a joint sees besides the cable (a tip force, the distal weight), in its proximal
/// frame (or the base frame, as its maker says): a force at a point and a couple (N·mm).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct TipLoad<R> {
    force: [R; 2],
    point: [R; 2],
    couple: R,
}

impl<R: Real> TipLoad<R> {
    /// A force at a point.
    fn at(force: [R; 2], point: [R; 2]) -> Self {
        TipLoad { force, point, couple: R::zero() }
    }

    /// This load and another force at another point: the forces summed at this point, the
    /// other's moment about it added to the couple.
    /// The same load in another scalar type.
    fn cast<S: Real>(&self) -> TipLoad<S> {
        let c = |x: R| S::from_f64(x.to_f64());
        TipLoad { force: [c(self.force[0]), c(self.force[1])], point: [c(self.point[0]), c(self.point[1])], couple: c(self.couple) }
    }

    /// The load times `s`.
    fn scaled(&self, s: R) -> Self {
        TipLoad { force: [self.force[0] * s, self.force[1] * s], point: self.point, couple: self.couple * s }
    }

    fn plus(self, force: [R; 2], at: [R; 2]) -> Self {
        let arm = [at[0] - self.point[0], at[1] - self.point[1]];
        TipLoad { force: [self.force[0] + force[0], self.force[1] + force[1]], point: self.point, couple: self.couple + arm[0] * force[1] - arm[1] * force[0] }
    }
}

/// A joint's marched state.
#[derive(Clone, Copy)]
struct JointState<R> {
    q: [[R; 3]; MAX_SUB],
    /// Hinge distal-end pose in the joint's proximal frame.
    end: Pose<R>,
    /// Link k's proximal guide hole, as the march arrives at it (proximal frame).
    hole: [R; 2],
    /// From Newton's last dual march (tension alone): the hole residual and the tangent
    /// determinant at the guess that gave this state, so `assemble` need not march again.
    tangent: Option<([R; 2], R)>,
}

/// The loads `Finger::span_loads` finds: cable force, tip force, its point and couple, their sum.
struct SpanLoads<R, T> {
    fc: [T; 2],
    ft: [R; 2],
    tp: [R; 2],
    tc: R,
    ftot: [T; 2],
}

/// Why a march stopped: the span at its floor (contact), or a state it cannot continue from.
#[derive(Clone, Copy, Debug)]
pub(crate) enum MarchError {
    Contact,
    Singular,
}

fn norm2<R: Real>(v: [R; 2]) -> R {
    (v[0] * v[0] + v[1] * v[1]).sqrt()
}

impl<R: Real> Finger<R> {
    /// Solve under cable tension alone (N) with one voltage per joint (V).
    ///
    /// `solve`, `solve_loaded` and `solve_with` are inlined into their callers so that a
    /// constant `method` (the firmware only ever asks for `Method::converged()`) selects one
    /// solver at compile time and the other is left out of the image (flash).
    #[inline(always)]
    pub fn solve(&self, tension: R, volts: &[R], method: Method<R>) -> Result<Solution<R>, Error> {
        let c = self.compliances(volts)?;
        self.solve_with(&c, tension, [R::zero(); 2], method)
    }

    /// Solve with an external tip force too (N, base frame): the joints couple.
    #[inline(always)]
    pub fn solve_loaded(&self, tension: R, volts: &[R], tip_force: [R; 2], method: Method<R>) -> Result<Solution<R>, Error> {
        let c = self.compliances(volts)?;
        self.solve_with(&c, tension, tip_force, method)
    }

    /// Solve with precomputed compliances (see `compliances`).
    #[inline(always)]
    pub fn solve_with(&self, c: &Compliances<R>, tension: R, tip_force: [R; 2], method: Method<R>) -> Result<Solution<R>, Error> {
        match method {
            Method::Stepping { n_inc } => stepping::solve(self, c, tension, tip_force, n_inc),
            Method::Converged { tol, max_iter } => self.solve_converged(c, tension, tip_force, tol, max_iter),
        }
    }

    /// `solve_with` under tension alone, started from `last` (a coupled answer of this finger
    /// kept from an earlier solve: the board's last posture) and kept into it. Under gravity
    /// with the converged method, Newton starts from `last`'s answer and Broyden Jacobian (at
    /// most `WARM_ITER` iterations, once more on forward differences) instead of from the
    /// straight finger under load continuation; a start that does not converge on the same
    /// branch (`loaded::same_branch`: no joint turned by more than 0.8 rad) falls back to
    /// that. Otherwise `solve_with` (and `last` stays).
    pub fn solve_from(&self, c: &Compliances<R>, tension: R, method: Method<R>, last: &mut Option<CoupledStart<R>>) -> Result<Solution<R>, Error> {
        let Method::Converged { tol, max_iter } = method else { return self.solve_with(c, tension, [R::zero(); 2], method) };
        if self.weights().is_none() {
            return self.solve_with(c, tension, [R::zero(); 2], method);
        }
        self.check_load(c, tension, [R::zero(); 2])?;
        if !tol.is_finite() || tol <= R::zero() {
            return Err(Error::Input { input: "tol", reason: "tolerance must be positive" });
        }
        if let Some(s) = last.as_mut() {
            if let Ok(iters) = s.step(self, c, tension, tol, WARM_ITER.min(max_iter)) {
                return self.assemble(c, tension, [R::zero(); 2], s.states(), Some(s.tip(self.p.n)), iters);
            }
        }
        let (s, iters) = loaded::CoupledStart::solve(self, c, tension, tol, max_iter)?;
        let s = last.insert(s);
        self.assemble(c, tension, [R::zero(); 2], s.states(), Some(s.tip(self.p.n)), iters)
    }

    // The solvers' entry points below delegate to their modules, inlined always: the image is
    // as when they were the solvers' own methods.

    /// The end of the equilibrium branch under tension alone for these voltages (to 1e-4
    /// relative): the tension, the first joint (1-based) and how it ends. If neither happens
    /// below a search bound (1000 times the tension that would turn the softest joint by 1 rad
    /// linearly), that bound is returned as `SearchBound`. The converged solver refuses
    /// tensions past this end (its continuation cannot pass it).
    #[inline(always)]
    pub fn fmax(&self, volts: &[R]) -> Result<BranchLimit<R>, Error> {
        branch_end::fmax(self, volts)
    }

    /// `fmax` with precomputed compliances and optional starting points per joint
    /// (`branch_end::fmax_with`).
    #[inline(always)]
    pub(crate) fn fmax_with(&self, c: &Compliances<R>, starts: Option<&[Option<[(R, [R; 2]); 2]>; MAX_JOINTS]>) -> Result<BranchLimit<R>, Error> {
        branch_end::fmax_with(self, c, starts)
    }

    /// Joint `joint`'s (1-based) equilibrium under tension alone for its sub-element compliances
    /// `c` (as in `Compliances::c[k]`), the same solve as `solve_with` does per joint. Newton
    /// from `guess` (link k's proximal hole, the joint's proximal frame) when given, accepted
    /// if the hole moved less than half a hinge length; else, or if it fails, load continuation
    /// from the straight joint. Additive, for the inverse model's per-joint root finding.
    #[inline(always)]
    pub fn joint_equilibrium(&self, joint: usize, c: &[Mat3<R>; MAX_SUB], tension: R, guess: Option<[R; 2]>, tol: R) -> Result<JointEquilibrium<R>, Error> {
        tension::joint_equilibrium(self, joint, c, tension, guess, tol)
    }

    /// The converged solve under tension alone from a guide-hole guess per joint, into `sol`
    /// (`tabled::solve_from_holes_into`).
    #[inline(always)]
    pub(crate) fn solve_from_holes_into(&self, c: &Compliances<R>, tension: R, holes: &[[R; 2]; MAX_JOINTS], sol: &mut Solution<R>) -> Result<(), Error> {
        tabled::solve_from_holes_into(self, c, tension, holes, sol)
    }

    /// The tip pinned where `free0`'s tip is, at tension `p` and `volts` (`pinned::solve`).
    #[inline(always)]
    pub(crate) fn pinned_tip(&self, free0: &Solution<R>, p: R, volts: &[R]) -> Result<pinned::Pinned<R>, Error> {
        pinned::solve(self, free0, p, volts)
    }

    /// The inputs every solve checks first.
    fn check_load(&self, c: &Compliances<R>, tension: R, tip_force: [R; 2]) -> Result<(), Error> {
        if !tension.is_finite() {
            return Err(Error::NonFinite { input: "tension" });
        }
        if tension < R::zero() {
            return Err(Error::Input { input: "tension", reason: "a cable cannot push: tension must be >= 0" });
        }
        if !(tip_force[0].is_finite() && tip_force[1].is_finite()) {
            return Err(Error::NonFinite { input: "tip force" });
        }
        if c.n != self.p.n || c.m != self.p.m {
            return Err(Error::Input { input: "compliances", reason: "computed for other parameters" });
        }
        Ok(())
    }

    /// The converged equilibrium (Newton to `tol` mm on the guide holes).
    fn solve_converged(&self, c: &Compliances<R>, tension: R, tip_force: [R; 2], tol: R, max_iter: u32) -> Result<Solution<R>, Error> {
        self.check_load(c, tension, tip_force)?;
        if !tol.is_finite() || tol <= R::zero() {
            return Err(Error::Input { input: "tol", reason: "tolerance must be positive" });
        }
        let tol = tol.max(self.resolution());
        if tip_force[0] != R::zero() || tip_force[1] != R::zero() || self.weights().is_some() {
            let (states, tip, iterations) = loaded::newton_coupled(self, c, tension, tip_force, tol, max_iter)?;
            self.assemble(c, tension, tip_force, &states, Some(tip), iterations)
        } else {
            tension::solve(self, c, tension, tol, max_iter)
        }
    }

    /// The finest hole-position residual the scalar type can resolve, mm.
    fn resolution(&self) -> R {
        R::from_f64(16.0 * R::EPS) * (self.p.hinge_len() + self.p.e + self.p.l)
    }

    fn straight(&self) -> JointState<R> {
        let lh = self.p.hinge_len();
        JointState { q: [[R::zero(); 3]; MAX_SUB], end: Pose { x: lh, y: R::zero(), theta: R::zero() }, hole: [lh, self.p.e], tangent: None }
    }

    /// The finest hole-position residual the scalar type can resolve, mm (crate-visible).
    pub(crate) fn hole_resolution(&self) -> R {
        self.resolution()
    }
}
