//! The tabled inverse (`solve_pose_tabled`, docs/inverse.md "The tabled inverse"): range ends
//! and step 4's start read off the branch table, each confirmed by one march of the full
//! model where the answer rests on it; the quasi-Newton solve only where that march is not
//! converged.

use super::*;

impl<'a, R: Real> Gen<'a, R> {
    /// One march of joint `joint` at tension `p` from hole `b` (`Finger::joint_march`, `by`
    /// `by::Cable` or `by::Stiffness`): its state when that is already an equilibrium of the
    /// full model to the quasi-Newton solves' own tolerance (`broyden_steps`: hole residual and
    /// joint angle), else None (also when the march fails). The sub-element displacements go to
    /// `q`.
    #[inline(never)]
    pub(super) fn converged_march(&self, joint: usize, by: impl By<R>, p: R, b: [R; 2], theta: R, q: &mut [[R; 3]; MAX_SUB]) -> Option<JointMarch<R>> {
        let st = self.f.joint_march(joint, by, p, b, q).ok()?;
        self.converged(st, b, theta)
    }

    /// `st` if its hole is `b` and its angle `theta` within the quasi-Newton solves' tolerance.
    #[inline(always)]
    pub(super) fn converged(&self, st: JointMarch<R>, b: [R; 2], theta: R) -> Option<JointMarch<R>> {
        let atol = self.angle_atol(theta);
        let htol = self.htol;
        let ok = (b[0] - st.hole[0]).abs() <= htol && (b[1] - st.hole[1]).abs() <= htol && (st.angle - theta).abs() <= atol;
        ok.then_some(st)
    }
}

/// Joint `k`'s (0-based) range end `e` (0 softest, 1 stiffest stack) held at `theta`,
/// confirmed in place from the table's reading `r`: kept where one march there is within the
/// solver's tolerance, else the quasi-Newton solve from it. Returns whether the tension moved.
/// The march's sub-element displacements go to `q` (the joint's own rows: step 4 writes them
/// again).
#[inline(always)]
#[allow(clippy::too_many_arguments)]
pub(super) fn confirm_end<R: Real>(
    g: &mut Gen<'_, R>,
    tb: &BranchTable<R>,
    k: usize,
    e: usize,
    r: &mut TableEnd<R>,
    theta: R,
    q: &mut [[R; 3]; MAX_SUB],
) -> Result<bool, Error> {
    let c = &tb.comp[e];
    if g.converged_march(k + 1, by::Cable(c), r.tension, r.hole, theta, q).is_some() {
        return Ok(false);
    }
    let h = g.hold_tension(k + 1, theta, c, tb.thickness[e], tb.slope0[e], Some((r.tension, r.hole)), None, Some(theta / r.tension), q)?;
    let moved = h.tension != r.tension;
    *r = TableEnd { tension: h.tension, hole: h.st.hole };
    Ok(moved)
}

/// Step 1b of `solve_tabled` with the tension free: confirm (`confirm_end`) the ends the
/// midpoint rule rests on, the feasible interval's bounds and any end within `TABLE_BAND` of
/// them, in the readings `rd` (per joint: softest, stiffest, middle); `interval` the readings'
/// bounds, updated when a confirmed tension moves them (then the scan starts again). The
/// marches' sub-element displacements go to each joint's rows of `sub_q`.
#[inline(never)]
pub(super) fn confirm_bounds<R: Real>(
    g: &mut Gen<'_, R>,
    tb: &BranchTable<R>,
    angles: &[R],
    rd: &mut [[TableEnd<R>; 3]; MAX_JOINTS],
    interval: &mut [R; 2],
    sub_q: &mut [[[R; 3]; MAX_SUB]; MAX_JOINTS],
) -> Result<(), Error> {
    let n = angles.len().min(MAX_JOINTS);
    let band = R::from_f64(TABLE_BAND);
    // (bit 2k + e: end e of joint k)
    let mut exact = 0u32;
    loop {
        // the ends near a bound, not yet confirmed, in the order of the bits
        let [lo, hi] = *interval;
        let (near_lo, near_hi) = (band * lo, band * hi);
        let mut todo = 0u32;
        for (k, rk) in rd.iter().enumerate().take(n) {
            for (e, end) in rk.iter().take(2).enumerate() {
                let x = end.tension;
                if (x - lo).abs() <= near_lo || (x - hi).abs() <= near_hi {
                    todo |= 1 << (2 * k + e);
                }
            }
        }
        todo &= !exact;
        let mut moved = false;
        while todo != 0 && !moved {
            let i = todo.trailing_zeros() as usize;
            let (k, e) = (i / 2, i % 2);
            moved = confirm_end(g, tb, k, e, &mut rd[k][e], angles[k], &mut sub_q[k])?;
            g.iters += 1;
            exact |= 1 << i;
            todo &= !(1 << i);
            // the same angle, the same end (a joint before at this angle has the same reading:
            // it was confirmed first)
            let solved = rd[k][e];
            for j in k + 1..n {
                if angles[j] == angles[k] {
                    rd[j][e] = solved;
                    exact |= 1 << (2 * j + e);
                    todo &= !(1 << (2 * j + e));
                }
            }
        }
        if !moved {
            return Ok(());
        }
        *interval = feasible_interval(n, |k| [rd[k][0].tension, rd[k][1].tension]);
    }
}

/// Step 4's march of joint `k` (0-based) by compliances at thickness `t`: the table's at either
/// end of the stack's range, else evaluated (after a stiffness march that was not converged:
/// a march more). `Gen::converged_march`'s answer; out of line, with its compliances' room.
#[inline(never)]
#[allow(clippy::too_many_arguments)]
pub(super) fn step_by_compliance<R: Real>(
    g: &mut Gen<'_, R>,
    tb: &BranchTable<R>,
    k: usize,
    t: R,
    p: R,
    b: [R; 2],
    theta: R,
    q: &mut [[R; 3]; MAX_SUB],
) -> Result<Option<JointMarch<R>>, Error> {
    let [t_top, t0, _] = tb.thickness;
    let mut c = [tb.comp[1][0]; MAX_SUB];
    let ck = if t >= t0 {
        &tb.comp[1]
    } else if t <= t_top {
        &tb.comp[0]
    } else {
        g.iters += 1;
        g.comp_into(t, &mut c)?;
        &c
    };
    Ok(g.converged_march(k + 1, by::Cable(ck), p, b, theta, q))
}

/// `solve_pose_tabled`'s path (docs/inverse.md, "The tabled inverse"): every joint's range
/// ends and step 4's start read off the table; each read confirmed by one march of the full
/// model where the answer depends on it, the quasi-Newton solve from there only where that
/// march is not within the solver's tolerance. Writes `out` in place (every field). Returns
/// false, leaving the answer to `solve`, where the table does not hold a target (outside its
/// angles, zero or negative angles) and on a refusal (the error's report is `solve`'s).
#[inline(never)]
pub(in crate::inverse) fn solve_tabled<R: Real>(tb: &BranchTable<R>, angles: &[R], tension: Option<R>, out: &mut PoseSolution<R>) -> Result<bool, Error> {
    let f = &tb.finger;
    let p = f.params();
    let n = p.n;
    let [t_top, t0, tm] = tb.thickness;
    if p.layers == 0 || !(t0 - t_top > R::from_f64(4.0 * R::EPS) * t0) {
        return Ok(false);
    }
    // (the table holds the straight joint's slopes: no link rotation needed)
    let mut g = Gen::with_link_rot(f, &tb.opts, R::zero());
    // per joint: the softest end, the stiffest end, the middle branch (tension, hole); joint k
    // repeats joint k-1 where their angles are equal (filled with the first joint's reading:
    // no zeroed array written twice)
    let len = tb.covered();
    let Some(e0) = tb.read(angles[0], len).filter(|_| angles[0] > R::zero()) else { return Ok(false) };
    let mut rd = [e0; MAX_JOINTS];
    for k in 1..n {
        if angles[k] == angles[k - 1] {
            rd[k] = rd[k - 1];
            continue;
        }
        match tb.read(angles[k], len) {
            Some(e) if angles[k] > R::zero() => rd[k] = e,
            _ => return Ok(false),
        }
    }
    // a solution's sub-element rows past its own (n, m) are zero (`PoseSolution`): only the
    // rows `out` held past this finger's (n, m) are cleared (none for `PoseSolution::empty()`
    // or an answer of this finger), before any march writes the rows inside them
    let (held_n, held_m) = (out.n.min(MAX_JOINTS), out.m.min(MAX_SUB));
    for k in 0..held_n {
        let from = if k < n { p.m } else { 0 };
        if from < held_m {
            for qj in out.sub_q[k][from..held_m].iter_mut() {
                *qj = [R::zero(); 3];
            }
        }
    }
    out.n = n;
    out.m = p.m;
    let band = R::from_f64(TABLE_BAND);
    let mut interval = feasible_interval(n, |k| [rd[k][0].tension, rd[k][1].tension]);
    // a target the readings refuse (the interval empty; a given tension outside a joint's
    // range by more than the band) is `solve`'s to refuse and report, before any march here
    let pt = match tension {
        Some(pg) => {
            // (some joint's range starts above pg + tol or ends below pg - tol: the interval
            // does, its bounds the largest start and the smallest end)
            let tol = band * pg;
            if interval[0] - pg > tol || pg - interval[1] > tol {
                return Ok(false);
            }
            // (no end confirmed: step 4's converged solve inside [t_top, t0] is what shows the
            // tension within a joint's range; near an end whose solve does not converge,
            // `solve` decides)
            pg
        }
        None => {
            if !(interval[0] <= interval[1]) {
                return Ok(false);
            }
            // 1b. confirm the ends the midpoint rule rests on
            confirm_bounds(&mut g, tb, angles, &mut rd, &mut interval, &mut out.sub_q)?;
            // 2-3. the midpoint of the interval (`choose_tension`'s rule); a refusal is
            //      `solve`'s to report
            if !(interval[0] <= interval[1]) {
                return Ok(false);
            }
            (interval[0] + interval[1]) / R::from_f64(2.0)
        }
    };
    // (the midpoint of a non-empty interval lies in every joint's range; a given tension was
    // checked against the readings above, and step 4 shows it inside or hands it to `solve`)
    if !(pt > R::zero()) {
        return Ok(false);
    }
    // the answer's scalars, and zeros past the n joints and m sub-elements (written in place)
    let zr = R::zero();
    out.tension_given = tension.is_some();
    out.interval = interval;
    out.tension = pt;
    // (element by element: `copy_from_slice` calls memcpy, 50 instructions for three angles)
    #[allow(clippy::manual_memcpy)]
    for k in 0..n {
        out.angles[k] = angles[k];
    }
    for k in n..MAX_JOINTS {
        out.angles[k] = zr;
        out.volts[k] = zr;
        out.thickness[k] = zr;
        out.q[k] = [zr; 3];
        out.links[k] = [zr; 3];
    }
    // 4. every joint's thickness at that tension: one compliance evaluation and one march at
    //    the table's start along the level curve, the quasi-Newton solve only if that march is
    //    not within the tolerance; then the voltage
    let lh = p.hinge_len();
    let (v_top, volts) = (tb.v_top, &tb.volts);
    let link = f.tension_link_q(pt);
    for k in 0..n {
        if k > 0 && angles[k] == angles[k - 1] {
            out.thickness[k] = out.thickness[k - 1];
            out.volts[k] = out.volts[k - 1];
            out.q[k] = out.q[k - 1];
            // (row by row, strided: no call to a byte-wise memcpy)
            for jj in 0..p.m {
                out.sub_q[k][jj] = out.sub_q[k - 1][jj];
            }
            out.links[k] = out.links[k - 1];
            continue;
        }
        let [lo, hi, md] = &rd[k];
        let (t_guess, b) = level_guess((lo.tension, t_top, lo.hole), (hi.tension, t0, hi.hole), Some((md.tension, tm, md.hole)), pt);
        // inside the stack's range one march from the stiffnesses (no compliance formed); the
        // compliance march at either end, and inside it only where that one is not converged
        let inside = t_guess < t0 && t_guess > t_top;
        let quick = if inside { g.converged_march(k + 1, by::Stiffness(&g.stack, t_guess, link), pt, b, angles[k], &mut out.sub_q[k]) } else { None };
        g.iters += 1;
        let marched = match quick {
            Some(st) => Some(st),
            None => step_by_compliance(&mut g, tb, k, t_guess, pt, b, angles[k], &mut out.sub_q[k])?,
        };
        let (t, st) = match marched {
            Some(st) => (t_guess, st),
            None if tension.is_some() && (0..2).any(|e| (rd[k][e].tension - pt).abs() <= band * pt) => {
                // a given tension near an unconfirmed end: `solve` confirms the range
                return Ok(false);
            }
            None => {
                let held = |e: &TableEnd<R>, t: R| Held {
                    tension: e.tension,
                    thickness: t,
                    st: JointMarch { hole: e.hole, angle: angles[k], ..g.straight_st() },
                    slope: angles[k] / e.tension,
                    jac: None,
                    exact: false,
                };
                let (l, h) = (held(lo, t_top), held(hi, t0));
                let r = g.hold_thickness(k + 1, angles[k], pt, &l, &h, Some((md.tension, tm, md.hole)), &mut out.sub_q[k])?;
                (r.thickness, r.st)
            }
        };
        let t = t.max(t_top).min(t0);
        out.thickness[k] = t;
        out.volts[k] = if t >= t0 { R::zero() } else { volts.voltage(k + 1, t)?.min(v_top) };
        out.q[k] = [st.end.x - lh, st.end.y, st.end.theta];
        out.links[k] = st.link;
    }
    out.iterations = g.iters;
    Ok(true)
}
