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

/// Rows of the regression processed per QR update.
const CHUNK: usize = 16384;

/// Solves min Σ‖y − ŷ(B, D, x0)‖² over B, D (optional) and the initial states (optional)
/// for fixed A and C (as SLICOT IB01CD). The regressor columns are simulated responses (unit B
/// entries by the row-vector recursion z(k+1) = z(k)A + u_q(k)C_o, unit D entries, unit initial
/// states); rows [φ(k) | y(k)] are built contiguously in chunks of CHUNK and compressed into the R
/// factor of a Householder QR (in place), so the regression matrix is never allocated whole: time
/// O(N·(l·m·n² + l·p²)) with p = n·m + l·m + n·(experiments), memory O(CHUNK·p).
/// The triangular system is solved by the backend's least squares (SVD when rank deficient).
/// With several outputs, each output's residual is weighted by 1/‖y_o − ȳ_o‖ (so every output's
/// fit % counts alike).
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
    for (e, d) in data.iter().enumerate() {
        if d.u.ncols() != m || d.y.ncols() != l || d.u.nrows() != d.y.nrows() {
            return Err(Error::Dimension(format!(
                "experiment {e} has different channel counts or lengths"
            )));
        }
    }
    // each output's rows are weighted by 1/‖y_o − ȳ_o‖, so that the fit of every output counts
    // alike in MIMO (the criterion then matches the per-output fit %); no effect for one output
    let mut wy = vec![T::one(); l];
    if l > 1 {
        for o in 0..l {
            let cnt: usize = data.iter().map(|d| d.len()).sum();
            let mean = data
                .iter()
                .flat_map(|d| (0..d.len()).map(move |k| d.y[(k, o)]))
                .fold(T::zero(), |s, v| s + v)
                / T::from_usize(cnt);
            let ss = data
                .iter()
                .flat_map(|d| (0..d.len()).map(move |k| d.y[(k, o)]))
                .fold(T::zero(), |s, v| s + (v - mean) * (v - mean));
            if ss > T::zero() && ss.is_finite() {
                wy[o] = T::one() / ss.sqrt();
            }
        }
    }
    let nc = np + 1; // regressors and the output
    // chunk buffer: the current R (nc rows) on top, then up to CHUNK new rows
    let mut blk = Mat::<T>::zeros(nc + CHUNK, nc);
    let mut filled = 0usize; // rows of blk in use
    // new rows are built contiguously (row-major) and moved into blk when a chunk is full
    let mut rows_buf: Vec<T> = Vec::with_capacity(CHUNK * nc);
    // A and C copied row-major into flat arrays for the inner loops
    let af: Vec<T> = (0..n * n).map(|k| a[(k / n, k % n)]).collect();
    let cf: Vec<T> = (0..l * n).map(|k| c[(k / n, k % n)]).collect();
    // responses to the entries of B: output o's response to B[p, q] is z_{o,q}(k)_p with the row
    // vector recursion z_{o,q}(k+1) = z_{o,q}(k) A + u_q(k) C_o, z(0) = 0 (O(l·m·n²) per sample)
    let mut zq = vec![T::zero(); l * m * n];
    let mut zn = vec![T::zero(); n];
    // free response C A^k (l×n, row-major)
    let mut cak = vec![T::zero(); l * n];
    let mut tmp_c = vec![T::zero(); l * n];
    for (e, d) in data.iter().enumerate() {
        zq.iter_mut().for_each(|v| *v = T::zero());
        cak.copy_from_slice(&cf);
        for k in 0..d.len() {
            if rows_buf.len() + l * nc > CHUNK * nc {
                flush_rows(la, &mut blk, &mut filled, &mut rows_buf, nc)?;
            }
            for o in 0..l {
                let start = rows_buf.len();
                // B entries: column q*n + p
                rows_buf.extend_from_slice(&zq[o * m * n..(o + 1) * m * n]);
                if with_d {
                    // column nb + q*l + o' is D[o', q]: u_q(k) for this output, zero for the others
                    for q in 0..m {
                        for o2 in 0..l {
                            rows_buf.push(if o2 == o { d.u[(k, q)] } else { T::zero() });
                        }
                    }
                }
                if estimate_x0 {
                    for e2 in 0..ne {
                        for j in 0..n {
                            rows_buf.push(if e2 == e { cak[o * n + j] } else { T::zero() });
                        }
                    }
                }
                rows_buf.push(d.y[(k, o)]);
                if l > 1 {
                    for v in rows_buf[start..].iter_mut() {
                        *v *= wy[o];
                    }
                }
            }
            // z_{o,q} ← z_{o,q} A + u_q(k) C_o
            for o in 0..l {
                for q in 0..m {
                    let uq = d.u[(k, q)];
                    let z = &mut zq[(o * m + q) * n..(o * m + q + 1) * n];
                    for (jj, znj) in zn.iter_mut().enumerate() {
                        let mut acc = uq * cf[o * n + jj];
                        for (ii, &zi) in z.iter().enumerate() {
                            acc += zi * af[ii * n + jj];
                        }
                        *znj = acc;
                    }
                    z.copy_from_slice(&zn);
                }
            }
            if estimate_x0 {
                for o in 0..l {
                    for cc in 0..n {
                        let mut acc = T::zero();
                        for j in 0..n {
                            acc += cak[o * n + j] * af[j * n + cc];
                        }
                        tmp_c[o * n + cc] = acc;
                    }
                }
                cak.copy_from_slice(&tmp_c);
            }
        }
    }
    flush_rows(la, &mut blk, &mut filled, &mut rows_buf, nc)?;
    compress_rows(la, &mut blk, &mut filled, nc)?;
    // [R_φ r_y] from the leading np rows: θ = R_φ⁺ r_y
    let rphi = blk.submatrix(0, 0, np, np);
    let ry = blk.submatrix(0, np, np, 1);
    let theta = la.lstsq(rphi, ry)?;
    if (0..np).any(|k| !theta[(k, 0)].is_finite()) {
        return Err(Error::Identification(
            "B, D, x0 least squares gave non-finite values".into(),
        ));
    }
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

/// Moves the buffered rows (row-major, `nc` per row) below the current R in `blk` and compresses.
fn flush_rows<T: Real>(
    la: &dyn LinAlg<T>,
    blk: &mut Mat<T>,
    filled: &mut usize,
    rows_buf: &mut Vec<T>,
    nc: usize,
) -> Result<()> {
    let new_rows = rows_buf.len() / nc;
    if new_rows == 0 {
        return Ok(());
    }
    for c in 0..nc {
        let col = blk
            .col_mut(c)
            .try_as_col_major_mut()
            .expect("owned faer columns are contiguous")
            .as_slice_mut();
        for (r, v) in col[*filled..*filled + new_rows].iter_mut().enumerate() {
            *v = rows_buf[r * nc + c];
        }
    }
    *filled += new_rows;
    rows_buf.clear();
    compress_rows(la, blk, filled, nc)
}

/// Replaces the first `filled` rows of `blk` by their R factor (nc rows, zero below) and resets
/// `filled` to nc.
fn compress_rows<T: Real>(
    la: &dyn LinAlg<T>,
    blk: &mut Mat<T>,
    filled: &mut usize,
    nc: usize,
) -> Result<()> {
    let r = la.qr_r_in_place(blk.as_mut().submatrix_mut(0, 0, *filled, nc))?;
    for i in 0..nc {
        for j in 0..nc {
            blk[(i, j)] = if i < r.nrows() && j >= i {
                r[(i, j)]
            } else {
                T::zero()
            };
        }
    }
    *filled = nc;
    Ok(())
}
