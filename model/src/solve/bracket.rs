//! Safeguarded brackets for one unknown:
//! - [`illinois`]: the root of f on [a, b] with f(a) f(b) < 0, by regula falsi with the
//!   Illinois modification (the retained end's value halved when it is kept twice), so the
//!   bracket always shrinks and the order stays superlinear;
//! - [`boundary`]: the end x* of a feasible set [lo, x*) (a solve exists below x*, not past
//!   it), from the caller's estimate of x* where it lies inside the bracket, else bisection.

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
                fa = fa / R::from_f64(2.0);
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
pub fn boundary<R: Real>(
    mut lo: R,
    mut hi: R,
    rel: R,
    max_iter: u32,
    mut estimate: Option<R>,
    probe: &mut dyn FnMut(R) -> Option<Option<R>>,
) -> ([R; 2], u32) {
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
}
