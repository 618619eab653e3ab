//! Dense LU decomposition with partial pivoting, PA = LU, of the leading `dim x dim` block of
//! an `N x N` array: computed once, then `solve`, `determinant`, `inverse` (after nalgebra's
//! `linalg/lu.rs`, without allocation). The factors overwrite the matrix they come from:
//! [`Lu::in_place`] on a `&mut` array (no copy), [`Lu::new`] on a copy of it.

use core::borrow::{Borrow, BorrowMut};

use crate::real::Real;

/// The factors of PA = LU (L unit lower, U upper, packed in one array `M`: the array itself, or
/// a `&mut` to the one factored in place) and the row order.
#[derive(Clone, Copy, Debug)]
pub struct Lu<R, const N: usize, M = [[R; N]; N]> {
    lu: M,
    perm: [usize; N],
    dim: usize,
    /// +1 or -1: the permutation's sign.
    sign: R,
}

impl<R: Real, const N: usize> Lu<R, N> {
    /// Factor the leading `dim` block of a copy of `a`. `None` if a pivot vanishes against the
    /// largest entry of its column (singular to the scalar's resolution) or is not finite.
    #[inline]
    pub fn new(a: &[[R; N]; N], dim: usize) -> Option<Self> {
        Lu::in_place(*a, dim)
    }
}

impl<R: Real, const N: usize, M: BorrowMut<[[R; N]; N]>> Lu<R, N, M> {
    /// Factor the leading `dim` block of `a` where it is (its entries become the factors; the
    /// rest untouched). `None` as [`Lu::new`].
    #[inline]
    pub fn in_place(mut a: M, dim: usize) -> Option<Self> {
        let dim = dim.min(N);
        let lu = a.borrow_mut();
        let mut perm = [0usize; N];
        for (i, p) in perm.iter_mut().enumerate() {
            *p = i;
        }
        let mut sign = R::one();
        let scale = lu[..dim].iter().flat_map(|r| r[..dim].iter()).fold(R::zero(), |m, x| m.max(x.abs()));
        let tiny = scale * R::from_f64(R::EPS * R::EPS);
        for col in 0..dim {
            let mut piv = col;
            for row in col + 1..dim {
                if lu[row][col].abs() > lu[piv][col].abs() {
                    piv = row;
                }
            }
            let pv = lu[piv][col];
            if !(pv.abs() > tiny) || !pv.is_finite() {
                return None;
            }
            if piv != col {
                lu.swap(col, piv);
                perm.swap(col, piv);
                sign = -sign;
            }
            for row in col + 1..dim {
                let f = lu[row][col] / lu[col][col];
                lu[row][col] = f;
                for k in col + 1..dim {
                    let v = lu[col][k];
                    lu[row][k] -= f * v;
                }
            }
        }
        Some(Lu { lu: a, perm, dim, sign })
    }
}

impl<R: Real, const N: usize, M: Borrow<[[R; N]; N]>> Lu<R, N, M> {
    /// x with A x = b (first `dim` entries).
    #[inline]
    pub fn solve(&self, b: &[R; N]) -> [R; N] {
        let (d, lu) = (self.dim, self.lu.borrow());
        let mut x = [R::zero(); N];
        for i in 0..d {
            let mut s = b[self.perm[i]];
            for k in 0..i {
                s -= lu[i][k] * x[k];
            }
            x[i] = s;
        }
        for i in (0..d).rev() {
            let mut s = x[i];
            for k in i + 1..d {
                s -= lu[i][k] * x[k];
            }
            x[i] = s / lu[i][i];
        }
        x
    }

    /// det A.
    pub fn determinant(&self) -> R {
        (0..self.dim).fold(self.sign, |p, i| p * self.lu.borrow()[i][i])
    }

    /// A⁻¹ (leading block; the rest zero).
    pub fn inverse(&self) -> [[R; N]; N] {
        let mut inv = [[R::zero(); N]; N];
        for col in 0..self.dim {
            let mut e = [R::zero(); N];
            e[col] = R::one();
            let x = self.solve(&e);
            for row in 0..self.dim {
                inv[row][col] = x[row];
            }
        }
        inv
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn solves_determinant_and_inverse_of_a_pivoting_system() {
        let a = [[0.0, 2.0, 1.0, 9.0], [1.0, 1.0, 0.0, 9.0], [3.0, 0.0, 4.0, 9.0], [9.0; 4]];
        let lu = Lu::new(&a, 3).unwrap();
        let x = lu.solve(&[5.0, 3.0, 10.0, 0.0]);
        for (i, row) in a[..3].iter().enumerate() {
            let ax: f64 = (0..3).map(|k| row[k] * x[k]).sum();
            assert!((ax - [5.0, 3.0, 10.0][i]).abs() < 1e-12);
        }
        // det by cofactors: 0*(4-0) - 2*(4-0) + 1*(0-3) = -11
        assert!((lu.determinant() + 11.0).abs() < 1e-12);
        let inv = lu.inverse();
        for i in 0..3 {
            for j in 0..3 {
                let p: f64 = (0..3).map(|k| a[i][k] * inv[k][j]).sum();
                assert!((p - if i == j { 1.0 } else { 0.0 }).abs() < 1e-12);
            }
        }
        assert!(Lu::new(&[[1.0f64, 2.0], [2.0, 4.0]], 2).is_none());
        // in place: the same factors, written over the matrix (its block; the rest untouched)
        let mut b = a;
        let lu2 = Lu::in_place(&mut b, 3).unwrap();
        assert_eq!(lu2.solve(&[5.0, 3.0, 10.0, 0.0]), x);
        assert_eq!(lu2.determinant(), lu.determinant());
        assert_eq!(b[3], a[3]);
        assert_ne!(b[..3], a[..3]);
    }
}
