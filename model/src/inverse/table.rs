//! The inverse's branch table: for one parameter set and one `Options::top`, the joint's
//! equilibrium branch under tension alone at both ends of the stack's range (and the middle),
//! tabulated against the joint angle: θ_i = i h (h = `TABLE_STEP_DEG`) → (P_i, b_i), the
//! tension that holds the joint at θ_i and link k's proximal guide hole there. One table
//! serves every joint (under tension alone the joints decouple and share their geometry).
//!
//! What it is: the table and its readings (its build, `BranchTable::new`, is the general
//! path's: inverse/general/build_table.rs, so the table needs nothing of the solver that
//! reads it) (the inverse's tension ranges, the forward's guide-hole guesses, fmax's start).
//! What it is not: a reduced model: every answer is a converged solve of the full model; the
//! table only decides where the solves start (docs/inverse.md "Module notes: the branch
//! table").

use super::Options;
use crate::de::Stack;
use crate::error::Error;
use crate::finger::{BranchLimit, Compliances, Finger, Method, Solution};
use crate::mat3::Mat3;
use crate::params::{MAX_JOINTS, MAX_SUB};
use crate::real::Real;

/// The relative band around the feasible interval's bounds inside which an end read off the
/// table is solved before the interval is decided (it might bound the interval instead). The
/// table's interpolation error is far below it (a host test shows < 1e-5 relative).
pub const TABLE_BAND: f64 = 1e-3;

/// Samples per stack end.
pub const TABLE_LEN: usize = 64;
/// The angle step between samples, degrees (64 samples reach 94.5°).
pub const TABLE_STEP_DEG: f64 = 1.5;

/// The forward lookup's tension grid: per interval a of the tensions [a dp, (a + 1) dp),
/// a + 1 < `grid_len`, the hole's cubic in s = P/dp - a (power form, the Lagrange cubic through
/// the four nodes around the interval, one-sided at the ends), for each coefficient of its
/// quadratic in stack thickness (powers of τ = t - the middle branch's thickness,
/// `BranchTable::thickness_quadratic`) and each coordinate: `grid[a][i][c]` for τ^i, hole x/y.
pub(super) type TensionGrid<R> = [[[[R; 4]; 2]; 3]; TABLE_LEN];

/// The inverse's reading of the three branches at a joint angle: per sample i (1 ..= len - 3,
/// len the samples held on all three), the cubic through samples i-1 .. i+2 of each branch's
/// tension and hole in power form (`cubic`, s in samples from i): `angle_cubics[i][e][c]` for
/// branch e, component c (P, hole x, hole y).
pub(super) type AngleCubics<R> = [[[[R; 4]; 3]; 3]; TABLE_LEN];

/// An empty tension grid (`BranchTable::new` starts from it).
pub(super) fn zero_grid<R: Real>() -> TensionGrid<R> {
    [[[[R::zero(); 4]; 2]; 3]; TABLE_LEN]
}

/// A joint end read off the table: the tension and the hole.
#[derive(Clone, Copy, Debug)]
pub(super) struct TableEnd<R> {
    pub tension: R,
    pub hole: [R; 2],
}

/// The branch table of one parameter set (module documentation). Branch 0 is the softest
/// stack (t_top), 1 the stiffest (t0, 0 V), 2 the middle thickness (t_top + t0)/2 (a third
/// point for step 4's first guess).
#[derive(Clone, Copy, Debug)]
pub struct BranchTable<R> {
    /// The finger and the options the table was built for (`solve_pose_tabled` solves with
    /// these: a table cannot be used with another parameter set).
    pub(super) finger: Finger<R>,
    pub(super) opts: Options<R>,
    /// Stack thickness of each branch, mm.
    pub(super) thickness: [R; 3],
    /// The top voltage (`top` x the ceiling), V.
    pub(super) v_top: R,
    /// The finger's thickness-to-voltage constants (`solve_pose_tabled`'s voltages).
    pub(super) volts: Stack<R>,
    /// Sub-element compliances at each end (the middle branch's are not kept).
    pub(super) comp: [[Mat3<R>; MAX_SUB]; 2],
    /// dθ/dP of the straight joint at each end, rad/N.
    pub(super) slope0: [R; 2],
    /// Angle step, rad.
    pub(super) step: R,
    pub(super) len: [usize; 3],
    /// (P N, hole x mm, hole y mm) per sample.
    pub(super) x: [[[R; 3]; TABLE_LEN]; 3],
    /// The samples' cubics in θ (`AngleCubics`, `build_angle_cubics`), what `ends` reads.
    pub(super) angle_cubics: AngleCubics<R>,
    /// The forward lookup's grid (`build_tension_grid`, `TensionGrid`), read directly below
    /// `grid_top` (N).
    pub(super) grid: TensionGrid<R>,
    pub(super) dp: R,
    pub(super) inv_dp: R,
    pub(super) grid_len: usize,
    pub(super) grid_top: R,
}

impl<R: Real> BranchTable<R> {
    /// The finger the table was built for.
    pub fn finger(&self) -> &Finger<R> {
        &self.finger
    }

    /// The inverse options the table was built for (`top` sets its softest branch).
    pub fn options(&self) -> &Options<R> {
        &self.opts
    }

    /// The largest angle the table holds on all three branches (what `solve_pose_tabled`
    /// reads off it), rad.
    pub fn max_angle(&self) -> R {
        self.step * R::from_u32(self.covered() as u32 - 1)
    }

    /// Samples held on all three branches.
    pub(super) fn covered(&self) -> usize {
        self.len[0].min(self.len[1]).min(self.len[2])
    }

    /// The tensions the table reads off for joint angle θ (rad): softest stack, stiffest, middle
    /// thickness (N). None where `solve_pose_tabled` solves instead (outside the table).
    pub fn tensions(&self, theta: R) -> Option<[R; 3]> {
        self.ends(theta).map(|e| [e[0].tension, e[1].tension, e[2].tension])
    }

    /// Samples per branch (softest end, stiffest end, middle).
    pub fn len(&self) -> [usize; 3] {
        self.len
    }

    /// The three branches (0 softest, 1 stiffest, 2 middle) at joint angle θ: the cubic
    /// through the four samples around θ (one-sided at the table's ends), one set of weights
    /// for all three (the same grid). None outside (0, last sample of the shortest branch]
    /// or with fewer than four samples.
    pub(super) fn ends(&self, theta: R) -> Option<[TableEnd<R>; 3]> {
        self.read(theta, self.covered())
    }

    /// `ends` with `len`, the samples held on all three branches (`covered`), given: the
    /// sample interval's cubics (`angle_cubics`) at θ.
    #[inline(never)]
    pub(super) fn read(&self, theta: R, len: usize) -> Option<[TableEnd<R>; 3]> {
        if len < 4 {
            return None;
        }
        let u = theta / self.step;
        if !(u > R::zero() && u <= R::from_u32(len as u32 - 1)) {
            return None;
        }
        // the sample interval [a, a+1] holding u (uniform samples: its integer part), the cubic
        // of the four samples around it (one-sided at the table's ends)
        let a = u.to_index().min(len - 2);
        let i = a.clamp(1, len - 3);
        let s = u - R::from_u32(i as u32);
        let k = self.angle_cubics.get(i)?;
        let at = |p: &[R; 4]| p[0] + s * (p[1] + s * (p[2] + s * p[3]));
        let end = |b: &[[R; 4]; 3]| TableEnd { tension: at(&b[0]), hole: [at(&b[1]), at(&b[2])] };
        let e = [end(&k[0]), end(&k[1]), end(&k[2])];
        (e[0].tension > R::zero() && e[1].tension > R::zero() && e[2].tension > R::zero()).then_some(e)
    }

    /// The cubics `read` evaluates (`AngleCubics`), from the samples.
    pub(super) fn build_angle_cubics(&mut self) {
        let len = self.covered();
        if len < 4 {
            return;
        }
        for i in 1..len - 2 {
            for e in 0..3 {
                for c in 0..3 {
                    self.angle_cubics[i][e][c] = cubic(&self.x[e][i - 1..i + 3], c);
                }
            }
        }
    }
}

/// Power-form coefficients (c0 + c1 s + c2 s² + c3 s³, s in node units from the second
/// node) of the cubic through four equally spaced samples' component `c`.
#[inline(always)]
fn cubic<R: Real>(y: &[[R; 3]], c: usize) -> [R; 4] {
    cubic4([y[0][c], y[1][c], y[2][c], y[3][c]])
}

/// `cubic` of four values.
#[inline(always)]
fn cubic4<R: Real>([y0, y1, y2, y3]: [R; 4]) -> [R; 4] {
    let (half, sixth) = (R::from_f64(0.5), R::from_f64(1.0 / 6.0));
    let c2 = (y0 + y2) * half - y1;
    let c3 = (y3 - y0) * sixth + (y1 - y2) * half;
    let c1 = y2 - y1 - c2 - c3;
    [y1, c1, c2, c3]
}

/// The three branches' holes at one tension (`BranchTable::branch_holes`), for the forward
/// lookup: per branch, the hole where the branch carries that tension.
#[derive(Clone, Copy, Debug)]
pub(crate) struct BranchHoles<R> {
    pub hole: [[R; 2]; 3],
}

impl<R: Real> BranchTable<R> {
    /// Where each branch carries tension `p` (N): the cubic P(θ) through the four samples
    /// around it (in power form on the interval, s in node units from node i) inverted by two
    /// Newton steps from the linear guess, and the hole's cubic there. None when `p` is not
    /// inside every branch's tabulated tensions (its last sample's included).
    #[inline(never)]
    pub(crate) fn branch_holes(&self, p: R) -> Option<BranchHoles<R>> {
        let mut out = BranchHoles { hole: [[R::zero(); 2]; 3] };
        let mut found: Option<usize> = None;
        for (e, o) in out.hole.iter_mut().enumerate() {
            let len = self.len[e];
            let xs = &self.x[e];
            if len < 4 || !(p > R::zero() && p <= xs[len - 1][0]) {
                return None;
            }
            // the sample interval [a, a+1] holding p (tensions rise along the branch): a
            // binary search on the first branch, a walk from its interval on the others (their
            // tensions differ by the stack's share)
            let mut a = match found {
                None => {
                    let (mut a, mut b) = (0usize, len - 1);
                    while b - a > 1 {
                        let mid = (a + b) / 2;
                        if xs[mid][0] <= p {
                            a = mid;
                        } else {
                            b = mid;
                        }
                    }
                    a
                }
                Some(a) => a.min(len - 2),
            };
            while a > 0 && xs[a][0] > p {
                a -= 1;
            }
            while a + 2 < len && xs[a + 1][0] <= p {
                a += 1;
            }
            found = Some(a);
            let i = a.clamp(1, len - 3);
            let cp = cubic(&xs[i - 1..i + 3], 0);
            // the linear guess inside [a, a+1], s from node i
            let (pa, pb) = (xs[a][0], xs[a + 1][0]);
            let mut s = R::from_u32(a as u32) - R::from_u32(i as u32) + (p - pa) / (pb - pa);
            let (two, three) = (R::from_f64(2.0), R::from_f64(3.0));
            for _ in 0..2 {
                let v = cp[0] + s * (cp[1] + s * (cp[2] + s * cp[3]));
                let d = cp[1] + s * (two * cp[2] + s * three * cp[3]);
                if !(d > R::zero()) {
                    return None;
                }
                s -= (v - p) / d;
            }
            for c in 0..2 {
                let h = cubic(&xs[i - 1..i + 3], c + 1);
                o[c] = h[0] + s * (h[1] + s * (h[2] + s * h[3]));
            }
            if !(o[0].is_finite() && o[1].is_finite()) {
                return None;
            }
        }
        Some(out)
    }

    /// The forward lookup's tension grid (`TensionGrid`), from the table itself: each
    /// branch's hole at the nodes P_j = j dp (the common tension range in TABLE_LEN - 1 steps)
    /// by `branch_holes`, each interval's cubic in P through the nodes around it, and the range
    /// `grid_top` over which that cubic reads what `branch_holes` reads, to 1/8 of the
    /// converged solver's tolerance (checked at the quarter, middle and three quarters of every
    /// interval; near a limit point the hole is not smooth in P, and the grid stops); then each
    /// interval's three branches as the quadratic in thickness. No solves: built from the
    /// samples in ~64 x 4 lookups.
    pub(super) fn build_tension_grid(&mut self) {
        self.grid_len = 0;
        self.grid_top = R::zero();
        if self.len.iter().any(|&l| l < 4) {
            return;
        }
        let top = self.len.iter().enumerate().map(|(e, &l)| self.x[e][l - 1][0]).fold(R::from_f64(f64::INFINITY), |a, b| a.min(b));
        self.dp = top / R::from_u32(TABLE_LEN as u32 - 1);
        self.inv_dp = R::one() / self.dp;
        // per node: each branch's hole
        let mut nodes = [[[R::zero(); 2]; 3]; TABLE_LEN];
        for e in 0..3 {
            nodes[0][e] = [self.x[e][0][1], self.x[e][0][2]];
        }
        let mut len = 1;
        for j in 1..TABLE_LEN {
            // the last node at the common range's end itself (`dp` x j may round past it)
            let pj = if j == TABLE_LEN - 1 { top } else { self.dp * R::from_u32(j as u32) };
            let Some(h) = self.branch_holes(pj) else { break };
            nodes[j] = h.hole;
            len = j + 1;
        }
        if len < 4 {
            return;
        }
        self.grid_len = len;
        for a in 0..len - 1 {
            let i = a.clamp(1, len - 3);
            let shift = R::from_u32(a as u32) - R::from_u32(i as u32);
            for e in 0..3 {
                for c in 0..2 {
                    // `cubic` in s from node i, shifted to s from node a (Taylor shift by a - i)
                    let [c0, c1, c2, c3] = cubic4([0, 1, 2, 3].map(|n| nodes[i - 1 + n][e][c]));
                    let (two, three) = (R::from_f64(2.0), R::from_f64(3.0));
                    self.grid[a][e][c] =
                        [c0 + shift * (c1 + shift * (c2 + shift * c3)), c1 + shift * (two * c2 + shift * three * c3), c2 + shift * three * c3, c3];
                }
            }
        }
        let p = self.finger.params();
        let res = R::from_f64(16.0 * R::EPS) * (p.hinge_len() + p.e + p.l);
        let bound = res.max(R::from_f64(1e-9)) * R::from_f64(0.125);
        'check: for j in 0..len - 1 {
            for f in [0.25, 0.5, 0.75] {
                let pj = self.dp * (R::from_u32(j as u32) + R::from_f64(f));
                let (Some(a), Some(b)) = (self.grid_holes(pj), self.branch_holes(pj)) else { break 'check };
                for e in 0..3 {
                    if !((a.hole[e][0] - b.hole[e][0]).abs() <= bound && (a.hole[e][1] - b.hole[e][1]).abs() <= bound) {
                        break 'check;
                    }
                }
            }
            self.grid_top = self.dp * R::from_u32(j as u32 + 1);
        }
        // each interval's three branches as the quadratic in thickness (`thickness_quadratic`):
        // what the forward reads (the map is linear: applied to each power of s)
        for a in 0..len - 1 {
            for k in 0..4 {
                let h = BranchHoles { hole: [0, 1, 2].map(|e| [self.grid[a][e][0][k], self.grid[a][e][1][k]]) };
                let Some(q) = self.thickness_quadratic(&h) else {
                    self.grid_len = 0;
                    self.grid_top = R::zero();
                    return;
                };
                for r in 0..3 {
                    for c in 0..2 {
                        self.grid[a][r][c][k] = q.hole[r][c];
                    }
                }
            }
        }
    }

    /// The hole's quadratic in the stack thickness t through the three branches' holes at one
    /// tension, in powers of τ = t - t_mid (the middle branch's thickness): `hole[i]` the
    /// coefficient of τ^i. None if two branch thicknesses coincide.
    fn thickness_quadratic(&self, h: &BranchHoles<R>) -> Option<BranchHoles<R>> {
        let [t_top, t0, tm] = self.thickness;
        // the Lagrange basis in τ: (d_top, d0) the outer thicknesses from the middle
        let (dt, d0) = (t_top - tm, t0 - tm);
        let (a, b, m) = (dt * (dt - d0), d0 * (d0 - dt), dt * d0);
        if a == R::zero() || b == R::zero() || m == R::zero() {
            return None;
        }
        let (ia, ib, im) = (R::one() / a, R::one() / b, R::one() / m);
        let mut out = BranchHoles { hole: [[R::zero(); 2]; 3] };
        for c in 0..2 {
            let (yt, y0, ym) = (h.hole[0][c] * ia, h.hole[1][c] * ib, h.hole[2][c] * im);
            out.hole[0][c] = h.hole[2][c];
            out.hole[1][c] = -(yt * d0 + y0 * dt + ym * (dt + d0));
            out.hole[2][c] = yt + y0 + ym;
        }
        Some(out)
    }

    /// The tension grid's three rows at tension `p` (N): its interval's cubics in P. The
    /// branches' holes while `build_tension_grid` checks the grid, their quadratic in thickness
    /// after. None outside the grid.
    #[inline(always)]
    fn grid_holes(&self, p: R) -> Option<BranchHoles<R>> {
        let len = self.grid_len;
        if len < 4 || !(p >= R::zero() && p < self.dp * R::from_u32(len as u32 - 1)) {
            return None;
        }
        let u = p * self.inv_dp;
        let a = u.to_index().min(len - 2);
        let s = u - R::from_u32(a as u32);
        let g = self.grid.get(a)?;
        let mut out = BranchHoles { hole: [[R::zero(); 2]; 3] };
        for r in 0..3 {
            for c in 0..2 {
                let k = &g[r][c];
                out.hole[r][c] = k[0] + s * (k[1] + s * (k[2] + s * k[3]));
            }
        }
        Some(out)
    }

    /// The hole at stack thickness `t` (mm) from the branches' holes at one tension: the
    /// quadratic through the three branch thicknesses. None outside [t_top, t0] (with a
    /// sliver of 1e-3 of the range: voltages between the table's top and the ceiling).
    #[inline(never)]
    pub(crate) fn hole_at_thickness(&self, h: &BranchHoles<R>, t: R) -> Option<[R; 2]> {
        let [t_top, t0, tm] = self.thickness;
        let slack = (t0 - t_top) * R::from_f64(1e-3);
        if !(t >= t_top - slack && t <= t0 + slack) {
            return None;
        }
        let (d01, d02, d12) = (t_top - t0, t_top - tm, t0 - tm);
        if d01 == R::zero() || d02 == R::zero() || d12 == R::zero() {
            return None;
        }
        let w = [(t - t0) * (t - tm) / (d01 * d02), -(t - t_top) * (t - tm) / (d01 * d12), (t - t_top) * (t - t0) / (d02 * d12)];
        let mut b = [R::zero(); 2];
        for c in 0..2 {
            b[c] = w[0] * h.hole[0][c] + w[1] * h.hole[1][c] + w[2] * h.hole[2][c];
        }
        Some(b)
    }
}

impl<R: Real> BranchTable<R> {
    /// The forward solve under tension alone (N) at these channel voltages (V), from the table:
    /// `solve_with` after `Finger::compliances`.
    pub fn solve(&self, tension: R, volts: &[R]) -> Result<Solution<R>, Error> {
        let c = self.finger.compliances(volts)?;
        self.solve_with(&c, tension)
    }

    /// The forward solve under tension alone with precomputed compliances (of this table's
    /// finger), returned by value: `solve_into` into a new solution.
    #[inline(always)]
    pub fn solve_with(&self, c: &Compliances<R>, tension: R) -> Result<Solution<R>, Error> {
        let mut sol = Solution::empty();
        self.solve_into(c, tension, &mut sol).map(|()| sol)
    }

    /// The forward solve under tension alone with precomputed compliances (of this table's
    /// finger, as `Finger::compliances` makes them: symmetric), written into `sol` (the
    /// caller's storage; no copy of the solution; rows it held past this finger's (n, m) are
    /// cleared, `Solution`): each
    /// joint's guide hole read off the table at (P, its stack thickness), then Newton on the
    /// full model from there (`Finger::solve_from_holes_into`: a joint whose march at the
    /// table's hole is within the solver's tolerance is answered by that march). The answer
    /// is `Finger::solve_with(Method::converged())`'s, to its tolerance; where the table does
    /// not hold (P, t) (P = 0, past its last sample, t outside its stack range) it is that
    /// solve. On an error `sol` holds no solution.
    pub fn solve_into(&self, c: &Compliances<R>, tension: R, sol: &mut Solution<R>) -> Result<(), Error> {
        let f = &self.finger;
        match self.forward_holes(c, tension) {
            Some(holes) => f.solve_from_holes_into(c, tension, &holes, sol),
            None => {
                *sol = f.solve_with(c, tension, [R::zero(); 2], Method::converged())?;
                Ok(())
            }
        }
    }

    /// Each joint's guide hole read off the table at (P, its stack thickness), or None where
    /// the table does not hold one of them: the quadratic in thickness at P (the tension
    /// grid's cubic in P, or `branch_holes` past the grid), evaluated at each distinct joint's
    /// thickness.
    #[inline(never)]
    fn forward_holes(&self, c: &Compliances<R>, tension: R) -> Option<[[R; 2]; MAX_JOINTS]> {
        let n = self.finger.params().n;
        // under gravity the joints are coupled: the table of the joints alone does not hold
        if !(tension.is_finite() && c.n == n) || self.finger.has_weight() {
            return None;
        }
        let h =
            if tension > R::zero() && tension < self.grid_top { self.grid_holes(tension)? } else { self.thickness_quadratic(&self.branch_holes(tension)?)? };
        let [t_top, t0, tm] = self.thickness;
        let slack = (t0 - t_top) * R::from_f64(1e-3);
        let (lo, hi) = (t_top - slack, t0 + slack);
        let mut holes = [[R::zero(); 2]; MAX_JOINTS];
        for k in 0..n {
            let t = c.thickness[k];
            if k > 0 && t == c.thickness[k - 1] {
                holes[k] = holes[k - 1];
                continue;
            }
            if !(t >= lo && t <= hi) {
                return None;
            }
            let tau = t - tm;
            for c in 0..2 {
                holes[k][c] = h.hole[0][c] + tau * (h.hole[1][c] + tau * h.hole[2][c]);
            }
        }
        Some(holes)
    }
}

impl<R: Real> BranchTable<R> {
    /// The end of the equilibrium branch under tension alone at these voltages
    /// (`Finger::fmax`, same answer and tolerance), its march up the branch continued, for each
    /// joint, from the table's last two samples (the three branches' last common angles, the
    /// tension and hole quadratic in the joint's stack thickness) instead of started at the
    /// straight joint.
    pub fn fmax(&self, volts: &[R]) -> Result<BranchLimit<R>, Error> {
        let f = &self.finger;
        let c = f.compliances(volts)?;
        let mut starts = [None; MAX_JOINTS];
        let last = self.covered();
        if last >= 4 {
            let at = |i: usize, k: usize| {
                let h = BranchHoles { hole: [0, 1, 2].map(|e| [self.x[e][i][1], self.x[e][i][2]]) };
                let p = BranchHoles { hole: [0, 1, 2].map(|e| [self.x[e][i][0], R::zero()]) };
                Some((self.hole_at_thickness(&p, c.thickness[k])?[0], self.hole_at_thickness(&h, c.thickness[k])?))
            };
            for (k, s) in starts.iter_mut().enumerate().take(f.params().n) {
                if let (Some(a), Some(b)) = (at(last - 2, k), at(last - 1, k)) {
                    *s = Some([a, b]);
                }
            }
        }
        f.fmax_with(&c, Some(&starts))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::params::Params;

    /// The forward's lookup (`forward_holes`: the tension grid's cubic in P, per coefficient of
    /// the quadratic in thickness) reads what the branch inversion and the Lagrange quadratic
    /// across the three branch thicknesses read (`branch_holes`, `hole_at_thickness`): in f32
    /// (where the grid holds over the whole table) to its bound (1/8 of the converged solver's
    /// tolerance) and the rounding of both, over the tensions and the stack's range; in f64
    /// (no grid at its tolerance) the power form of the quadratic to rounding.
    #[test]
    fn forward_lookup_is_the_branch_quadratic() {
        fn check<R: Real>(tol: f64, grid: bool) {
            let f = Finger::new(Params::<R>::default()).unwrap();
            let t = BranchTable::new(&f, &Options::default()).unwrap();
            let top = f.voltage_ceiling().to_f64() * (1.0 - 1e-4);
            let p_end = t.dp.to_f64() * (TABLE_LEN - 1) as f64;
            assert_eq!(t.grid_top.to_f64() > 0.99 * p_end, grid, "grid to {} of {p_end}", t.grid_top.to_f64());
            let mut checked = 0;
            for i in 1..200 {
                let p = R::from_f64(p_end * 1.02 * i as f64 / 200.0);
                for v in [[0.0, 0.5 * top, top], [0.9 * top, 0.2 * top, 0.7 * top]] {
                    let c = f.compliances(&v.map(R::from_f64)).unwrap();
                    let (Some(got), Some(h)) = (t.forward_holes(&c, p), t.branch_holes(p)) else { continue };
                    for k in 0..3 {
                        let want = t.hole_at_thickness(&h, c.thickness[k]).unwrap();
                        for x in 0..2 {
                            let e = (got[k][x] - want[x]).to_f64().abs();
                            assert!(e < tol, "P {} joint {k}: {e} mm", p.to_f64());
                        }
                    }
                    checked += 1;
                }
            }
            assert!(checked > 380, "{checked}");
        }
        check::<f32>(2e-5, true);
        check::<f64>(1e-11, false);
    }
}
