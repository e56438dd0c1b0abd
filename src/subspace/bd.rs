//! B, D and initial states given A and C, by linear least squares on the simulation error
//! (the output is linear in vec(B), vec(D) and x0 once A and C are fixed), as SLICOT IB01CD.
//!
//! The Hammerstein loop's B/D/x0 step (`fit::linear_ls::fit_given_ac`) is this least squares too
//! ([`bd_x0_least_squares`]), with a constant offset column and the fold matrix reused across
//! its search's calls.

use crate::data::IoView;
use crate::error::{Error, Result};
use crate::real::Real;
use crate::solvers::LinAlg;
use crate::solvers::columns::{column, columns_mut, row_major};
use crate::solvers::recursion::row_responses;
use faer::{Mat, MatRef};
use std::borrow::Cow;

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
/// states C_o A^k; `solvers::recursion`, all chains of one output in one pass); they are built
/// column-wise in chunks of CHUNK rows below the current R factor and compressed by a Householder
/// QR in place, so the regression matrix is never allocated whole: time O(N·(l·m·n² + l·p²)) with
/// p = n·m + l·m + n·(experiments), memory O(CHUNK·p). Once the rows C_o A^k of a chunk are all
/// below ε·max|C| (a stable A after its transient), the chunk updates only the trailing block of
/// R without the initial-state columns.
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
    let terms = BdTerms {
        with_d,
        x0: estimate_x0,
        offset: false,
    };
    let (est, _) = bd_x0_least_squares(la, a, c, data, terms, None)?;
    let finite = |m: &Mat<T>| (0..m.nrows()).all(|i| (0..m.ncols()).all(|j| m[(i, j)].is_finite()));
    if !finite(&est.b) || !finite(&est.d) || est.x0.iter().flatten().any(|v| !v.is_finite()) {
        return Err(Error::Identification(
            "B, D, x0 least squares gave non-finite values".into(),
        ));
    }
    Ok(est)
}

/// What [`bd_x0_least_squares`] estimates besides B.
#[derive(Debug, Clone, Copy)]
pub(crate) struct BdTerms {
    /// D.
    pub with_d: bool,
    /// The initial state of each experiment.
    pub x0: bool,
    /// A constant offset per output (the Hammerstein loop's).
    pub offset: bool,
}

/// The least squares of [`estimate_bd_x0`] with an optional constant offset per output (a
/// column of ones acting on that output, after D), for the subspace identification and the
/// Hammerstein loop's B/D/x0 step (`fit::linear_ls::fit_given_ac`). `buffer`: the matrix the
/// chunks are folded in, reused from call to call by a caller that solves many problems on one
/// record (the loop's search; `None`: allocated here). Returns the estimates and the offsets
/// (zeros when not estimated); the solution is not checked for finite values.
pub(crate) fn bd_x0_least_squares<T: Real>(
    la: &dyn LinAlg<T>,
    a: MatRef<'_, T>,
    c: MatRef<'_, T>,
    data: &[IoView<'_, T>],
    terms: BdTerms,
    buffer: Option<&mut Mat<T>>,
) -> Result<(BdX0<T>, Vec<T>)> {
    let BdTerms {
        with_d,
        x0: estimate_x0,
        offset,
    } = terms;
    let n = a.nrows();
    let l = c.nrows();
    if data.is_empty() {
        return Err(Error::NoExperiment);
    }
    let m = data[0].u.ncols();
    if a.ncols() != n || c.ncols() != n {
        return Err(Error::Dimension("A must be n×n and C l×n".into()));
    }
    if n == 0 {
        return Err(Error::Dimension(
            "A is 0×0: the model order must be at least 1".into(),
        ));
    }
    if l == 0 || m == 0 {
        return Err(Error::Dimension(format!(
            "at least one input and one output are needed (got {m} input(s), C has {l} row(s))"
        )));
    }
    let ne = data.len();
    let nb = n * m;
    let nd = if with_d { l * m } else { 0 };
    let nx = if estimate_x0 { n * ne } else { 0 };
    let no = if offset { l } else { 0 };
    let np = nb + nd + nx + no;
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
    // columns: the initial states (n per experiment) first, then B (q·n + p), D (q·l + o), the
    // offsets (one per output), y
    let ib = nx;
    let id = nx + nb;
    let io = id + nd;
    let nc = np + 1;
    // samples per chunk (each gives l rows)
    let longest = data.iter().map(|d| d.len()).max().unwrap_or(0);
    let kmax = (CHUNK / l).clamp(1, longest.max(1));
    // the current R on top (zero before the first chunk), then the chunk's rows
    let mut own = Mat::new();
    let blk = buffer.unwrap_or(&mut own);
    blk.resize_with(nc + kmax * l, nc, |_, _| T::zero());
    // R starts at zero; every chunk row is written before the QR reads it
    blk.as_mut().submatrix_mut(0, 0, nc, nc).fill(T::zero());
    let af = row_major(a);
    let cm = row_major(c);
    let c_rows: Vec<&[T]> = cm.chunks(n.max(1)).collect();
    // x0 entries below ε·max|C| are round-off of the first rows' size: a chunk whose C A^k rows
    // are all below it updates only the trailing block of R (its x0 columns count as zero)
    let c_scale = cm.iter().fold(T::zero(), |s, v| s.max(v.abs()));
    let x0_tiny = T::epsilon() * c_scale;
    for (e, d) in data.iter().enumerate() {
        let us: Vec<Cow<'_, [T]>> = (0..m).map(|q| column(d.u, q)).collect();
        let ys: Vec<Cow<'_, [T]>> = (0..l).map(|o| column(d.y, o)).collect();
        // per output: the m B-response states, then the free-response row (starts at C_o)
        let mut states: Vec<Vec<T>> = c_rows
            .iter()
            .map(|co| {
                let mut z = vec![T::zero(); (m + 1) * n];
                z[m * n..].copy_from_slice(co);
                z
            })
            .collect();
        let mut k0 = 0;
        while k0 < d.len() {
            let kk = kmax.min(d.len() - k0);
            let zeros = vec![T::zero(); kk];
            let mut x0_max = T::zero();
            for o in 0..l {
                let r0 = nc + o * kk;
                let mut cols: Vec<&mut [T]> = columns_mut(blk)
                    .into_iter()
                    .map(|col| &mut col[r0..r0 + kk])
                    .collect();
                // B responses and the free rows C_o A^k in one interleaved pass
                let (xcols, rest) = cols.split_at_mut(ib);
                let (bcols, rest) = rest.split_at_mut(nb);
                let (dcols, rest) = rest.split_at_mut(nd);
                let (ocols, ycol) = rest.split_at_mut(no);
                let mut fs: Vec<&[T]> = us.iter().map(|u| &u[k0..k0 + kk]).collect();
                let mut outs: Vec<&mut [T]> = bcols.iter_mut().map(|c| &mut c[..]).collect();
                if estimate_x0 {
                    for (e2, chunk) in xcols.chunks_mut(n).enumerate() {
                        if e2 != e {
                            chunk.iter_mut().for_each(|col| col.fill(T::zero()));
                        }
                    }
                    fs.push(&zeros);
                    outs.extend(xcols[e * n..(e + 1) * n].iter_mut().map(|c| &mut c[..]));
                }
                row_responses(&af, c_rows[o], &fs, &mut states[o], &mut outs);
                drop(outs);
                if estimate_x0 {
                    for col in xcols[e * n..(e + 1) * n].iter() {
                        x0_max = col.iter().fold(x0_max, |s, v| s.max(v.abs()));
                    }
                }
                // D[o2, q] (column q·l + o2) acts on output o2 only
                for (qo, col) in dcols.iter_mut().enumerate() {
                    let (q, o2) = (qo / l, qo % l);
                    if o2 == o {
                        col.copy_from_slice(&us[q][k0..k0 + kk]);
                    } else {
                        col.fill(T::zero());
                    }
                }
                for (o2, col) in ocols.iter_mut().enumerate() {
                    col.fill(if o2 == o { T::one() } else { T::zero() });
                }
                ycol[0].copy_from_slice(&ys[o][k0..k0 + kk]);
                if l > 1 {
                    for col in cols.iter_mut() {
                        col.iter_mut().for_each(|v| *v *= wy[o]);
                    }
                }
            }
            // x0 columns negligible in every row of the chunk: only the trailing block changes
            // (Householder steps on columns that are zero below R's diagonal are identities)
            let c0 = if estimate_x0 && x0_max <= x0_tiny {
                nx
            } else {
                0
            };
            let rows = nc + kk * l;
            let r = la.qr_r_in_place(blk.as_mut().submatrix_mut(c0, c0, rows - c0, nc - c0))?;
            for i in c0..nc {
                for j in c0..nc {
                    blk[(i, j)] = if j >= i && i - c0 < r.nrows() {
                        r[(i - c0, j - c0)]
                    } else {
                        T::zero()
                    };
                }
            }
            k0 += kk;
        }
    }
    // [R_φ r_y] from the leading np rows: θ = R_φ⁺ r_y
    let rphi = blk.submatrix(0, 0, np, np);
    let ry = blk.submatrix(0, np, np, 1);
    let theta = la.lstsq(rphi, ry)?;
    let b = Mat::from_fn(n, m, |p, q| theta[(ib + q * n + p, 0)]);
    let dm = if with_d {
        Mat::from_fn(l, m, |o, q| theta[(id + q * l + o, 0)])
    } else {
        Mat::zeros(l, m)
    };
    let x0 = (0..ne)
        .map(|e| {
            if estimate_x0 {
                (0..n).map(|j| theta[(e * n + j, 0)]).collect()
            } else {
                vec![T::zero(); n]
            }
        })
        .collect();
    let offsets = (0..l)
        .map(|o| {
            if offset {
                theta[(io + o, 0)]
            } else {
                T::zero()
            }
        })
        .collect();
    Ok((BdX0 { b, d: dm, x0 }, offsets))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::data::IoData;
    use crate::solvers::Faer;

    #[test]
    fn chunked_regression_equals_the_whole_least_squares_problem() {
        // order 2, one input, 40 000 samples: three chunks, the later ones without the decayed
        // initial-state columns; noisy output so that the solution is a genuine LS compromise
        let a = Mat::from_fn(2, 2, |i, j| [[0.2, 1.0], [-0.35, 0.0]][i][j]);
        let c = Mat::from_fn(1, 2, |_, j| [1.0, 0.0][j]);
        let (b, d, x0) = ([1.0, 0.5], 0.3, [2.0, -1.0]);
        let nn = 40_000;
        let u: Vec<f64> = (0..nn)
            .map(|k| ((k * 7919 % 2003) as f64 / 1001.5) - 1.0)
            .collect();
        let mut x = x0;
        let mut y = Vec::with_capacity(nn);
        for (k, &uk) in u.iter().enumerate() {
            let noise = 0.1 * (((k * 104_729) % 1009) as f64 / 504.5 - 1.0);
            y.push(x[0] + d * uk + noise);
            x = [0.2 * x[0] + x[1] + b[0] * uk, -0.35 * x[0] + b[1] * uk];
        }
        let data = IoData::siso(&u, &y).unwrap();
        let la = Faer::default();
        let est = estimate_bd_x0(&la, a.as_ref(), c.as_ref(), &[data.view()], true, true).unwrap();
        // the whole regression [responses to B entries, u, C A^k] solved at once
        let mut reg = Mat::<f64>::zeros(nn, 5);
        let (mut z, mut o) = ([[0.0; 2]; 1], [1.0, 0.0]);
        for k in 0..nn {
            reg[(k, 0)] = z[0][0];
            reg[(k, 1)] = z[0][1];
            reg[(k, 2)] = u[k];
            reg[(k, 3)] = o[0];
            reg[(k, 4)] = o[1];
            let zz = z[0];
            z[0] = [
                zz[0] * 0.2 + zz[1] * -0.35 + u[k],
                zz[0] * 1.0 + zz[1] * 0.0,
            ];
            o = [o[0] * 0.2 + o[1] * -0.35, o[0] * 1.0];
        }
        let rhs = Mat::from_fn(nn, 1, |k, _| y[k]);
        let th = LinAlg::<f64>::lstsq(&la, reg.as_ref(), rhs.as_ref()).unwrap();
        let got = [
            est.b[(0, 0)],
            est.b[(1, 0)],
            est.d[(0, 0)],
            est.x0[0][0],
            est.x0[0][1],
        ];
        for (i, g) in got.iter().enumerate() {
            assert!((g - th[(i, 0)]).abs() < 1e-10, "{i}: {g} vs {}", th[(i, 0)]);
        }
        // and close to the truth (noise 0.1)
        assert!(
            (got[0] - 1.0).abs() < 0.01 && (got[3] - 2.0).abs() < 0.2,
            "{got:?}"
        );
        // with an offset column (the Hammerstein loop's problem) on y + 0.7: the whole
        // regression [.., 1]'s solution, the offset near 0.7, the same with a reused buffer
        let ys: Vec<f64> = y.iter().map(|v| v + 0.7).collect();
        let shifted = IoData::siso(&u, &ys).unwrap();
        let reg1 = Mat::from_fn(nn, 6, |k, j| if j < 5 { reg[(k, j)] } else { 1.0 });
        let rhs1 = Mat::from_fn(nn, 1, |k, _| ys[k]);
        let th1 = LinAlg::<f64>::lstsq(&la, reg1.as_ref(), rhs1.as_ref()).unwrap();
        let terms = BdTerms {
            with_d: true,
            x0: true,
            offset: true,
        };
        let mut buffer = Mat::<f64>::from_fn(3, 3, |_, _| f64::NAN);
        for _ in 0..2 {
            let (est, offsets) = bd_x0_least_squares(
                &la,
                a.as_ref(),
                c.as_ref(),
                &[shifted.view()],
                terms,
                Some(&mut buffer),
            )
            .unwrap();
            let with = [
                est.b[(0, 0)],
                est.b[(1, 0)],
                est.d[(0, 0)],
                est.x0[0][0],
                est.x0[0][1],
            ];
            for (i, g) in with.iter().chain(&offsets).enumerate() {
                assert!(
                    (g - th1[(i, 0)]).abs() < 1e-10,
                    "{i}: {g} vs {}",
                    th1[(i, 0)]
                );
            }
            assert!((offsets[0] - 0.7).abs() < 0.01, "{offsets:?}");
        }
    }
}
