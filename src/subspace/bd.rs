//! B, D and initial states given A and C, by linear least squares on the simulation error
//! (the output is linear in vec(B), vec(D) and x0 once A and C are fixed), as SLICOT IB01CD.

use crate::data::IoView;
use crate::error::{Error, Result};
use crate::real::Real;
use crate::solvers::LinAlg;
use faer::{Mat, MatRef};

/// Estimated input matrices and initial states.
#[derive(Debug, Clone)]
pub struct BdX0<T: Real> {
    /// Input matrix, n×m.
    pub b: Mat<T>,
    /// Feed-through, l×m (zero when not estimated).
    pub d: Mat<T>,
    /// Initial state per experiment (zeros when not estimated).
    pub x0: Vec<Vec<T>>,
}

/// Solves min Σ‖y − ŷ(B, D, x0)‖² over B, D (optional) and the initial states (optional)
/// for fixed A and C. Regressor columns are simulated responses (unit B entries, unit D entries,
/// unit initial states); the problem is solved by QR (SVD when rank deficient).
pub fn estimate_bd_x0<T: Real>(
    la: &dyn LinAlg<T>,
    a: MatRef<'_, T>,
    c: MatRef<'_, T>,
    data: &[IoView<'_, T>],
    with_d: bool,
    estimate_x0: bool,
) -> Result<BdX0<T>> {
    let n = a.nrows();
    let l = c.nrows();
    if data.is_empty() {
        return Err(Error::InvalidParameter("no experiment given".into()));
    }
    let m = data[0].u.ncols();
    if a.ncols() != n || c.ncols() != n {
        return Err(Error::Dimension("A must be n×n and C l×n".into()));
    }
    let ne = data.len();
    let nb = n * m;
    let nd = if with_d { l * m } else { 0 };
    let nx = if estimate_x0 { n * ne } else { 0 };
    let np = nb + nd + nx;
    let rows: usize = data.iter().map(|d| d.len() * l).sum();
    if rows < np {
        return Err(Error::TooFewSamples {
            needed: np.div_ceil(l),
            got: rows / l,
            reason: "estimating B, D and the initial state".into(),
        });
    }
    let mut phi = Mat::<T>::zeros(rows, np);
    let mut rhs = Mat::<T>::zeros(rows, 1);
    let mut row0 = 0;
    for (e, d) in data.iter().enumerate() {
        if d.u.ncols() != m || d.y.ncols() != l {
            return Err(Error::Dimension(format!(
                "experiment {e} has different channel counts"
            )));
        }
        let nn = d.len();
        // state responses to unit input through B = I: X_q(k+1) = A X_q(k) + I u_q(k)  (n×n each)
        let mut xq: Vec<Mat<T>> = vec![Mat::zeros(n, n); m];
        // free response O(k) = C A^k (l×n)
        let mut cak = c.to_owned();
        for k in 0..nn {
            for o in 0..l {
                let r = row0 + k * l + o;
                rhs[(r, 0)] = d.y[(k, o)];
                // B entries: column (q*n + p): y_o = (C X_q(k))[o, p]
                for q in 0..m {
                    for p in 0..n {
                        let mut s = T::zero();
                        for j in 0..n {
                            s += c[(o, j)] * xq[q][(j, p)];
                        }
                        phi[(r, q * n + p)] = s;
                    }
                }
                if with_d {
                    for q in 0..m {
                        phi[(r, nb + q * l + o)] = d.u[(k, q)];
                    }
                }
                if estimate_x0 {
                    for j in 0..n {
                        phi[(r, nb + nd + e * n + j)] = cak[(o, j)];
                    }
                }
            }
            for q in 0..m {
                let mut next = a * &xq[q];
                for p in 0..n {
                    next[(p, p)] += d.u[(k, q)];
                }
                xq[q] = next;
            }
            if estimate_x0 {
                cak = &cak * a;
            }
        }
        row0 += nn * l;
    }
    let theta = la.lstsq(phi.as_ref(), rhs.as_ref())?;
    let b = Mat::from_fn(n, m, |p, q| theta[(q * n + p, 0)]);
    let dm = if with_d {
        Mat::from_fn(l, m, |o, q| theta[(nb + q * l + o, 0)])
    } else {
        Mat::zeros(l, m)
    };
    let x0 = (0..ne)
        .map(|e| {
            if estimate_x0 {
                (0..n).map(|j| theta[(nb + nd + e * n + j, 0)]).collect()
            } else {
                vec![T::zero(); n]
            }
        })
        .collect();
    Ok(BdX0 { b, d: dm, x0 })
}
