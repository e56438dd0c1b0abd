//! The backend trait: the coarse factorisations the subspace methods and the loop need.

use super::columns::all_finite;
use crate::error::Result;
use crate::real::Real;
use faer::prelude::Reborrow;
use faer::{Mat, MatMut, MatRef};

/// A thin singular value decomposition A = U·diag(s)·Vᵀ, singular values non-increasing.
#[derive(Debug, Clone)]
pub struct Svd<T: Real> {
    /// Left singular vectors, m×k.
    pub u: Mat<T>,
    /// Singular values, k = min(m, n), non-increasing.
    pub s: Vec<T>,
    /// Right singular vectors, n×k (V, not Vᵀ).
    pub v: Mat<T>,
}

/// Dense linear algebra on faer matrices; implemented by [`crate::solvers::Faer`] and
/// (feature `lapack`) `solvers::Lapack`. Generic code never names a backend.
///
/// Implementations validate shapes and return errors instead of panicking.
pub trait LinAlg<T: Real>: Send + Sync + std::fmt::Debug {
    /// Backend name ("faer", "lapack").
    fn name(&self) -> &'static str;
    /// Upper-triangular factor R (min(m,n)×n) of the Householder QR of `a` (m×n); Q is never formed.
    fn qr_r(&self, a: MatRef<'_, T>) -> Result<Mat<T>>;
    /// The same R as [`qr_r`](Self::qr_r), allowed to overwrite `a` (saves copying it).
    fn qr_r_in_place(&self, a: MatMut<'_, T>) -> Result<Mat<T>> {
        self.qr_r(a.rb())
    }
    /// Thin SVD of `a`.
    fn svd(&self, a: MatRef<'_, T>) -> Result<Svd<T>>;
    /// Singular values of `a`, non-increasing.
    fn singular_values(&self, a: MatRef<'_, T>) -> Result<Vec<T>>;
    /// Least-squares solution X of min ‖A X − B‖ (QR; minimum-norm SVD solution when A is rank deficient).
    fn lstsq(&self, a: MatRef<'_, T>, b: MatRef<'_, T>) -> Result<Mat<T>>;
    /// The same least-squares solution, allowed to overwrite `a` and `b` (saves copying A).
    fn lstsq_in_place(&self, a: MatMut<'_, T>, b: MatMut<'_, T>) -> Result<Mat<T>> {
        self.lstsq(a.rb(), b.rb())
    }
    /// Solution X of A X = B for square A (LU with partial pivoting).
    fn solve(&self, a: MatRef<'_, T>, b: MatRef<'_, T>) -> Result<Mat<T>>;
    /// Upper Cholesky factor R (RᵀR = A) of a symmetric matrix, `None` when A is not positive definite.
    fn cholesky_upper(&self, a: MatRef<'_, T>) -> Result<Option<Mat<T>>>;
    /// Cholesky factor L (L·Lᵀ = A) of the symmetric matrix whose lower triangle (diagonal
    /// included) `a` holds, written over that lower triangle; the strictly upper triangle is not
    /// read, and may be overwritten. `false` when A is not positive definite (`a` then holds a
    /// partial factor). The same factor as [`cholesky_upper`]
    /// (Self::cholesky_upper), transposed, without a second n×n matrix where the backend allows.
    fn cholesky_lower_in_place(&self, mut a: MatMut<'_, T>) -> Result<bool> {
        let n = a.nrows();
        if a.ncols() != n {
            return Err(crate::error::Error::Dimension(
                "Cholesky of a non-square matrix".into(),
            ));
        }
        let sym = Mat::from_fn(n, n, |i, j| if i >= j { a[(i, j)] } else { a[(j, i)] });
        let Some(r) = self.cholesky_upper(sym.as_ref())? else {
            return Ok(false);
        };
        for j in 0..n {
            for i in j..n {
                a[(i, j)] = r[(j, i)];
            }
        }
        Ok(true)
    }
}

/// A typed error when `a` has a non-finite entry.
pub(crate) fn check_finite<T: Real>(a: MatRef<'_, T>, what: &str) -> Result<()> {
    for j in 0..a.ncols() {
        // contiguous columns (the common case) are screened as slices first
        if let Some(c) = a.col(j).try_as_col_major()
            && all_finite(c.as_slice())
        {
            continue;
        }
        if let Some(i) = (0..a.nrows()).position(|i| !a[(i, j)].is_finite()) {
            return Err(crate::error::Error::LinAlg(format!(
                "{what}: non-finite entry at ({i}, {j})"
            )));
        }
    }
    Ok(())
}

/// Whether the diagonal of a triangular factor (of an `rows`-row problem) is numerically full rank.
pub(crate) fn full_rank<T: Real>(diag: impl Iterator<Item = T> + Clone, rows: usize) -> bool {
    let dmax = diag.clone().map(|d| d.abs()).fold(T::zero(), T::max);
    let dmin = diag.map(|d| d.abs()).fold(T::infinity(), T::min);
    dmax > T::zero() && dmin > dmax * T::epsilon() * T::from_usize(rows) * T::lit(10.0)
}

/// Minimum-norm least-squares solution from the SVD of A, singular values below
/// σ₁·ε·`rows` dropped.
pub(crate) fn min_norm_solve<T: Real>(svd: &Svd<T>, b: MatRef<'_, T>, rows: usize) -> Mat<T> {
    let smax = svd.s.first().copied().unwrap_or(T::zero());
    let tol = smax * T::epsilon() * T::from_usize(rows);
    let utb = svd.u.transpose() * b;
    let mut z = Mat::<T>::zeros(svd.s.len(), b.ncols());
    for i in 0..svd.s.len() {
        if svd.s[i] > tol {
            for j in 0..b.ncols() {
                z[(i, j)] = utb[(i, j)] / svd.s[i];
            }
        }
    }
    &svd.v * &z
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn check_finite_finds_every_kind_of_non_finite_entry() {
        let a = Mat::<f64>::from_fn(37, 3, |i, j| (i * 3 + j) as f64 * 1e300);
        assert!(check_finite(a.as_ref(), "t").is_ok());
        for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
            // in the vectorised body and in the remainder of a column
            for (i, j) in [(0, 0), (17, 1), (36, 2)] {
                let mut b = a.clone();
                b[(i, j)] = bad;
                let msg = check_finite(b.as_ref(), "t").unwrap_err().to_string();
                assert!(msg.contains(&format!("({i}, {j})")), "{msg}");
            }
        }
        // a strided (non-contiguous) view
        let mut b = a.clone();
        b[(5, 1)] = f64::NAN;
        assert!(check_finite(b.as_ref().transpose(), "t").is_err());
    }
}
