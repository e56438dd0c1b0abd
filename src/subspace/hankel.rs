//! Data compression: the triangular factor R of the block-Hankel matrix H, obtained without ever
//! forming H (memory O((2i(m+l))²) plus the record itself, time linear in N).
//!
//! Two algorithms, chosen by [`Compression`]:
//! - `Cholesky` (default, SLICOT IB01AD with ALG = 'C', i.e. IB01MY's idea): the correlation matrix
//!   HᵀH is accumulated exploiting the block-Hankel structure — only the first block row of lag
//!   products costs O(N·2i·(m+l)²), every other block follows from the shift recursion
//!   C(s+1,t+1) = C(s,t) + x(M+s)x(M+t)ᵀ − x(s)x(t)ᵀ in O(K²) — and R is its upper Cholesky factor.
//!   When HᵀH is not numerically positive definite (noise-free or badly excited data), the QR path
//!   is used instead, as IB01AD does (its IWARN = 2).
//! - `Qr` (SLICOT ALG = 'Q'): Householder QR of H processed in row chunks. It does not square the
//!   condition number and is the reference, but costs O(N·K²).
//! - `Semidefinite`: the Cholesky path that falls back only for an all-zero HᵀH: every dependent column,
//!   input or output, gets a zero row of R (Higham 1990). For the Hammerstein loop, whose
//!   noise-free records make the outputs exactly dependent near convergence (the QR fallback
//!   then cost 2.9 of a full-UDN fit's 11.7 ms; the fits stay exact, see `docs/performance.md`).

use crate::data::IoView;
use crate::error::{Error, Result};
use crate::real::Real;
use crate::solvers::LinAlg;
use crate::solvers::columns::{all_finite, col_slice};
use faer::Mat;
use std::borrow::Cow;

/// Rows of the transposed block-Hankel matrix processed per QR update.
const CHUNK: usize = 4096;
/// Samples per cache block when accumulating lag products.
const LAG_BLOCK: usize = 2048;

/// How the block-Hankel data are compressed to the triangular factor R.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Compression {
    /// Cholesky factor of the structured correlation matrix HᵀH (SLICOT IB01AD ALG = 'C'); fast,
    /// O(N·i·(m+l)²). Falls back to `Qr` automatically when HᵀH is numerically singular.
    #[default]
    Cholesky,
    /// Chunked Householder QR of H (SLICOT IB01AD ALG = 'Q'); reference accuracy, O(N·K²).
    Qr,
    /// Cholesky of HᵀH with zero rows of R for numerically dependent columns, inputs and
    /// outputs alike, instead of the QR fallback (QR only for an all-zero HᵀH).
    Semidefinite,
}

impl std::str::FromStr for Compression {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        match s.to_ascii_lowercase().as_str() {
            "cholesky" | "c" => Ok(Self::Cholesky),
            "qr" | "q" => Ok(Self::Qr),
            "semidefinite" | "s" => Ok(Self::Semidefinite),
            _ => Err(Error::UnknownName {
                kind: crate::error::NameKind::Compression,
                name: s.to_string(),
                expected: "cholesky|qr|semidefinite",
            }),
        }
    }
}

/// Checks channel counts, finiteness and record lengths for horizon `i`; returns (m, l).
fn check_data<T: Real>(data: &[IoView<'_, T>], i: usize) -> Result<(usize, usize)> {
    super::check_horizon_range(i)?;
    let first = data.first().ok_or(Error::NoExperiment)?;
    let (m, l) = (first.u.ncols(), first.y.ncols());
    if m == 0 || l == 0 {
        return Err(Error::NoChannels {
            what: "at least one input and one output are needed",
        });
    }
    for (e, d) in data.iter().enumerate() {
        if d.u.ncols() != m || d.y.ncols() != l {
            return Err(Error::Dimension(format!(
                "experiment {e} has different channel counts"
            )));
        }
        if d.u.nrows() != d.y.nrows() {
            return Err(Error::LengthMismatch {
                what: format!(
                    "experiment {e}: input has {} samples, output has {}",
                    d.u.nrows(),
                    d.y.nrows()
                ),
            });
        }
        let n = d.len();
        if n < 2 * i {
            return Err(Error::TooFewSamples {
                needed: 2 * i,
                got: n,
                reason: format!("experiment {e} with horizon {i}"),
            });
        }
        for (what, mat) in [("input", d.u), ("output", d.y)] {
            for j in 0..mat.ncols() {
                let col = col_slice(mat.col(j));
                if all_finite(&col) {
                    continue;
                }
                if let Some(k) = col.iter().position(|v| !v.is_finite()) {
                    return Err(Error::NonFinite {
                        what: format!("{what} {} of experiment {e}", j + 1),
                        index: k,
                    });
                }
            }
        }
    }
    // the block Hankel matrix has 2i(m + l) columns: fewer rows (n − 2i + 1 per experiment)
    // leave it rank-deficient, its singular values and the order read from them meaningless
    let rows: usize = data.iter().map(|d| d.len() + 1 - 2 * i).sum();
    let columns = 2 * i * (m + l);
    if rows < columns {
        let n: usize = data.iter().map(|d| d.len()).sum();
        return Err(Error::TooFewSamples {
            needed: n + columns - rows,
            got: n,
            reason: format!(
                "horizon {i} with {m} input(s) and {l} output(s): the block Hankel matrix needs \
                 {columns} rows"
            ),
        });
    }
    Ok((m, l))
}

/// Column of natural index (block s, channel a; channels u₁..u_m, y₁..y_l) in the
/// [U_f, U_p, Y_p, Y_f] ordering used by the methods.
fn our_column(s: usize, a: usize, i: usize, m: usize, l: usize) -> usize {
    if a < m {
        if s >= i {
            (s - i) * m + a
        } else {
            i * m + s * m + a
        }
    } else {
        let o = a - m;
        if s < i {
            2 * i * m + s * l + o
        } else {
            2 * i * m + i * l + (s - i) * l + o
        }
    }
}

/// Correlation matrix HᵀH (K×K, columns ordered U_f, U_p, Y_p, Y_f) summed over experiments,
/// built with the block-Hankel shift recursion (SLICOT IB01MY's idea); also returns the sample count.
///
/// One experiment (the usual case) is built in the matrix returned, symmetrised and permuted in
/// place: one K×K matrix, not two (the Prandtl–Ishlinskii refit's 640 × 640, 3.3 MB a copy).
pub fn correlation<T: Real>(data: &[IoView<'_, T>], i: usize) -> Result<(Mat<T>, usize)> {
    let (m, l) = check_data(data, i)?;
    let p = m + l;
    let nb = 2 * i; // block rows
    let kc = nb * p;
    // natural-order correlation of one experiment (row/col index s·p + a)
    let mut g = Mat::<T>::zeros(kc, kc);
    if let [d] = data {
        natural_correlation(d, nb, p, &mut g);
        // symmetric fill of the lower block triangle (the diagonal blocks are full)
        for s in 0..nb {
            for t in s + 1..nb {
                for a in 0..p {
                    for b in 0..p {
                        g[(t * p + b, s * p + a)] = g[(s * p + a, t * p + b)];
                    }
                }
            }
        }
        let target: Vec<usize> = (0..kc).map(|x| our_column(x / p, x % p, i, m, l)).collect();
        permute_symmetric_in_place(&mut g, &target);
        return Ok((g, d.len()));
    }
    let mut out = Mat::<T>::zeros(kc, kc);
    let mut total = 0;
    for d in data {
        total += d.len();
        natural_correlation(d, nb, p, &mut g);
        // symmetric fill and permutation to [U_f, U_p, Y_p, Y_f]
        for s in 0..nb {
            for t in s..nb {
                for a in 0..p {
                    for b in 0..p {
                        let v = g[(s * p + a, t * p + b)];
                        let r = our_column(s, a, i, m, l);
                        let c = our_column(t, b, i, m, l);
                        out[(r, c)] += v;
                        if s != t {
                            out[(c, r)] += v;
                        }
                    }
                }
            }
        }
    }
    Ok((out, total))
}

/// The upper block triangle (block rows s ≤ t, the diagonal blocks full) of one experiment's
/// natural-order correlation g[(s·p + a, t·p + b)] = Σ_k x_a(k+s) x_b(k+t), written into `g`
/// (`nb` block rows of the `p` channels u then y); the lower block triangle is left as it was.
fn natural_correlation<T: Real>(d: &IoView<'_, T>, nb: usize, p: usize, g: &mut Mat<T>) {
    let m = d.u.ncols();
    let n = d.len();
    let mrows = n - nb + 1;
    // the channels as contiguous slices (borrowed from column-major data, copied otherwise;
    // a copy of 1e6 samples costs more in page faults than the lag products of a block)
    let cols: Vec<Cow<'_, [T]>> = (0..p)
        .map(|a| col_slice(if a < m { d.u.col(a) } else { d.y.col(a - m) }))
        .collect();
    // first block row C(0,t)[a,b] = Σ_{k<M} x_a(k) x_b(k+t): SIMD dot products (faer's
    // runtime-dispatched `inner_prod`) over blocks of LAG_BLOCK samples, so that each block of
    // the channels stays in cache for all 2i·p² lag products
    for mut v in g.as_mut().subrows_mut(0, p).col_iter_mut() {
        v.fill(T::zero());
    }
    let mut k0 = 0;
    while k0 < mrows {
        let len = LAG_BLOCK.min(mrows - k0);
        for t in 0..nb {
            for a in 0..p {
                let xa = faer::RowRef::from_slice(&cols[a][k0..k0 + len]);
                for b in 0..p {
                    let xb = faer::ColRef::from_slice(&cols[b][k0 + t..k0 + t + len]);
                    let d = faer::linalg::matmul::dot::inner_prod(
                        xa,
                        faer::Conj::No,
                        xb,
                        faer::Conj::No,
                    );
                    g[(a, t * p + b)] += d;
                }
            }
        }
        k0 += len;
    }
    // shift recursion for the upper block triangle s ≥ 1, t ≥ s
    for s in 1..nb {
        for t in s..nb {
            for a in 0..p {
                let xs_new = cols[a][mrows + s - 1];
                let xs_old = cols[a][s - 1];
                for b in 0..p {
                    let v = g[((s - 1) * p + a, (t - 1) * p + b)] + xs_new * cols[b][mrows + t - 1]
                        - xs_old * cols[b][t - 1];
                    g[(s * p + a, t * p + b)] = v;
                }
            }
        }
    }
}

/// G ← P G Pᵀ in place, where P moves index x to `target[x]` (a permutation): the entry at
/// (x, y) ends at (target[x], target[y]). Rows, then columns, are moved along the permutation's
/// cycles by swaps, so every value is moved, never recomputed.
fn permute_symmetric_in_place<T: Real>(g: &mut Mat<T>, target: &[usize]) {
    let k = target.len();
    let mut done = vec![false; k];
    for start in 0..k {
        if done[start] {
            continue;
        }
        done[start] = true;
        // the row (column) at `start` holds, after each swap, the one whose place comes next in
        // the cycle: start → target[start] → …
        let mut x = target[start];
        while x != start {
            done[x] = true;
            for j in 0..k {
                let v = g[(start, j)];
                g[(start, j)] = g[(x, j)];
                g[(x, j)] = v;
            }
            for r in 0..k {
                let v = g[(r, start)];
                g[(r, start)] = g[(r, x)];
                g[(r, x)] = v;
            }
            x = target[x];
        }
    }
}

/// R by Cholesky of the structured correlation matrix; `None` when HᵀH is not numerically
/// positive definite (a pivot r_jj² below 100·K·ε·max_j (HᵀH)_jj, or Cholesky breakdown) in an
/// output column (`dependent_outputs = false`) or in any column (`true`; such pivots give zero
/// rows, like those of exactly dependent inputs always do).
pub fn accumulate_r_cholesky<T: Real>(
    la: &dyn LinAlg<T>,
    data: &[IoView<'_, T>],
    i: usize,
    dependent_outputs: bool,
) -> Result<(Option<Mat<T>>, usize)> {
    let (mut corr, total) = correlation(data, i)?;
    let kc = corr.nrows();
    let dmax = (0..kc).map(|j| corr[(j, j)]).fold(T::zero(), T::max);
    if dmax <= T::zero() {
        return Ok((None, total));
    }
    let tol = T::lit(100.0) * T::from_usize(kc) * T::epsilon() * dmax;
    // `correlation` validated the data: the input count is that of the first experiment
    let m = data[0].u.ncols();
    // factored in its own storage (one K×K matrix, not two)
    if la.cholesky_lower_in_place(corr.as_mut())?
        && !(0..kc).any(|j| {
            let d = corr[(j, j)] * corr[(j, j)];
            d.is_nan() || d <= tol
        })
    {
        // R = Lᵀ
        for j in 0..kc {
            for r in j + 1..kc {
                corr[(j, r)] = corr[(r, j)];
                corr[(r, j)] = T::zero();
            }
        }
        if std::env::var_os("HS_DBG").is_some() {
            eprintln!("CHOLOK {kc} {total}");
        }
        return Ok((Some(corr), total));
    }
    // not numerically positive definite: exactly dependent input columns (regressors spanning a
    // constant repeat it in every block row) still allow a factor; dependent outputs only when
    // asked for. The factorisation overwrote HᵀH: it is built again (a second pass over the
    // data on this path only, rather than a second K×K matrix on every call)
    drop(corr);
    if std::env::var_os("HS_DBG").is_some() {
        eprintln!("CHOLFALLBACK {kc} {total}");
    }
    let (corr, _) = correlation(data, i)?;
    let zero_rows_allowed = if dependent_outputs { kc } else { 2 * i * m };
    Ok((
        cholesky_with_zero_rows(&corr, zero_rows_allowed, tol),
        total,
    ))
}

/// Upper factor R with RᵀR = G of a positive semidefinite G whose numerically zero pivots all lie
/// among its first `zero_rows_allowed` columns: those rows of R are set to zero (an exactly
/// dependent column's residual, and so its row of the QR factor, is zero; Higham, "Analysis of
/// the Cholesky decomposition of a semi-definite matrix", 1990, without pivoting). `None` when a
/// later column has a pivot at or below `tol` (or NaN): then only QR of the data is reliable.
fn cholesky_with_zero_rows<T: Real>(
    g: &Mat<T>,
    zero_rows_allowed: usize,
    tol: T,
) -> Option<Mat<T>> {
    let k = g.nrows();
    let mut r = Mat::<T>::zeros(k, k);
    for j in 0..k {
        let colj: Vec<T> = (0..j).map(|i| r[(i, j)]).collect();
        let d = g[(j, j)] - colj.iter().fold(T::zero(), |s, &x| s + x * x);
        if d.is_nan() || d <= tol {
            if j < zero_rows_allowed {
                continue; // row j stays zero
            }
            return None;
        }
        let rjj = d.sqrt();
        r[(j, j)] = rjj;
        for c in j + 1..k {
            let mut s = g[(j, c)];
            for (i, &x) in colj.iter().enumerate() {
                s -= x * r[(i, c)];
            }
            r[(j, c)] = s / rjj;
        }
    }
    Some(r)
}

/// R by the requested compression, falling back from Cholesky to QR when needed; also returns the
/// sample count and the compression actually used.
pub fn compress<T: Real>(
    la: &dyn LinAlg<T>,
    data: &[IoView<'_, T>],
    i: usize,
    how: Compression,
) -> Result<(Mat<T>, usize, Compression)> {
    if how != Compression::Qr
        && let (Some(r), total) =
            accumulate_r_cholesky(la, data, i, how == Compression::Semidefinite)?
    {
        return Ok((r, total, how));
    }
    let (r, total) = accumulate_r(la, data, i)?;
    Ok((r, total, Compression::Qr))
}

/// Upper-triangular R (K×K, K = 2i(m+l)) with Rᵀ R = Hᵀ H, where row k of H is
/// [u(k+i..k+2i), u(k..k+i), y(k..k+i), y(k+i..k+2i)] (U_f, U_p, Y_p, Y_f; samples flattened
/// time-major), by chunked Householder QR. Several experiments are stacked, i.e. their R factors
/// accumulated (multi-experiment form, as SLICOT IB01MD with BATCH = 'F','I','L').
pub fn accumulate_r<T: Real>(
    la: &dyn LinAlg<T>,
    data: &[IoView<'_, T>],
    i: usize,
) -> Result<(Mat<T>, usize)> {
    let (m, l) = check_data(data, i)?;
    let kc = 2 * i * (m + l);
    let mut r: Mat<T> = Mat::zeros(0, kc);
    let mut total = 0usize;
    let mut blk = Mat::<T>::zeros(0, 0);
    for d in data.iter() {
        let n = d.len();
        total += n;
        let rows = n - 2 * i + 1;
        let mut start = 0;
        while start < rows {
            let len = CHUNK.min(rows - start);
            let prev = r.nrows();
            if blk.nrows() != prev + len || blk.ncols() != kc {
                blk = Mat::<T>::zeros(prev + len, kc);
            }
            for a in 0..prev {
                for b in 0..kc {
                    blk[(a, b)] = if b >= a { r[(a, b)] } else { T::zero() };
                }
            }
            for kk in 0..len {
                let k = start + kk;
                let row = prev + kk;
                let mut c = 0;
                for t in 0..i {
                    for q in 0..m {
                        blk[(row, c)] = d.u[(k + i + t, q)];
                        c += 1;
                    }
                }
                for t in 0..i {
                    for q in 0..m {
                        blk[(row, c)] = d.u[(k + t, q)];
                        c += 1;
                    }
                }
                for t in 0..i {
                    for q in 0..l {
                        blk[(row, c)] = d.y[(k + t, q)];
                        c += 1;
                    }
                }
                for t in 0..i {
                    for q in 0..l {
                        blk[(row, c)] = d.y[(k + i + t, q)];
                        c += 1;
                    }
                }
            }
            r = la.qr_r_in_place(blk.as_mut())?;
            start += len;
        }
    }
    // pad to K×K when there were fewer rows than columns
    if r.nrows() < kc {
        let mut full = Mat::<T>::zeros(kc, kc);
        for a in 0..r.nrows() {
            for b in 0..kc {
                full[(a, b)] = r[(a, b)];
            }
        }
        r = full;
    }
    Ok((r, total))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// H (200×5): columns 0..3 inputs with column 2 = column 0 + column 1, then two outputs.
    fn data(dependent_output: bool) -> Mat<f64> {
        Mat::from_fn(200, 5, |k, c| {
            let x = |s: usize| (((k * (7 + 3 * s) + s * 11) % 23) as f64 - 11.0) / 7.0;
            match c {
                0 => x(0),
                1 => x(1),
                2 => x(0) + x(1),
                3 => x(3),
                _ if dependent_output => 2.0 * x(3) - x(0),
                _ => x(4),
            }
        })
    }

    /// Asserts RᵀR = G to 1e-9·`scale`.
    fn assert_factors(r: &Mat<f64>, g: &Mat<f64>, scale: f64) {
        let rtr = r.transpose() * r;
        for a in 0..g.nrows() {
            for b in 0..g.ncols() {
                assert!(
                    (rtr[(a, b)] - g[(a, b)]).abs() <= 1e-9 * scale,
                    "RᵀR = G at ({a}, {b})"
                );
            }
        }
    }

    /// An exactly dependent input (column 2 = column 0 + column 1 of the data) makes the
    /// in-place Cholesky of HᵀH fail; the factor then comes from HᵀH built again, with the
    /// dependent input's rows zero: RᵀR = HᵀH.
    #[test]
    fn a_failed_in_place_cholesky_falls_back_on_the_correlation_built_again() {
        // irregular signals (no period within the horizon), input 2 = input 0 + input 1
        let x = |k: usize, s: usize| ((k * k) as f64 * 0.013 + (k * (s + 3)) as f64 * 0.7).sin();
        let u = Mat::from_fn(
            300,
            3,
            |k, c| if c == 2 { x(k, 0) + x(k, 1) } else { x(k, c) },
        );
        let y = Mat::from_fn(300, 2, |k, c| x(k, c + 4));
        let view = IoView::new(u.as_ref(), y.as_ref()).unwrap();
        let la = crate::solvers::Faer::default();
        let i = 2;
        let (g, _) = correlation(&[view], i).unwrap();
        assert!(
            !la.cholesky_lower_in_place(g.clone().as_mut()).unwrap()
                || (0..g.nrows()).any(|j| {
                    let mut l = g.clone();
                    la.cholesky_lower_in_place(l.as_mut()).unwrap();
                    l[(j, j)] * l[(j, j)] <= 100.0 * 20.0 * f64::EPSILON * g[(0, 0)].abs()
                }),
            "the plain factorisation must not be usable here"
        );
        let (r, _) = accumulate_r_cholesky(&la, &[view], i, false).unwrap();
        let r = r.expect("dependent inputs allow a factor");
        let scale = (0..g.nrows()).map(|j| g[(j, j)]).fold(0.0, f64::max);
        assert_factors(&r, &g, scale);
        assert!(
            (0..r.nrows()).any(|a| (0..r.ncols()).all(|b| r[(a, b)] == 0.0)),
            "a dependent input's row is zero"
        );
    }

    #[test]
    fn semidefinite_cholesky_zeroes_dependent_input_rows_only() {
        let h = data(false);
        let g = h.transpose() * &h;
        let dmax = (0..5).map(|j| g[(j, j)]).fold(0.0, f64::max);
        let tol = 100.0 * 5.0 * f64::EPSILON * dmax;
        let r = cholesky_with_zero_rows(&g, 3, tol).expect("inputs may be dependent");
        assert!(
            (0..5).all(|c| r[(2, c)] == 0.0),
            "row of the dependent input is zero"
        );
        assert_factors(&r, &g, dmax);
        // the same dependency declared among outputs (zero rows allowed in 2 columns) is refused
        assert!(cholesky_with_zero_rows(&g, 2, tol).is_none());
        // a dependent output column is refused, unless zero rows are allowed everywhere
        let h = data(true);
        let g = h.transpose() * &h;
        assert!(cholesky_with_zero_rows(&g, 3, tol).is_none());
        let r = cholesky_with_zero_rows(&g, 5, tol).expect("zero rows allowed in every column");
        assert!(
            (0..5).all(|c| r[(4, c)] == 0.0),
            "row of the dependent output"
        );
        assert_factors(&r, &g, dmax);
    }
}
