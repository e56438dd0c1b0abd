//! The default backend: faer, sequential (faster than rayon on small dense problems and safe inside
//! rayon-parallel Monte Carlo loops).

use super::backend::{LinAlg, Svd, check_finite, full_rank, min_norm_solve};
use crate::error::{Error, Result};
use crate::real::Real;
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::llt::factor::{cholesky_in_place, cholesky_in_place_scratch};
use faer::linalg::qr::no_pivoting::factor::{
    qr_in_place, qr_in_place_scratch, recommended_block_size,
};
use faer::linalg::qr::no_pivoting::solve::solve_lstsq_in_place_scratch;
use faer::linalg::solvers::{SolveCore, SolveLstsq};
use faer::prelude::{Reborrow, ReborrowMut};
use faer::{Conj, Mat, MatMut, MatRef, Par};

/// faer backend with an explicit parallelism setting (default: sequential).
#[derive(Debug, Clone, Copy)]
pub struct Faer {
    /// faer parallelism for the factorisations.
    pub par: Par,
}

impl Default for Faer {
    fn default() -> Self {
        Self { par: Par::Seq }
    }
}

/// Matrices up to this many columns are factored by the unblocked Householder QR
/// (`householder::qr_unblocked_in_place`), wider ones by faer's blocked `qr_in_place`.
const UNBLOCKED_COLS: usize = 32;

impl Faer {
    /// Householder QR of `a` in place (R in the upper triangle, the reflectors below it, as
    /// faer's `qr_in_place` stores them); returns the block coefficients. Up to
    /// `UNBLOCKED_COLS` columns unblocked by this crate's kernel (2000×17: faer's unblocked
    /// 130 µs, its default block of 32 190 µs), wider ones by faer's blocked QR.
    fn householder_in_place<T: Real>(&self, a: MatMut<'_, T>) -> Mat<T> {
        let (m, n) = (a.nrows(), a.ncols());
        if n <= UNBLOCKED_COLS {
            let mut tau = Mat::<T>::zeros(1, m.min(n));
            super::householder::qr_unblocked_in_place(a, tau.as_mut().row_mut(0));
            return tau;
        }
        let bs = recommended_block_size::<T>(m, n);
        let mut q_coeff = Mat::<T>::zeros(bs, m.min(n));
        let mut mem = MemBuffer::new(qr_in_place_scratch::<T>(
            m,
            n,
            bs,
            self.par,
            Default::default(),
        ));
        qr_in_place(
            a,
            q_coeff.as_mut(),
            self.par,
            MemStack::new(&mut mem),
            Default::default(),
        );
        q_coeff
    }

    fn with_par<R>(&self, f: impl FnOnce() -> R) -> R {
        // faer's high-level API reads the global parallelism. It is set (not restored) so that
        // concurrent callers that all use the same setting never race each other.
        if faer::get_global_parallelism() != self.par {
            faer::set_global_parallelism(self.par);
        }
        f()
    }
}

impl<T: Real> LinAlg<T> for Faer {
    fn name(&self) -> &'static str {
        "faer"
    }

    fn qr_r(&self, a: MatRef<'_, T>) -> Result<Mat<T>> {
        check_finite(a, "QR")?;
        if a.nrows() == 0 || a.ncols() == 0 {
            return Ok(Mat::zeros(a.nrows().min(a.ncols()), a.ncols()));
        }
        Ok(self.with_par(|| a.qr().thin_R().to_owned()))
    }

    /// faer's Householder QR in place (`qr_in_place`), R read off the upper triangle.
    fn qr_r_in_place(&self, mut a: MatMut<'_, T>) -> Result<Mat<T>> {
        check_finite(a.rb(), "QR")?;
        let (m, n) = (a.nrows(), a.ncols());
        if m == 0 || n == 0 {
            return Ok(Mat::zeros(m.min(n), n));
        }
        let size = m.min(n);
        self.householder_in_place(a.rb_mut());
        Ok(Mat::from_fn(size, n, |i, j| {
            if j >= i { a[(i, j)] } else { T::zero() }
        }))
    }

    fn svd(&self, a: MatRef<'_, T>) -> Result<Svd<T>> {
        check_finite(a, "SVD")?;
        let k = a.nrows().min(a.ncols());
        if k == 0 {
            return Ok(Svd {
                u: Mat::zeros(a.nrows(), 0),
                s: vec![],
                v: Mat::zeros(a.ncols(), 0),
            });
        }
        let svd = self
            .with_par(|| a.thin_svd())
            .map_err(|e| Error::LinAlg(format!("SVD did not converge: {e:?}")))?;
        let s = (0..k).map(|i| svd.S()[i]).collect();
        Ok(Svd {
            u: svd.U().to_owned(),
            s,
            v: svd.V().to_owned(),
        })
    }

    fn singular_values(&self, a: MatRef<'_, T>) -> Result<Vec<T>> {
        check_finite(a, "SVD")?;
        if a.nrows().min(a.ncols()) == 0 {
            return Ok(vec![]);
        }
        self.with_par(|| a.singular_values())
            .map_err(|e| Error::LinAlg(format!("SVD did not converge: {e:?}")))
    }

    fn lstsq(&self, a: MatRef<'_, T>, b: MatRef<'_, T>) -> Result<Mat<T>> {
        if a.nrows() != b.nrows() {
            return Err(Error::Dimension(format!(
                "least squares: A has {} rows, B has {}",
                a.nrows(),
                b.nrows()
            )));
        }
        check_finite(a, "least squares")?;
        check_finite(b, "least squares")?;
        let n = a.ncols();
        if n == 0 {
            return Ok(Mat::zeros(0, b.ncols()));
        }
        if a.nrows() >= n && n <= UNBLOCKED_COLS {
            // narrow: the unblocked Householder QR on copies (faer's blocked `qr` costs more
            // than the factorisation itself on such shapes)
            return self.lstsq_in_place(a.to_owned().as_mut(), b.to_owned().as_mut());
        }
        if a.nrows() >= n {
            let qr = self.with_par(|| a.qr());
            let r = qr.thin_R();
            if full_rank((0..n).map(|i| r[(i, i)]), a.nrows().max(n)) {
                return Ok(self.with_par(|| qr.solve_lstsq(b)));
            }
        }
        // rank deficient or underdetermined: minimum-norm solution by SVD with a relative cut-off
        Ok(min_norm_solve(&self.svd(a)?, b, a.nrows().max(n)))
    }

    /// Householder QR of `a` in place (faer's blocked `qr_in_place`, no copy of A), Qᵀb, then the
    /// triangular solve; when R is numerically rank deficient, the minimum-norm solution of
    /// R x = (Qᵀb)₁..ₙ by SVD of the n×n factor R (the same solution as the SVD of A, since Q is
    /// orthogonal).
    fn lstsq_in_place(&self, mut a: MatMut<'_, T>, mut b: MatMut<'_, T>) -> Result<Mat<T>> {
        let (m, n) = (a.nrows(), a.ncols());
        if m != b.nrows() {
            return Err(Error::Dimension(format!(
                "least squares: A has {m} rows, B has {}",
                b.nrows()
            )));
        }
        if n == 0 || m < n {
            return self.lstsq(a.rb(), b.rb());
        }
        check_finite(a.rb(), "least squares")?;
        check_finite(b.rb(), "least squares")?;
        let par = self.par;
        let q_coeff = self.householder_in_place(a.rb_mut());
        let mut mem = MemBuffer::new(solve_lstsq_in_place_scratch::<T>(
            m,
            n,
            q_coeff.nrows(),
            b.ncols(),
            par,
        ));
        faer::linalg::householder::apply_block_householder_sequence_transpose_on_the_left_in_place_with_conj(
            a.rb(),
            q_coeff.as_ref(),
            Conj::Yes,
            b.rb_mut(),
            par,
            MemStack::new(&mut mem),
        );
        let r = Mat::from_fn(n, n, |i, j| if j >= i { a[(i, j)] } else { T::zero() });
        let qtb = b.rb().subrows(0, n).to_owned();
        if full_rank((0..n).map(|i| r[(i, i)]), m) {
            let mut x = qtb;
            faer::linalg::triangular_solve::solve_upper_triangular_in_place(
                r.as_ref(),
                x.as_mut(),
                par,
            );
            return Ok(x);
        }
        // rank deficient: minimum-norm solution with the cut-off of `lstsq` (relative to σ₁)
        Ok(min_norm_solve(&self.svd(r.as_ref())?, qtb.as_ref(), m))
    }

    fn solve(&self, a: MatRef<'_, T>, b: MatRef<'_, T>) -> Result<Mat<T>> {
        if a.nrows() != a.ncols() || a.nrows() != b.nrows() {
            return Err(Error::Dimension(format!(
                "solve: A is {}×{}, B has {} rows",
                a.nrows(),
                a.ncols(),
                b.nrows()
            )));
        }
        check_finite(a, "solve")?;
        let lu = self.with_par(|| a.partial_piv_lu());
        let mut x = b.to_owned();
        lu.solve_in_place_with_conj(faer::Conj::No, x.as_mut());
        if (0..x.nrows()).any(|i| (0..x.ncols()).any(|j| !x[(i, j)].is_finite())) {
            return Err(Error::LinAlg("solve: matrix is singular".into()));
        }
        Ok(x)
    }

    fn cholesky_upper(&self, a: MatRef<'_, T>) -> Result<Option<Mat<T>>> {
        if a.nrows() != a.ncols() {
            return Err(Error::Dimension("Cholesky of a non-square matrix".into()));
        }
        check_finite(a, "Cholesky")?;
        // faer's `Llt::new` (the lower triangle copied, factored in place by
        // `cholesky_in_place`, the same parameters) with R = Lᵀ formed by transposing that one
        // copy in place: one n×n matrix beside `a`, not two
        let n = a.nrows();
        let mut r = Mat::<T>::zeros(n, n);
        r.copy_from_triangular_lower(a);
        if !self.cholesky_lower_in_place(r.as_mut())? {
            return Ok(None);
        }
        for j in 0..n {
            for i in j + 1..n {
                r[(j, i)] = r[(i, j)];
                r[(i, j)] = T::zero();
            }
        }
        Ok(Some(r))
    }

    fn cholesky_lower_in_place(&self, mut a: MatMut<'_, T>) -> Result<bool> {
        let n = a.nrows();
        if a.ncols() != n {
            return Err(Error::Dimension("Cholesky of a non-square matrix".into()));
        }
        // the lower triangle only: the strictly upper one may hold anything
        for j in 0..n {
            if let Some(i) = (j..n).find(|&i| !a[(i, j)].is_finite()) {
                return Err(Error::LinAlg(format!(
                    "Cholesky: non-finite entry at ({i}, {j})"
                )));
            }
        }
        // faer's left-looking block Cholesky (`cholesky_in_place`, as `Llt::new` calls it) reads
        // the lower triangle only; it may use the strictly upper one as workspace
        let mut mem = MemBuffer::new(cholesky_in_place_scratch::<T>(
            n,
            self.par,
            Default::default(),
        ));
        Ok(cholesky_in_place(
            a.as_mut(),
            Default::default(),
            self.par,
            MemStack::new(&mut mem),
            Default::default(),
        )
        .is_ok())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: &Mat<f64>, b: &Mat<f64>, tol: f64) {
        assert_eq!(a.shape(), b.shape());
        for j in 0..a.ncols() {
            for i in 0..a.nrows() {
                assert!(
                    (a[(i, j)] - b[(i, j)]).abs() <= tol,
                    "({i}, {j}): {} vs {}",
                    a[(i, j)],
                    b[(i, j)]
                );
            }
        }
    }

    /// A triangular factor with a zero pivot (the B/D/x0 step's R of an over-parametrised
    /// block): the QR skips the column, and the least squares give the finite minimum-norm
    /// solution (the crate's unblocked QR once left the unreached rows' τ at 0, where faer sets
    /// ∞: `subspace --order 12` on 600 samples of a second-order system then failed with "B, D,
    /// x0 least squares gave non-finite values"; the rank-deficient case of the next test
    /// caught it too).
    #[test]
    fn a_triangular_factor_with_a_zero_pivot_gives_the_minimum_norm_solution() {
        let la = Faer::default();
        let n = 7;
        let r = Mat::from_fn(n, n, |i, j| {
            if j < i || (i == 3 && j == 3) {
                0.0
            } else {
                1.0 + ((i * 5 + j * 3) % 7) as f64
            }
        });
        let b = Mat::from_fn(n, 1, |i, _| 1.0 + i as f64);
        let x = LinAlg::<f64>::lstsq(&la, r.as_ref(), b.as_ref()).unwrap();
        let x_ref = min_norm_solve(&LinAlg::<f64>::svd(&la, r.as_ref()).unwrap(), b.as_ref(), n);
        close(&x, &x_ref, 1e-10);
    }

    /// The in-place Cholesky reads the lower triangle only (sentinel values in the strictly
    /// upper one change nothing), equals the copying factor transposed, and says `false` for an
    /// indefinite matrix; the trait's default (the LAPACK backend's) gives the same factor.
    #[test]
    fn the_in_place_cholesky_touches_only_the_lower_triangle() {
        #[derive(Debug)]
        struct Default_(Faer);
        impl LinAlg<f64> for Default_ {
            fn name(&self) -> &'static str {
                "default"
            }
            fn qr_r(&self, a: MatRef<'_, f64>) -> Result<Mat<f64>> {
                self.0.qr_r(a)
            }
            fn svd(&self, a: MatRef<'_, f64>) -> Result<Svd<f64>> {
                self.0.svd(a)
            }
            fn singular_values(&self, a: MatRef<'_, f64>) -> Result<Vec<f64>> {
                self.0.singular_values(a)
            }
            fn lstsq(&self, a: MatRef<'_, f64>, b: MatRef<'_, f64>) -> Result<Mat<f64>> {
                self.0.lstsq(a, b)
            }
            fn solve(&self, a: MatRef<'_, f64>, b: MatRef<'_, f64>) -> Result<Mat<f64>> {
                self.0.solve(a, b)
            }
            fn cholesky_upper(&self, a: MatRef<'_, f64>) -> Result<Option<Mat<f64>>> {
                self.0.cholesky_upper(a)
            }
        }
        let la = Faer::default();
        let n = 150; // above faer's recursion threshold: the blocked path
        let h = Mat::from_fn(400, n, |i, j| {
            ((i * j) as f64 * 0.37 + i as f64 * 1.3).sin()
        });
        let g = h.transpose() * &h + Mat::<f64>::identity(n, n);
        let r = LinAlg::<f64>::cholesky_upper(&la, g.as_ref())
            .unwrap()
            .expect("positive definite");
        for backend in [&la as &dyn LinAlg<f64>, &Default_(Faer::default())] {
            let mut a = g.clone();
            for j in 1..n {
                for i in 0..j {
                    a[(i, j)] = -7.5;
                }
            }
            assert!(backend.cholesky_lower_in_place(a.as_mut()).unwrap());
            for j in 0..n {
                for i in j..n {
                    assert!((a[(i, j)] - r[(j, i)]).abs() <= 1e-9 * r[(j, j)].abs());
                }
            }
            // indefinite: a negative diagonal entry
            let mut bad = g.clone();
            bad[(n / 2, n / 2)] = -1.0;
            assert!(!backend.cholesky_lower_in_place(bad.as_mut()).unwrap());
            // non-finite in the lower triangle: a typed error naming the entry
            let mut nan = g.clone();
            nan[(5, 2)] = f64::NAN;
            let err = backend
                .cholesky_lower_in_place(nan.as_mut())
                .unwrap_err()
                .to_string();
            assert!(err.contains("non-finite"), "{err}");
        }
    }

    #[test]
    fn in_place_qr_and_least_squares_match_the_copying_ones() {
        let la = Faer::default();
        // full rank, 300×6, two right-hand sides
        let a = Mat::from_fn(300, 6, |i, j| {
            ((i * 7 + j * 13) % 17) as f64 - 8.0 + 0.1 * j as f64
        });
        let b = Mat::from_fn(300, 2, |i, j| ((i * 5 + j) % 11) as f64 - 5.0);
        let x_ref = LinAlg::<f64>::lstsq(&la, a.as_ref(), b.as_ref()).unwrap();
        let (mut a2, mut b2) = (a.clone(), b.clone());
        let x = la.lstsq_in_place(a2.as_mut(), b2.as_mut()).unwrap();
        close(&x, &x_ref, 1e-10);
        // rank deficient: column 5 = column 0 + column 1 → the minimum-norm solution
        let ad = Mat::from_fn(300, 6, |i, j| {
            if j == 5 {
                a[(i, 0)] + a[(i, 1)]
            } else {
                a[(i, j)]
            }
        });
        let x_ref = LinAlg::<f64>::lstsq(&la, ad.as_ref(), b.as_ref()).unwrap();
        let (mut a3, mut b3) = (ad.clone(), b.clone());
        let x = la.lstsq_in_place(a3.as_mut(), b3.as_mut()).unwrap();
        close(&x, &x_ref, 1e-9);
        // and it is a least-squares solution: the residual is orthogonal to the columns
        let res = &ad * &x - &b;
        let g = ad.transpose() * &res;
        assert!((0..6).all(|i| (0..2).all(|j| g[(i, j)].abs() < 1e-7)));
        // R in place equals R by copy (same algorithm, same signs)
        let r_ref = LinAlg::<f64>::qr_r(&la, a.as_ref()).unwrap();
        let mut a5 = a.clone();
        let r = la.qr_r_in_place(a5.as_mut()).unwrap();
        close(&r, &r_ref, 1e-10);
        // mismatched rows: a typed error
        let (mut a4, mut b4) = (a.clone(), Mat::<f64>::zeros(299, 1));
        assert!(la.lstsq_in_place(a4.as_mut(), b4.as_mut()).is_err());
    }
}
