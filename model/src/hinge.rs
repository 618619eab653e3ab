//! The elliptical flexure hinge: notch thickness and its compliance by Castigliano's theorem
//! (docs/model.md "Hinge compliance"), over the whole hinge or one sub-element's stretch of it.
//!
//! What it is: the four compliance integrals of a cantilever clamped at the stretch's proximal
//! end, loaded at its distal end (Euler-Bernoulli, shear neglected), computed once per
//! parameter set by Gauss-Legendre quadrature. What it is not: the DE stack (see `de`) or the
//! assembly of the two (see `joint`).
//!
//! Quadrature: with x = a (1 + sin(phi)) the notch thickness becomes
//! t = t_min + (b - t_min)(1 - cos(phi)) and dx = a cos(phi) dphi, so every integrand is an
//! analytic function of phi (the square-root ends of the ellipse disappear) and composite
//! Gauss-Legendre converges exponentially: 8 nodes per panel, panels of at most 0.2 rad in phi,
//! reach better than 1e-12 relative in f64 (host test against an independent quadrature in x).

use crate::mat3::Mat3;
use crate::real::Real;

/// Gauss-Legendre, 8 nodes on [-1, 1]: (node, weight), the positive half.
const GL8: [(f64, f64); 4] = [
    (0.183_434_642_495_649_8, 0.362_683_783_378_362),
    (0.525_532_409_916_329, 0.313_706_645_877_887_3),
    (0.796_666_477_413_626_7, 0.222_381_034_453_374_5),
    (0.960_289_856_497_536_3, 0.101_228_536_290_376_3),
];

/// Hinge thickness at x in [0, 2a] (docs/model.md, two-sided elliptical notch):
/// `t(x) = t_min + (b - t_min) (1 - sqrt(1 - ((x - a)/a)^2))`.
pub fn notch_thickness<R: Real>(b: R, t_min: R, a: R, x: R) -> R {
    let u = (x - a) / a;
    let r = (R::one() - u * u).max(R::zero());
    t_min + (b - t_min) * (R::one() - r.sqrt())
}

/// The compliance integrals of one stretch [x0, x1] of the notch, for bending modulus `e`
/// (MPa) and width `w` (mm). Loads (Fx, Fy, M) at the stretch's distal end x1, components in
/// its proximal frame, M about x1:
/// - `C_x-Fx = ∫ dx / (E w t)`
/// - `C_y-Fy = ∫ (x1 - x)^2 12 / (E w t^3) dx`
/// - `C_y-M = C_θ-Fy = ∫ (x1 - x) 12 / (E w t^3) dx`
/// - `C_θ-M = ∫ 12 / (E w t^3) dx`
///
/// Returned as the compliance matrix `[[C_x-Fx,0,0],[0,C_y-Fy,C_y-M],[0,C_y-M,C_θ-M]]`.
pub fn stretch_compliance<R: Real>(b: R, t_min: R, a: R, e: R, w: R, x0: R, x1: R) -> Mat3<R> {
    let one = R::one();
    // phi bounds: asin((x - a)/a) via atan2 (no asin in `Real`).
    let phi_of = |x: R| {
        let u = ((x - a) / a).max(-one).min(one);
        u.atan2((one - u * u).max(R::zero()).sqrt())
    };
    let (p0, p1) = (phi_of(x0), phi_of(x1));
    let span = p1 - p0;
    // panels of at most 0.2 rad, at least 2
    let mut panels = 2u32;
    while R::from_u32(panels) * R::from_f64(0.2) < span && panels < 64 {
        panels += 1;
    }
    let h = span / R::from_u32(panels);
    let twelve = R::from_f64(12.0);
    let (mut cx, mut cyy, mut cym, mut cmm) = (R::zero(), R::zero(), R::zero(), R::zero());
    for p in 0..panels {
        let mid = p0 + h * (R::from_u32(p) + R::from_f64(0.5));
        for &(node, weight) in GL8.iter() {
            // half the node and weight (exact in binary); the pair ±node, in R (no f64
            // arithmetic at run time)
            let half = R::from_f64(0.5);
            let off = h * (R::from_f64(node) * half);
            let half_weight = R::from_f64(weight) * half;
            for phi in [mid - off, mid + off] {
                let (s, c) = phi.sin_cos();
                let x = a * (one + s);
                let t = t_min + (b - t_min) * (one - c);
                let dx = a * c * h * half_weight;
                let arm = x1 - x;
                let inv_ei = twelve / (e * w * t * t * t);
                cx += dx / (e * w * t);
                cmm += dx * inv_ei;
                cym += dx * arm * inv_ei;
                cyy += dx * arm * arm * inv_ei;
            }
        }
    }
    let z = R::zero();
    [[cx, z, z], [z, cyy, cym], [z, cym, cmm]]
}

/// The end points of sub-element j of m along the hinge (equal lengths in x).
pub fn sub_element_bounds<R: Real>(a: R, m: usize, j: usize) -> (R, R) {
    let len = (a + a) / R::from_u32(m as u32);
    (len * R::from_u32(j as u32), len * R::from_u32(j as u32 + 1))
}
