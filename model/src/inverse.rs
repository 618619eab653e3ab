//! The inverse model: joint angles (and optionally a cable tension) to the tension and the
//! channel voltages that hold them; the interval of tensions that can hold a posture (its
//! stiffness range); and the contact force of a tip held at a point (the paper's second
//! conclusion). docs/inverse.md has the algorithm with its reasons.
//!
//! What it is: the entry points and the steps every path shares (the feasible interval, the
//! tension rule, the unreachable report). `fast` is the m = 1 rigid-link fast path (closed
//! per-joint Newton solves with the joint angle fixed), `general` does the same steps for every
//! other parameter set, `table` holds the branch table, `contact` the pinned tip. What it is not: a forward solver
//! (see `finger`), or anything that drives hardware.

use crate::calibration::Calibration;
use crate::error::Error;
use crate::finger::{Finger, Heading, Method, Pose, Solution};
use crate::mat3::Mat3;
use crate::params::{MAX_JOINTS, MAX_SUB};
use crate::real::Real;

mod contact;
mod fast;
mod general;
mod gravity;
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
    // under gravity the table of the joints alone does not hold: the untabled inverse
    if takes_general(f) && !f.has_weight() && general::solve_tabled(table, angles, tension, out)? {
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
    if f.has_weight() {
        gravity::solve(f, angles, tension, opts, &mut out)?;
    } else if takes_general(f) {
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
    } else {
        out = fast::solve(f, angles, tension, opts, out)?;
    }
    reached_from_rest(f, &out, opts)?;
    Ok(out)
}

/// The answer's check against the forward model (docs/inverse.md "Reached from rest"): the
/// converged forward solve at the answer's tension and voltages, from the straight finger,
/// gives back every joint's angle. Each joint's hold solves find an equilibrium at its target
/// angle; where a joint's branch from rest folds (far-off parameter sets, never the board's
/// finger) that can be another equilibrium than the one the finger reaches, or one past the
/// branch's limit point. Refused as `LimitPoint` at the first joint off, or with the forward's
/// own refusal. The tabled path needs no check: the table is the branch from rest.
fn reached_from_rest<R: Real>(f: &Finger<R>, out: &PoseSolution<R>, opts: &Options<R>) -> Result<(), Error> {
    let n = out.n;
    let back = f.solve(out.tension, &out.volts[..n], Method::converged())?;
    // the inverse's own accuracy (docs/inverse.md "Tolerances": 1e-9 rad in f64, 2e-5 in f32),
    // 100 and 1 times over; without stacks its angle tolerance
    let mut tol = R::from_f64(if R::EPS > 1e-10 { 2e-5 } else { 1e-7 });
    if f.params().layers == 0 {
        tol = tol.max(opts.angle_tol * R::from_f64(1.001));
    }
    match (0..n).find(|&k| !((back.joint_angle[k] - out.angles[k]).abs() <= tol)) {
        Some(k) => Err(Error::LimitPoint { joint: k + 1, tension: out.tension.to_f64() }),
        None => Ok(()),
    }
}

/// How far past either end of the stack's thickness range [t at the top voltage, `t0`] a solved
/// thickness may lie and still be that end (rounding, both paths): 1e-6 of t0, or 256 eps in a
/// coarser scalar (f32's Newton wanders 1e-5 of t0 at a low tension).
fn thickness_slack<R: Real>(t0: R) -> R {
    R::from_f64(1e-6_f64.max(256.0 * R::EPS)) * t0
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
