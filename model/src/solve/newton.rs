//! Newton's method, two ways:
//! - [`solve`]: damped Newton, the step from an LU of the Jacobian, then a backtracking line
//!   search that halves the step until |r| falls (at most `max_halvings` times). Converged at
//!   |r| <= tol, or when no step lowers |r| and |r| is already at the type's resolution.
//! - [`full_steps`]: undamped Newton for a start already close and a closed-form Jacobian:
//!   residual and Jacobian from one evaluation, full steps, converged on the step. One
//!   evaluation and one fixed-size inverse per iteration (closed form at 3 x 3), no trial
//!   evaluations.

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
    /// `jacobian` into `jac` (what [`solve`] calls: a system that keeps its own Jacobian
    /// writes its leading `dim()` block, no array moved by value). Default: `jacobian`'s.
    #[inline]
    fn jacobian_into(&mut self, x: &[R; N], r: &[R; N], slot: usize, jac: &mut [[R; N]; N]) -> Result<(), Self::Refusal> {
        *jac = self.jacobian(x, r, slot)?;
        Ok(())
    }
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
    // the root in R (f32 on the target: no soft-float f64; correctly rounded either way)
    if squared::<R>() {
        m.sqrt().to_f64()
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
    // the Jacobian, then its factors (in place: one array for the whole solve)
    let mut jac = [[R::zero(); N]; N];
    for it in 0..opts.max_iter {
        if rn <= tol {
            return Ok((Converged { iterations: it, residual: R::from_f64(unmetric(rn)) }, cur));
        }
        if let Err(e) = eq.jacobian_into(x, &r, cur, &mut jac) {
            return Err(Failure::Stalled { iterations: it, residual: unmetric(rn), last: Some(e) });
        }
        let Some(lu) = Lu::in_place(&mut jac, dim) else { return Err(Failure::Singular { iterations: it }) };
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
            lambda /= two;
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

/// A system r(x) = 0 of N equations whose residual and Jacobian come from one evaluation.
pub trait Linearized<R: Real, const N: usize> {
    /// Why r cannot be evaluated at a point.
    type Refusal: Copy;
    /// r(x) and ∂r/∂x at x.
    fn linearize(&mut self, x: &[R; N]) -> Result<([R; N], [[R; N]; N]), Self::Refusal>;
    /// Whether the step `dx` that led to `x` is within the caller's tolerances.
    fn step_converged(&self, x: &[R; N], dx: &[R; N]) -> bool;
    /// Whether `x` lies in r's domain (finite by default).
    fn admissible(&self, x: &[R; N]) -> bool {
        x.iter().all(|v| v.is_finite())
    }
}

/// J⁻¹ of a Newton step: closed form (scaled cofactors, `mat3::inverse`) for 3 x 3, else from
/// the LU. `None` if J is singular to the scalar's resolution.
#[inline]
pub fn inverse<R: Real, const N: usize>(jac: &[[R; N]; N]) -> Option<[[R; N]; N]> {
    if N == 3 {
        let mut m = [[R::zero(); 3]; 3];
        for (i, row) in m.iter_mut().enumerate() {
            row.copy_from_slice(&jac[i][..3]);
        }
        let inv = crate::mat3::inverse(&m)?;
        let mut out = [[R::zero(); N]; N];
        for (i, row) in out.iter_mut().enumerate() {
            row[..3].copy_from_slice(&inv[i]);
        }
        Some(out)
    } else {
        Some(Lu::new(jac, N)?.inverse())
    }
}

/// A x.
#[inline]
pub fn mul_vec<R: Real, const N: usize>(a: &[[R; N]; N], x: &[R; N]) -> [R; N] {
    let mut y = [R::zero(); N];
    for (yi, row) in y.iter_mut().zip(a) {
        *yi = row.iter().zip(x).fold(R::zero(), |s, (&p, &q)| s + p * q);
    }
    y
}

/// Full Newton steps x -= J⁻¹ r from `x` (updated in place), at most `max_iter`: for a start
/// already close and a closed-form Jacobian (one evaluation, one fixed-size inverse, no trial
/// points per step). Converged when `step_converged(x, dx)`; the report's iterations count the
/// steps, its residual is |r| at the last linearization (before the converging step). Returns
/// J⁻¹ there too (implicit derivatives at the answer). A step out of the domain is `Stalled`.
#[inline]
pub fn full_steps<R: Real, const N: usize, S: Linearized<R, N>>(
    eq: &mut S,
    x: &mut [R; N],
    max_iter: u32,
) -> Result<(Converged<R>, [[R; N]; N]), Failure<S::Refusal>> {
    let norm = |r: &[R; N]| r.iter().fold(R::zero(), |a, &v| a + v * v).sqrt();
    // the last residual, its norm taken only for a report
    let mut last = [R::zero(); N];
    for it in 1..=max_iter {
        let (r, jac) = match eq.linearize(x) {
            Ok(v) => v,
            Err(e) if it == 1 => return Err(Failure::Domain(e)),
            Err(e) => return Err(Failure::Stalled { iterations: it - 1, residual: norm(&last).to_f64(), last: Some(e) }),
        };
        let Some(inv) = inverse(&jac) else { return Err(Failure::Singular { iterations: it - 1 }) };
        let dx = mul_vec(&inv, &r);
        for i in 0..N {
            x[i] -= dx[i];
        }
        if !eq.admissible(x) {
            return Err(Failure::Stalled { iterations: it, residual: f64::INFINITY, last: None });
        }
        if eq.step_converged(x, &dx) {
            return Ok((Converged { iterations: it, residual: norm(&r) }, inv));
        }
        last = r;
    }
    Err(Failure::MaxIter { iterations: max_iter, residual: if max_iter == 0 { f64::INFINITY } else { norm(&last).to_f64() } })
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

    /// The same system with its Jacobian in closed form, by full steps converged on the step.
    impl Linearized<f64, 2> for Circle {
        type Refusal = ();
        fn linearize(&mut self, x: &[f64; 2]) -> Result<([f64; 2], [[f64; 2]; 2]), ()> {
            Ok(([x[0] * x[0] + x[1] * x[1] - 4.0, x[0] * x[1] - 1.0], [[2.0 * x[0], 2.0 * x[1]], [x[1], x[0]]]))
        }
        fn step_converged(&self, _: &[f64; 2], dx: &[f64; 2]) -> bool {
            dx.iter().all(|d| d.abs() <= 1e-13)
        }
    }

    #[test]
    fn full_steps_converge_quadratically_and_refuse_a_singular_start() {
        let mut x = [2.0, 0.3];
        let (c, inv) = full_steps(&mut Circle, &mut x, 30).unwrap();
        assert!((x[0] * x[1] - 1.0).abs() < 1e-12 && (x[0] * x[0] + x[1] * x[1] - 4.0).abs() < 1e-12);
        assert!(c.iterations > 1 && c.iterations < 10, "{c:?}");
        // the returned inverse is the Jacobian's at (nearly) the root: J J⁻¹ = I
        let j = [[2.0 * x[0], 2.0 * x[1]], [x[1], x[0]]];
        for r in 0..2 {
            for c in 0..2 {
                let p: f64 = (0..2).map(|k| j[r][k] * inv[k][c]).sum();
                assert!((p - if r == c { 1.0 } else { 0.0 }).abs() < 1e-9);
            }
        }
        assert!(matches!(full_steps(&mut Circle, &mut [0.0, 0.0], 30), Err(Failure::Singular { iterations: 0 })));
        assert!(matches!(full_steps(&mut Circle, &mut [2.0, 0.3], 1), Err(Failure::MaxIter { iterations: 1, .. })));
    }
}
