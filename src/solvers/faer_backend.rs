//! The default backend: faer, sequential (faster than rayon on small dense problems and safe inside
//! rayon-parallel Monte Carlo loops).

use super::backend::{LinAlg, Svd};
use crate::error::{Error, Result};
use crate::real::Real;
use faer::linalg::solvers::{SolveCore, SolveLstsq};
use faer::{Mat, MatRef, Par, Side};

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

fn check_finite<T: Real>(a: MatRef<'_, T>, what: &str) -> Result<()> {
    for j in 0..a.ncols() {
        for i in 0..a.nrows() {
            if !a[(i, j)].is_finite() {
                return Err(Error::LinAlg(format!(
                    "{what}: non-finite entry at ({i}, {j})"
                )));
            }
        }
    }
    Ok(())
}

impl Faer {
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
        if a.nrows() >= n {
            let qr = self.with_par(|| a.qr());
            let r = qr.thin_R();
            let dmax = (0..n).map(|i| r[(i, i)].abs()).fold(T::zero(), T::max);
            let dmin = (0..n).map(|i| r[(i, i)].abs()).fold(T::infinity(), T::min);
            if dmax > T::zero()
                && dmin > dmax * T::epsilon() * T::from_usize(a.nrows().max(n)) * T::lit(10.0)
            {
                return Ok(self.with_par(|| qr.solve_lstsq(b)));
            }
        }
        // rank deficient or underdetermined: minimum-norm solution by SVD with a relative cut-off
        let svd = self.svd(a)?;
        let smax = svd.s.first().copied().unwrap_or(T::zero());
        let tol = smax * T::epsilon() * T::from_usize(a.nrows().max(n));
        let utb = svd.u.transpose() * b;
        let mut z = Mat::<T>::zeros(svd.s.len(), b.ncols());
        for i in 0..svd.s.len() {
            if svd.s[i] > tol {
                for j in 0..b.ncols() {
                    z[(i, j)] = utb[(i, j)] / svd.s[i];
                }
            }
        }
        Ok(&svd.v * &z)
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
        match self.with_par(|| a.llt(Side::Lower)) {
            Ok(llt) => Ok(Some(llt.L().transpose().to_owned())),
            Err(_) => Ok(None),
        }
    }
}
