//! The fixed-point inverse at a given tension: target joint angles to each joint's stack
//! thickness (then its voltage). Set-up (float, once per parameter change): the sub-element
//! compliances at [`NODES`] stack thicknesses from the rest thickness to the ceiling's, each
//! matrix row at one exponent across the nodes. Solve: per joint, regula falsi (Illinois) on
//! the thickness with the compliances interpolated linearly between nodes and the joint
//! equilibrium of [`FixedFinger`]. Without a tension ([`FixedInverseDirect::solve_free`]):
//! the float inverse's rule (`inverse::choose_tension`), each joint's tensions at the two stack
//! ends by following its branch from 0 N, the midpoint of the feasible interval. Not here: fmax.
use super::branch_end::SEARCH_BOUND_N;
use super::forward::{cmat, CMat, FixedFinger, MarchError};
use super::q::{Mm, Nt, Rad, Q};
use crate::de;
use crate::error::Error;
use crate::finger::Finger;
use crate::params::{MAX_JOINTS, MAX_SUB};
use crate::real::Real;

/// Thickness nodes of the compliance table.
pub const NODES: usize = 33;
/// Stop: the hinge angle within this many Q28 units (~6e-8 rad).
const TOL_RAW: i32 = 16;
const MAX_ITER: u32 = 40;
/// A target this close past an end of the range (Q28 units, ~1e-6 rad) is that end.
const END_TOL_RAW: i64 = 268;

pub struct FixedInverse {
    fwd: FixedFinger,
    table: [[CMat; MAX_SUB]; NODES],
    /// Stack thickness at node 0 (0 V) and at the last node (the ceiling), mm.
    t_rest: Mm,
    t_ceiling: Mm,
}

/// Each joint's stack thickness for the target angles.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FixedPoseSolution {
    pub n: usize,
    pub thickness: [Mm; MAX_JOINTS],
    pub tension: Nt,
    /// Joint solves, all joints.
    pub evaluations: u32,
}

fn lerp(a: i32, b: i32, w: i64) -> i32 {
    (a as i64 + (((b as i64 - a as i64) * w + (1 << 15)) >> 16)) as i32
}

impl FixedInverse {
    pub fn new<R: Real>(f: &Finger<R>) -> Result<Self, Error> {
        let p = f.params();
        if p.layers == 0 {
            return Err(Error::Input { input: "layers", reason: "the fixed-point inverse needs stacks" });
        }
        let n = p.n;
        let zero = [R::zero(); MAX_JOINTS];
        let fwd = FixedFinger::new(f, &zero[..n])?;
        let vmax = f.ceiling_in_force(None) * R::from_f64(1.0 - 1e-6);
        let (t_rest, t_ceiling) = (f.stack_thickness(R::zero())?, f.stack_thickness(vmax)?);
        let mut table = [[CMat::default(); MAX_SUB]; NODES];
        for (i, node) in table.iter_mut().enumerate() {
            let t = t_rest - (t_rest - t_ceiling) * R::from_u32(i as u32) / R::from_u32(NODES as u32 - 1);
            let v = if i == 0 { R::zero() } else { de::voltage_for_thickness(p, 1, t.max(t_ceiling))? };
            let mut vs = [R::zero(); MAX_JOINTS];
            vs[..n].iter_mut().for_each(|x| *x = v);
            let comp = f.compliances(&vs[..n])?;
            for (c, src) in node.iter_mut().zip(&comp.c[0][..p.m]) {
                *c = cmat(src);
            }
        }
        // one exponent per (sub-element, row) across the nodes: the largest row keeps 30 bits
        for j in 0..p.m {
            for r in 0..3 {
                let t = table.iter().map(|nd| nd[j].t[r]).min().unwrap_or(0);
                for nd in table.iter_mut() {
                    let d = nd[j].t[r] - t;
                    for x in nd[j].m[r].iter_mut() {
                        *x = super::q::shr_round(*x as i64, d) as i32;
                    }
                    nd[j].t[r] = t;
                }
            }
            for pick in [0, 1] {
                let get = |nd: &[CMat; MAX_SUB]| if pick == 0 { nd[j].d02 } else { nd[j].d12 };
                let sh = table.iter().filter(|nd| get(nd).m != 0).map(|nd| get(nd).sh).min().unwrap_or(0);
                for nd in table.iter_mut() {
                    let d = if pick == 0 { &mut nd[j].d02 } else { &mut nd[j].d12 };
                    d.m = super::q::shr_round(d.m as i64, d.sh - sh) as i32;
                    d.sh = sh;
                }
            }
        }
        let mm = |x: R| Mm::from_real(x);
        Ok(FixedInverse { fwd, table, t_rest: mm(t_rest), t_ceiling: mm(t_ceiling) })
    }

    /// The compliances at table position `u` (Q16 nodes: 0 = rest thickness).
    fn at(&self, u: i64) -> [CMat; MAX_SUB] {
        let last = ((NODES - 1) as i64) << 16;
        let u = u.clamp(0, last);
        let i = ((u >> 16) as usize).min(NODES - 2);
        let w = u - ((i as i64) << 16);
        let (a, b) = (&self.table[i], &self.table[i + 1]);
        let mut o = *a;
        for j in 0..self.fwd.m {
            for r in 0..3 {
                for c in 0..3 {
                    o[j].m[r][c] = lerp(a[j].m[r][c], b[j].m[r][c], w);
                }
            }
            o[j].d02.m = lerp(a[j].d02.m, b[j].d02.m, w);
            o[j].d12.m = lerp(a[j].d12.m, b[j].d12.m, w);
        }
        o
    }

    /// Each joint's stack thickness that holds `angles` (rad, joint angles as the forward
    /// solve reports them) at `tension`; `Error::Unreachable` when a joint's angle lies outside
    /// what the stack spans at this tension (needed, min, max: the angle, rad).
    pub fn solve(&self, angles: &[Rad], tension: Nt) -> Result<FixedPoseSolution, Error> {
        solve_by(&self.fwd, self.t_rest, self.t_ceiling, |u| Ok(self.at(u)), angles, tension)
    }

    /// The channel voltages for a solution (float: the DE thinning's closed form).
    pub fn volts<R: Real>(&self, f: &Finger<R>, sol: &FixedPoseSolution) -> Result<[R; MAX_JOINTS], Error> {
        volts_of(f, self.t_rest, sol)
    }
}

/// Stack thickness at position `u` (Q16 nodes from the rest thickness to the ceiling's).
fn thickness_at(t_rest: Mm, t_ceiling: Mm, u: i64) -> Mm {
    let span = (t_rest.0 - t_ceiling.0) as i64;
    Q(t_rest.0 - ((span * u) / (((NODES - 1) as i64) << 16)) as i32)
}

fn volts_of<R: Real>(f: &Finger<R>, t_rest: Mm, sol: &FixedPoseSolution) -> Result<[R; MAX_JOINTS], Error> {
    let p = f.params();
    let mut v = [R::zero(); MAX_JOINTS];
    for (k, (vk, tk)) in v.iter_mut().zip(&sol.thickness).enumerate().take(sol.n) {
        *vk = if tk.0 >= t_rest.0 { R::zero() } else { de::voltage_for_thickness(p, k + 1, tk.to_real())? };
    }
    Ok(v)
}

/// The inverse at a given tension without the table: each evaluation computes the joint's
/// sub-element compliances at its stack thickness in the float model (`C = (K_hinge +
/// K_stack(t))^-1`, as `Finger::compliances`), so it holds one joint's compliances instead of
/// the table's NODES x MAX_SUB (17 KB): the Cortex-M3 image's `pose` (20 KiB of RAM). Slower
/// (a float set-up per evaluation), and no interpolation error.
pub struct FixedInverseDirect<'a, R: Real> {
    f: &'a Finger<R>,
    fwd: &'a FixedFinger,
    t_rest: Mm,
    t_ceiling: Mm,
    t_rest_r: R,
    t_ceiling_r: R,
}

impl<'a, R: Real> FixedInverseDirect<'a, R> {
    /// `fwd`: `f` prepared at any voltages (its lengths and the joint solve are used, not its
    /// compliances); `v_top`: the highest voltage the inverse commands (V, below the ceiling in
    /// force; the float inverse's `Options::top` x ceiling): the stack spans the rest thickness
    /// to the one at `v_top`.
    pub fn new(f: &'a Finger<R>, fwd: &'a FixedFinger, v_top: R) -> Result<Self, Error> {
        let p = f.params();
        if p.layers == 0 {
            return Err(Error::Input { input: "layers", reason: "the fixed-point inverse needs stacks" });
        }
        if fwd.n != p.n || fwd.m != p.m {
            return Err(Error::Input { input: "fwd", reason: "prepared for other parameters" });
        }
        let (t_rest, t_ceiling) = (f.stack_thickness(R::zero())?, f.stack_thickness(v_top)?);
        let mm = |x: R| Mm::from_real(x);
        Ok(FixedInverseDirect { f, fwd, t_rest: mm(t_rest), t_ceiling: mm(t_ceiling), t_rest_r: t_rest, t_ceiling_r: t_ceiling })
    }

    /// The sub-element compliances at position `u` (as the table's: 0 = rest thickness).
    fn at(&self, u: i64) -> Result<[CMat; MAX_SUB], Error> {
        let last = ((NODES - 1) as i64) << 16;
        let u = u.clamp(0, last);
        let frac = R::from_u32(u as u32) / R::from_u32(last as u32);
        let t = (self.t_rest_r - (self.t_rest_r - self.t_ceiling_r) * frac).max(self.t_ceiling_r);
        let kj = self.f.joint_stiffness(t);
        let mut o = [CMat::default(); MAX_SUB];
        for (j, c) in o.iter_mut().enumerate().take(self.fwd.m) {
            *c = cmat(&kj.compliance(j)?);
        }
        Ok(o)
    }

    /// As [`FixedInverse::solve`].
    pub fn solve(&self, angles: &[Rad], tension: Nt) -> Result<FixedPoseSolution, Error> {
        solve_by(self.fwd, self.t_rest, self.t_ceiling, |u| self.at(u), angles, tension)
    }

    /// Without a tension: the tension by the float inverse's rule ([`tension_rule`]), then
    /// [`FixedInverseDirect::solve`] at it. Also returns the feasible interval (N; empty, lo > hi,
    /// when no tension holds the posture: then the error names a joint at the reference tension,
    /// written to `used` as the chosen one is).
    pub fn solve_free(&self, angles: &[Rad], used: &mut Nt) -> Result<(FixedPoseSolution, [Nt; 2]), Error> {
        let rule = tension_rule(self.fwd, |u| self.at(u), angles)?;
        *used = rule.tension;
        if rule.tension.0 == 0 && rule.feasible {
            // every angle zero: the straight finger at 0 N, 0 V
            let sol = FixedPoseSolution { n: self.fwd.n, thickness: [self.t_rest; MAX_JOINTS], tension: Nt::ZERO, evaluations: rule.evaluations };
            return Ok((sol, rule.interval));
        }
        if rule.tension.0 == 0 {
            let k = angles.iter().position(|a| a.0 < 0).unwrap_or(0);
            return Err(Error::Unreachable { joint: k + 1, needed: angles[k].to_report(), min: 0.0, max: 0.0 });
        }
        let mut sol = self.solve(angles, rule.tension)?;
        sol.evaluations += rule.evaluations;
        Ok((sol, rule.interval))
    }

    /// The channel voltages for a solution (float: the DE thinning's closed form).
    pub fn volts(&self, sol: &FixedPoseSolution) -> Result<[R; MAX_JOINTS], Error> {
        volts_of(self.f, self.t_rest, sol)
    }
}

/// The tension chosen for a posture and the interval it came from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TensionRule {
    pub tension: Nt,
    /// [largest low end, smallest high end] of the joints' tension ranges, N.
    pub interval: [Nt; 2],
    /// Whether the interval holds a tension and no angle is negative (else `tension` is the
    /// reference of the unreachable report: the median of the joints' mid-range tensions).
    pub feasible: bool,
    /// Joint solves.
    pub evaluations: u32,
}

/// The float inverse's tension rule (`inverse::choose_tension`): each joint's range is the
/// [min, max] of the tensions that hold its angle at the stiffest stack (rest thickness, table
/// position 0) and at the softest (the top voltage, the last position), by [`hold_tension`];
/// the tension is the midpoint of their intersection, else the median of the mid-ranges.
fn tension_rule(fwd: &FixedFinger, at: impl Fn(i64) -> Result<[CMat; MAX_SUB], Error>, angles: &[Rad]) -> Result<TensionRule, Error> {
    let n = fwd.n;
    if angles.len() != n {
        return Err(Error::Input { input: "angles", reason: "one angle per joint is required" });
    }
    let (c_soft, c_stiff) = (at(((NODES - 1) as i64) << 16)?, at(0)?);
    let mut ends = [[Nt::ZERO; 2]; MAX_JOINTS];
    let mut evals = 0u32;
    for k in 0..n {
        if k > 0 && angles[k] == angles[k - 1] {
            ends[k] = ends[k - 1];
            continue;
        }
        let lo = hold_tension(fwd, &c_soft, angles[k], k + 1, Nt::ZERO, &mut evals)?;
        ends[k] = [lo, hold_tension(fwd, &c_stiff, angles[k], k + 1, lo, &mut evals)?];
    }
    let range = |e: &[Nt; 2]| (e[0].min(e[1]), e[0].max(e[1]));
    let mut interval = [Nt::ZERO, Nt::MAX];
    let mut mids = [Nt::ZERO; MAX_JOINTS];
    for (k, e) in ends[..n].iter().enumerate() {
        let (a, b) = range(e);
        interval = [interval[0].max(a), interval[1].min(b)];
        mids[k] = Q(a.0 + (b.0 - a.0) / 2);
    }
    let feasible = interval[0] <= interval[1] && angles.iter().all(|a| a.0 >= 0);
    let tension = if feasible {
        Q(interval[0].0 + (interval[1].0 - interval[0].0) / 2)
    } else {
        let m = &mut mids[..n];
        m.sort_unstable();
        if n % 2 == 1 {
            m[n / 2]
        } else {
            Q(m[n / 2 - 1].0 + (m[n / 2].0 - m[n / 2 - 1].0) / 2)
        }
    };
    Ok(TensionRule { tension, interval, feasible, evaluations: evals })
}

/// One step of regula falsi, Illinois, on the bracket (a, ga, b, gb) (raw values, g(a) < 0 <=
/// g(b)): the point `u` with g(u) = `gu` replaces the end of its sign (then runs `lower` if it
/// was the lower one), and the end that stays twice halves its weight (`side`: the end the
/// last point replaced, -1 the lower, 1 the upper, 0 none yet).
macro_rules! illinois {
    (($a:ident, $ga:ident, $b:ident, $gb:ident, $side:ident) <- ($u:ident, $gu:ident) $(, lower: $($lower:tt)*)?) => {
        if $gu < 0 {
            ($a, $ga) = ($u, $gu);
            $($($lower)*;)?
            if $side == -1 {
                $gb /= 2;
            }
            $side = -1;
        } else {
            ($b, $gb) = ($u, $gu);
            if $side == 1 {
                $ga /= 2;
            }
            $side = 1;
        }
    };
}

/// The tension at which a joint with compliances `c` holds `angle` (its joint angle: the
/// hinge's and the link's), following its branch from 0 N (`joint`: 1-based, for errors):
/// trial tensions from the secant through the origin (past the target by 1/16, at most
/// doubling), each warm-started from the last converged hole and halved when refused, then
/// regula falsi (Illinois) on the bracket. The branch's end before the angle: its error.
/// `from`: a tension known to lie below (0: none). 0 N for an angle <= 0.
fn hold_tension(fwd: &FixedFinger, c: &[CMat; MAX_SUB], angle: Rad, joint: usize, from: Nt, evals: &mut u32) -> Result<Nt, Error> {
    if angle.0 <= 0 {
        return Ok(Nt::ZERO);
    }
    let mut iters = 0u32;
    let refused = Error::NotConverged { iterations: MAX_ITER, residual: f64::INFINITY };
    // θ(P) - θ*, and the converged hole
    let mut g = |p: i64, hole: Option<[Mm; 2]>| -> Result<(i64, [Mm; 2]), MarchError> {
        *evals += 1;
        let (end, h) = fwd.joint(c, Q(p as i32), hole, &mut iters)?;
        Ok(((end.theta + fwd.link_q(Q(p as i32)).2).0 as i64 - angle.0 as i64, h))
    };
    let bound = (SEARCH_BOUND_N as i64) << 22;
    // lower end: (P, g, hole); the upper (P, g) once found
    let (mut a, mut ga, mut ha) = (0i64, -(angle.0 as i64), None);
    if from.0 > 0 {
        if let Ok((gf, h)) = g(from.0 as i64, None) {
            if gf < 0 {
                (a, ga, ha) = (from.0 as i64, gf, Some(h));
            }
        }
    }
    // first trial: 1/4 N, or the secant through the origin
    let mut step = if a == 0 { 1i64 << 20 } else { 0 };
    let mut trials = 0u32;
    let (b, gb) = loop {
        trials += 1;
        if trials > 4 * MAX_ITER {
            return Err(refused);
        }
        let want = if a == 0 { step } else { (a * 17 / 16) * angle.0 as i64 / (angle.0 as i64 + ga).max(1) - a };
        let p = a + if step > 0 { step.min(want.max(1)) } else { want.clamp(1, a) };
        if p > bound {
            return Err(Error::LimitPoint { joint, tension: Q::<22>(bound as i32).to_report() });
        }
        match g(p, ha) {
            Ok((gp, _)) if gp >= 0 => break (p, gp),
            Ok((gp, h)) => {
                (a, ga, ha) = (p, gp, Some(h));
                step = 0;
            }
            Err(e) => {
                // refused: a shorter step, down to the stop's resolution
                let d = (p - a) / 2;
                if d <= (a >> 14).max(1) {
                    let t = Q::<22>(p as i32).to_report();
                    return Err(match e {
                        MarchError::Contact => Error::Contact { joint, tension: t },
                        MarchError::Singular => Error::LimitPoint { joint, tension: t },
                    });
                }
                step = d;
            }
        }
    };
    let (mut b, mut gb) = (b, gb);
    if gb <= TOL_RAW as i64 {
        return Ok(Q(b as i32));
    }
    let mut side = 0i32;
    let mut u = b;
    for _ in 0..MAX_ITER {
        if b - a <= 1 {
            break;
        }
        u = (a + (b - a) * (-ga) / (gb - ga)).clamp(a + 1, b - 1);
        let (gu, h) = g(u, ha).map_err(|_| refused)?;
        if gu.abs() <= TOL_RAW as i64 {
            break;
        }
        illinois!((a, ga, b, gb, side) <- (u, gu), lower: ha = Some(h));
    }
    Ok(Q(u as i32))
}

/// Each joint's stack thickness that holds `angles` at `tension`, the compliances at table
/// position `u` from `at`.
fn solve_by(
    fwd: &FixedFinger,
    t_rest: Mm,
    t_ceiling: Mm,
    at: impl Fn(i64) -> Result<[CMat; MAX_SUB], Error>,
    angles: &[Rad],
    tension: Nt,
) -> Result<FixedPoseSolution, Error> {
    {
        let n = fwd.n;
        if angles.len() != n {
            return Err(Error::Input { input: "angles", reason: "one angle per joint is required" });
        }
        if tension.0 <= 0 || tension.is_sat() {
            return Err(Error::Input { input: "tension", reason: "must be > 0 and within the fixed-point range" });
        }
        let link = fwd.link_q(tension).2;
        let mut thickness = [Mm::ZERO; MAX_JOINTS];
        let mut evals = 0u32;
        let mut iters = 0u32;
        let last = ((NODES - 1) as i64) << 16;
        for k in 0..n {
            // the same angle as the joint before: the same thickness (the joints are alike)
            if k > 0 && angles[k] == angles[k - 1] {
                thickness[k] = thickness[k - 1];
                continue;
            }
            let target = angles[k] - link;
            let mut hole = None;
            let mut g = |u: i64, hole: &mut Option<[Mm; 2]>, evals: &mut u32| -> Result<i64, Error> {
                *evals += 1;
                let (end, h) =
                    fwd.joint(&at(u)?, tension, *hole, &mut iters).map_err(|_| Error::NotConverged { iterations: *evals, residual: f64::INFINITY })?;
                *hole = Some(h);
                Ok(end.theta.0 as i64 - target.0 as i64)
            };
            let (mut a, mut b) = (0i64, last);
            let (mut ga, mut gb) = (g(a, &mut hole, &mut evals)?, g(b, &mut hole, &mut evals)?);
            // at an end of the stack's range within the forward solve's own error: that end
            if ga > 0 && ga <= END_TOL_RAW {
                thickness[k] = t_rest;
                continue;
            }
            if gb < 0 && -gb <= END_TOL_RAW {
                thickness[k] = t_ceiling;
                continue;
            }
            if ga > 0 || gb < 0 {
                let unit = |x: i64| (Rad::from_raw_sat(x + target.0 as i64) + link).to_report();
                return Err(Error::Unreachable { joint: k + 1, needed: angles[k].to_report(), min: unit(ga), max: unit(gb) });
            }
            let mut u = a;
            let mut side = 0i32;
            for _ in 0..MAX_ITER {
                // regula falsi, Illinois
                u = if gb != ga { a + (b - a) * (-ga) / (gb - ga) } else { (a + b) / 2 };
                u = u.clamp(a, b);
                let gu = g(u, &mut hole, &mut evals)?;
                if gu.abs() <= TOL_RAW as i64 || b - a <= 1 {
                    break;
                }
                illinois!((a, ga, b, gb, side) <- (u, gu));
            }
            thickness[k] = thickness_at(t_rest, t_ceiling, u);
        }
        Ok(FixedPoseSolution { n, thickness, tension, evaluations: evals })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Method, Params};

    #[test]
    fn round_trip_within_0_05_deg() {
        let f = Finger::new(Params::<f64> { layers: 4, ..Params::default() }).unwrap();
        let inv = FixedInverse::new(&f).unwrap();
        let mut worst = 0f64;
        for (p, v) in [(0.5, [0.0, 2000.0, 4000.0]), (0.8, [1000.0, 3000.0, 5000.0]), (1.0, [9000.0, 5000.0, 100.0]), (1.5, [2000.0; 3]), (0.3, [8000.0; 3])] {
            let want = f.solve(p, &v, Method::converged()).unwrap();
            let angles = [0, 1, 2].map(|k| Rad::from_f64(want.joint_angle[k]));
            let sol = inv.solve(&angles, Nt::from_f64(p)).unwrap();
            let volts = inv.volts(&f, &sol).unwrap();
            let back = f.solve(p, &volts[..3], Method::converged()).unwrap();
            for k in 0..3 {
                worst = worst.max((back.joint_angle[k] - want.joint_angle[k]).abs().to_degrees());
            }
        }
        assert!(worst < 0.05, "{worst}");
    }

    /// The untabled inverse (the M3 image's `pose`) round-trips as the tabled one does, and
    /// refuses the same unreachable posture.
    #[test]
    fn direct_round_trip_within_0_05_deg() {
        let f = Finger::new(Params::<f64> { layers: 4, ..Params::default() }).unwrap();
        let fwd = FixedFinger::new(&f, &[0.0; 3]).unwrap();
        let inv = FixedInverseDirect::new(&f, &fwd, f.ceiling_in_force(None) * (1.0 - 1e-6)).unwrap();
        let mut worst = 0f64;
        for (p, v) in [(0.5, [0.0, 2000.0, 4000.0]), (0.8, [1000.0, 3000.0, 5000.0]), (1.0, [9000.0, 5000.0, 100.0]), (1.5, [2000.0; 3]), (0.3, [8000.0; 3])] {
            let want = f.solve(p, &v, Method::converged()).unwrap();
            let angles = [0, 1, 2].map(|k| Rad::from_f64(want.joint_angle[k]));
            let sol = inv.solve(&angles, Nt::from_f64(p)).unwrap();
            let volts = inv.volts(&sol).unwrap();
            let back = f.solve(p, &volts[..3], Method::converged()).unwrap();
            for k in 0..3 {
                worst = worst.max((back.joint_angle[k] - want.joint_angle[k]).abs().to_degrees());
            }
        }
        assert!(worst < 0.05, "{worst}");
        let a = Rad::from_f64(1.2);
        assert!(matches!(inv.solve(&[a, a, a], Nt::from_f64(0.5)), Err(Error::Unreachable { joint: 1, .. })));
    }

    /// Without a tension (the M3 image's `pose` without P): the float inverse's rule at the
    /// board's finger (docs/model.md's, with its FE calibration): the same interval and midpoint as
    /// the f64 `solve_pose` (the fixed-point joint angles' error over dθ/dP: within 1e-4
    /// relative), and the answer holds the posture through the f64 forward (0.05 deg).
    #[test]
    fn free_tension_is_the_f64_rule() {
        use crate::calibration::Calibration;
        let p = Params::<f64>::default();
        let f = Finger::with_calibration(p, Calibration::for_params(&p)).unwrap();
        assert_ne!(*f.calibration(), Calibration::none());
        let fwd = FixedFinger::new(&f, &[0.0; 3]).unwrap();
        let top = crate::inverse::Options::<f64>::default().top;
        let inv = FixedInverseDirect::new(&f, &fwd, f.ceiling_in_force(None) * top).unwrap();
        let (mut worst_p, mut worst_deg) = (0f64, 0f64);
        for (p, v) in [
            (0.5, [0.0, 2000.0, 4000.0]),
            (0.8, [1000.0, 3000.0, 5000.0]),
            (1.0, [9000.0, 5000.0, 100.0]),
            (1.5, [2000.0; 3]),
            (0.3, [8000.0; 3]),
            (4.0, [0.0, 6000.0, 9000.0]),
        ] {
            let want = f.solve(p, &v, Method::converged()).unwrap();
            let ang = [want.joint_angle[0], want.joint_angle[1], want.joint_angle[2]];
            let fl = crate::inverse::solve_pose(&f, &ang, None).unwrap();
            let (sol, interval) = inv.solve_free(&ang.map(Rad::from_f64), &mut Q(0)).unwrap();
            let rel = |a: Nt, b: f64| (a.to_f64() - b).abs() / b;
            worst_p = worst_p.max(rel(sol.tension, fl.tension)).max(rel(interval[0], fl.interval[0])).max(rel(interval[1], fl.interval[1]));
            assert!(
                fl.interval[0] <= p * (1.0 + 1e-9) && p <= fl.interval[1] * (1.0 + 1e-9),
                "{p} {v:?}: f64 {} {:?} fixed {} {:?}",
                fl.tension,
                fl.interval,
                sol.tension.to_f64(),
                [interval[0].to_f64(), interval[1].to_f64()]
            );
            let volts = inv.volts(&sol).unwrap();
            let back = f.solve(sol.tension.to_f64(), &volts[..3], Method::converged()).unwrap();
            for k in 0..3 {
                worst_deg = worst_deg.max((back.joint_angle[k] - ang[k]).abs().to_degrees());
            }
        }
        assert!(worst_p < 1e-4, "tension {worst_p}");
        assert!(worst_deg < 0.05, "{worst_deg}");
        // no tension holds it: refused, naming a joint; the straight finger: 0 N, 0 V
        let a = [Rad::from_f64(0.02), Rad::from_f64(0.02), Rad::from_f64(0.6)];
        assert!(matches!(inv.solve_free(&a, &mut Q(0)), Err(Error::Unreachable { .. })));
        assert!(matches!(inv.solve_free(&[Rad::from_f64(-0.1), Rad::from_f64(0.1), Rad::from_f64(0.1)], &mut Q(0)), Err(Error::Unreachable { joint: 1, .. })));
        let (z, _) = inv.solve_free(&[Rad::ZERO; 3], &mut Q(0)).unwrap();
        assert_eq!(z.tension, Nt::ZERO);
        assert_eq!(inv.volts(&z).unwrap()[..3], [0.0; 3]);
    }

    #[test]
    fn a_posture_past_the_stacks_is_unreachable() {
        let f = Finger::new(Params::<f64> { layers: 4, ..Params::default() }).unwrap();
        let inv = FixedInverse::new(&f).unwrap();
        let a = Rad::from_f64(1.2);
        assert!(matches!(inv.solve(&[a, a, a], Nt::from_f64(0.5)), Err(Error::Unreachable { joint: 1, .. })));
    }
}
