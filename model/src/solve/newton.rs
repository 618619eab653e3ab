//! Damped Newton: the Newton step from an LU of the Jacobian, then a backtracking line search
//! that halves the step until |r| falls (at most `max_halvings` times). Converged at
//! |r| <= tol, or when no step lowers |r| and |r| is already at the type's resolution.

use super::lu::Lu;
use super::{Converged, Failure, SolveOptions};
use crate::real::Real;

/// Slot for a forward-difference evaluation: it must not overwrite the iterates' states.
pub const SCRATCH: usize = 2;

/// A system of `dim() <= N` equations r(x) = 0. An evaluation may keep a state (the marched
/// joint, ...) in one of three slots: 0 and 1 for the iterate and the trial (swapped by index,
/// no copies), [`SCRATCH`] for finite differences.
pub trait Equations<R: Real, const N: usize> {
    /// Why r cannot be evaluated at a point (contact, a singular march, ...).
    type Refusal: Copy;
    fn dim(&self) -> usize {
        N
    }
    /// r(x), its state into `slot`.
    fn residual(&mut self, x: &[R; N], slot: usize) -> Result<[R; N], Self::Refusal>;
    /// ∂r/∂x at x, `r = residual(x, slot)` the last evaluation into `slot`.
    fn jacobian(&mut self, x: &[R; N], r: &[R; N], slot: usize) -> Result<[[R; N]; N], Self::Refusal>;
}

/// Forward differences of `eq`'s residual, step `h[i]` in unknown i (for `jacobian`).
pub fn forward_difference<R: Real, const N: usize, S: Equations<R, N> + ?Sized>(
    eq: &mut S,
    x: &[R; N],
    r: &[R; N],
    h: &[R; N],
) -> Result<[[R; N]; N], S::Refusal> {
    let dim = eq.dim();
    let mut jac = [[R::zero(); N]; N];
    for i in 0..dim {
        let mut xp = *x;
        xp[i] += h[i];
        let rp = eq.residual(&xp, SCRATCH)?;
        for row in 0..dim {
            jac[row][i] = (rp[row] - r[row]) / h[i];
        }
    }
    Ok(jac)
}

/// The norm the line search compares: |r|² where the type resolves the square of its
/// resolution (floats: no square root per trial), else |r| (fixed point would lose small
/// residuals to its quantum).
fn metric<R: Real, const N: usize>(r: &[R; N], dim: usize) -> R {
    let s = r[..dim].iter().fold(R::zero(), |a, &v| a + v * v);
    if squared::<R>() {
        s
    } else {
        s.sqrt()
    }
}

fn squared<R: Real>() -> bool {
    R::from_f64(R::EPS * R::EPS) > R::zero()
}

fn unmetric<R: Real>(m: R) -> f64 {
    if squared::<R>() {
        m.to_f64().sqrt()
    } else {
        m.to_f64()
    }
}

/// Damped Newton from `x` (updated in place). Returns the report and the slot that holds the
/// answer's state.
pub fn solve<R: Real, const N: usize, S: Equations<R, N> + ?Sized>(
    eq: &mut S,
    x: &mut [R; N],
    opts: &SolveOptions<R>,
) -> Result<(Converged<R>, usize), Failure<S::Refusal>> {
    let dim = eq.dim();
    let mut cur = 0usize;
    let mut r = eq.residual(x, cur).map_err(Failure::Domain)?;
    let mut rn = metric(&r, dim);
    let (tol, floor) = if squared::<R>() { (opts.tol * opts.tol, opts.floor * opts.floor) } else { (opts.tol, opts.floor) };
    let two = R::from_f64(2.0);
    for it in 0..opts.max_iter {
        if rn <= tol {
            return Ok((Converged { iterations: it, residual: R::from_f64(unmetric(rn)) }, cur));
        }
        let jac = match eq.jacobian(x, &r, cur) {
            Ok(j) => j,
            Err(e) => return Err(Failure::Stalled { iterations: it, residual: unmetric(rn), last: Some(e) }),
        };
        let Some(lu) = Lu::new(&jac, dim) else { return Err(Failure::Singular { iterations: it }) };
        let dx = lu.solve(&r);
        let mut lambda = R::one();
        let mut accepted = false;
        let mut last = None;
        for _ in 0..opts.max_halvings {
            let mut xt = *x;
            for i in 0..dim {
                xt[i] -= lambda * dx[i];
            }
            match eq.residual(&xt, 1 - cur) {
                Ok(rt) => {
                    let rtn = metric(&rt, dim);
                    if rtn < rn {
                        *x = xt;
                        r = rt;
                        rn = rtn;
                        cur = 1 - cur;
                        accepted = true;
                        break;
                    }
                }
                Err(e) => last = Some(e),
            }
            lambda = lambda / two;
        }
        if !accepted {
            // at the scalar's resolution the residual stops falling: that is convergence
            if rn <= floor {
                return Ok((Converged { iterations: it + 1, residual: R::from_f64(unmetric(rn)) }, cur));
            }
            return Err(Failure::Stalled { iterations: it + 1, residual: unmetric(rn), last });
        }
    }
    if rn <= tol {
        Ok((Converged { iterations: opts.max_iter, residual: R::from_f64(unmetric(rn)) }, cur))
    } else {
        Err(Failure::MaxIter { iterations: opts.max_iter, residual: unmetric(rn) })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// x² + y² = 4, x y = 1: Newton from (2, 0.3) converges to the root with x > y.
    struct Circle;
    impl Equations<f64, 2> for Circle {
        type Refusal = ();
        fn residual(&mut self, x: &[f64; 2], _: usize) -> Result<[f64; 2], ()> {
            Ok([x[0] * x[0] + x[1] * x[1] - 4.0, x[0] * x[1] - 1.0])
        }
        fn jacobian(&mut self, x: &[f64; 2], r: &[f64; 2], _: usize) -> Result<[[f64; 2]; 2], ()> {
            forward_difference(self, x, r, &[1e-7; 2])
        }
    }

    #[test]
    fn damped_newton_finds_the_root_and_refuses_a_singular_start() {
        let mut x = [2.0, 0.3];
        let (c, _) = solve(&mut Circle, &mut x, &SolveOptions::new(1e-10, 1e-14, 50)).unwrap();
        assert!((x[0] * x[1] - 1.0).abs() < 1e-9 && (x[0] * x[0] + x[1] * x[1] - 4.0).abs() < 1e-9);
        assert!(c.iterations > 0 && c.residual <= 1e-10);
        let mut z = [0.0, 0.0];
        assert!(matches!(solve(&mut Circle, &mut z, &SolveOptions::new(1e-10, 1e-14, 50)), Err(Failure::Singular { .. })));
    }
}
