//! Broyden's method ("good" update): Newton steps on a Jacobian estimate that each step
//! corrects by the rank-one update J += (Δf - J Δx) Δxᵀ / |Δx|², one evaluation per step and
//! no derivatives after the first Jacobian. No line search: the caller starts it close (and
//! falls back to a bracket when it fails).

use super::lu::Lu;
use super::{Converged, Failure};
use crate::real::Real;

/// Broyden from `x` with residual `f = r(x)` and Jacobian estimate `jac` (all updated in
/// place: on return they hold the last iterate). `converged(f, k)` is the caller's test with
/// its tolerances scaled by k; a step below the scalar's resolution ends the solve (accepted at
/// k = 16). At most `max_iter` steps.
pub fn solve<R: Real, const N: usize, E>(
    eval: &mut dyn FnMut(&[R; N]) -> Result<[R; N], E>,
    x: &mut [R; N],
    f: &mut [R; N],
    jac: &mut [[R; N]; N],
    dim: usize,
    converged: &dyn Fn(&[R; N], R) -> bool,
    max_iter: u32,
) -> Result<Converged<R>, Failure<E>> {
    let norm = |f: &[R; N]| f[..dim].iter().fold(R::zero(), |a, &v| a + v * v).sqrt();
    for it in 0..max_iter {
        if converged(f, R::one()) {
            return Ok(Converged { iterations: it, residual: norm(f) });
        }
        let Some(lu) = Lu::new(jac, dim) else { return Err(Failure::Singular { iterations: it }) };
        let d = lu.solve(f);
        let mut xn = *x;
        let mut tiny = true;
        for i in 0..dim {
            xn[i] = x[i] - d[i];
            if (xn[i] - x[i]).abs() > R::from_f64(4.0 * R::EPS) * x[i].abs().max(R::one()) {
                tiny = false;
            }
        }
        let fnew = eval(&xn).map_err(|e| Failure::Stalled { iterations: it + 1, residual: norm(f).to_f64(), last: Some(e) })?;
        if !fnew[..dim].iter().all(|v| v.is_finite()) {
            return Err(Failure::Stalled { iterations: it + 1, residual: f64::INFINITY, last: None });
        }
        let dx2 = d[..dim].iter().fold(R::zero(), |a, &v| a + v * v);
        if dx2 > R::zero() {
            for row in 0..dim {
                let jd = (0..dim).fold(R::zero(), |a, c| a + jac[row][c] * d[c]);
                // Δx = -d
                let u = (fnew[row] - f[row] + jd) / dx2;
                for col in 0..dim {
                    jac[row][col] -= u * d[col];
                }
            }
        }
        *x = xn;
        *f = fnew;
        if tiny {
            return if converged(f, R::from_f64(16.0)) {
                Ok(Converged { iterations: it + 1, residual: norm(f) })
            } else {
                Err(Failure::Stalled { iterations: it + 1, residual: norm(f).to_f64(), last: None })
            };
        }
    }
    if converged(f, R::one()) {
        Ok(Converged { iterations: max_iter, residual: norm(f) })
    } else {
        Err(Failure::MaxIter { iterations: max_iter, residual: norm(f).to_f64() })
    }
}
