//! The inverse model: joint angles (and optionally a cable tension) to the tension and the
//! channel voltages that hold them; the interval of tensions that can hold a posture (its
//! stiffness range); and the contact force of a tip held at a point (the paper's second
//! conclusion). docs/inverse.md has the algorithm with its reasons.
//!
//! What it is: the entry points, the steps every path shares (the feasible interval, the
//! tension rule, the unreachable report), and the m = 1 rigid-link fast path: closed per-joint
//! Newton solves on the joint equilibrium with the joint angle fixed (docs/inverse.md "Module
//! notes: the m = 1 fast path"). `general` does the same steps for every other parameter set,
//! `table` holds the branch table, `contact` the pinned tip. What it is not: a forward solver
//! (see `finger`), or anything that drives hardware.

use crate::calibration::Calibration;
use crate::de;
use crate::error::Error;
use crate::finger::{Finger, Heading, JointStiffness, Pose, Solution};
use crate::mat3::{self, Mat3};
use crate::params::{Params, MAX_JOINTS, MAX_SUB};
use crate::real::Real;
use crate::solve::{newton, Failure};

mod contact;
mod general;
mod table;

pub use contact::{contact_force, Contact};

pub use table::{BranchTable, TABLE_BAND, TABLE_LEN, TABLE_STEP_DEG};

/// Tuning of the inverse solve.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Options<R> {
    /// The highest voltage the inverse commands, as a fraction of the ceiling (< 1; the ceiling
    /// itself is refused by the model). Default 1 - 1e-4.
    pub top: R,
    /// Without stacks: the largest joint-angle error one tension may leave, rad. Default 1e-4
    /// rad (0.0057°).
    pub angle_tol: R,
    /// Newton iterations per joint solve. Default 30.
    pub max_iter: u32,
    /// The HV modules' full scale, V, when a board drives them: the ceiling is then
    /// `Finger::ceiling_in_force(hv_fs)`. Default None (the model's ceiling alone).
    pub hv_fs: Option<R>,
}

impl<R: Real> Default for Options<R> {
    fn default() -> Self {
        Options { top: R::from_f64(1.0 - 1e-4), angle_tol: R::from_f64(1e-4), max_iter: 30, hv_fs: None }
    }
}

/// The answer of the inverse model.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PoseSolution<R> {
    pub n: usize,
    /// The target joint angles, rad.
    pub angles: [R; MAX_JOINTS],
    /// The cable tension, N.
    pub tension: R,
    /// Whether the tension was given (else chosen by the midpoint rule).
    pub tension_given: bool,
    /// Channel voltages, V.
    pub volts: [R; MAX_JOINTS],
    /// Stack thickness per joint, mm (0 without stacks).
    pub thickness: [R; MAX_JOINTS],
    /// Hinge distal-end displacement per joint (δax mm, δtr mm, θ rad) in the joint's proximal
    /// frame: the hinge's end pose less its nominal length (for m = 1 the sub-element's q).
    pub q: [[R; 3]; MAX_JOINTS],
    /// Sub-elements per hinge the solution is for.
    pub m: usize,
    /// Sub-element displacements q = (δax, δtr, Δθ), `sub_q[k][j]` (as `Solution::q`); the
    /// rows past its n joints and m sub-elements are zero (`solve_pose_tabled_into` clears only
    /// the rows an earlier answer held there).
    pub sub_q: [[[R; 3]; MAX_SUB]; MAX_JOINTS],
    /// Link deflections (as `Solution::links`; zero for rigid links).
    pub links: [[R; 3]; MAX_JOINTS],
    /// The tensions that can hold the posture, [low, high], N.
    pub interval: [R; 2],
    /// Newton iterations spent in all.
    pub iterations: u32,
}

impl<R: Real> PoseSolution<R> {
    /// An all-zero solution (no joints): storage for `solve_pose_tabled_into`.
    pub fn empty() -> Self {
        PoseSolution {
            n: 0,
            angles: [R::zero(); MAX_JOINTS],
            tension: R::zero(),
            tension_given: false,
            volts: [R::zero(); MAX_JOINTS],
            thickness: [R::zero(); MAX_JOINTS],
            q: [[R::zero(); 3]; MAX_JOINTS],
            m: 0,
            sub_q: [[[R::zero(); 3]; MAX_SUB]; MAX_JOINTS],
            links: [[R::zero(); 3]; MAX_JOINTS],
            interval: [R::zero(); 2],
            iterations: 0,
        }
    }
}

/// The stiffness range of a posture: the solutions at both ends of its tension interval and
/// the tip stiffness (`Finger::tip_stiffness`) at each.
#[derive(Clone, Copy, Debug)]
pub struct StiffnessRange<R> {
    /// [low-tension end, high-tension end].
    pub ends: [PoseSolution<R>; 2],
    /// K_tip at each end (x mm, y mm, θ rad; N/mm, N·mm/rad).
    pub stiffness: [Mat3<R>; 2],
}

/// One joint held at its angle: the Newton result.
#[derive(Clone, Copy, Debug)]
struct Hold<R> {
    delta: [R; 2],
    tension: R,
    thickness: R,
    /// Moment per newton of tension at the solution, N·mm/N.
    wm: R,
    /// dP/dθ at fixed t (only from `hold_tension`), N/rad.
    dp_dtheta: R,
    iters: u32,
}

/// What the solver needs of the finger, prepared once per solve.
struct Ctx<'a, R> {
    f: &'a Finger<R>,
    p: &'a Params<R>,
    stack: de::StackStiffness<R>,
    lh: R,
    max_iter: u32,
    rel: R,
}

/// The joint's target angle with its sine and cosine.
#[derive(Clone, Copy)]
struct Angle<R> {
    theta: R,
    s: R,
    c: R,
}

/// ŵ, its derivatives by δax, δtr, θ (columns), and the span length.
struct Wrench<R> {
    w: [R; 3],
    d: [[R; 3]; 3],
}

impl<'a, R: Real> Ctx<'a, R> {
    fn new(f: &'a Finger<R>, opts: &Options<R>) -> Result<Self, Error> {
        let p = f.params();
        let rel = R::from_f64(1e-11_f64.max(64.0 * R::EPS));
        Ok(Ctx { f, p, stack: f.stack(), lh: p.hinge_len(), max_iter: opts.max_iter.max(1), rel })
    }

    /// The joint's stiffness K(t) = K_hinge + K_de(t) and dK/dt (`Finger::joint_stiffness`; m = 1:
    /// its one sub-element; K_hinge alone without stacks).
    fn stiffness(&self, t: R) -> JointStiffness<'a, R> {
        JointStiffness::new(self.f, &self.stack, t)
    }

    /// ŵ at (δax, δtr, θ) and its derivatives. v = B - A (A = (0, e) the hole at node k-1,
    /// B = D + e (-sin θ, cos θ) link k's proximal hole, D = (L_h + δax, δtr) the hinge's
    /// distal end); the force per newton is f = -v/|v|, the moment about D is
    /// M = (B - D) × f = -e (sin θ f_y + cos θ f_x).
    fn wrench(&self, ang: &Angle<R>, d: [R; 2], joint: usize, tension: R) -> Result<Wrench<R>, Error> {
        let e = self.p.e;
        let v = [self.lh + d[0] - e * ang.s, d[1] + e * ang.c - e];
        let rho = (v[0] * v[0] + v[1] * v[1]).sqrt();
        if !(rho >= self.p.span_floor) {
            return Err(Error::Contact { joint, tension: tension.to_f64() });
        }
        let u = [v[0] / rho, v[1] / rho];
        let f = [-u[0], -u[1]];
        let m = -e * (ang.s * f[1] + ang.c * f[0]);
        // df/dv = -(I - u uᵀ)/rho
        let j00 = -(R::one() - u[0] * u[0]) / rho;
        let j01 = u[0] * u[1] / rho;
        let j11 = -(R::one() - u[1] * u[1]) / rho;
        let dmdf = |df0: R, df1: R| -e * (ang.s * df1 + ang.c * df0);
        // by δax (v0), δtr (v1)
        let col0 = [j00, j01, dmdf(j00, j01)];
        let col1 = [j01, j11, dmdf(j01, j11)];
        // by θ: dv/dθ = e (-cos θ, -sin θ), plus the explicit dependence of M on θ
        let dv = [-e * ang.c, -e * ang.s];
        let df = [j00 * dv[0] + j01 * dv[1], j01 * dv[0] + j11 * dv[1]];
        let col2 = [df[0], df[1], -e * (ang.c * f[1] - ang.s * f[0]) + dmdf(df[0], df[1])];
        Ok(Wrench { w: [f[0], f[1], m], d: [col0, col1, col2] })
    }

    /// Joint `joint` (1-based) held at `ang` with stack thickness t: Newton on (δax, δtr, P) of
    /// `K q - P ŵ(q) = 0` (`solve::newton::full_steps`). Also the implicit dP/dθ at fixed t.
    /// Not the march's `SubElement`: with θ given and P (or t) unknown the residual is solved for
    /// the load, where the march solves q for a given load; K is the same `JointStiffness`.
    fn hold_tension(&self, joint: usize, ang: &Angle<R>, t: R, guess: [R; 2]) -> Result<Hold<R>, Error> {
        let k = self.stiffness(t).matrix(0);
        // first tension from the moment row with the guessed δ
        let w0 = self.wrench(ang, guess, joint, R::zero())?;
        let p0 = (k[2][0] * guess[0] + k[2][1] * guess[1] + k[2][2] * ang.theta) / w0.w[2];
        let mut eq = HoldTension { ctx: self, joint, ang, k, w: w0 };
        let mut x = [guess[0], guess[1], p0];
        let (c, inv) = newton::full_steps(&mut eq, &mut x, self.max_iter).map_err(|e| match e {
            Failure::Singular { .. } => Error::LimitPoint { joint, tension: x[2].to_f64() },
            e => hold_error(e),
        })?;
        let (p, w) = (x[2], &eq.w);
        // implicit derivative: J (dδ, dP) = -(K[:,2] - P dŵ/dθ)
        let rhs = [-(k[0][2] - p * w.d[2][0]), -(k[1][2] - p * w.d[2][1]), -(k[2][2] - p * w.d[2][2])];
        let dp = newton::mul_vec(&inv, &rhs)[2];
        Ok(Hold { delta: [x[0], x[1]], tension: p, thickness: t, wm: w.w[2], dp_dtheta: dp, iters: c.iterations })
    }

    /// Joint held at `ang` under tension P: Newton on (δax, δtr, t) of `K(t) q - P ŵ(q) = 0`
    /// (`solve::newton::full_steps`).
    fn hold_thickness(&self, joint: usize, ang: &Angle<R>, p: R, guess: Hold<R>) -> Result<Hold<R>, Error> {
        let w0 = Wrench { w: [R::zero(); 3], d: [[R::zero(); 3]; 3] };
        let mut eq = HoldThickness { ctx: self, joint, ang, p, w: w0, slack: R::one() };
        let mut x = [guess.delta[0], guess.delta[1], guess.thickness];
        let mut r = newton::full_steps(&mut eq, &mut x, self.max_iter);
        if let Err(Failure::MaxIter { .. }) = r {
            // At a low tension the stack's thickness moves the joint little: in f32 the steps
            // can wander at the residual's rounding above `rel`. Once more from there, the
            // steps' tolerance 64 x looser (a thickness error that moves the joint by less).
            eq.slack = R::from_f64(64.0);
            r = newton::full_steps(&mut eq, &mut x, self.max_iter);
        }
        let (c, _) = r.map_err(|e| match e {
            Failure::Singular { .. } => Error::Singular { what: "inverse joint Jacobian" },
            e => hold_error(e),
        })?;
        Ok(Hold { delta: [x[0], x[1]], tension: p, thickness: x[2], wm: eq.w.w[2], dp_dtheta: R::zero(), iters: c.iterations })
    }

    /// The joint's effective compliance θ/M at its target posture when held with tension P
    /// (moment per newton `wm`), or its linear limit (C(t) ŵ)_θ / ŵ_M when P M vanishes.
    fn compliance(&self, ang: &Angle<R>, p: R, wm: R, t: R) -> f64 {
        let m = p * wm;
        if m.abs() > R::from_f64(1e-30_f64.max(R::EPS * 1e-20)) {
            return (ang.theta / m).to_f64();
        }
        let Ok(c) = self.stiffness(t).compliance(0) else { return 0.0 };
        let Ok(w) = self.wrench(ang, [R::zero(); 2], 0, R::zero()) else { return 0.0 };
        let cw = mat3::mul_vec(&c, &w.w);
        (cw[2] / w.w[2]).to_f64()
    }
}

/// `K q - P ŵ(q) = 0` in (δax, δtr, P) at a fixed stiffness K; `w` the last wrench evaluated.
struct HoldTension<'c, 'a, R> {
    ctx: &'c Ctx<'a, R>,
    joint: usize,
    ang: &'c Angle<R>,
    k: Mat3<R>,
    w: Wrench<R>,
}

impl<R: Real> newton::Linearized<R, 3> for HoldTension<'_, '_, R> {
    type Refusal = Error;
    #[inline]
    fn linearize(&mut self, x: &[R; 3]) -> Result<([R; 3], Mat3<R>), Error> {
        let (k, p) = (&self.k, x[2]);
        self.w = self.ctx.wrench(self.ang, [x[0], x[1]], self.joint, p)?;
        let w = &self.w;
        let mut r = [R::zero(); 3];
        let mut jm: Mat3<R> = mat3::zero();
        for row in 0..3 {
            r[row] = k[row][0] * x[0] + k[row][1] * x[1] + k[row][2] * self.ang.theta - p * w.w[row];
            jm[row][0] = k[row][0] - p * w.d[0][row];
            jm[row][1] = k[row][1] - p * w.d[1][row];
            jm[row][2] = -w.w[row];
        }
        Ok((r, jm))
    }
    #[inline]
    fn step_converged(&self, x: &[R; 3], dx: &[R; 3]) -> bool {
        let (rel, tol_len) = (self.ctx.rel, self.ctx.rel * self.ctx.lh);
        dx[0].abs() <= tol_len && dx[1].abs() <= tol_len && dx[2].abs() <= rel * (x[2].abs() + rel)
    }
}

/// `K(t) q - P ŵ(q) = 0` in (δax, δtr, t) at a fixed tension P; `w` the last wrench evaluated.
struct HoldThickness<'c, 'a, R> {
    ctx: &'c Ctx<'a, R>,
    joint: usize,
    ang: &'c Angle<R>,
    p: R,
    w: Wrench<R>,
    /// The steps' tolerance in units of `rel` (1; 64 on the retry).
    slack: R,
}

impl<R: Real> newton::Linearized<R, 3> for HoldThickness<'_, '_, R> {
    type Refusal = Error;
    #[inline]
    fn linearize(&mut self, x: &[R; 3]) -> Result<([R; 3], Mat3<R>), Error> {
        let (ctx, p) = (self.ctx, self.p);
        let kj = ctx.stiffness(x[2]);
        let (k, kd) = (kj.matrix(0), kj.dt(&ctx.stack));
        self.w = ctx.wrench(self.ang, [x[0], x[1]], self.joint, p)?;
        let w = &self.w;
        let q = [x[0], x[1], self.ang.theta];
        let kq = mat3::mul_vec(&k, &q);
        let kdq = mat3::mul_vec(&kd, &q);
        let mut r = [R::zero(); 3];
        let mut jm: Mat3<R> = mat3::zero();
        for row in 0..3 {
            r[row] = kq[row] - p * w.w[row];
            jm[row][0] = k[row][0] - p * w.d[0][row];
            jm[row][1] = k[row][1] - p * w.d[1][row];
            jm[row][2] = kdq[row];
        }
        Ok((r, jm))
    }
    #[inline]
    fn step_converged(&self, x: &[R; 3], dx: &[R; 3]) -> bool {
        let rel = self.ctx.rel * self.slack;
        let tol_len = rel * self.ctx.lh;
        dx[0].abs() <= tol_len && dx[1].abs() <= tol_len && dx[2].abs() <= rel * x[2]
    }
    #[inline]
    fn admissible(&self, x: &[R; 3]) -> bool {
        x.iter().all(|v| v.is_finite()) && x[2] > R::zero()
    }
}

/// A joint hold's failure as the model's error (the wrench's refusal as it is).
fn hold_error(e: Failure<Error>) -> Error {
    match e {
        Failure::Domain(e) | Failure::Stalled { last: Some(e), .. } => e,
        Failure::Singular { iterations } => Error::NotConverged { iterations, residual: f64::INFINITY },
        Failure::Stalled { iterations, .. } | Failure::MaxIter { iterations, .. } => Error::NotConverged { iterations, residual: f64::INFINITY },
    }
}

/// Inverse model at the default options: target joint angles (rad, one per joint) and
/// optionally a tension (N) to the tension and the voltages that hold them. The entry point
/// for the target benchmark: `inverse::solve_pose(&finger, &angles, None)`.
pub fn solve_pose<R: Real>(f: &Finger<R>, angles: &[R], tension: Option<R>) -> Result<PoseSolution<R>, Error> {
    solve_pose_with(f, angles, tension, &Options::default())
}

/// Inverse model with explicit options (see the module documentation for the algorithm).
pub fn solve_pose_with<R: Real>(f: &Finger<R>, angles: &[R], tension: Option<R>, opts: &Options<R>) -> Result<PoseSolution<R>, Error> {
    solve(f, Table::None, angles, tension, opts)
}

/// The inverse with a branch table (table.rs), for the finger and the options the table was
/// built for: step 1's tension ranges are read off the table and only the ends the answer
/// rests on are confirmed (without a tension: the feasible interval's bounds), step 4 starts
/// on the table's level curve (docs/inverse.md, "The branch table"). The same answers to the
/// same tolerance (with a given tension, `interval` is the table's reading), at a fraction of
/// the cost. The m = 1 fast path does not use it. `solve_pose_tabled_into` without the copy.
pub fn solve_pose_tabled<R: Real>(table: &BranchTable<R>, angles: &[R], tension: Option<R>) -> Result<PoseSolution<R>, Error> {
    solve(table.finger(), Table::TryTabled(table), angles, tension, table.options())
}

/// `solve_pose_tabled` written into `out` (the caller's storage, every field set; no copy of
/// the solution on the tabled path): the same answer. On an error `out` holds no solution.
pub fn solve_pose_tabled_into<R: Real>(table: &BranchTable<R>, angles: &[R], tension: Option<R>, out: &mut PoseSolution<R>) -> Result<(), Error> {
    let f = table.finger();
    check_inputs(f, angles, tension, None)?;
    if takes_general(f) && general::solve_tabled(table, angles, tension, out)? {
        return Ok(());
    }
    // (the tabled path tried already: not again)
    *out = solve(f, Table::Tried(table), angles, tension, table.options())?;
    Ok(())
}

/// The options' own checks.
fn check_options<R: Real>(opts: &Options<R>) -> Result<(), Error> {
    if !(opts.top.is_finite() && opts.top > R::zero() && opts.top < R::one()) {
        return Err(Error::Input { input: "top", reason: "fraction of the ceiling in (0, 1)" });
    }
    if let Some(fs) = opts.hv_fs {
        if !(fs.is_finite() && fs > R::zero()) {
            return Err(Error::Input { input: "hv_fs", reason: "the HV full scale must be > 0 V" });
        }
    }
    if !(opts.angle_tol.is_finite() && opts.angle_tol > R::zero()) {
        return Err(Error::Input { input: "angle_tol", reason: "must be positive" });
    }
    Ok(())
}

/// The inputs' own checks (both entry points), and the options' (None: a table's, checked
/// when it was built).
fn check_inputs<R: Real>(f: &Finger<R>, angles: &[R], tension: Option<R>, opts: Option<&Options<R>>) -> Result<(), Error> {
    if angles.len() != f.params().n {
        return Err(Error::Input { input: "angles", reason: "one angle per joint is required" });
    }
    if angles.iter().any(|a| !a.is_finite()) {
        return Err(Error::NonFinite { input: "angle" });
    }
    // past half a turn the links pass through each other, and the hinge's geometry (its sine
    // and cosine) repeats: such an angle has equilibria the finger cannot reach from rest
    let half_turn = R::from_f64(core::f64::consts::PI);
    if angles.iter().any(|a| a.abs() >= half_turn) {
        return Err(Error::Input { input: "angles", reason: "a joint turns less than half a turn (|angle| < pi rad)" });
    }
    if let Some(t) = tension {
        if !t.is_finite() {
            return Err(Error::NonFinite { input: "tension" });
        }
        if t < R::zero() {
            return Err(Error::Input { input: "tension", reason: "a cable cannot push: tension must be >= 0" });
        }
    }
    opts.map_or(Ok(()), check_options)
}

/// Whether `f`'s inverse takes the general path (inverse/general.rs): sub-divided hinges,
/// flexible links, a calibrated finger (the fast path's K(t) is docs/model.md's), or a build
/// without the m = 1 fast path.
fn takes_general<R: Real>(f: &Finger<R>) -> bool {
    let p = f.params();
    !cfg!(feature = "inverse-fast") || p.m != 1 || p.flex_links || *f.calibration() != Calibration::none()
}

/// The branch table `solve` has (built for its finger and options), and whether the general
/// path's `solve_tabled` is still to try.
#[derive(Clone, Copy)]
enum Table<'t, R> {
    /// No table: the general path solves from scratch.
    None,
    /// `solve_tabled` first, then the general path with the table's ends.
    TryTabled(&'t BranchTable<R>),
    /// `solve_tabled` tried already: the general path with the table's ends.
    Tried(&'t BranchTable<R>),
}

impl<'t, R> Table<'t, R> {
    fn table(self) -> Option<&'t BranchTable<R>> {
        match self {
            Table::None => None,
            Table::TryTabled(tb) | Table::Tried(tb) => Some(tb),
        }
    }
}

/// `solve_pose_with` and `solve_pose_tabled` (`table`: see `Table`). One copy in the image
/// for both entry points.
#[inline(never)]
fn solve<R: Real>(f: &Finger<R>, table: Table<'_, R>, angles: &[R], tension: Option<R>, opts: &Options<R>) -> Result<PoseSolution<R>, Error> {
    check_inputs(f, angles, tension, Some(opts))?;
    let p = f.params();
    let n = p.n;
    let mut out = PoseSolution {
        n,
        angles: [R::zero(); MAX_JOINTS],
        tension: R::zero(),
        tension_given: tension.is_some(),
        volts: [R::zero(); MAX_JOINTS],
        thickness: [R::zero(); MAX_JOINTS],
        q: [[R::zero(); 3]; MAX_JOINTS],
        m: p.m,
        sub_q: [[[R::zero(); 3]; MAX_SUB]; MAX_JOINTS],
        links: [[R::zero(); 3]; MAX_JOINTS],
        interval: [R::zero(); 2],
        iterations: 0,
    };
    out.angles[..n].copy_from_slice(angles);
    if takes_general(f) {
        // sub-divided hinges or flexible links: bracketed root finding around the forward
        // per-joint equilibrium (`general`). A build without `inverse-fast` (the firmware,
        // whose default model is m = 8) takes this path for m = 1 too and leaves the fast
        // path's code out of the image.
        if let Table::TryTabled(tb) = table {
            if general::solve_tabled(tb, angles, tension, &mut out)? {
                return Ok(out);
            }
        }
        general::solve(f, table.table(), angles, tension, opts, &mut out)?;
        return Ok(out);
    }
    let ctx = Ctx::new(f, opts)?;
    let mut ang = [Angle { theta: R::zero(), s: R::zero(), c: R::one() }; MAX_JOINTS];
    for k in 0..n {
        let (s, c) = crate::finger::turn(angles[k]);
        ang[k] = Angle { theta: angles[k], s, c };
    }
    let out = if p.layers == 0 { no_stacks(&ctx, &ang, tension, opts, out)? } else { fast(f, &ctx, &ang, tension, opts, out)? };
    // a posture held only by a pushing cable is no answer (a cable cannot push)
    if !(out.tension >= R::zero()) {
        return Err(Error::Input { input: "angles", reason: "the posture needs a pushing cable (tension < 0)" });
    }
    Ok(fill_sub(out))
}

/// The m = 1 fast path: the sub-element q is the hinge's q.
fn fill_sub<R: Real>(mut out: PoseSolution<R>) -> PoseSolution<R> {
    for k in 0..out.n {
        out.sub_q[k][0] = out.q[k];
    }
    out
}

/// The m = 1, rigid-link solve with stacks (module documentation, steps 1-4).
fn fast<R: Real>(
    f: &Finger<R>,
    ctx: &Ctx<'_, R>,
    ang: &[Angle<R>; MAX_JOINTS],
    tension: Option<R>,
    opts: &Options<R>,
    mut out: PoseSolution<R>,
) -> Result<PoseSolution<R>, Error> {
    let p = f.params();
    let n = out.n;

    // 1. every joint's tension range: stiffest stack (0 V) and softest (top voltage)
    let t0 = R::from_u32(p.layers) * p.z0;
    let v_top = f.ceiling_in_force(opts.hv_fs) * opts.top;
    let t_top = if v_top > R::zero() { de::stack_thickness(p, 1, v_top)? } else { t0 };
    let mut hi = [ctx.hold_tension(1, &ang[0], t0, [R::zero(); 2])?; MAX_JOINTS];
    let mut lo = hi;
    for k in 0..n {
        // a joint at the same angle as the one before holds it the same way (no work)
        if k > 0 && ang[k].theta == ang[k - 1].theta {
            hi[k] = hi[k - 1];
            lo[k] = lo[k - 1];
            continue;
        }
        if k > 0 {
            // first guess: the previous joint's deflection scaled by the angle ratio
            let g = if ang[k - 1].theta != R::zero() { ang[k].theta / ang[k - 1].theta } else { R::zero() };
            let guess = [hi[k - 1].delta[0] * g, hi[k - 1].delta[1] * g];
            hi[k] = ctx.hold_tension(k + 1, &ang[k], t0, guess)?;
        }
        lo[k] = ctx.hold_tension(k + 1, &ang[k], t_top, hi[k].delta)?;
        out.iterations += hi[k].iters + lo[k].iters;
        for h in [&hi[k], &lo[k]] {
            if !(h.dp_dtheta > R::zero()) && ang[k].theta != R::zero() {
                return Err(Error::LimitPoint { joint: k + 1, tension: h.tension.to_f64() });
            }
        }
    }
    // 2-3. the feasible interval and the tension (`choose_tension`)
    let mut ends = [[R::zero(); 2]; MAX_JOINTS];
    for k in 0..n {
        ends[k] = [lo[k].tension, hi[k].tension];
    }
    let (interval, pt, worst) = choose_tension(&ends[..n], tension, None, ctx.rel);
    out.interval = interval;
    if let Some(k) = worst {
        // the range the ceiling allows, whichever end is the more compliant
        let (c_hi, c_lo) = (ctx.compliance(&ang[k], hi[k].tension, hi[k].wm, t0), ctx.compliance(&ang[k], lo[k].tension, lo[k].wm, t_top));
        return Err(Error::Unreachable { joint: k + 1, needed: ctx.compliance(&ang[k], pt, hi[k].wm, t0), min: c_hi.min(c_lo), max: c_hi.max(c_lo) });
    }
    out.tension = pt;
    // 4. every joint's thickness at that tension, then its voltage. At zero tension (every
    //    angle zero, or the check above refused it) any voltage holds the straight finger: 0 V.
    for k in 0..n {
        if pt == R::zero() {
            out.thickness[k] = t0;
            out.q[k] = [hi[k].delta[0], hi[k].delta[1], ang[k].theta];
            continue;
        }
        if k > 0 && ang[k].theta == ang[k - 1].theta {
            out.thickness[k] = out.thickness[k - 1];
            out.volts[k] = out.volts[k - 1];
            out.q[k] = out.q[k - 1];
            continue;
        }
        let span = hi[k].tension - lo[k].tension;
        let frac = if span != R::zero() { ((pt - lo[k].tension) / span).max(R::zero()).min(R::one()) } else { R::one() };
        let lerp = |a: R, b: R| a + (b - a) * frac;
        let guess = Hold { delta: [lerp(lo[k].delta[0], hi[k].delta[0]), lerp(lo[k].delta[1], hi[k].delta[1])], thickness: lerp(t_top, t0), ..hi[k] };
        let h = ctx.hold_thickness(k + 1, &ang[k], pt, guess)?;
        out.iterations += h.iters;
        let t = h.thickness.max(t_top).min(t0);
        out.thickness[k] = t;
        out.volts[k] = if t >= t0 { R::zero() } else { de::voltage_for_thickness(p, k + 1, t)?.min(v_top) };
        out.q[k] = [h.delta[0], h.delta[1], ang[k].theta];
    }
    Ok(out)
}

/// The finger without stacks: only the tension is free.
// same parameters as `fast`: the other branch of one dispatch, another computation
fn no_stacks<R: Real>(
    ctx: &Ctx<'_, R>,
    ang: &[Angle<R>; MAX_JOINTS],
    tension: Option<R>,
    opts: &Options<R>,
    mut out: PoseSolution<R>,
) -> Result<PoseSolution<R>, Error> {
    let n = out.n;
    let z = R::zero();
    let mut h = [ctx.hold_tension(1, &ang[0], z, [z; 2])?; MAX_JOINTS];
    // weights dθ/dP
    let mut wt = [z; MAX_JOINTS];
    for k in 0..n {
        if k > 0 {
            h[k] = ctx.hold_tension(k + 1, &ang[k], z, [z; 2])?;
        }
        out.iterations += h[k].iters;
        if !(h[k].dp_dtheta > z) {
            return Err(Error::LimitPoint { joint: k + 1, tension: h[k].tension.to_f64() });
        }
        wt[k] = R::one() / h[k].dp_dtheta;
        out.q[k] = [h[k].delta[0], h[k].delta[1], ang[k].theta];
    }
    let mut tensions = [z; MAX_JOINTS];
    for k in 0..n {
        tensions[k] = h[k].tension;
    }
    let (interval, pt, worst) = one_tension(&tensions[..n], &wt[..n], tension, opts.angle_tol);
    out.interval = interval;
    if let Some(k) = worst {
        let c = ctx.compliance(&ang[k], h[k].tension, h[k].wm, z);
        return Err(Error::Unreachable { joint: k + 1, needed: ctx.compliance(&ang[k], pt, h[k].wm, z), min: c, max: c });
    }
    out.tension = pt;
    Ok(out)
}

/// The no-stacks rule, for both paths: without stacks only the tension is free. Joint k holds
/// its angle at tension `p[k]`, its angle moving `w[k]` rad per newton (dθ_k/dP). Returns the
/// tensions that hold every joint within `tol` rad, the tension (`given`, else the weighted
/// Chebyshev centre: the one that minimises the largest angle error) and the joint furthest
/// past `tol` at it, if any (0.1 % slack: the interval's ends sit exactly on the tolerance).
fn one_tension<R: Real>(p: &[R], w: &[R], given: Option<R>, tol: R) -> ([R; 2], R, Option<usize>) {
    let z = R::zero();
    let n = p.len();
    let mut lo = p[0] - tol / w[0];
    let mut hi = p[0] + tol / w[0];
    for k in 1..n {
        lo = lo.max(p[k] - tol / w[k]);
        hi = hi.min(p[k] + tol / w[k]);
    }
    let pt = match given {
        Some(t) => t,
        None => {
            let mut best = (p[0], R::from_f64(-1.0));
            for i in 0..n {
                for j in i + 1..n {
                    let e = w[i] * w[j] * (p[i] - p[j]).abs() / (w[i] + w[j]);
                    if e > best.1 {
                        best = ((w[i] * p[i] + w[j] * p[j]) / (w[i] + w[j]), e);
                    }
                }
            }
            best.0.max(z)
        }
    };
    let mut worst: Option<(usize, R)> = None;
    for k in 0..n {
        let err = (pt - p[k]).abs() * w[k];
        if err > tol * R::from_f64(1.001) && worst.is_none_or(|(_, e)| err > e) {
            worst = Some((k, err));
        }
    }
    ([lo.max(z), hi.max(z)], pt, worst.map(|(k, _)| k))
}

/// Steps 2-3, the same for both paths. `ends[k]`: joint k's tensions at the softest and the
/// stiffest stack (top voltage, 0 V). Each joint's range is the [min, max] of its two ends:
/// thinning the stack usually softens the joint (the 0 V end needs the most tension), but
/// where the stack's axial-bending coupling dominates (a small cable offset) it stiffens it
/// and the ends swap (found by the property test `inverse_of_a_reachable_posture_holds_it`).
/// The feasible interval is the ranges' intersection; the tension the one `given`, else the
/// interval's midpoint, else (infeasible, or `refuse` set) the median of the mid-range
/// tensions. Returns the interval, the tension and the joint to report as unreachable: `refuse`,
/// else the one furthest outside its range (a tension on an end, within a relative slack of
/// max(1e-8, 256 eps), is accepted).
fn choose_tension<R: Real>(ends: &[[R; 2]], given: Option<R>, refuse: Option<usize>, rel: R) -> ([R; 2], R, Option<usize>) {
    let range = |e: &[R; 2]| (e[0].min(e[1]), e[0].max(e[1]));
    let [p_lo, p_hi] = feasible_interval(ends.len(), |k| ends[k]);
    let pt = match given {
        Some(t) => t,
        None if p_lo <= p_hi && refuse.is_none() => (p_lo + p_hi) / R::from_f64(2.0),
        None => {
            let mut mids = [R::zero(); MAX_JOINTS];
            for (m, e) in mids.iter_mut().zip(ends) {
                *m = (e[0] + e[1]) / R::from_f64(2.0);
            }
            median(&mut mids[..ends.len()])
        }
    };
    if refuse.is_some() {
        return ([p_lo, p_hi], pt, refuse);
    }
    let slack = R::from_f64(1e-8_f64.max(256.0 * R::EPS)) * (pt.abs() + rel);
    let mut worst: Option<(usize, R)> = None;
    for (k, e) in ends.iter().enumerate() {
        let v = (range(e).0 - pt).max(pt - range(e).1);
        if v > slack && worst.is_none_or(|(_, w)| v > w) {
            worst = Some((k, v));
        }
    }
    ([p_lo, p_hi], pt, worst.map(|(k, _)| k))
}

/// The intersection of the joints' tension ranges ([min, max] of each joint's two ends):
/// [largest low end, smallest high end] (empty when the first exceeds the second).
/// `end(k)`: joint k's two ends, k < n (n >= 1).
fn feasible_interval<R: Real>(n: usize, end: impl Fn(usize) -> [R; 2]) -> [R; 2] {
    let e = end(0);
    let mut out = [e[0].min(e[1]), e[0].max(e[1])];
    for k in 1..n {
        let e = end(k);
        out = [out[0].max(e[0].min(e[1])), out[1].min(e[0].max(e[1]))];
    }
    out
}

/// Median of a short slice (sorted in place; insertion sort, no allocation).
fn median<R: Real>(v: &mut [R]) -> R {
    for i in 1..v.len() {
        let mut j = i;
        while j > 0 && v[j - 1] > v[j] {
            v.swap(j - 1, j);
            j -= 1;
        }
    }
    let n = v.len();
    if n == 0 {
        R::zero()
    } else if n % 2 == 1 {
        v[n / 2]
    } else {
        (v[n / 2 - 1] + v[n / 2]) / R::from_f64(2.0)
    }
}

impl<R: Real> PoseSolution<R> {
    /// The posture as a forward `Solution` (nodes, spans, cable excursion), built from `q`
    /// without a forward solve, so that `Finger::tip_stiffness` and the console can use it.
    /// `residual` is 0 and `tangent_det` 1 (not evaluated here; the inverse checked dP/dθ > 0).
    pub fn to_solution(&self, f: &Finger<R>) -> Result<Solution<R>, Error> {
        let p = f.params();
        if p.m != self.m || self.n != p.n {
            return Err(Error::Input { input: "pose solution", reason: "computed for other parameters" });
        }
        let n = self.n;
        let lh = p.hinge_len();
        let link = p.l - lh;
        let mut sol = Solution {
            n,
            m: p.m,
            tension: self.tension,
            tip_force: [R::zero(); 2],
            q: self.sub_q,
            links: self.links,
            joint_angle: [R::zero(); MAX_JOINTS],
            nodes: [Pose::origin(); MAX_JOINTS + 1],
            span: [R::zero(); MAX_JOINTS],
            thickness: self.thickness,
            volts: self.volts,
            cable_excursion: R::zero(),
            iterations: self.iterations,
            residual: R::zero(),
            tangent_det: [R::one(); MAX_JOINTS],
        };
        let mut node = Heading::origin();
        for k in 0..n {
            let end = f.walk(&self.sub_q[k]);
            let l = self.links[k];
            sol.joint_angle[k] = end.pose.theta + l[2];
            let hole = end.point(R::zero(), p.e);
            let span = (hole[0].sq() + (hole[1] - p.e).sq()).sqrt();
            sol.span[k] = span;
            sol.cable_excursion += lh - span;
            let e = end.pose;
            node = node.then(e.x, e.y, e.theta).then(link + l[0], l[1], l[2]);
            sol.nodes[k + 1] = node.pose;
        }
        Ok(sol)
    }
}

/// The stiffness range of the posture `sol` was solved for: the inverse at both ends of its
/// tension interval, and the tip stiffness at each.
pub fn stiffness_range<R: Real>(f: &Finger<R>, sol: &PoseSolution<R>) -> Result<StiffnessRange<R>, Error> {
    let angles = &sol.angles[..sol.n];
    let a = solve_pose(f, angles, Some(sol.interval[0]))?;
    let b = solve_pose(f, angles, Some(sol.interval[1]))?;
    let ka = f.tip_stiffness(&a.to_solution(f)?)?;
    let kb = f.tip_stiffness(&b.to_solution(f)?)?;
    Ok(StiffnessRange { ends: [a, b], stiffness: [ka, kb] })
}
