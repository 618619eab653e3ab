//! The quasi-Newton joint solve: Broyden's method on (hole, P) or (hole, t), one forward march
//! per step (`Finger::joint_march`), from a circular-arc first guess. Not the bracketed
//! fallback (`hold`).

use super::*;

/// A converged quasi-Newton solve: the unknowns x = (b0, b1, s), the state, and the last
/// Jacobian of F in the unknowns x (reused as the next solve's first Jacobian).
#[derive(Clone, Copy)]
pub(super) struct Qn<R> {
    pub(super) x: [R; 3],
    pub(super) st: JointMarch<R>,
    /// None when the first guess was converged and no Jacobian was given.
    pub(super) jac: Option<Mat3<R>>,
}

impl<'a, R: Real> Gen<'a, R> {
    /// The hole of a joint bent to θ as a circular arc (the first guess of a quasi-Newton
    /// solve): hinge end (L_h sin θ/θ, L_h (1 - cos θ)/θ), link k's proximal hole e above it.
    #[inline(never)]
    pub(super) fn arc_hole(&self, theta: R) -> [R; 2] {
        let lh = self.p.hinge_len();
        let (s, c) = theta.sin_cos();
        let (ex, ey) = if theta.abs() > R::from_f64(1e-6) { (lh * s / theta, lh * (R::one() - c) / theta) } else { (lh, R::zero()) };
        [ex - self.p.e * s, ey + self.p.e * c]
    }

    /// Broyden's method ("good" update, scaled unknowns y = x / scale) on the joint's three
    /// equations F(x) = (b - hole(b, s), θ(b, s) - θ*) = 0, x = (b0, b1, s), s the tension
    /// (`hold_tension`) or the stack thickness (`hold_thickness`); `ev(x)` is one plain march.
    /// The first Jacobian is `jac` (a previous solve's) or forward differences (3 marches).
    /// Converged when the hole residual is within the march's resolution and the angle
    /// within the root tolerance. `None` when it does not converge in 16 steps, or a march
    /// fails: the caller falls back to the bracketed root (robust, 3-5x the marches).
    /// Each step costs one march and no derivatives: cheaper than the dual-number Newton
    /// nested in a secant (the inverse's instruction count).
    /// Returns the solve (if it converged) and the marches it took.
    /// (One instance for both solves: `ev` is a trait object, which keeps the firmware image
    /// small.)
    #[allow(clippy::too_many_arguments)]
    pub(super) fn broyden(
        &self,
        ev: &mut dyn FnMut([R; 3], &mut [[R; 3]; MAX_SUB]) -> Result<JointMarch<R>, Error>,
        x0: [R; 3],
        scale: [R; 3],
        jac_x: Mat3<R>,
        fd: [bool; 3],
        theta: R,
        q_out: &mut [[R; 3]; MAX_SUB],
    ) -> (Option<Qn<R>>, u32) {
        let mut evals = 0u32;
        let mut ev = |x: [R; 3], q: &mut [[R; 3]; MAX_SUB]| {
            evals += 1;
            ev(x, q)
        };
        let r = self.broyden_steps(&mut ev, x0, scale, jac_x, fd, theta, q_out);
        (r, evals)
    }

    /// The iteration of `broyden`. The iterates' marches write their sub-element displacements
    /// to `q_out` (the converged state is always the last iterate marched), the forward
    /// differences to a scratch buffer.
    // same parameters as `broyden`, its counting wrapper (one `dyn` instance for both solves)
    #[allow(clippy::too_many_arguments)]
    #[inline(never)]
    pub(super) fn broyden_steps<F>(
        &self,
        ev: &mut F,
        x0: [R; 3],
        scale: [R; 3],
        jac_x: Mat3<R>,
        fd: [bool; 3],
        theta: R,
        q_out: &mut [[R; 3]; MAX_SUB],
    ) -> Option<Qn<R>>
    where
        F: FnMut([R; 3], &mut [[R; 3]; MAX_SUB]) -> Result<JointMarch<R>, Error>,
    {
        let atol = self.angle_atol(theta);
        let htol = self.htol;
        let resid = |x: &[R; 3], st: &JointMarch<R>| [x[0] - st.hole[0], x[1] - st.hole[1], st.angle - theta];
        let mut x = x0;
        let st = ev(x, q_out).ok()?;
        let mut fx = resid(&x, &st);
        let unscaled = |j: &Mat3<R>| {
            let mut jx = *j;
            for row in 0..3 {
                for col in 0..3 {
                    jx[row][col] = j[row][col] / scale[col];
                }
            }
            jx
        };
        let converged = |f: &[R; 3], k: R| f[0].abs() <= k * htol && f[1].abs() <= k * htol && f[2].abs() <= k * atol;
        // a first guess already converged (from the branch table) needs no Jacobian
        if converged(&fx, R::one()) {
            let jac = if fd.iter().any(|&d| d) { None } else { Some(jac_x) };
            return Some(Qn { x, st, jac });
        }
        // the Jacobian in the scaled unknowns; columns marked `fd` by forward differences
        let mut j = jac_x;
        if fd.iter().any(|&d| d) {
            let mut scratch = [[R::zero(); 3]; MAX_SUB];
            for col in 0..3 {
                if fd[col] {
                    let h = R::from_f64(R::SQRT_EPS);
                    let mut xp = x;
                    xp[col] += h * scale[col];
                    let sp = ev(xp, &mut scratch).ok()?;
                    let fp = resid(&xp, &sp);
                    for row in 0..3 {
                        j[row][col] = (fp[row] - fx[row]) / h;
                    }
                }
            }
        }
        for col in 0..3 {
            if !fd[col] {
                for row in 0..3 {
                    j[row][col] = jac_x[row][col] * scale[col];
                }
            }
        }
        // Broyden (`solve::broyden`) in the scaled unknowns y = x / scale; the marches write
        // the iterate's displacements to `q_out` (no line search: the last one is the answer's)
        let mut y = [x[0] / scale[0], x[1] / scale[1], x[2] / scale[2]];
        let mut last = st;
        let mut eval = |y: &[R; 3]| -> Result<[R; 3], Error> {
            let xn = [y[0] * scale[0], y[1] * scale[1], y[2] * scale[2]];
            let sn = ev(xn, q_out)?;
            last = sn;
            Ok(resid(&xn, &sn))
        };
        let done = broyden::solve(&mut eval, &mut y, &mut fx, &mut j, 3, &converged, 16);
        done.ok()?;
        x = [y[0] * scale[0], y[1] * scale[1], y[2] * scale[2]];
        Some(Qn { x, st: last, jac: Some(unscaled(&j)) })
    }

    /// dθ/dP along the equilibrium at fixed t from a solve's Jacobian (unknowns (b, P)):
    /// J dx = (0, 0, dθ*) gives dP/dθ* = (J⁻¹)[2][2].
    pub(super) fn slope_of(jac: &Mat3<R>) -> R {
        // (J⁻¹)[2][2] = C22 / det J, C22 = j00 j11 - j01 j10 its cofactor
        let det = mat3::det(jac);
        let c22 = jac[0][0] * jac[1][1] - jac[0][1] * jac[1][0];
        if mat3::singular(jac, det) || c22 == R::zero() {
            R::zero()
        } else {
            det / c22
        }
    }
}
