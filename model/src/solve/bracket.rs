//! Safeguarded brackets for one unknown:
//! - [`illinois`]: the root of f on [a, b] with f(a) f(b) < 0, by regula falsi with the
//!   Illinois modification (the retained end's value halved when it is kept twice), so the
//!   bracket always shrinks and the order stays superlinear;
//! - [`boundary`]: the end x* of a feasible set [lo, x*) (a solve exists below x*, not past
//!   it), from the caller's estimate of x* where it lies inside the bracket, else bisection;
//! - [`increasing_root`]: the root of an increasing h(x) on [lo, hi], hi possibly unknown (the
//!   bracket grows until it holds the root), where a trial may be refused as past the end of
//!   h's domain: secant steps kept inside the bracket, bisection when one end is kept three
//!   times (the Illinois failure mode).

use super::{Converged, Failure};
use crate::real::Real;

/// Root of f in [a, b] given f(a) = fa and f(b) = fb of opposite signs; stops when the bracket
/// is narrower than `xtol` or |f| <= `ftol`. Returns the root and the report (residual |f|).
#[allow(clippy::too_many_arguments)]
pub fn illinois<R: Real, E>(
    f: &mut dyn FnMut(R) -> Result<R, E>,
    mut a: R,
    mut fa: R,
    mut b: R,
    mut fb: R,
    xtol: R,
    ftol: R,
    max_iter: u32,
) -> Result<(R, Converged<R>), Failure<E>> {
    if !(fa * fb <= R::zero()) {
        return Err(Failure::Singular { iterations: 0 });
    }
    let mut side = 0i8;
    for it in 0..max_iter {
        if fa.abs() <= ftol {
            return Ok((a, Converged { iterations: it, residual: fa.abs() }));
        }
        if fb.abs() <= ftol || (b - a).abs() <= xtol {
            let (x, fx) = if fa.abs() < fb.abs() { (a, fa) } else { (b, fb) };
            return Ok((x, Converged { iterations: it, residual: fx.abs() }));
        }
        let mut c = (a * fb - b * fa) / (fb - fa);
        if !(c.is_finite()) || c <= a.min(b) || c >= a.max(b) {
            c = (a + b) / R::from_f64(2.0);
        }
        let fc = f(c).map_err(|e| Failure::Stalled { iterations: it + 1, residual: fa.abs().min(fb.abs()).to_f64(), last: Some(e) })?;
        if fc * fb < R::zero() {
            a = b;
            fa = fb;
            b = c;
            fb = fc;
            side = 0;
        } else {
            b = c;
            fb = fc;
            if side == 1 {
                fa /= R::from_f64(2.0);
            }
            side = 1;
        }
    }
    Err(Failure::MaxIter { iterations: max_iter, residual: fa.abs().min(fb.abs()).to_f64() })
}

/// The end of a feasible interval: `lo` feasible, `hi` not (or `hi` an upper bound). Each
/// trial `probe(x)` returns `Some(estimate)` when x is feasible (it then becomes `lo`; the
/// estimate of x* is the caller's, from the solve at x, and may be None inside the `Some`),
/// `None` when not (x becomes `hi`). The next trial is the latest estimate, nudged a quarter
/// of the target width past it, when that lies inside the bracket and the last two trials
/// shrank it by half or more; else the midpoint. Stops when hi - lo <= rel * hi. Returns
/// [lo, hi] and the trials.
pub fn boundary<R: Real>(mut lo: R, mut hi: R, rel: R, max_iter: u32, mut estimate: Option<R>, probe: &mut dyn FnMut(R) -> Option<Option<R>>) -> ([R; 2], u32) {
    let two = R::from_f64(2.0);
    let mut widths = [hi - lo; 2];
    for it in 0..max_iter {
        let w = hi - lo;
        if w <= rel * hi {
            return ([lo, hi], it);
        }
        let shrinking = widths[1] <= widths[0] / two || it < 2;
        let nudge = rel * hi / R::from_f64(4.0);
        let x = match estimate {
            Some(e) if shrinking && e.is_finite() => {
                // aim just past the estimate from below, just short of it from above
                let x = if e + nudge < hi { e + nudge } else { e - nudge };
                if x > lo && x < hi {
                    x
                } else {
                    (lo + hi) / two
                }
            }
            _ => (lo + hi) / two,
        };
        match probe(x) {
            Some(e) => {
                lo = x;
                if e.is_some() {
                    estimate = e;
                }
            }
            None => hi = x,
        }
        widths = [widths[1], hi - lo];
    }
    ([lo, hi], max_iter)
}

/// A point of [`increasing_root`]: the parameter, h(x) and the caller's state there.
#[derive(Clone, Copy, Debug)]
pub struct Point<R, S> {
    pub x: R,
    pub h: R,
    pub state: S,
}

/// What one trial of [`increasing_root`] found at x.
#[derive(Clone, Copy, Debug)]
pub enum Trial<R, S, E> {
    /// h(x) and the caller's state.
    Value(R, S),
    /// x lies past the end of h's domain (the caller's solve stops existing there): it
    /// bounds the bracket from above.
    Beyond(E),
}

/// The bracket a trial starts from (the caller's starting guess for its own solve): the
/// evaluated points at its ends, and the last point evaluated.
pub struct Around<'a, R, S> {
    pub left: Option<&'a Point<R, S>>,
    pub right: Option<&'a Point<R, S>>,
    pub last: Option<&'a Point<R, S>>,
}

/// Why [`increasing_root`] has no root.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum RootError<E> {
    /// The root lies past the end of h's domain, which is located to `beyond_rel`: the last
    /// refusal there.
    Beyond(E),
    /// A non-finite h, no evaluated point when the bracket closed, or `max_iter` used up.
    NotConverged,
    /// A trial failed for another reason (the caller's error, passed on).
    Refused(E),
}

/// Tolerances of [`increasing_root`].
#[derive(Clone, Copy, Debug)]
pub struct RootOptions<R> {
    /// Converged when |h| <= atol.
    pub atol: R,
    /// The bracket closed: hi - lo <= rel max(|lo|, |hi|) (the best point is the answer).
    pub rel: R,
    /// The domain's end is located when hi - lo <= beyond_rel hi (and hi was refused).
    pub beyond_rel: R,
    pub max_iter: u32,
}

/// The root of an increasing h on [lo, hi] (`hi` None: unbounded, the bracket grows at most
/// fourfold per step), from the first trial `x0`; `left` is a known point at lo, `slope` an
/// estimate of dh/dx > 0. Each trial `trial(x, around)` returns h(x) and the caller's state,
/// or `Beyond` past the end of h's domain, or an error that ends the search. The next trial
/// is the secant through the last two points (the slope estimate with one), kept inside the
/// bracket: when it leaves it, an end not yet evaluated is tried first, else the midpoint;
/// when one end has been kept three times, the midpoint. Returns the root's point and dh/dx
/// there (the secant's, else `slope`).
pub fn increasing_root<R: Real, S: Copy, E: Copy>(
    trial: &mut dyn FnMut(R, &Around<'_, R, S>) -> Result<Trial<R, S, E>, E>,
    lo: R,
    hi: Option<R>,
    left: Option<Point<R, S>>,
    x0: R,
    slope: R,
    opts: &RootOptions<R>,
) -> Result<(Point<R, S>, R), RootError<E>> {
    let two = R::from_f64(2.0);
    let (mut l_x, mut l_pt) = (lo, left);
    let (mut r_x, mut r_pt): (Option<R>, Option<Point<R, S>>) = (hi, None);
    let (mut prev, mut last): (Option<Point<R, S>>, Option<Point<R, S>>) = (left, None);
    let mut beyond: Option<E> = None;
    let (mut run_side, mut run) = (0i8, 0u32);
    let mut x = x0;
    let slope_of = |a: Option<Point<R, S>>, b: &Point<R, S>| match a {
        Some(a) if a.x != b.x => {
            let s = (b.h - a.h) / (b.x - a.x);
            if s.is_finite() && s > R::zero() {
                s
            } else {
                slope
            }
        }
        _ => slope,
    };
    for _ in 0..opts.max_iter {
        let side;
        let around = Around { left: l_pt.as_ref(), right: r_pt.as_ref(), last: last.as_ref() };
        match trial(x, &around).map_err(RootError::Refused)? {
            Trial::Value(h, state) => {
                let pt = Point { x, h, state };
                if !h.is_finite() {
                    return Err(RootError::NotConverged);
                }
                if h.abs() <= opts.atol {
                    return Ok((pt, slope_of(last.or(prev), &pt)));
                }
                if h < R::zero() {
                    l_x = x;
                    l_pt = Some(pt);
                    side = -1;
                } else {
                    r_x = Some(x);
                    r_pt = Some(pt);
                    side = 1;
                }
                if last.is_some() {
                    prev = last;
                }
                last = Some(pt);
            }
            Trial::Beyond(e) => {
                r_x = Some(x);
                r_pt = None;
                beyond = Some(e);
                side = 1;
            }
        }
        if side == run_side {
            run += 1;
        } else {
            run_side = side;
            run = 1;
        }
        // the root lies past the domain's end, which is now located
        if let (Some(rx), None, Some(e)) = (r_x, r_pt, beyond) {
            if rx - l_x <= opts.beyond_rel * rx {
                return Err(RootError::Beyond(e));
            }
        }
        // the bracket has closed: the best point, or the domain's end
        if let Some(rx) = r_x {
            if rx - l_x <= opts.rel * rx.abs().max(l_x.abs()) {
                if let (None, Some(e)) = (r_pt, beyond) {
                    return Err(RootError::Beyond(e));
                }
                let best = match (l_pt, r_pt) {
                    (Some(a), Some(b)) => Some(if a.h.abs() <= b.h.abs() { a } else { b }),
                    (a, b) => a.or(b),
                };
                let Some(pt) = best else { return Err(RootError::NotConverged) };
                let s = slope_of(if last.map(|z| z.x) == Some(pt.x) { prev } else { last }, &pt);
                return Ok((pt, s));
            }
        }
        // next trial: secant through the last two points, else the slope estimate
        let mut xn = match (prev, last) {
            (Some(a), Some(b)) if b.h != a.h => b.x - b.h * (b.x - a.x) / (b.h - a.h),
            (_, Some(b)) => b.x - b.h / slope,
            _ => (l_x + x) / two,
        };
        let inside = xn.is_finite() && xn > l_x && r_x.is_none_or(|rx| xn < rx);
        match r_x {
            None => {
                // unbounded: grow at most fourfold per step
                let cap = R::from_f64(4.0) * l_x.max(x);
                if !inside || run >= 3 {
                    xn = two * l_x.max(x);
                }
                xn = xn.min(cap);
            }
            Some(rx) => {
                if run >= 3 {
                    xn = (l_x + rx) / two;
                } else if !inside {
                    // an end of the range not yet evaluated is tried first
                    xn = if xn >= rx && r_pt.is_none() && beyond.is_none() {
                        rx
                    } else if xn <= l_x && l_pt.is_none() {
                        l_x
                    } else {
                        (l_x + rx) / two
                    };
                }
            }
        }
        x = xn;
    }
    Err(RootError::NotConverged)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn illinois_finds_a_cubic_root_and_boundary_finds_a_feasible_end() {
        let mut f = |x: f64| -> Result<f64, ()> { Ok(x * x * x - 2.0) };
        let (x, c) = illinois(&mut f, 0.0, -2.0, 2.0, 6.0, 1e-14, 1e-14, 100).unwrap();
        assert!((x - 2f64.cbrt()).abs() < 1e-12 && c.iterations < 40, "{x} {c:?}");
        // feasible below 1.2345, exact estimate: a handful of trials
        let mut n = 0;
        let ([lo, hi], _) = boundary(0.0, 100.0, 1e-6, 200, None, &mut |x: f64| {
            n += 1;
            (x < 1.2345).then_some(Some(1.2345 - 0.5 * (1.2345 - x) * (1.2345 - x)))
        });
        assert!(lo < 1.2345 && hi >= 1.2345 && hi - lo <= 1e-6 * hi, "{lo} {hi}");
        assert!(n < 40, "{n} trials");
    }

    /// h(x) = x³ - 2 on a domain that ends at 1.5: from x0 = 0.1 with no upper end the bracket
    /// grows to the root; with the root placed past the domain's end (h(x) = x - 3), the
    /// search ends in `Beyond`, the end located.
    #[test]
    fn increasing_root_grows_its_bracket_and_locates_the_domain_end() {
        let opts = RootOptions { atol: 1e-12, rel: 1e-15, beyond_rel: 1e-6, max_iter: 200 };
        let mut f = |x: f64, _: &Around<'_, f64, ()>| -> Result<Trial<f64, (), &str>, &str> {
            Ok(if x < 1.5 { Trial::Value(x * x * x - 2.0, ()) } else { Trial::Beyond("end") })
        };
        let (p, s) = increasing_root(&mut f, 0.0, None, None, 0.1, 1.0, &opts).unwrap();
        assert!((p.x - 2f64.cbrt()).abs() < 1e-9 && s > 0.0, "{p:?}");
        let mut g = |x: f64, _: &Around<'_, f64, ()>| -> Result<Trial<f64, (), &str>, &str> {
            Ok(if x < 1.5 { Trial::Value(x - 3.0, ()) } else { Trial::Beyond("end") })
        };
        assert_eq!(increasing_root(&mut g, 0.0, None, None, 0.1, 1.0, &opts).map(|r| r.0.x), Err(RootError::Beyond("end")));
    }
}
