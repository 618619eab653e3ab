//! 3x3 matrices and 3-vectors for compliances and wrenches: the few operations the model
//! needs, on fixed arrays, no allocation. Not a linear-algebra library.

use crate::real::Real;

pub type Vec3<R> = [R; 3];
pub type Mat3<R> = [[R; 3]; 3];

pub fn zero<R: Real>() -> Mat3<R> {
    [[R::zero(); 3]; 3]
}

pub fn mul_vec<R: Real>(m: &Mat3<R>, v: &Vec3<R>) -> Vec3<R> {
    let mut o = [R::zero(); 3];
    for i in 0..3 {
        o[i] = m[i][0] * v[0] + m[i][1] * v[1] + m[i][2] * v[2];
    }
    o
}

pub fn add<R: Real>(a: &Mat3<R>, b: &Mat3<R>) -> Mat3<R> {
    let mut o = *a;
    for i in 0..3 {
        for j in 0..3 {
            o[i][j] += b[i][j];
        }
    }
    o
}

pub fn mul<R: Real>(a: &Mat3<R>, b: &Mat3<R>) -> Mat3<R> {
    let mut o = zero();
    for i in 0..3 {
        for j in 0..3 {
            o[i][j] = a[i][0] * b[0][j] + a[i][1] * b[1][j] + a[i][2] * b[2][j];
        }
    }
    o
}

pub fn transpose<R: Real>(a: &Mat3<R>) -> Mat3<R> {
    let mut o = zero();
    for i in 0..3 {
        for j in 0..3 {
            o[i][j] = a[j][i];
        }
    }
    o
}

pub fn det<R: Real>(m: &Mat3<R>) -> R {
    m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
}

/// The symmetric matrix with upper triangle (m00, m01, m02, m11, m12, m22).
#[inline(always)]
pub fn from_upper<R: Real>([a, b, c, d, e, f]: [R; 6]) -> Mat3<R> {
    [[a, b, c], [b, d, e], [c, e, f]]
}

/// Inverse of a symmetric positive-definite matrix (a stiffness or a compliance), from the
/// upper triangle by cofactors: the model's one 3x3 solve for these; `inverse` for any other
/// 3x3 matrix. `None` unless det > 64 ε Π m_ii (for a positive-definite matrix
/// det ≤ Π m_ii, so this is a scale-free singularity test), the diagonal is positive and
/// every entry is finite.
pub fn inverse_spd<R: Real>(m: &Mat3<R>) -> Option<Mat3<R>> {
    if !(m[0][0] > R::zero() && m[1][1] > R::zero() && m[2][2] > R::zero()) {
        return None;
    }
    let (o, check) = inverse_spd_upper([m[0][0], m[0][1], m[0][2], m[1][1], m[1][2], m[2][2]]);
    check.is_finite().then_some(from_upper(o))
}

/// `inverse_spd`'s kernel on upper triangles (m00, m01, m02, m11, m12, m22) whose diagonal is
/// positive (the caller's to know: `inverse_spd` checks it; a positive definite matrix plus a
/// positive semi-definite one has it), for callers that test many at once: the inverse's upper
/// triangle and a check value, finite (the determinant plus the entries) when `inverse_spd`
/// would accept the matrix, else NaN; a finite sum of checks stands for every entry's test.
#[inline(always)]
pub fn inverse_spd_upper<R: Real>([a, b, c, d, e, f]: [R; 6]) -> ([R; 6], R) {
    let ca = d * f - e * e;
    let cb = c * e - b * f;
    let cc = b * e - c * d;
    let det = a * ca + b * cb + c * cc;
    let ok = det > a * d * f * R::from_f64(64.0 * R::EPS);
    let inv = R::one() / det;
    let (cd, ce, cf) = (a * f - c * c, b * c - a * e, a * d - b * b);
    let o = [ca * inv, cb * inv, cc * inv, cd * inv, ce * inv, cf * inv];
    let check = if ok { det + o[0] + o[1] + o[2] + o[3] + o[4] + o[5] } else { R::from_f64(f64::NAN) };
    (o, check)
}

/// Inverse of any 3x3 matrix (a Newton step's Jacobian); `None` if it is singular to working
/// precision or not finite. A symmetric positive-definite matrix takes `inverse_spd`, larger
/// systems `solve::lu`.
///
/// Compliance and stiffness matrices mix units (mm/N next to rad/(N·mm)) and their diagonal
/// spans decades, so a positive-diagonal matrix is first scaled symmetrically to a unit
/// diagonal, `M' = S M S` with `S = diag(1/√m_ii)`, and `M⁻¹ = S M'⁻¹ S`: the singularity test
/// then measures the matrix's conditioning, not its units.
pub fn inverse<R: Real>(m: &Mat3<R>) -> Option<Mat3<R>> {
    let mut s = [R::one(); 3];
    if m[0][0] > R::zero() && m[1][1] > R::zero() && m[2][2] > R::zero() {
        for i in 0..3 {
            s[i] = R::one() / m[i][i].sqrt();
        }
    }
    let mut ms = *m;
    for i in 0..3 {
        for j in 0..3 {
            ms[i][j] = s[i] * m[i][j] * s[j];
        }
    }
    let mut inv = inverse_unscaled(&ms)?;
    for i in 0..3 {
        for j in 0..3 {
            inv[i][j] = s[i] * inv[i][j] * s[j];
        }
    }
    if inv.iter().flatten().all(|x| x.is_finite()) {
        Some(inv)
    } else {
        None
    }
}

/// Whether `m`, of determinant `d`, is singular to working precision: d small against the
/// product of the row norms (Hadamard's bound), or not finite.
pub fn singular<R: Real>(m: &Mat3<R>, d: R) -> bool {
    let mut scale = R::one();
    for row in m {
        scale *= (row[0].sq() + row[1].sq() + row[2].sq()).sqrt();
    }
    !(d.is_finite() && scale.is_finite()) || d.abs() <= scale * R::from_f64(64.0 * R::EPS)
}

/// `inverse` by cofactors without the scaling; `None` where `singular`.
fn inverse_unscaled<R: Real>(m: &Mat3<R>) -> Option<Mat3<R>> {
    let d = det(m);
    if singular(m, d) {
        return None;
    }
    let inv_d = R::one() / d;
    let c = |a: usize, b: usize, x: usize, y: usize| m[a][b] * m[x][y] - m[a][y] * m[x][b];
    Some([
        [c(1, 1, 2, 2) * inv_d, -c(0, 1, 2, 2) * inv_d, c(0, 1, 1, 2) * inv_d],
        [-c(1, 0, 2, 2) * inv_d, c(0, 0, 2, 2) * inv_d, -c(0, 0, 1, 2) * inv_d],
        [c(1, 0, 2, 1) * inv_d, -c(0, 0, 2, 1) * inv_d, c(0, 0, 1, 1) * inv_d],
    ])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn inverse_spd_matches_the_scaled_inverse() {
        // a stiffness-like matrix (axial decades above bending, coupled) and a compliance
        let ms: [Mat3<f64>; 2] =
            [[[2.0e4, 0.0, 150.0], [0.0, 30.0, -40.0], [150.0, -40.0, 300.0]], [[1.0e-4, 2.0e-6, 3.0e-5], [2.0e-6, 0.5, 0.02], [3.0e-5, 0.02, 0.004]]];
        for m in ms {
            let a = inverse_spd(&m).unwrap();
            let b = inverse(&m).unwrap();
            for i in 0..3 {
                for j in 0..3 {
                    assert!((a[i][j] - b[i][j]).abs() <= 1e-12 * b[i][i].abs().max(b[j][j].abs()), "{i}{j}: {} {}", a[i][j], b[i][j]);
                }
            }
            // and it is the inverse
            let id = mul(&m, &a);
            for i in 0..3 {
                assert!((id[i][i] - 1.0).abs() < 1e-12);
            }
        }
        // singular, indefinite and non-finite matrices are refused
        assert!(inverse_spd(&[[1.0, 1.0, 0.0], [1.0, 1.0, 0.0], [0.0, 0.0, 1.0]]).is_none());
        assert!(inverse_spd(&[[1.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, 1.0]]).is_none());
        assert!(inverse_spd(&[[f64::NAN, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]).is_none());
    }
}
