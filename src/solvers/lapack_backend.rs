//! LAPACK backend through nalgebra-lapack (xGEQRF, xGESDD, xGETRF, xPOTRF), linked against
//! Debian's OpenBLAS. Implemented per concrete scalar: nalgebra-lapack's SVD scalar trait is private.

use super::backend::{LinAlg, Svd, check_finite, full_rank, min_norm_solve};
use crate::error::{Error, Result};
use crate::real::Real;
use faer::{Mat, MatRef};
use nalgebra::DMatrix;
use nalgebra_lapack::{Cholesky, LU, QR, QrDecomposition, SVD};

// Debian's libopenblas.so carries both BLAS and LAPACK symbols.
#[link(name = "openblas")]
unsafe extern "C" {}

/// LAPACK backend (OpenBLAS); for `f32` and `f64`.
#[derive(Debug, Clone, Copy, Default)]
pub struct Lapack;

pub(super) fn boxed<T: Real>() -> Result<Box<dyn LinAlg<T>>> {
    // Lapack implements LinAlg<f32> and LinAlg<f64>; pick by type identity.
    let any: Box<dyn std::any::Any> =
        if std::any::TypeId::of::<T>() == std::any::TypeId::of::<f64>() {
            Box::new(Box::new(Lapack) as Box<dyn LinAlg<f64>>)
        } else {
            Box::new(Box::new(Lapack) as Box<dyn LinAlg<f32>>)
        };
    any.downcast::<Box<dyn LinAlg<T>>>()
        .map(|b| *b)
        .map_err(|_| Error::InvalidParameter("LAPACK backend: unsupported scalar".into()))
}

macro_rules! lapack_impl {
    ($t:ty) => {
        impl LinAlg<$t> for Lapack {
            fn name(&self) -> &'static str {
                "lapack"
            }

            fn qr_r(&self, a: MatRef<'_, $t>) -> Result<Mat<$t>> {
                check_finite(a, "QR")?;
                let (m, n) = (a.nrows(), a.ncols());
                if m == 0 || n == 0 {
                    return Ok(Mat::zeros(m.min(n), n));
                }
                // xGEQRF needs rows >= cols: pad with zero rows (does not change R's leading rows)
                let rows = m.max(n);
                let dm =
                    DMatrix::<$t>::from_fn(rows, n, |i, j| if i < m { a[(i, j)] } else { 0.0 });
                let qr = QR::new(dm).map_err(|e| Error::LinAlg(format!("xGEQRF: {e:?}")))?;
                let r = qr.r();
                Ok(Mat::from_fn(m.min(n), n, |i, j| r[(i, j)]))
            }

            fn svd(&self, a: MatRef<'_, $t>) -> Result<Svd<$t>> {
                check_finite(a, "SVD")?;
                let (m, n) = (a.nrows(), a.ncols());
                let k = m.min(n);
                if k == 0 {
                    return Ok(Svd {
                        u: Mat::zeros(m, 0),
                        s: vec![],
                        v: Mat::zeros(n, 0),
                    });
                }
                if m > n {
                    // tall: QR first (xGESDD of nalgebra-lapack forms the full m×m U), then SVD of R
                    let dm = DMatrix::<$t>::from_fn(m, n, |i, j| a[(i, j)]);
                    let qr = QR::new(dm).map_err(|e| Error::LinAlg(format!("xGEQRF: {e:?}")))?;
                    let q = qr.q();
                    let r = qr.r();
                    let svd = SVD::new(r)
                        .ok_or_else(|| Error::LinAlg("xGESDD did not converge".into()))?;
                    let u = &q * &svd.u;
                    return Ok(Svd {
                        u: Mat::from_fn(m, k, |i, j| u[(i, j)]),
                        s: svd.singular_values.iter().copied().collect(),
                        v: Mat::from_fn(n, k, |i, j| svd.vt[(j, i)]),
                    });
                }
                let dm = DMatrix::<$t>::from_fn(m, n, |i, j| a[(i, j)]);
                let svd =
                    SVD::new(dm).ok_or_else(|| Error::LinAlg("xGESDD did not converge".into()))?;
                Ok(Svd {
                    u: Mat::from_fn(m, k, |i, j| svd.u[(i, j)]),
                    s: svd.singular_values.iter().copied().collect(),
                    v: Mat::from_fn(n, k, |i, j| svd.vt[(j, i)]),
                })
            }

            fn singular_values(&self, a: MatRef<'_, $t>) -> Result<Vec<$t>> {
                let (m, n) = (a.nrows(), a.ncols());
                if m > n {
                    let r = self.qr_r(a)?;
                    return Ok(<Self as LinAlg<$t>>::svd(self, r.as_ref())?.s);
                }
                Ok(<Self as LinAlg<$t>>::svd(self, a)?.s)
            }

            fn lstsq(&self, a: MatRef<'_, $t>, b: MatRef<'_, $t>) -> Result<Mat<$t>> {
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
                    let dm = DMatrix::<$t>::from_fn(a.nrows(), n, |i, j| a[(i, j)]);
                    let qr = QR::new(dm).map_err(|e| Error::LinAlg(format!("xGEQRF: {e:?}")))?;
                    let r = qr.r();
                    if full_rank((0..n).map(|i| r[(i, i)]), a.nrows().max(n)) {
                        let db = DMatrix::<$t>::from_fn(b.nrows(), b.ncols(), |i, j| b[(i, j)]);
                        let x = qr
                            .solve(db)
                            .map_err(|e| Error::LinAlg(format!("xORMQR/xTRTRS: {e:?}")))?;
                        return Ok(Mat::from_fn(n, b.ncols(), |i, j| x[(i, j)]));
                    }
                }
                // minimum-norm solution by SVD with a relative cut-off
                Ok(min_norm_solve(
                    &<Self as LinAlg<$t>>::svd(self, a)?,
                    b,
                    a.nrows().max(n),
                ))
            }

            fn solve(&self, a: MatRef<'_, $t>, b: MatRef<'_, $t>) -> Result<Mat<$t>> {
                if a.nrows() != a.ncols() || a.nrows() != b.nrows() {
                    return Err(Error::Dimension(
                        "solve: A must be square with as many rows as B".into(),
                    ));
                }
                check_finite(a, "solve")?;
                let lu = LU::new(DMatrix::<$t>::from_fn(a.nrows(), a.ncols(), |i, j| {
                    a[(i, j)]
                }));
                let db = DMatrix::<$t>::from_fn(b.nrows(), b.ncols(), |i, j| b[(i, j)]);
                let x = lu
                    .solve(&db)
                    .ok_or_else(|| Error::LinAlg("solve: matrix is singular".into()))?;
                Ok(Mat::from_fn(x.nrows(), x.ncols(), |i, j| x[(i, j)]))
            }

            fn cholesky_upper(&self, a: MatRef<'_, $t>) -> Result<Option<Mat<$t>>> {
                if a.nrows() != a.ncols() {
                    return Err(Error::Dimension("Cholesky of a non-square matrix".into()));
                }
                check_finite(a, "Cholesky")?;
                let dm = DMatrix::<$t>::from_fn(a.nrows(), a.ncols(), |i, j| a[(i, j)]);
                Ok(Cholesky::new(dm).map(|c| {
                    let l = c.l();
                    Mat::from_fn(l.ncols(), l.nrows(), |i, j| l[(j, i)])
                }))
            }
        }
    };
}

lapack_impl!(f32);
lapack_impl!(f64);
