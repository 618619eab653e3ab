//! The end of the equilibrium branch under tension alone (fmax): the lowest tension at which a
//! joint's cable span closes to its floor (docs/model.md "Contact": the links touch) or its
//! equilibrium tangent turns singular (a limit point: the branch turns back).
//!
//! Per distinct joint (joints with the same compliances end at the same tension and are solved
//! once): a march up the branch in doubling tension steps (Newton from a secant predictor),
//! then the feasible boundary (`solve::bracket::boundary`) between the last tension solved and
//! the first refused, from an estimate of the end: the span's secant through its floor, or the
//! squared tangent determinant's secant through zero (det² is linear in P near a fold). A
//! refused trial that is neither near contact nor near a limit point was a step too long: the
//! march resumes from the last point with shorter steps.
//!
//! The joints go most-thinned stack first; each later one marches only up to the end found
//! so far (reaching it, it does not end before), so fmax at mixed voltages costs little more
//! than one joint's. A point's Newton takes few line-search halvings: on the branch the
//! predictor's full steps converge, past its end a trial fails fast (docs/fmax-cost.md).

use super::{loaded, tension, BranchEnd, BranchLimit, Compliances, Finger, JointState, MarchError};
use crate::error::Error;
use crate::mat3::Mat3;
use crate::params::{MAX_JOINTS, MAX_SUB};
use crate::real::Real;
use crate::solve::{bracket, SolveOptions};

/// Relative width at which the end is known.
const REL: f64 = 1e-4;
/// Tangent determinant below which a solved point counts as at a limit point (1 unloaded).
const NEAR_FOLD: f64 = 0.2;
/// Newton iterations per point on the branch, and line-search halvings per iteration.
const POINT_ITER: u32 = 12;
const POINT_HALVINGS: u32 = 2;
/// A march cycle that advances the tension by less than this fraction has stalled.
const STALL: f64 = 1e-3;
/// Newton iterations a step of fmax's walk up the coupled branch may take (each try).
const WALK_ITER: u32 = 20;

/// A solved point on the branch.
#[derive(Clone, Copy)]
struct Pt<R> {
    p: R,
    st: JointState<R>,
    span: R,
    det: R,
}

/// `Finger::fmax`: `fmax_with` at these voltages' compliances.
pub(super) fn fmax<R: Real>(f: &Finger<R>, volts: &[R]) -> Result<BranchLimit<R>, Error> {
    let c = f.compliances(volts)?;
    fmax_with(f, &c, None)
}

/// `fmax` with precomputed compliances and, per joint, optionally two points near its
/// branch (tensions and hole guesses, from the branch table: the march up the branch
/// continues from them instead of starting at the straight joint).
pub(super) fn fmax_with<R: Real>(f: &Finger<R>, c: &Compliances<R>, starts: Option<&[Option<[(R, [R; 2]); 2]>; MAX_JOINTS]>) -> Result<BranchLimit<R>, Error> {
    if f.weights().is_some() {
        return fmax_coupled(f, c);
    }
    let (n, m) = (f.p.n, f.p.m);
    // the most thinned stack first (it usually ends first); each later joint marches only
    // up to the end found so far: reaching it, it does not end before
    let mut order = [0usize; MAX_JOINTS];
    for k in 0..n {
        order[k] = k;
    }
    order[..n].sort_unstable_by(|&a, &b| c.volts[b].partial_cmp(&c.volts[a]).unwrap_or(core::cmp::Ordering::Equal).then(a.cmp(&b)));
    let mut best: Option<BranchLimit<R>> = None;
    for (i, &k) in order[..n].iter().enumerate() {
        // a joint with the compliances of one before it ends where that one ends
        if order[..i].iter().any(|&j| c.c[j][..m] == c.c[k][..m] && f.same_held(j, k)) {
            continue;
        }
        let start = starts.and_then(|s| s[k]);
        let Some(end) = joint_end(f, k, &c.c[k], best.map(|b| b.tension), start)? else { continue };
        if best.is_none_or(|b| end.tension < b.tension || (end.tension == b.tension && end.joint < b.joint)) {
            best = Some(end);
        }
    }
    best.ok_or(Error::Input { input: "n", reason: "no joints" })
}

fn branch_point<R: Real>(f: &Finger<R>, c: &[Mat3<R>; MAX_SUB], from: &Pt<R>, prev: Option<&Pt<R>>, p: R) -> Result<Pt<R>, Option<MarchError>> {
    let tol = f.resolution().max(R::from_f64(1e-9));
    let dp = p - from.p;
    let guess = match prev {
        Some(a) if from.p > a.p => {
            let s = dp / (from.p - a.p);
            [from.st.hole[0] + s * (from.st.hole[0] - a.st.hole[0]), from.st.hole[1] + s * (from.st.hole[1] - a.st.hole[1])]
        }
        _ => from.st.hole,
    };
    // a point on the branch converges from the predictor in full steps; past the end there
    // is none: few halvings, so that a trial there fails fast
    let opts = SolveOptions { max_halvings: POINT_HALVINGS, ..SolveOptions::new(tol, f.resolution(), POINT_ITER) };
    let attempt = match f.newton_dual_with(c, p, guess, None, &opts) {
        Err(_) if guess != from.st.hole => f.newton_dual_with(c, p, from.st.hole, None, &opts),
        other => other,
    };
    let (st, _) = attempt.map_err(|(why, _)| why)?;
    if !tension::same_branch(f, &from.st, &st, false) {
        return Err(None);
    }
    let span = super::norm2([st.hole[0], st.hole[1] - f.p.e]);
    let det = st.tangent.map_or(R::one(), |t| t.1);
    Ok(Pt { p, st, span, det })
}

/// Where the branch ends, estimated from its last two points: the span's secant through the
/// floor, the squared determinant's through zero, whichever comes first past `b`.
fn end_estimate<R: Real>(f: &Finger<R>, a: Option<&Pt<R>>, b: &Pt<R>) -> Option<R> {
    let a = a?;
    let dp = b.p - a.p;
    if !(dp > R::zero()) {
        return None;
    }
    let mut best: Option<R> = None;
    let mut take = |x: R| {
        if x.is_finite() && x > b.p {
            best = Some(best.map_or(x, |y: R| y.min(x)));
        }
    };
    if b.span < a.span {
        take(b.p + (b.span - f.p.span_floor) * dp / (a.span - b.span));
    }
    let (d2a, d2b) = (a.det * a.det, b.det * b.det);
    if d2b < d2a {
        take(b.p + d2b * dp / (d2a - d2b));
    }
    best
}

/// Joint `k`'s branch end (see the module header); None if it has an equilibrium at
/// `bound` (it does not end below the end found so far).
fn joint_end<R: Real>(
    f: &Finger<R>,
    k: usize,
    c: &[Mat3<R>; MAX_SUB],
    bound: Option<R>,
    start: Option<[(R, [R; 2]); 2]>,
) -> Result<Option<BranchLimit<R>>, Error> {
    let c33 = c[..f.p.m].iter().fold(R::zero(), |a, m| a + m[2][2]);
    let p_lin = R::one() / (f.p.e * c33);
    let p_search = R::from_f64(1000.0) * p_lin;
    let p_hi = bound.map_or(p_search, |b| b.min(p_search));
    let lh = f.p.hinge_len();
    let mut lo = Pt { p: R::zero(), st: f.straight(), span: lh, det: R::one() };
    let mut prev: Option<Pt<R>> = None;
    let mut step = p_lin / R::from_f64(8.0);
    // two points on the branch from the table (its last two samples at this stack): solved
    // there, the march continues from them (secant predictor, the table's spacing as the
    // first step)
    if let Some(pts) = start.filter(|s| s[0].0 > R::zero() && s[0].0 < s[1].0 && s[1].0 < p_hi) {
        let tol = f.resolution().max(R::from_f64(1e-9));
        let opts = SolveOptions { max_halvings: POINT_HALVINGS, ..SolveOptions::new(tol, f.resolution(), POINT_ITER) };
        let solved = pts.map(|(ps, guess)| {
            let (st, _) = f.newton_dual_with(c, ps, guess, None, &opts).ok()?;
            // on the table's branch: the solved hole within a twentieth of a hinge length
            // of the table's
            (super::norm2([st.hole[0] - guess[0], st.hole[1] - guess[1]]) <= lh / R::from_f64(20.0)).then(|| {
                let span = super::norm2([st.hole[0], st.hole[1] - f.p.e]);
                Pt { p: ps, st, span, det: st.tangent.map_or(R::one(), |t| t.1) }
            })
        });
        if let [Some(a), Some(b)] = solved {
            step = b.p - a.p;
            prev = Some(a);
            lo = b;
        }
    }
    let mut why: Option<MarchError> = None;
    let min_step = p_lin * R::from_f64(1e-6);
    let mut stalled = 0u32;
    for _ in 0..64 {
        let start_p = lo.p;
        // march: doubling steps until a refusal (or the search bound)
        let hi = loop {
            let p = (lo.p + step).min(p_hi);
            match branch_point(f, c, &lo, prev.as_ref(), p) {
                Ok(pt) => {
                    prev = Some(lo);
                    lo = pt;
                    if p >= p_hi {
                        if bound.is_some_and(|b| b <= p_search) {
                            return Ok(None);
                        }
                        return Ok(Some(BranchLimit { tension: p_hi, joint: k + 1, kind: BranchEnd::SearchBound }));
                    }
                    step = step + step;
                }
                Err(w) => {
                    why = w.or(why);
                    break p;
                }
            }
        };
        // the boundary between lo and hi
        let est = end_estimate(f, prev.as_ref(), &lo);
        let lo_p = lo.p;
        let (lo_ref, prev_ref, why_ref) = (&mut lo, &mut prev, &mut why);
        let mut probe = |x: R| match branch_point(f, c, lo_ref, prev_ref.as_ref(), x) {
            Ok(pt) => {
                *prev_ref = Some(*lo_ref);
                *lo_ref = pt;
                Some(end_estimate(f, prev_ref.as_ref(), lo_ref))
            }
            Err(w) => {
                *why_ref = w.or(*why_ref);
                None
            }
        };
        let ([_, hi_end], _trials) = bracket::boundary(lo_p, hi, R::from_f64(REL), 60, est, &mut probe);
        let near_contact =
            matches!(why, Some(MarchError::Contact)) || lo.span - f.p.span_floor <= R::from_f64(0.05) * (lh - f.p.span_floor).max(f.p.span_floor);
        let near_fold = lo.det.abs() < R::from_f64(NEAR_FOLD);
        if near_contact || near_fold {
            // the last tension with an equilibrium: a forward solve at fmax answers
            let contact = near_contact && (!near_fold || matches!(why, Some(MarchError::Contact)));
            let kind = if contact { BranchEnd::Contact } else { BranchEnd::LimitPoint };
            return Ok(Some(BranchLimit { tension: lo.p, joint: k + 1, kind }));
        }
        // short steps from lo no longer advance (twice): the branch ends at lo in this
        // scalar type (its solve stops existing there short of both criteria); named by
        // the nearer one, the last tension with an equilibrium
        if lo.p - start_p <= R::from_f64(STALL) * lo.p {
            stalled += 1;
            if stalled >= 2 {
                // stalled just short of the end found so far: it does not end before it
                if bound.is_some_and(|b| lo.p >= b * (R::one() - R::from_f64(STALL))) {
                    return Ok(None);
                }
                let to_floor = (lo.span - f.p.span_floor) / (lh - f.p.span_floor).max(f.p.span_floor);
                let kind = if to_floor <= lo.det.abs() { BranchEnd::Contact } else { BranchEnd::LimitPoint };
                return Ok(Some(BranchLimit { tension: lo.p, joint: k + 1, kind }));
            }
        } else {
            stalled = 0;
        }
        // a step too long, not the end: march on from lo with short steps
        step = ((hi_end - lo.p) / R::from_f64(4.0)).max(min_step);
        why = None;
    }
    Err(Error::NotConverged { iterations: 0, residual: f64::INFINITY })
}

/// fmax under gravity (docs/model.md "Gravity": the joints are coupled): the end of the
/// coupled equilibrium's branch in the tension, to `REL`, followed from the weight alone
/// (`loaded::CoupledStart::step`: each step's solve starts from the last answer) in steps that
/// double from an eighth of the softest joint's linear one-radian tension up to the search
/// bound (1000 times that), halving after a refused one. The end is where a forward solve
/// (from the straight finger) holds: if it does not, the bisection of forward solves below it
/// answers. Where a refusal is a contact, so is the end; else a limit point.
fn fmax_coupled<R: Real>(f: &Finger<R>, c: &Compliances<R>) -> Result<BranchLimit<R>, Error> {
    let n = f.p.n;
    let c33 = (0..n).map(|k| c.c[k][..f.p.m].iter().fold(R::zero(), |a, m| a + m[2][2])).fold(R::zero(), |a, b| a.max(b));
    let p_lin = R::one() / (f.p.e * c33);
    let bound = R::from_f64(1000.0) * p_lin;
    let method = super::Method::converged();
    let super::Method::Converged { tol, max_iter } = method else { unreachable!() };
    // the finger under its own weight alone must stand
    let (mut walk, _) = loaded::CoupledStart::solve(f, c, R::zero(), tol, max_iter)?;
    let (mut h, mut grow, mut contact) = (p_lin / R::from_f64(8.0), true, false);
    loop {
        let lo = walk.tension();
        if lo >= bound {
            return Ok(BranchLimit { tension: bound, joint: 1, kind: BranchEnd::SearchBound });
        }
        if !grow && h <= R::from_f64(REL) * (lo + h) {
            break;
        }
        match walk.step(f, c, (lo + h).min(bound), tol, WALK_ITER) {
            // a step doubles after two taken in a row (one, before the first refusal)
            Ok(_) if grow => h = h + h,
            Ok(_) => grow = true,
            Err(why) => {
                contact |= matches!(why, Some(MarchError::Contact));
                (h, grow) = (h / R::from_f64(2.0), false);
            }
        }
    }
    let lo = walk.tension();
    match f.solve_with(c, lo, [R::zero(); 2], method) {
        Ok(s) => Ok(ends_at(f, lo, s, contact, None)),
        Err(e) => fmax_bisected(f, c, R::zero(), lo, Some(e)),
    }
}

/// fmax under gravity by the bisection of forward solves between a tension that holds, `lo`,
/// and one that does not, `hi` (refused with `why`).
fn fmax_bisected<R: Real>(f: &Finger<R>, c: &Compliances<R>, mut lo: R, mut hi: R, mut why: Option<Error>) -> Result<BranchLimit<R>, Error> {
    let holds = |p: R| f.solve_with(c, p, [R::zero(); 2], super::Method::converged());
    let mut last = holds(lo)?;
    let mut contact = matches!(why, Some(Error::Contact { .. }));
    while hi - lo > R::from_f64(REL) * hi {
        let mid = R::from_f64(0.5) * (lo + hi);
        match holds(mid) {
            Ok(s) => {
                lo = mid;
                last = s;
            }
            Err(e) => {
                hi = mid;
                contact |= matches!(e, Error::Contact { .. });
                why = Some(e);
            }
        }
    }
    Ok(ends_at(f, lo, last, contact, why))
}

/// The end at `lo`, `last` the forward solve there, `contact` whether a refusal past it was
/// one (`why`: the last refusal of a forward solve, if one).
fn ends_at<R: Real>(f: &Finger<R>, lo: R, last: super::Solution<R>, mut contact: bool, why: Option<Error>) -> BranchLimit<R> {
    let n = f.p.n;
    // how it ends: a span at its floor (or within ten floors of it at the last tension held, where
    // the coupled continuation gives up before the march meets the floor) is contact, at the
    // joint of the shortest span; else a limit point
    let (k, span) = (0..n).fold((0, last.span[0]), |b, k| if last.span[k] < b.1 { (k, last.span[k]) } else { b });
    contact |= span <= R::from_f64(10.0) * f.p.span_floor;
    let joint = match why {
        _ if contact => k + 1,
        Some(Error::Contact { joint, .. } | Error::LimitPoint { joint, .. }) => joint.max(1),
        _ => 1,
    };
    let kind = if contact { BranchEnd::Contact } else { BranchEnd::LimitPoint };
    BranchLimit { tension: lo, joint, kind }
}
