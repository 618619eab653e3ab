//! The finger: joint equilibrium under cable tension (and an optional tip load), posture,
//! cable excursion and tip stiffness (MODEL.md "Cable", "Equilibrium"; the paper's n-FEM-NI,
//! sections II-C/D).
//!
//! What it is: a prepared finger (`Finger::new` validates the parameters and computes the
//! hinge compliances once) and two solvers: the converged equilibrium (Newton) and the paper's
//! load stepping (Eq. 29). What it is not: the inverse (see `inverse`) or anything that drives
//! hardware.
//!
//! Each hinge is split into m sub-elements (m = 1 is the paper's model). Sub-element j of
//! joint k carries q = (δax, δtr, Δθ): the displacement of its distal end in its proximal frame,
//! `q = C · w`, with w the wrench (Fx, Fy, M) on its distal end from everything distal to it,
//! in its proximal frame, M about its distal end (the paper's Eq. 7 and 15, with the loads
//! taken in the deformed geometry rather than its Eq. 12-14 and 32-34).
//!
//! Under tension alone the cable's only load on the distal chain beyond a cut in hinge k is
//! P along span k, applied at link k's proximal hole B (spans further out pull on two points
//! of the distal chain and cancel). So a joint's state is fixed by where B sits: the solver
//! guesses B (two numbers, in the joint's proximal frame), marches through the sub-elements
//! with their loads (each a closed form: the moment's dependence on the sub-element's own
//! deflection is linear), and asks that the hole it arrives at is the guessed B. Newton on that
//! 2x2 residual, with a finite-difference Jacobian and backtracking, and load continuation
//! when a full step fails. A tip load couples the joints: then the unknowns are every B and
//! the tip position, solved together.

use crate::error::Error;
use crate::mat3::{self, Mat3};
use crate::params::{Params, MAX_JOINTS, MAX_SUB};
use crate::real::Real;
use crate::calibration::Calibration;
use crate::{de, hinge};

mod branch_end;
mod march;
mod march_stiffness;
mod pinned;

use crate::solve::continuation::{self, Step};
use crate::solve::newton::{self as newton_solve, Equations};
use crate::solve::{self, SolveOptions};

/// Unknowns of the coupled (tip-loaded) solve: each joint's hole, then the tip position.
const COUPLED: usize = 2 * MAX_JOINTS + 2;

/// The coupled residual (`Finger::coupled_residual`) for `solve::newton`, each slot's marched
/// joint states kept.
struct Coupled<'a, R> {
    f: &'a Finger<R>,
    c: &'a Compliances<R>,
    tension: R,
    force: [R; 2],
    states: [[JointState<R>; MAX_JOINTS]; 3],
}

impl<R: Real> Equations<R, COUPLED> for Coupled<'_, R> {
    type Refusal = MarchError;
    fn dim(&self) -> usize {
        2 * self.f.p.n + 2
    }
    fn residual(&mut self, x: &[R; COUPLED], slot: usize) -> Result<[R; COUPLED], MarchError> {
        let (r, st) = self.f.coupled_residual(self.c, self.tension, self.force, x)?;
        self.states[slot] = st;
        Ok(r)
    }
    fn jacobian(&mut self, x: &[R; COUPLED], r: &[R; COUPLED], _: usize) -> Result<[[R; COUPLED]; COUPLED], MarchError> {
        let h = R::from_f64(R::SQRT_EPS) * (self.f.p.hinge_len() + self.f.p.e);
        newton_solve::forward_difference(self, x, r, &[h; COUPLED])
    }
}

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
    /// `self ∘ (dx, dy, dθ)`: move by (dx, dy) in this pose's frame, then turn by dθ.
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

fn cast_mat<R: Real, S: Real>(m: &Mat3<R>) -> Mat3<S> {
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
    /// point; issue 5).
    pub fn cast<S: Real>(&self) -> Compliances<S> {
        let mut c = [[mat3::zero(); MAX_SUB]; MAX_JOINTS];
        for k in 0..MAX_JOINTS {
            for j in 0..MAX_SUB {
                c[k][j] = cast_mat(&self.c[k][j]);
            }
        }
        Compliances {
            n: self.n,
            m: self.m,
            c,
            thickness: self.thickness.map(|x| S::from_f64(x.to_f64())),
            volts: self.volts.map(|x| S::from_f64(x.to_f64())),
        }
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
    fn arrived(end: Pose<R>, hole: [R; 2], link: [R; 3]) -> Self {
        JointMarch { end, hole, link, angle: end.theta + link[2] }
    }
}

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
    /// FE calibration of the sub-element compliances (`Calibration::none()`: MODEL.md as is).
    cal: Calibration<R>,
}

/// The stack stiffness's upper triangle at thickness t in closed form (`Finger::stack_stiffness`
/// multiplied out: K_a = g_a EA/L (1, 0, d)ᵀ(1, 0, d) plus g_b EI times the beam's bending
/// block, d = (t_min + t)/2, EA ∝ t, EI ∝ t³, g = g0 + g1 t).
#[derive(Clone, Copy)]
pub(crate) struct StackUpper<R> {
    /// E_de w / L.
    ka: R,
    /// The axial and bending factors' (g0, g1).
    ga: [R; 2],
    gb: [R; 2],
    /// t_min / 2.
    d0: R,
    /// E_de w (1/L³, -1/(2 L²), 1/(3 L)): the bending block's entries per t³.
    kb: [R; 3],
}

impl<R: Real> StackUpper<R> {
    /// (k00, k01, k02, k11, k12, k22) at thickness t, mm.
    #[inline(always)]
    pub(crate) fn at(&self, t: R) -> [R; 6] {
        let gka = (self.ga[0] + self.ga[1] * t) * (self.ka * t);
        let d = self.d0 + t * R::from_f64(0.5);
        let e3 = (self.gb[0] + self.gb[1] * t) * (t * t * t);
        let k02 = gka * d;
        [gka, R::zero(), k02, self.kb[0] * e3, self.kb[1] * e3, self.kb[2] * e3 + k02 * d]
    }
}

/// The loads a joint sees besides the cable, in its proximal frame.
#[derive(Clone, Copy)]
struct TipLoad<R> {
    force: [R; 2],
    point: [R; 2],
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

/// The loads `Finger::span_loads` finds: cable force, tip force and its point, their sum.
struct SpanLoads<R> {
    fc: [R; 2],
    ft: [R; 2],
    tp: [R; 2],
    ftot: [R; 2],
}

#[derive(Clone, Copy, Debug)]
enum MarchError {
    Contact,
    Singular,
}

fn norm2<R: Real>(v: [R; 2]) -> R {
    (v[0] * v[0] + v[1] * v[1]).sqrt()
}

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
        Ok(Finger { p, hinge_c, hinge_k, sub_len, link_len, link_c, cal })
    }

    pub fn params(&self) -> &Params<R> {
        &self.p
    }

    /// The same prepared finger in another scalar type: the parameters and the hinge
    /// compliances computed once in `R` and cast (fixed point cannot hold the quadrature's
    /// intermediate products; issue 5).
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

    /// Stiffness of a stack stretch of one sub-element at stack thickness t (mm), calibrated.
    pub fn stack_stiffness(&self, t: R) -> Mat3<R> {
        self.cal.stack_stiffness(&self.p, &de::stack_stiffness(&self.p, self.sub_len, t), self.sub_len, t)
    }

    /// `stack_stiffness`'s upper triangle as a function of the thickness, its constants taken
    /// once (`StackUpper::at`).
    pub(crate) fn stack_upper(&self) -> StackUpper<R> {
        let (p, l) = (&self.p, self.sub_len);
        let ew = p.e_de() * p.w;
        let half = R::from_f64(0.5);
        StackUpper {
            ka: ew / l,
            ga: self.cal.stack_axial,
            gb: self.cal.stack_bending,
            d0: p.t_min * half,
            kb: [ew / (l * l * l), -ew * half / (l * l), ew / (R::from_f64(3.0) * l)],
        }
    }

    /// Hinge compliance of sub-element j (no stack): the Castigliano integrals of MODEL.md
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
        let mut out = Compliances {
            n: p.n,
            m: p.m,
            c: [[mat3::zero(); MAX_SUB]; MAX_JOINTS],
            thickness: [R::zero(); MAX_JOINTS],
            volts: [R::zero(); MAX_JOINTS],
        };
        out.volts[..p.n].copy_from_slice(volts);
        for (k, &v) in volts.iter().enumerate() {
            de::check_voltage(p, k + 1, v)?;
            // a build without the `de` feature refuses stacks in `new`, and leaves the stack's
            // code (thinning, stack stiffness) out of the image
            if p.layers == 0 || cfg!(not(feature = "de")) {
                out.c[k][..p.m].copy_from_slice(&self.hinge_c[..p.m]);
                continue;
            }
            let t = de::stack_thickness(p, k + 1, v)?;
            out.thickness[k] = t;
            let k_de = self.stack_stiffness(t);
            for j in 0..p.m {
                let k_sum = mat3::add(&self.hinge_k[j], &k_de);
                out.c[k][j] = mat3::inverse_spd(&k_sum).ok_or(Error::Singular { what: "joint stiffness" })?;
            }
        }
        Ok(out)
    }

    /// Solve under cable tension alone (N) with one voltage per joint (V).
    ///
    /// `solve`, `solve_loaded` and `solve_with` are inlined into their callers so that a
    /// constant `method` (the firmware only ever asks for `Method::converged()`) selects one
    /// solver at compile time and the other is left out of the image (issue 3: flash).
    #[inline(always)]
    pub fn solve(&self, tension: R, volts: &[R], method: Method<R>) -> Result<Solution<R>, Error> {
        let c = self.compliances(volts)?;
        self.solve_with(&c, tension, [R::zero(); 2], method)
    }

    /// Solve with an external tip force too (N, base frame): the joints couple.
    #[inline(always)]
    pub fn solve_loaded(
        &self,
        tension: R,
        volts: &[R],
        tip_force: [R; 2],
        method: Method<R>,
    ) -> Result<Solution<R>, Error> {
        let c = self.compliances(volts)?;
        self.solve_with(&c, tension, tip_force, method)
    }

    /// Solve with precomputed compliances (see `compliances`).
    #[inline(always)]
    pub fn solve_with(
        &self,
        c: &Compliances<R>,
        tension: R,
        tip_force: [R; 2],
        method: Method<R>,
    ) -> Result<Solution<R>, Error> {
        match method {
            Method::Stepping { n_inc } => self.solve_stepping(c, tension, tip_force, n_inc),
            Method::Converged { tol, max_iter } => self.solve_converged(c, tension, tip_force, tol, max_iter),
        }
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

    /// The paper's explicit load stepping (Eq. 29), `n_inc` steps.
    fn solve_stepping(&self, c: &Compliances<R>, tension: R, tip_force: [R; 2], n_inc: u32) -> Result<Solution<R>, Error> {
        self.check_load(c, tension, tip_force)?;
        if n_inc == 0 {
            return Err(Error::Input { input: "n_inc", reason: "at least one load step" });
        }
        let states = self.stepping(c, tension, tip_force, n_inc)?;
        self.assemble(c, tension, tip_force, &states, None, n_inc)
    }

    /// The converged equilibrium (Newton to `tol` mm on the guide holes).
    fn solve_converged(&self, c: &Compliances<R>, tension: R, tip_force: [R; 2], tol: R, max_iter: u32) -> Result<Solution<R>, Error> {
        self.check_load(c, tension, tip_force)?;
        if !tol.is_finite() || tol <= R::zero() {
            return Err(Error::Input { input: "tol", reason: "tolerance must be positive" });
        }
        let tol = tol.max(self.resolution());
        if tip_force[0] != R::zero() || tip_force[1] != R::zero() {
            let (states, tip, iterations) = self.newton_coupled(c, tension, tip_force, tol, max_iter)?;
            self.assemble(c, tension, tip_force, &states, Some(tip), iterations)
        } else {
            self.solve_tension_alone(c, tension, tol, max_iter)
        }
    }

    /// The converged solve under tension alone: the joints decouple, each solved by Newton on
    /// its own; the solution is written in place (no joint-state arrays, no second march for
    /// the residual and tangent: Newton's last dual march gives them).
    fn solve_tension_alone(&self, c: &Compliances<R>, tension: R, tol: R, max_iter: u32) -> Result<Solution<R>, Error> {
        let mut out = Ok(Solution { n: self.p.n, m: self.p.m, tension, thickness: c.thickness, volts: c.volts, ..Solution::empty() });
        if let Ok(sol) = &mut out {
            if let Err(e) = self.fill_tension_alone(c, tension, tol, max_iter, sol) {
                out = Err(e);
            }
        }
        out
    }

    /// The converged equilibrium under tension alone (MODEL.md "Equilibrium", the joints
    /// decoupled) started from a guide-hole guess per joint (a branch table's,
    /// `inverse::BranchTable::solve_into`), written into the caller's `sol`: Newton on the full
    /// model from the guess, its first evaluation one plain march; a march whose residual is
    /// within the converged solver's tolerance is the answer (Newton's own test at its first
    /// evaluation), else Newton with dual marches from the guess, else the load continuation
    /// of `solve`. The same tolerance and answer as `solve_with(Method::converged())`.
    /// `tangent_det` is 1 for a joint answered at its first march (not evaluated). On an error
    /// `sol` holds no solution.
    #[inline(never)]
    pub(crate) fn solve_from_holes_into(&self, c: &Compliances<R>, tension: R, holes: &[[R; 2]; MAX_JOINTS], sol: &mut Solution<R>) -> Result<(), Error> {
        self.check_load(c, tension, [R::zero(); 2])?;
        let Method::Converged { tol, max_iter } = Method::<R>::converged() else { return Err(Error::Singular { what: "method" }) };
        let tol = tol.max(self.resolution());
        self.fill_from_holes(c, tension, holes, tol, max_iter, sol)
    }

    /// `solve_from_holes_into`'s joints and posture, written in place in one pass: the
    /// solution's scalars set, the rows it held past this finger's (n, m) cleared (only
    /// those), one march per distinct joint into its rows (`march_tension`; Newton,
    /// `polish_joint`, only where that march is not converged), and the posture as it goes
    /// (MODEL.md "Equilibrium": node k = node k-1 ∘ hinge ∘ link; "Cable": the excursion
    /// Σ (L_h - |span k|)): `chain_ends` with the node rotations composed from the marches' own
    /// (sin, cos) and the link's (the same for every link under tension alone, by the series
    /// turn). A span below its floor is contact.
    #[inline(always)]
    fn fill_from_holes(
        &self,
        c: &Compliances<R>,
        tension: R,
        holes: &[[R; 2]; MAX_JOINTS],
        tol: R,
        max_iter: u32,
        sol: &mut Solution<R>,
    ) -> Result<(), Error> {
        let (n, m) = (self.p.n, self.p.m);
        // a solution's rows past its own (n, m) are zero (`Solution`): only the rows `sol`
        // held past this finger's (n, m) are cleared (none for `Solution::empty()` or a
        // solution of this finger)
        let (held_n, held_m) = (sol.n.min(MAX_JOINTS), sol.m.min(MAX_SUB));
        for k in 0..held_n {
            let from = if k < n { m } else { 0 };
            if from < held_m {
                for row in sol.q[k][from..held_m].iter_mut() {
                    *row = [R::zero(); 3];
                }
            }
        }
        for k in n..held_n {
            sol.nodes[k + 1] = Pose::origin();
            sol.links[k] = [R::zero(); 3];
            sol.joint_angle[k] = R::zero();
            sol.span[k] = R::zero();
            sol.tangent_det[k] = R::one();
        }
        sol.n = n;
        sol.m = m;
        sol.tension = tension;
        sol.tip_force = [R::zero(); 2];
        sol.thickness = c.thickness;
        sol.volts = c.volts;
        let link = self.link_q(tension, &Pose::origin(), None);
        // the link's rotation (small: the series turn where it holds, `march::small_turn`)
        let (ls, lc) = if link[2] == R::zero() {
            (R::zero(), R::one())
        } else if link[2].abs() < R::from_f64(march::small_turn(R::EPS)) {
            link[2].sin_cos_small()
        } else {
            link[2].sin_cos()
        };
        let (lx, ly) = (self.link_len + link[0], link[1]);
        let mut node = Pose::origin();
        let (mut s, mut co) = (R::zero(), R::one());
        sol.nodes[0] = node;
        // the joint before: hinge end, (sin, cos) of its angle, the hole it arrived at, its
        // squared residual and tangent determinant
        let mut prev = (Pose::origin(), [R::zero(), R::one()], [R::zero(); 2], R::zero(), R::one());
        let (mut res2, mut iters, mut excursion, mut dets) = (R::zero(), 0u32, R::zero(), R::zero());
        for k in 0..n {
            let b = holes[k];
            // a joint with the same voltage, thickness and guess as the one before has its
            // state (`compliances` makes a joint's compliances a function of its voltage; the
            // first sub-element's are compared too)
            let (end, turn, hole, r2, det) = if k > 0
                && b == holes[k - 1]
                && c.volts[k] == c.volts[k - 1]
                && c.thickness[k] == c.thickness[k - 1]
                && c.c[k][0] == c.c[k - 1][0]
            {
                // the whole row: its sub-elements past m are zero in both
                sol.q[k] = sol.q[k - 1];
                prev
            } else {
                match self.march_tension(&c.c[k], tension, b, &mut sol.q[k]) {
                    Ok((end, hole, sc, r2)) if r2 <= tol * tol => (end, sc, hole, r2, R::one()),
                    _ => {
                        let (st, it) = self.polish_joint(k, &c.c[k], tension, b, tol, max_iter)?;
                        iters += it;
                        sol.q[k][..m].copy_from_slice(&st.q[..m]);
                        let (se, ce) = st.end.theta.sin_cos();
                        let (r, det) = st.tangent.unwrap_or(([R::zero(); 2], R::one()));
                        (st.end, [se, ce], st.hole, r[0] * r[0] + r[1] * r[1], det)
                    }
                }
            };
            prev = (end, turn, hole, r2, det);
            res2 += r2;
            dets += det;
            sol.tangent_det[k] = det;
            let [se, ce] = turn;
            let hinge = Pose { x: node.x + co * end.x - s * end.y, y: node.y + s * end.x + co * end.y, theta: node.theta + end.theta };
            let (hs, hc) = (s * ce + co * se, co * ce - s * se);
            node = Pose { x: hinge.x + hc * lx - hs * ly, y: hinge.y + hs * lx + hc * ly, theta: hinge.theta + link[2] };
            (s, co) = (hs * lc + hc * ls, hc * lc - hs * ls);
            sol.nodes[k + 1] = node;
            sol.links[k] = link;
            sol.joint_angle[k] = end.theta + link[2];
            // the span as the final geometry has it (not the one the loads came from)
            let span = norm2([hole[0], hole[1] - self.p.e]);
            if !(span >= self.p.span_floor) {
                return Err(Error::Contact { joint: k + 1, tension: tension.to_f64() });
            }
            sol.span[k] = span;
            excursion += self.p.hinge_len() - span;
        }
        sol.iterations = iters;
        sol.cable_excursion = excursion;
        sol.residual = res2.sqrt();
        // a non-finite node carries on to the tip; one test for all (a sum is finite only if
        // every term is)
        if !(node.x + node.y + node.theta + res2 + excursion + dets).is_finite() {
            return Err(Error::Singular { what: "solution (non-finite)" });
        }
        Ok(())
    }

    /// Joint k's equilibrium from the hole guess `b` (`solve_from_holes_into`) when its first march
    /// is not converged: Newton from `b` (dual marches), accepted if it stays within half a
    /// hinge length of the guess; else the load continuation from the straight joint.
    #[inline(never)]
    fn polish_joint(&self, k: usize, c: &[Mat3<R>; MAX_SUB], tension: R, b: [R; 2], tol: R, max_iter: u32) -> Result<(JointState<R>, u32), Error> {
        match self.newton_dual(c, tension, b, tol, max_iter) {
            Ok((st, it)) if norm2([st.hole[0] - b[0], st.hole[1] - b[1]]) <= self.p.hinge_len() / R::from_f64(2.0) => Ok((st, it)),
            _ => self.newton_joint(k, c, tension, tol, max_iter, tension / R::from_f64(4096.0)),
        }
    }

    fn fill_tension_alone(
        &self,
        c: &Compliances<R>,
        tension: R,
        tol: R,
        max_iter: u32,
        sol: &mut Solution<R>,
    ) -> Result<(), Error> {
        let (n, m) = (self.p.n, self.p.m);
        let mut ends = [Pose::origin(); MAX_JOINTS];
        let mut holes = [[R::zero(); 2]; MAX_JOINTS];
        let mut res2 = R::zero();
        let mut r2_prev = R::zero();
        let mut iters = 0;
        for k in 0..n {
            // a joint with the same compliance as the one before has the same state (no work)
            if k > 0 && c.c[k][..m] == c.c[k - 1][..m] {
                let (done, rest) = sol.q.split_at_mut(k);
                rest[0][..m].copy_from_slice(&done[k - 1][..m]);
                ends[k] = ends[k - 1];
                holes[k] = holes[k - 1];
                sol.tangent_det[k] = sol.tangent_det[k - 1];
                res2 += r2_prev;
                continue;
            }
            let min_step = tension / R::from_f64(4096.0);
            let (st, it) = self.newton_joint(k, &c.c[k], tension, tol, max_iter, min_step)?;
            iters += it;
            sol.q[k][..m].copy_from_slice(&st.q[..m]);
            ends[k] = st.end;
            holes[k] = st.hole;
            let tangent = match st.tangent {
                Some(t) => Some(t),
                None => self
                    .eval_dual(&c.c[k], tension, st.hole)
                    .ok()
                    .map(|(_, r, j)| (r, j[0][0] * j[1][1] - j[0][1] * j[1][0])),
            };
            let r2 = match tangent {
                Some((r, det)) => {
                    sol.tangent_det[k] = det;
                    r[0] * r[0] + r[1] * r[1]
                }
                None => match self.hole_residual(&c.c[k], tension, st.hole, None) {
                    Ok((r, _)) => r[0] * r[0] + r[1] * r[1],
                    Err(_) => return Err(Error::Contact { joint: k + 1, tension: tension.to_f64() }),
                },
            };
            r2_prev = r2;
            res2 += r2;
        }
        self.finish_tension_alone(tension, &ends, &holes, res2, iters, sol)
    }

    /// The posture of a solve under tension alone from each joint's hinge end and guide hole
    /// (MODEL.md "Equilibrium": node k = node k-1 ∘ hinge ∘ link; "Cable": the excursion
    /// Σ (L_h - |span k|)), into `sol`; a span below its floor is contact.
    #[inline(never)]
    fn finish_tension_alone(
        &self,
        tension: R,
        ends: &[Pose<R>; MAX_JOINTS],
        holes: &[[R; 2]; MAX_JOINTS],
        res2: R,
        iters: u32,
        sol: &mut Solution<R>,
    ) -> Result<(), Error> {
        let n = self.p.n;
        let (nodes, links) = self.chain_ends(ends, tension, [R::zero(); 2], None);
        sol.nodes = nodes;
        sol.links = links;
        sol.iterations = iters;
        for k in 0..n {
            sol.joint_angle[k] = ends[k].theta + links[k][2];
            // the span as the final geometry has it (not the one the loads came from)
            let span = norm2([holes[k][0], holes[k][1] - self.p.e]);
            if !(span >= self.p.span_floor) {
                return Err(Error::Contact { joint: k + 1, tension: tension.to_f64() });
            }
            sol.span[k] = span;
            sol.cable_excursion += self.p.hinge_len() - span;
        }
        sol.residual = res2.sqrt();
        let all_finite = nodes.iter().take(n + 1).all(|p| p.x.is_finite() && p.y.is_finite() && p.theta.is_finite())
            && sol.residual.is_finite()
            && sol.cable_excursion.is_finite()
            && sol.tangent_det[..n].iter().all(|d| d.is_finite());
        if !all_finite {
            return Err(Error::Singular { what: "solution (non-finite)" });
        }
        Ok(())
    }

    /// The finest hole-position residual the scalar type can resolve, mm.
    fn resolution(&self) -> R {
        R::from_f64(16.0 * R::EPS) * (self.p.hinge_len() + self.p.e + self.p.l)
    }

    fn straight(&self) -> JointState<R> {
        let lh = self.p.hinge_len();
        JointState {
            q: [[R::zero(); 3]; MAX_SUB],
            end: Pose { x: lh, y: R::zero(), theta: R::zero() },
            hole: [lh, self.p.e],
            tangent: None,
        }
    }

    /// Cable statics, `f = -P (B - A)/|B - A|` along span k (MODEL.md "Cable", "Equilibrium").
    /// The loads on a joint's distal chain for a guide-hole position `b_hole` (the joint's
    /// proximal frame): the cable's force P along the span toward the hole at the proximal node,
    /// the tip load if any, and their sum. A span at its floor is contact.
    fn span_loads(&self, tension: R, b_hole: [R; 2], tip: Option<TipLoad<R>>) -> Result<SpanLoads<R>, MarchError> {
        let span_v = [b_hole[0], b_hole[1] - self.p.e];
        let span = norm2(span_v);
        if !(span >= self.p.span_floor) {
            return Err(MarchError::Contact);
        }
        let fc = [-tension * span_v[0] / span, -tension * span_v[1] / span];
        let (ft, tp) = match tip {
            Some(t) => (t.force, t.point),
            None => ([R::zero(); 2], [R::zero(); 2]),
        };
        Ok(SpanLoads { fc, ft, tp, ftot: [fc[0] + ft[0], fc[1] + ft[1]] })
    }

    /// March through joint k's sub-elements for a guessed guide-hole position `b_hole` (the
    /// joint's proximal frame): cable force P along the span from `b_hole` to the hole at the
    /// proximal node, plus an optional tip load. Each sub-element's deflection is the closed
    /// solution of `q = C (f, M0 + s)` with `s = -f_y δax + f_x δtr` (the moment arm's own
    /// change, linear in δ).
    fn march(
        &self,
        c: &[Mat3<R>; MAX_SUB],
        tension: R,
        b_hole: [R; 2],
        tip: Option<TipLoad<R>>,
    ) -> Result<JointState<R>, MarchError> {
        // the arithmetic is `march_t`'s in R (one copy of the march in the image; the test
        // `march_t_matches_march` keeps the two entry points bit-equal)
        let mut q = [[R::zero(); 3]; MAX_SUB];
        let (end, hole, _) = self.march_into(c, tension, b_hole, tip, &mut q)?;
        Ok(JointState { q, end, hole, tangent: None })
    }

    /// `march_t` in R: the one plain march in the image (`march` and `joint_march` share it;
    /// issue 3: flash).
    #[inline(never)]
    fn march_into(
        &self,
        c: &[Mat3<R>; MAX_SUB],
        tension: R,
        b_hole: [R; 2],
        tip: Option<TipLoad<R>>,
        q: &mut [[R; 3]; MAX_SUB],
    ) -> Result<(Pose<R>, [R; 2], [R; 2]), MarchError> {
        self.march_t::<R>(c, tension, b_hole, tip, q, |x| x)
    }

    /// Residual of the hole guess: guess - arrived.
    fn hole_residual(
        &self,
        c: &[Mat3<R>; MAX_SUB],
        tension: R,
        b: [R; 2],
        tip: Option<TipLoad<R>>,
    ) -> Result<([R; 2], JointState<R>), MarchError> {
        let st = self.march(c, tension, b, tip)?;
        Ok(([b[0] - st.hole[0], b[1] - st.hole[1]], st))
    }

    /// The exact 2x2 tangent of a joint's hole residual (tension alone), from one march on
    /// dual numbers (see `dual`).
    fn joint_tangent(
        &self,
        c: &[Mat3<R>; MAX_SUB],
        tension: R,
        b: [R; 2],
        _r: [R; 2],
    ) -> Result<[[R; 2]; 2], MarchError> {
        self.eval_dual(c, tension, b).map(|(_, _, jac)| jac)
    }

    /// Converged equilibrium of joint k under tension alone: Newton on the hole position
    /// (`newton_dual`, on `solve::newton`) under load continuation (`solve::continuation`: the
    /// increment doubles on success, halves on failure, down to `min_step`), from a secant
    /// predictor; each accepted step stays on the physical branch (`same_branch`).
    fn newton_joint(
        &self,
        k: usize,
        c: &[Mat3<R>; MAX_SUB],
        tension: R,
        tol: R,
        max_iter: u32,
        min_step: R,
    ) -> Result<(JointState<R>, u32), Error> {
        if tension == R::zero() {
            let st = self.march(c, tension, [self.p.hinge_len(), self.p.e], None).map_err(|_| Error::Singular { what: "joint" })?;
            return Ok((st, 0));
        }
        // the unloaded joint is straight (the march at zero tension gives exactly this)
        let mut last = self.straight();
        let mut b = last.hole;
        let mut iters = 0u32;
        let mut attempts = 0u32;
        // secant predictor: the hole's rate of change with tension over the last accepted step
        let mut rate = [R::zero(); 2];
        let mut failed_at = tension;
        let mut step = |from: R, to: R| -> Result<(), Step<Option<MarchError>>> {
            let (done, target) = (tension * from, tension * to);
            let dp = target - done;
            let guess = [b[0] + rate[0] * dp, b[1] + rate[1] * dp];
            let attempt = match self.newton_dual(c, target, guess, tol, max_iter.saturating_sub(iters)) {
                Err((_, it)) if done > R::zero() => {
                    // the predictor overshot: retry from the last solution itself
                    iters += it;
                    self.newton_dual(c, target, b, tol, max_iter.saturating_sub(iters))
                }
                other => other,
            };
            let (it, outcome) = match attempt {
                Ok((st, it)) => (it, if self.same_branch(&last, &st) { Ok(st) } else { Err(None) }),
                Err((why, it)) => (it, Err(why)),
            };
            iters += it;
            match outcome {
                Ok(st) => {
                    rate = [(st.hole[0] - b[0]) / dp, (st.hole[1] - b[1]) / dp];
                    b = st.hole;
                    last = st;
                    Ok(())
                }
                Err(why) => {
                    failed_at = target;
                    attempts += 1;
                    if iters >= max_iter || attempts > 4 * max_iter {
                        Err(Step::Stop(why))
                    } else {
                        Err(Step::Retry(why))
                    }
                }
            }
        };
        let mut why_failed = None;
        let mut track = |from: R, to: R| -> Result<(), Step<Option<MarchError>>> {
            step(from, to).map_err(|e| {
                let (Step::Retry(w) | Step::Stop(w)) = e;
                if w.is_some() {
                    why_failed = w;
                }
                e
            })
        };
        match continuation::run(R::one(), min_step / tension, None, &mut track) {
            Ok(_) => Ok((last, iters)),
            Err((lam, _)) => {
                let done = tension * lam;
                Err(match why_failed {
                    Some(MarchError::Contact) => Error::Contact { joint: k + 1, tension: failed_at.to_f64() },
                    _ if done > R::zero() && self.near_limit_point(c, done, &last) => {
                        Error::LimitPoint { joint: k + 1, tension: done.to_f64() }
                    }
                    _ => Error::NotConverged { iterations: iters, residual: f64::INFINITY },
                })
            }
        }
    }

    /// Load continuation stays on the physical branch: under a growing tension a joint flexes
    /// further (its angle grows) by a bounded amount per step. A Newton solution that fails
    /// this (a jump to another branch, far from the last one) is rejected and the step halved.
    fn same_branch(&self, last: &JointState<R>, next: &JointState<R>) -> bool {
        let dtheta = next.end.theta - last.end.theta;
        let dhole = norm2([next.hole[0] - last.hole[0], next.hole[1] - last.hole[1]]);
        dtheta >= -R::from_f64(1e-9) && dtheta <= R::from_f64(0.8) && dhole <= R::from_f64(0.5) * self.p.hinge_len()
    }

    /// Whether the equilibrium tangent at a solved state is (nearly) singular: the branch
    /// turns back there (a limit point), so no solution exists just beyond it.
    fn near_limit_point(&self, c: &[Mat3<R>; MAX_SUB], tension: R, st: &JointState<R>) -> bool {
        let Ok((r, _)) = self.hole_residual(c, tension, st.hole, None) else { return false };
        match self.joint_tangent(c, tension, st.hole, r) {
            Ok(j) => (j[0][0] * j[1][1] - j[0][1] * j[1][0]).abs() < R::from_f64(0.2),
            Err(_) => false,
        }
    }

    /// Link compliance, `q = C_link w` (a uniform beam; the model's `flex_links`, docs/model.md).
    /// Deflection of a link (proximal frame `hinge_end`, base frame) when `flex_links` is set:
    /// the cable inside the link compresses it with P at the offset e (moment P·e about its
    /// axis), plus the tip load if any; linear, loads in the undeformed link frame.
    fn link_q(&self, tension: R, hinge_end: &Pose<R>, tip: Option<([R; 2], [R; 2])>) -> [R; 3] {
        if !self.p.flex_links {
            return [R::zero(); 3];
        }
        let mut w = [-tension, R::zero(), tension * self.p.e];
        if let Some((force, point)) = tip {
            let end = hinge_end.then(self.link_len, R::zero(), R::zero());
            let tl = Self::tip_in_frame(&end, force, point);
            let (s, c) = hinge_end.theta.sin_cos();
            w[0] += c * force[0] + s * force[1];
            w[1] += -s * force[0] + c * force[1];
            w[2] += tl.point[0] * tl.force[1] - tl.point[1] * tl.force[0];
        }
        mat3::mul_vec(&self.link_c, &w)
    }

    /// Node poses 0..=n (node k-1 is joint k's proximal frame; node n the tip) for given joint
    /// states, and each link's deflection.
    fn chain(
        &self,
        states: &[JointState<R>; MAX_JOINTS],
        tension: R,
        tip_force: [R; 2],
        tip_point: Option<[R; 2]>,
    ) -> ([Pose<R>; MAX_JOINTS + 1], [[R; 3]; MAX_JOINTS]) {
        let mut ends = [Pose::origin(); MAX_JOINTS];
        for k in 0..self.p.n {
            ends[k] = states[k].end;
        }
        self.chain_ends(&ends, tension, tip_force, tip_point)
    }

    /// `chain` from each joint's hinge end pose alone.
    fn chain_ends(
        &self,
        ends: &[Pose<R>; MAX_JOINTS],
        tension: R,
        tip_force: [R; 2],
        tip_point: Option<[R; 2]>,
    ) -> ([Pose<R>; MAX_JOINTS + 1], [[R; 3]; MAX_JOINTS]) {
        let loaded = tip_force[0] != R::zero() || tip_force[1] != R::zero();
        let mut nodes = [Pose::origin(); MAX_JOINTS + 1];
        let mut links = [[R::zero(); 3]; MAX_JOINTS];
        // with a tip load on flexible links the tip point enters the links' loads: the solved
        // tip when the caller has it (the coupled and pinned solves carry it as an unknown),
        // else a fixed point on the tip from the rigid-link tip (the load stepping)
        let n = self.p.n;
        let given = tip_point.is_some();
        let passes = if loaded && self.p.flex_links && !given { 8 } else { 1 };
        let mut tip_point = if loaded && self.p.flex_links { tip_point } else { None };
        for _ in 0..passes {
            let tip = if loaded { tip_point.map(|t| (tip_force, t)) } else { None };
            for k in 0..n {
                let e = ends[k];
                let hinge_end = nodes[k].then(e.x, e.y, e.theta);
                links[k] = if loaded && tip.is_none() { [R::zero(); 3] } else { self.link_q(tension, &hinge_end, tip) };
                let q = links[k];
                nodes[k + 1] = hinge_end.then(self.link_len + q[0], q[1], q[2]);
            }
            let new_tip = [nodes[n].x, nodes[n].y];
            if given {
                break;
            }
            if let Some(t) = tip_point {
                if (new_tip[0] - t[0]).abs() + (new_tip[1] - t[1]).abs() <= self.resolution() {
                    break;
                }
            }
            tip_point = Some(new_tip);
        }
        (nodes, links)
    }

    /// The tip load as joint k sees it (its proximal frame), from a base-frame force at a
    /// base-frame point.
    fn tip_in_frame(frame: &Pose<R>, force: [R; 2], point: [R; 2]) -> TipLoad<R> {
        let (s, c) = frame.theta.sin_cos();
        let dx = point[0] - frame.x;
        let dy = point[1] - frame.y;
        TipLoad {
            force: [c * force[0] + s * force[1], -s * force[0] + c * force[1]],
            point: [c * dx + s * dy, -s * dx + c * dy],
        }
    }

    /// Tip-loaded equilibrium, every hole and the tip together (MODEL.md "Equilibrium": an
    /// external tip load couples the joints).
    /// Coupled residual for the tip-loaded case. Unknowns: each joint's hole (2 per joint),
    /// then the tip position (2). Returns the residual and the marched states.
    fn coupled_residual(
        &self,
        c: &Compliances<R>,
        tension: R,
        force: [R; 2],
        x: &[R; 2 * MAX_JOINTS + 2],
    ) -> Result<([R; 2 * MAX_JOINTS + 2], [JointState<R>; MAX_JOINTS]), MarchError> {
        let n = self.p.n;
        let tip = [x[2 * n], x[2 * n + 1]];
        let mut states = [self.straight(); MAX_JOINTS];
        let mut r = [R::zero(); 2 * MAX_JOINTS + 2];
        let mut frame = Pose::origin();
        for k in 0..n {
            let tl = Self::tip_in_frame(&frame, force, tip);
            let b = [x[2 * k], x[2 * k + 1]];
            let st = self.march(&c.c[k], tension, b, Some(tl))?;
            r[2 * k] = b[0] - st.hole[0];
            r[2 * k + 1] = b[1] - st.hole[1];
            let hinge_end = frame.then(st.end.x, st.end.y, st.end.theta);
            let ql = self.link_q(tension, &hinge_end, Some((force, tip)));
            frame = hinge_end.then(self.link_len + ql[0], ql[1], ql[2]);
            states[k] = st;
        }
        r[2 * n] = tip[0] - frame.x;
        r[2 * n + 1] = tip[1] - frame.y;
        Ok((r, states))
    }

    /// Converged equilibrium with a tip load: damped Newton (`solve::newton`, forward-difference
    /// Jacobian) on all holes and the tip together, under load continuation
    /// (`solve::continuation`) in the load factor λ (tension and tip force together).
    fn newton_coupled(
        &self,
        c: &Compliances<R>,
        tension: R,
        force: [R; 2],
        tol: R,
        max_iter: u32,
    ) -> Result<([JointState<R>; MAX_JOINTS], [R; 2], u32), Error> {
        let n = self.p.n;
        let mut x = [R::zero(); COUPLED];
        for k in 0..n {
            x[2 * k] = self.p.hinge_len();
            x[2 * k + 1] = self.p.e;
        }
        x[2 * n] = R::from_u32(n as u32) * self.p.l;
        let mut eq = Coupled { f: self, c, tension: R::zero(), force: [R::zero(); 2], states: [[self.straight(); MAX_JOINTS]; 3] };
        let mut iters = 0u32;
        let mut result = None;
        let opts_for = |left: u32| SolveOptions::new(tol, self.resolution() * R::from_u32(n as u32), left);
        let mut step = |_: R, to: R| -> Result<(), Step<Option<MarchError>>> {
            eq.tension = tension * to;
            eq.force = [force[0] * to, force[1] * to];
            let mut xt = x;
            let left = max_iter.saturating_sub(iters);
            match solve::newton::solve(&mut eq, &mut xt, &opts_for(left)) {
                Ok((rep, slot)) => {
                    iters += rep.iterations;
                    x = xt;
                    result = Some(eq.states[slot]);
                    Ok(())
                }
                Err(fail) => {
                    iters += fail.iterations();
                    let why = fail.refusal().copied();
                    if iters >= max_iter { Err(Step::Stop(why)) } else { Err(Step::Retry(why)) }
                }
            }
        };
        match continuation::run(R::one(), R::from_f64(1.0 / 4096.0), None, &mut step) {
            Ok(_) => match result {
                Some(states) => Ok((states, [x[2 * n], x[2 * n + 1]], iters)),
                None => Err(Error::NotConverged { iterations: iters, residual: f64::INFINITY }),
            },
            Err((lam, why)) => Err(match why {
                Some(MarchError::Contact) => Error::Contact { joint: 0, tension: (tension * lam).to_f64() },
                _ => Error::NotConverged { iterations: iters, residual: f64::INFINITY },
            }),
        }
    }

    /// The paper's load stepping (Eq. 29): P_n = n/n_inc P; each step's loads (direction of the
    /// span, moment arms, tip-load point) come from the geometry of the step before, and each
    /// sub-element takes `q = C w` at once.
    fn stepping(
        &self,
        c: &Compliances<R>,
        tension: R,
        force: [R; 2],
        n_inc: u32,
    ) -> Result<[JointState<R>; MAX_JOINTS], Error> {
        let n = self.p.n;
        let mut states = [self.straight(); MAX_JOINTS];
        let loaded = force[0] != R::zero() || force[1] != R::zero();
        for step in 1..=n_inc {
            let lam = R::from_u32(step as u32) / R::from_u32(n_inc as u32);
            let p = tension * lam;
            let f = [force[0] * lam, force[1] * lam];
            let (nodes, _) = self.chain(&states, p, f, None);
            let tip = [nodes[n].x, nodes[n].y];
            let mut next = states;
            for k in 0..n {
                let tl = Self::tip_in_frame(&nodes[k], f, tip);
                next[k] = self
                    .explicit_step(&c.c[k], p, &states[k], if loaded { Some(tl) } else { None })
                    .map_err(|_| Error::Contact { joint: k + 1, tension: p.to_f64() })?;
            }
            states = next;
        }
        Ok(states)
    }

    /// One explicit step for a joint: loads from the previous geometry `prev`.
    fn explicit_step(
        &self,
        c: &[Mat3<R>; MAX_SUB],
        tension: R,
        prev: &JointState<R>,
        tip: Option<TipLoad<R>>,
    ) -> Result<JointState<R>, MarchError> {
        let e = self.p.e;
        let b = prev.hole;
        let SpanLoads { fc, ft, tp, ftot } = self.span_loads(tension, b, tip)?;
        let mut pose: Pose<R> = Pose::origin();
        let mut q = [[R::zero(); 3]; MAX_SUB];
        for j in 0..self.p.m {
            let (s, co) = pose.theta.sin_cos();
            let qp = prev.q[j];
            // previous distal end of this sub-element
            let d = [
                pose.x + co * (self.sub_len + qp[0]) - s * qp[1],
                pose.y + s * (self.sub_len + qp[0]) + co * qp[1],
            ];
            let mut mo = (b[0] - d[0]) * fc[1] - (b[1] - d[1]) * fc[0];
            if tip.is_some() {
                mo += (tp[0] - d[0]) * ft[1] - (tp[1] - d[1]) * ft[0];
            }
            let f = [co * ftot[0] + s * ftot[1], -s * ftot[0] + co * ftot[1]];
            q[j] = mat3::mul_vec(&c[j], &[f[0], f[1], mo]);
            pose = Pose { x: d[0], y: d[1], theta: pose.theta + qp[2] };
        }
        // new geometry from the new q
        let mut end = Pose::origin();
        for qj in q.iter().take(self.p.m) {
            end = end.then(self.sub_len + qj[0], qj[1], qj[2]);
        }
        let hole = end.point(R::zero(), e);
        if !(hole[0].is_finite() && hole[1].is_finite()) {
            return Err(MarchError::Singular);
        }
        Ok(JointState { q, end, hole, tangent: None })
    }

    /// Collect the solution: nodes, joint angles, spans, excursion, residual, tangents.
    fn assemble(
        &self,
        c: &Compliances<R>,
        tension: R,
        tip_force: [R; 2],
        states: &[JointState<R>; MAX_JOINTS],
        tip_point: Option<[R; 2]>,
        iterations: u32,
    ) -> Result<Solution<R>, Error> {
        let n = self.p.n;
        let (nodes, links) = self.chain(states, tension, tip_force, tip_point);
        let mut sol = Solution { n, m: self.p.m, tension, tip_force, nodes, thickness: c.thickness, volts: c.volts, iterations, ..Solution::empty() };
        let loaded = tip_force[0] != R::zero() || tip_force[1] != R::zero();
        // the solved tip (the load's point in the joints' residuals), and its mismatch with
        // the chain's tip in the residual
        let chain_tip = [nodes[n].x, nodes[n].y];
        let tip = tip_point.unwrap_or(chain_tip);
        let mut res2 = (tip[0] - chain_tip[0]).sq() + (tip[1] - chain_tip[1]).sq();
        // residual and tangent determinant of the joint before (tension alone)
        let mut prev: Option<([R; 2], R)> = None;
        for k in 0..n {
            let st = &states[k];
            sol.q[k] = st.q;
            sol.links[k] = links[k];
            sol.joint_angle[k] = st.end.theta + links[k][2];
            // the span as the final geometry has it (not the one the loads came from)
            let span = norm2([st.hole[0], st.hole[1] - self.p.e]);
            if !(span >= self.p.span_floor) {
                return Err(Error::Contact { joint: k + 1, tension: tension.to_f64() });
            }
            sol.span[k] = span;
            sol.cable_excursion += self.p.hinge_len() - span;
            let tl = if loaded { Some(Self::tip_in_frame(&nodes[k], tip_force, tip)) } else { None };
            // tension alone: one dual march gives the residual and the exact tangent; a joint
            // equal to the one before (same compliance, same hole) has the same ones
            let same = k > 0 && c.c[k][..self.p.m] == c.c[k - 1][..self.p.m] && st.hole == states[k - 1].hole;
            let dual = match (loaded, same, prev) {
                (true, _, _) => None,
                (false, true, Some(p)) => Some(p),
                (false, _, _) => self
                    .eval_dual(&c.c[k], tension, st.hole)
                    .ok()
                    .map(|(_, r, j)| (r, j[0][0] * j[1][1] - j[0][1] * j[1][0])),
            };
            prev = dual;
            if let Some((r, det)) = dual {
                res2 += r[0] * r[0] + r[1] * r[1];
                sol.tangent_det[k] = det;
                continue;
            }
            match self.hole_residual(&c.c[k], tension, st.hole, tl) {
                Ok((r, _)) => {
                    res2 += r[0] * r[0] + r[1] * r[1];
                    if let Ok(jac) = self.joint_tangent(&c.c[k], tension, st.hole, r) {
                        sol.tangent_det[k] = jac[0][0] * jac[1][1] - jac[0][1] * jac[1][0];
                    }
                }
                Err(_) => return Err(Error::Contact { joint: k + 1, tension: tension.to_f64() }),
            }
        }
        sol.residual = res2.sqrt();
        let all_finite = nodes.iter().take(n + 1).all(|p| p.x.is_finite() && p.y.is_finite() && p.theta.is_finite())
            && sol.residual.is_finite()
            && sol.cable_excursion.is_finite()
            && sol.tangent_det[..n].iter().all(|d| d.is_finite());
        if !all_finite {
            return Err(Error::Singular { what: "solution (non-finite)" });
        }
        Ok(sol)
    }

    /// Joint `joint`'s (1-based) equilibrium under tension alone for its sub-element compliances
    /// `c` (as in `Compliances::c[k]`), the same solve as `solve_with` does per joint. Newton
    /// from `guess` (link k's proximal hole, the joint's proximal frame) when given, accepted
    /// if the hole moved less than half a hinge length; else, or if it fails, load continuation
    /// from the straight joint. Additive, for the inverse model's per-joint root finding.
    pub fn joint_equilibrium(
        &self,
        joint: usize,
        c: &[Mat3<R>; MAX_SUB],
        tension: R,
        guess: Option<[R; 2]>,
        tol: R,
    ) -> Result<JointEquilibrium<R>, Error> {
        if !tension.is_finite() || tension < R::zero() {
            return Err(Error::Input { input: "tension", reason: "a cable cannot push: tension must be >= 0" });
        }
        let tol = tol.max(self.resolution());
        let k = joint.max(1) - 1;
        let warm = guess.and_then(|b| match self.newton_dual(c, tension, b, tol, 40) {
            Ok((st, it)) if norm2([st.hole[0] - b[0], st.hole[1] - b[1]]) <= self.p.hinge_len() / R::from_f64(2.0) => {
                Some((st, it))
            }
            _ => None,
        });
        let (st, iterations) = match warm {
            Some(v) => v,
            None => self.newton_joint(k, c, tension, tol, 200, tension / R::from_f64(4096.0))?,
        };
        let link = self.link_q(tension, &st.end, None);
        Ok(JointEquilibrium { q: st.q, end: st.end, hole: st.hole, link, angle: st.end.theta + link[2], iterations })
    }

    /// One march of joint `joint` (1-based) under tension alone from the hole guess `b` (no
    /// Newton): the state it arrives at, with `hole` the hole it arrives at (the residual is
    /// `b - hole`) and `angle` the joint angle (hinge and flexible link). For the inverse
    /// model's quasi-Newton solves (inverse/general.rs); `iterations` is 0.
    /// The sub-element displacements go to `q`.
    pub(crate) fn joint_march(
        &self,
        joint: usize,
        c: &[Mat3<R>; MAX_SUB],
        tension: R,
        b: [R; 2],
        q: &mut [[R; 3]; MAX_SUB],
    ) -> Result<JointMarch<R>, Error> {
        let (end, hole, _) = self.march_into(c, tension, b, None, q).map_err(|e| match e {
            MarchError::Contact => Error::Contact { joint, tension: tension.to_f64() },
            MarchError::Singular => Error::Singular { what: "joint march" },
        })?;
        let link = self.link_q(tension, &end, None);
        Ok(JointMarch::arrived(end, hole, link))
    }

    /// `joint_march` by `march_tension` (the same equations carried in each sub-element's own
    /// frame, the same answer to rounding: test `tension_march_matches_march`) where that march
    /// applies (P > 0 and its `den` positive), else `joint_march`'s plain march, as the branch
    /// table's forward does (`fill_from_holes`). For the tabled inverse's confirming marches.
    #[inline(always)]
    pub(crate) fn joint_march_tension(
        &self,
        joint: usize,
        c: &[Mat3<R>; MAX_SUB],
        tension: R,
        b: [R; 2],
        q: &mut [[R; 3]; MAX_SUB],
    ) -> Result<JointMarch<R>, Error> {
        match self.march_tension(c, tension, b, q) {
            Ok((end, hole, _, _)) => {
                let link = self.link_q(tension, &end, None);
                Ok(JointMarch::arrived(end, hole, link))
            }
            Err(_) => self.joint_march(joint, c, tension, b, q),
        }
    }

    /// A joint's march under tension alone from the stiffnesses K_hinge,j + K_de (`kd` the
    /// stack's upper triangle): `march_stiffness`, with `link` the link's deflection at that
    /// tension (`tension_link_q`); None where it refuses (the caller takes the compliance path).
    #[inline(always)]
    pub(crate) fn joint_march_stiffness(&self, kd: &[R; 6], tension: R, link: [R; 3], b: [R; 2], q: &mut [[R; 3]; MAX_SUB]) -> Option<JointMarch<R>> {
        let (end, hole, _, _) = self.march_stiffness(kd, tension, b, q).ok()?;
        Some(JointMarch::arrived(end, hole, link))
    }

    /// A link's deflection under tension alone, the same for every joint (`link_q` without a
    /// tip load).
    pub(crate) fn tension_link_q(&self, tension: R) -> [R; 3] {
        self.link_q(tension, &Pose::origin(), None)
    }

    /// Hinge sub-element j's stiffness (the inverse of its compliance, computed in `new`).
    pub(crate) fn hinge_stiffness(&self, j: usize) -> &Mat3<R> {
        &self.hinge_k[j]
    }

    /// The finest hole-position residual the scalar type can resolve, mm (crate-visible).
    pub(crate) fn hole_resolution(&self) -> R {
        self.resolution()
    }

    /// Linearised tip compliance `C_tip = Σ J C Jᵀ` over every sub-element (MODEL.md "Tip
    /// stiffness"), J mapping a sub-element's distal-end displacement (its proximal frame,
    /// rotation about its distal end) to the tip's (x, y, θ) in the base frame.
    pub fn tip_compliance(&self, c: &Compliances<R>, sol: &Solution<R>) -> Mat3<R> {
        let n = sol.n;
        let tip = sol.nodes[n];
        let mut ct = mat3::zero();
        for k in 0..n {
            let mut pose = sol.nodes[k];
            for j in 0..sol.m {
                let qj = sol.q[k][j];
                let (s, co) = pose.theta.sin_cos();
                let next = pose.then(self.sub_len + qj[0], qj[1], qj[2]);
                let (dx, dy) = (tip.x - next.x, tip.y - next.y);
                let jm: Mat3<R> = [[co, -s, -dy], [s, co, dx], [R::zero(), R::zero(), R::one()]];
                let jc = mat3::mul(&jm, &c.c[k][j]);
                ct = mat3::add(&ct, &mat3::mul(&jc, &mat3::transpose(&jm)));
                pose = next;
            }
            if self.p.flex_links {
                let (s, co) = pose.theta.sin_cos();
                let end = sol.nodes[k + 1];
                let (dx, dy) = (tip.x - end.x, tip.y - end.y);
                let jm: Mat3<R> = [[co, -s, -dy], [s, co, dx], [R::zero(), R::zero(), R::one()]];
                let jc = mat3::mul(&jm, &self.link_c);
                ct = mat3::add(&ct, &mat3::mul(&jc, &mat3::transpose(&jm)));
            }
        }
        ct
    }

    /// The forward equilibrium residual of a solved posture under its own tension, voltages
    /// and tip load (MODEL.md "Equilibrium": each guide hole where its joint's march puts it,
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
            let mut end = Pose::origin();
            for q in sol.q[k].iter().take(self.p.m) {
                end = end.then(self.sub_len + q[0], q[1], q[2]);
            }
            let hole = end.point(R::zero(), self.p.e);
            x[2 * k] = hole[0];
            x[2 * k + 1] = hole[1];
        }
        x[2 * n] = sol.tip().x;
        x[2 * n + 1] = sol.tip().y;
        let (r, _) = self
            .coupled_residual(&c, sol.tension, sol.tip_force, &x)
            .map_err(|_| Error::Contact { joint: 0, tension: sol.tension.to_f64() })?;
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

/// Compliance of a uniform beam (modulus e, width w, thickness t, length len), clamped at its
/// proximal end, loads at its distal end: [[L/EA,0,0],[0,L³/3EI,L²/2EI],[0,L²/2EI,L/EI]].
pub fn uniform_beam_compliance<R: Real>(e: R, w: R, t: R, len: R) -> Mat3<R> {
    let ea = e * w * t;
    let ei = e * w * t * t * t / R::from_f64(12.0);
    let z = R::zero();
    [
        [len / ea, z, z],
        [z, len * len * len / (R::from_f64(3.0) * ei), len * len / (R::from_f64(2.0) * ei)],
        [z, len * len / (R::from_f64(2.0) * ei), len / ei],
    ]
}
