//! The linear least-squares steps of the loop: B (and D), the initial state and the output offset
//! for fixed A and C, and simulation on slices.
//!
//! Once A and C are fixed the output y(k) = C A^k x0 + Σ_j C A^(k-1-j) B φ(j) + D φ(k) + c is linear
//! in (vec B, D, x0, c); the regressors are the simulated responses to unit entries (as SLICOT
//! IB01CD does).
//!
//! One B/D/x0 routine (issue 14): `fit_given_ac` is the subspace identification's least squares,
//! `subspace::bd_x0_least_squares` (the core of `estimate_bd_x0`: chunked Householder QR of
//! [Φ | y], the decayed initial-state columns skipped), with its offset column and with the fold
//! matrix kept in `LsWork` across the search's calls. Before, the loop built the whole N×p
//! matrix and solved it by the backend's QR. The two factorisations agree to round-off; what
//! the switch changed (measured when it was made): the demo's table, its report and the paper
//! study's printed numbers (114/114 targets) stayed the same to the last printed digit (CPU time
//! of the demo 0.42 s both); five settings fitted on three Example 1 records (40, 20, 10 dB) gave
//! the same numbers to ≤ 3e-15 relative for 10 of the 15 f64 fits and ≤ 6.5e-13 for two more,
//! a delayed fit moved by 4.4e-6 and the 10 dB record's two SH fits (automatic and fixed order)
//! by 0.9 % (z1 2.6207 → 2.6437, training MSE 1.704587 → 1.704569: the loop's accept/stop
//! decisions compare near-equal MSEs and amplify round-off); f32 fits by ≤ 6.7e-6; the subspace
//! estimates unchanged. The gains given a known block (`fit_gains_given_block`: the regressors
//! are the block's outputs, not unit-B responses) and the initial state given a forced response
//! (`fit_x0`) are other problems and keep their own solvers (the whole-matrix QR with the C·A^k
//! cache, and the sequential TSQR).

use crate::data::IoView;
use crate::error::{Error, Result};
use crate::real::Real;
use crate::solvers::LinAlg;
use crate::solvers::columns::{column, columns_mut, row_major};
use crate::solvers::recursion::{SisoBlock, WIDE, free_rows};
use crate::solvers::tsqr::{BLOCK_ROWS, Tsqr, solve_from_r};
use crate::subspace::{BdTerms, bd_x0_least_squares};
use faer::{Mat, MatRef};
use std::borrow::Cow;

/// B, D, x0 and offset for fixed (A, C), with m inputs.
#[derive(Debug, Clone)]
pub(crate) struct LinearFit<T: Real> {
    /// Input matrix, n×m.
    pub b: Mat<T>,
    /// Feed-through, one row of m (zeros when not estimated).
    pub d: Vec<T>,
    /// Initial state (zeros when not estimated).
    pub x0: Vec<T>,
    /// Output offset (zero when not estimated).
    pub offset: T,
}

/// Reusable buffers of the least-squares steps: the regression matrix of `fit_gains_given_block`
/// and the fold matrix of `fit_given_ac` (reusing it across calls saves allocating and faulting
/// in fresh memory on every call) and the C·A^k columns.
#[derive(Debug)]
pub(crate) struct LsWork<T: Real> {
    reg: Mat<T>,
    free: FreeCache<T>,
}

impl<T: Real> Default for LsWork<T> {
    fn default() -> Self {
        Self {
            reg: Mat::new(),
            free: FreeCache {
                key: Vec::new(),
                cols: Vec::new(),
            },
        }
    }
}

impl<T: Real> LsWork<T> {
    /// Builds the N×np regression matrix with `fill` (which must write every column; the
    /// C·A^k cache is handed along) and solves min ‖reg·θ − y‖ by the backend's in-place QR.
    /// `what` names the estimated quantities in the error for too short a record.
    fn solve(
        &mut self,
        la: &dyn LinAlg<T>,
        y: &[T],
        np: usize,
        what: &str,
        fill: impl FnOnce(&mut [&mut [T]], &mut FreeCache<T>),
    ) -> Result<Mat<T>> {
        let nn = y.len();
        if nn < np + 1 {
            return Err(Error::TooFewSamples {
                needed: np + 1,
                got: nn,
                reason: format!("estimating {what}"),
            });
        }
        // every column is written by `fill`, so a reused matrix needs no clearing
        self.reg.resize_with(nn, np, |_, _| T::zero());
        let mut cols = columns_mut(&mut self.reg);
        fill(&mut cols, &mut self.free);
        drop(cols);
        let mut rhs = Mat::from_fn(nn, 1, |k, _| y[k]);
        la.lstsq_in_place(self.reg.as_mut(), rhs.as_mut())
    }
}

/// The last C·A^k columns with the (A, C) they belong to (the search's candidates share (A, C)).
#[derive(Debug)]
struct FreeCache<T: Real> {
    key: Vec<T>,
    cols: Vec<T>,
}

impl<T: Real> FreeCache<T> {
    /// Writes C A^k into `out[j][k]` (k < `len`), from the cache when (A, C) are those of the
    /// last call.
    fn fill(&mut self, am: &[T], cv: &[T], len: usize, out: &mut [&mut [T]]) {
        let n = cv.len();
        let same = self.cols.len() == n * len
            && self.key.len() == am.len() + cv.len()
            && self.key[..am.len()] == *am
            && self.key[am.len()..] == *cv;
        if !same {
            self.key.clear();
            self.key.extend_from_slice(am);
            self.key.extend_from_slice(cv);
            self.cols.clear();
            self.cols.resize(n * len, T::zero());
            let mut cols: Vec<&mut [T]> = self.cols.chunks_mut(len.max(1)).collect();
            free_responses(am, cv, &mut cols);
        }
        for (j, o) in out.iter_mut().enumerate() {
            o.copy_from_slice(&self.cols[j * len..(j + 1) * len]);
        }
    }
}

/// What the least-squares step estimates besides B.
#[derive(Debug, Clone, Copy)]
pub(crate) struct LsTerms {
    /// Estimate D.
    pub with_d: bool,
    /// Estimate x0.
    pub x0: bool,
    /// Estimate a constant output offset.
    pub offset: bool,
}

/// Solves min ‖y − ŷ(B, D, x0, c)‖ for fixed A (n×n), C (1×n) and inputs `phi` (N×m): the
/// subspace identification's B/D/x0 least squares (`subspace::bd_x0_least_squares`, chunked
/// QR) with the offset column, its fold matrix reused from `work`.
pub(crate) fn fit_given_ac<T: Real>(
    la: &dyn LinAlg<T>,
    a: MatRef<'_, T>,
    c: MatRef<'_, T>,
    phi: MatRef<'_, T>,
    y: &[T],
    terms: LsTerms,
    work: &mut LsWork<T>,
) -> Result<LinearFit<T>> {
    let n = a.nrows();
    let m = phi.ncols();
    let nn = y.len();
    if phi.nrows() != nn {
        return Err(Error::LengthMismatch {
            what: format!("regressors have {} rows, output {}", phi.nrows(), nn),
        });
    }
    let np = n * m
        + if terms.with_d { m } else { 0 }
        + if terms.x0 { n } else { 0 }
        + usize::from(terms.offset);
    if nn < np + 1 {
        return Err(Error::TooFewSamples {
            needed: np + 1,
            got: nn,
            reason: "estimating B, D, the initial state and the offset".into(),
        });
    }
    let ym = Mat::from_fn(nn, 1, |k, _| y[k]);
    let data = IoView {
        u: phi,
        y: ym.as_ref(),
    };
    let bd_terms = BdTerms {
        with_d: terms.with_d,
        x0: terms.x0,
        offset: terms.offset,
    };
    let (est, offsets) = bd_x0_least_squares(la, a, c, &[data], bd_terms, Some(&mut work.reg))?;
    Ok(LinearFit {
        b: est.b,
        d: (0..m).map(|q| est.d[(0, q)]).collect(),
        x0: est.x0.into_iter().next().unwrap_or_default(),
        offset: offsets[0],
    })
}

/// Gains, initial state and offset of min ‖y − Σ_q g_q·G(φ_q) − C A^k x0 − c‖ for a fully known
/// single-input block G = (A, b, C, d): the gain step of an alternating least-squares pass (the
/// block fixed, g free). Its regressors are the block's responses to each regressor column;
/// `work` as in `fit_given_ac`.
/// The gains are returned as the single row of `b`.
#[allow(clippy::too_many_arguments)]
pub(crate) fn fit_gains_given_block<T: Real>(
    la: &dyn LinAlg<T>,
    a: MatRef<'_, T>,
    b: &[T],
    c: MatRef<'_, T>,
    d: T,
    phi: MatRef<'_, T>,
    y: &[T],
    terms: LsTerms,
    work: &mut LsWork<T>,
) -> Result<LinearFit<T>> {
    let n = a.nrows();
    let m = phi.ncols();
    let nn = y.len();
    if phi.nrows() != nn || b.len() != n {
        return Err(Error::LengthMismatch {
            what: format!(
                "regressors have {} rows, output {nn}; b has {} entries for order {n}",
                phi.nrows(),
                b.len()
            ),
        });
    }
    let nx = if terms.x0 { n } else { 0 };
    let no = usize::from(terms.offset);
    let np = m + nx + no;
    let am = row_major(a);
    let cv = row_major(c);
    let phi_cols: Vec<Cow<'_, [T]>> = (0..m).map(|q| column(phi, q)).collect();
    let what = "the gains, the initial state and the offset";
    let theta = work.solve(la, y, np, what, |cols, free| {
        let (g_cols, rest) = cols.split_at_mut(m);
        let (x_cols, o_cols) = rest.split_at_mut(nx);
        block_outputs(&am, b, &cv, d, &phi_cols, g_cols);
        if terms.x0 {
            free.fill(&am, &cv, nn, x_cols);
        }
        for col in o_cols.iter_mut() {
            col.fill(T::one());
        }
    })?;
    let (x0, offset) = x0_and_offset(&theta, m, n, terms);
    Ok(LinearFit {
        b: Mat::from_fn(1, m, |_, q| theta[(q, 0)]),
        d: vec![T::zero(); m],
        x0,
        offset,
    })
}

/// The initial state (n entries from `start`, when estimated) and the offset (the last entry,
/// when estimated) of a least-squares solution; zeros for what was not estimated.
fn x0_and_offset<T: Real>(theta: &Mat<T>, start: usize, n: usize, terms: LsTerms) -> (Vec<T>, T) {
    let x0 = (0..n)
        .map(|j| {
            if terms.x0 {
                theta[(start + j, 0)]
            } else {
                T::zero()
            }
        })
        .collect();
    let offset = if terms.offset {
        theta[(theta.nrows() - 1, 0)]
    } else {
        T::zero()
    };
    (x0, offset)
}

/// Initial state (and offset when `fit_offset`) for a fully known single-input block: solves
/// min ‖y − c − y_forced − O x0‖ with O(k) = C A^k. `offset` is used as given when not fitted.
pub(crate) fn fit_x0<T: Real>(
    la: &dyn LinAlg<T>,
    a: MatRef<'_, T>,
    c: MatRef<'_, T>,
    y_forced: &[T],
    y: &[T],
    offset: T,
    fit_offset: bool,
) -> Result<(Vec<T>, T)> {
    let n = a.nrows();
    let nn = y.len();
    let np = n + usize::from(fit_offset);
    if nn < np + 1 {
        return Err(Error::TooFewSamples {
            needed: np + 1,
            got: nn,
            reason: "estimating the initial state".into(),
        });
    }
    // rows [C A^k, 1 | y − forced] folded into R block by block (sequential TSQR, Demmel et al.
    // 2012; `solvers/tsqr.rs`): memory O(n²), not O(N·n)
    let am = row_major(a);
    let mut o = row_major(c);
    let mut ts = Tsqr::new(la, np + 1);
    let mut block = vec![T::zero(); n * BLOCK_ROWS.min(nn)];
    let mut row = vec![T::zero(); np + 1];
    let mut k0 = 0;
    while k0 < nn {
        let m = BLOCK_ROWS.min(nn - k0);
        {
            let mut cols: Vec<&mut [T]> = block[..n * m].chunks_mut(m.max(1)).collect();
            free_rows(&am, &mut o, &mut cols);
        }
        for t in 0..m {
            for (j, r) in row.iter_mut().take(n).enumerate() {
                *r = block[j * m + t];
            }
            if fit_offset {
                row[n] = T::one();
            }
            let k = k0 + t;
            row[np] = y[k] - y_forced[k] - if fit_offset { T::zero() } else { offset };
            ts.push_row(&row)?;
        }
        k0 += m;
    }
    let (sol, _) = solve_from_r(la, &ts.finish()?, nn)?;
    let theta = Mat::from_fn(np, 1, |j, _| sol[j]);
    let x0 = (0..n).map(|j| theta[(j, 0)]).collect();
    let off = if fit_offset { theta[(n, 0)] } else { offset };
    Ok((x0, off))
}

/// The outputs of the single-input block (A, b, C, d) from a zero state driven by each input
/// `phi_cols[q]`, into `out[q]`, up to `WIDE` inputs per pass (see `fit_given_ac`).
fn block_outputs<T: Real>(
    am: &[T],
    bv: &[T],
    cv: &[T],
    d: T,
    phi_cols: &[Cow<'_, [T]>],
    out: &mut [&mut [T]],
) {
    let n = cv.len();
    for (fs, out) in phi_cols.chunks(WIDE).zip(out.chunks_mut(WIDE)) {
        let fs: Vec<&[T]> = fs.iter().map(|c| c.as_ref()).collect();
        let blk = SisoBlock {
            a: am,
            b: bv,
            c: cv,
            d,
            offset: T::zero(),
        };
        blk.run_many(&vec![T::zero(); n], &fs, out);
    }
}

/// The rows C A^k, k = 0..len, of the observability matrix as n columns (column j at
/// `[j·len, (j+1)·len)`): the free output responses to the unit initial states, o(k+1) = o(k) A.
pub(crate) fn observability_columns<T: Real>(
    a: MatRef<'_, T>,
    c: MatRef<'_, T>,
    len: usize,
) -> Vec<T> {
    let n = a.nrows();
    let am = row_major(a);
    let cv = row_major(c);
    let mut out = vec![T::zero(); n * len];
    let mut cols: Vec<&mut [T]> = out.chunks_mut(len.max(1)).collect();
    free_responses(&am, &cv, &mut cols);
    out
}

/// Consecutive rows of the observability matrix that must all lie below the decay tolerance for
/// [`free_response_length`] to end the free response there (at least n of them).
const DECAY_RUN: usize = 64;

/// The number of leading samples k of a record of `len` samples over which the free response
/// C A^k of the block (A, C) is not negligible: the first k after which [`DECAY_RUN`] (at least n)
/// consecutive rows C A^k all have entries below `ε·10⁻³` times the largest entry seen (ε the
/// machine epsilon of `T`), or `len` when the response has not decayed by then (an unstable or
/// very slow block).
///
/// Why the run and not the first small row: by Cayley–Hamilton every row after n consecutive
/// small ones is a combination of them with the characteristic polynomial's coefficients, so
/// the tail stays at the level of the run (times a factor bounded for a stable block); a single
/// small row of an oscillating response proves nothing. What a caller gains: a least squares
/// for the initial state (and any quantity that enters only through the free response) needs
/// the rows up to this length only — the later rows of its regressors are zero to below
/// round-off — so its memory and time no longer grow with the record.
pub(crate) fn free_response_length<T: Real>(
    a: MatRef<'_, T>,
    c: MatRef<'_, T>,
    len: usize,
) -> usize {
    let n = a.nrows();
    if n == 0 {
        return len.min(1);
    }
    let am = row_major(a);
    let mut o: Vec<T> = row_major(c);
    let mut next = vec![T::zero(); n];
    let tol = T::epsilon().as_f64() * 1e-3;
    let run = DECAY_RUN.max(n);
    let mut peak = 0.0f64;
    let mut small = 0usize;
    for k in 0..len {
        let m = o.iter().fold(0.0f64, |m, x| m.max(x.as_f64().abs()));
        if !m.is_finite() {
            return len;
        }
        peak = peak.max(m);
        if m <= tol * peak {
            small += 1;
            if small >= run {
                return (k + 1).min(len);
            }
        } else {
            small = 0;
        }
        // o ← o A (row vector times the row-major A)
        for (j, nx) in next.iter_mut().enumerate() {
            *nx = (0..n).fold(T::zero(), |s, i| s + o[i] * am[i * n + j]);
        }
        std::mem::swap(&mut o, &mut next);
    }
    len
}

/// Writes C A^k (A row-major `am`, C = `cv`) into `out[j][k]` for every k < `out[j].len()`.
fn free_responses<T: Real>(am: &[T], cv: &[T], out: &mut [&mut [T]]) {
    let mut o = cv.to_vec();
    free_rows(am, &mut o, out);
}

/// Output of the single-input block (A, b, C, d) driven by `v` from `x0`, plus `offset`, into `out`.
#[allow(clippy::too_many_arguments)]
pub(crate) fn simulate_into<T: Real>(
    a: MatRef<'_, T>,
    b: &[T],
    c: MatRef<'_, T>,
    d: T,
    x0: &[T],
    offset: T,
    v: &[T],
    out: &mut Vec<T>,
) {
    out.clear();
    out.resize(v.len(), T::zero());
    with_block(a, b, c, d, offset, |blk| {
        blk.run_many(x0, &[v], &mut [out.as_mut_slice()])
    });
}

/// [`simulate_into`] with the output written over its input: `buf` holds v on entry and the
/// block's output on return (the same bits; one signal of the record's length, not two).
pub(crate) fn simulate_in_place<T: Real>(
    a: MatRef<'_, T>,
    b: &[T],
    c: MatRef<'_, T>,
    d: T,
    x0: &[T],
    offset: T,
    buf: &mut [T],
) {
    with_block(a, b, c, d, offset, |blk| blk.run_in_place(x0, buf));
}

/// `run` on the simulation kernel's block (A and C row-major) of (A, b, C, d) plus `offset`.
fn with_block<T: Real, R>(
    a: MatRef<'_, T>,
    b: &[T],
    c: MatRef<'_, T>,
    d: T,
    offset: T,
    run: impl FnOnce(&SisoBlock<'_, T>) -> R,
) -> R {
    let am = row_major(a);
    let cv = row_major(c);
    run(&SisoBlock {
        a: &am,
        b,
        c: &cv,
        d,
        offset,
    })
}

/// Mean squared difference of two equally long slices, in f64.
pub(crate) fn mse<T: Real>(y: &[T], y_hat: &[T]) -> f64 {
    let n = y.len().max(1) as f64;
    y.iter()
        .zip(y_hat)
        .map(|(&a, &b)| {
            let e = (a - b).as_f64();
            e * e
        })
        .sum::<f64>()
        / n
}

/// The input delayed by `nk` samples, the first sample held before the record starts (the
/// input itself, borrowed, without a delay).
pub(crate) fn delayed<T: Real>(u: &[T], nk: usize) -> std::borrow::Cow<'_, [T]> {
    if nk == 0 {
        return std::borrow::Cow::Borrowed(u);
    }
    (0..u.len()).map(|k| u[k.saturating_sub(nk)]).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The free response of a stable block ends where its rows fall below round-off, and its
    /// neglected rows are indeed below it; an unstable block's never ends before the record.
    #[test]
    fn the_free_response_ends_where_it_has_decayed() {
        let a = Mat::<f64>::from_fn(2, 2, |i, j| [[0.2, 1.0], [-0.35, 0.0]][i][j]);
        let c = Mat::<f64>::from_fn(1, 2, |_, j| [1.0, 0.0][j]);
        let len = 100_000;
        let head = free_response_length(a.as_ref(), c.as_ref(), len);
        assert!(head > DECAY_RUN && head < 1000, "head {head}");
        let all: Vec<f64> = observability_columns(a.as_ref(), c.as_ref(), 2 * head);
        let peak = all.iter().fold(0.0f64, |m, x| m.max(f64::abs(*x)));
        let tail = (0..2)
            .flat_map(|j| all[j * 2 * head + head..(j + 1) * 2 * head].iter())
            .fold(0.0f64, |m, x| m.max(f64::abs(*x)));
        assert!(tail <= 1e-18 * peak, "tail {tail:e}, peak {peak:e}");
        let unstable = Mat::<f64>::from_fn(2, 2, |i, j| [[1.01, 0.0], [0.0, 0.5]][i][j]);
        let c1 = Mat::<f64>::from_fn(1, 2, |_, _| 1.0);
        assert_eq!(
            free_response_length(unstable.as_ref(), c1.as_ref(), 5000),
            5000
        );
        // a slow but stable block: the record ends first
        let slow = Mat::<f64>::from_fn(1, 1, |_, _| 0.9999);
        let c2 = Mat::<f64>::from_fn(1, 1, |_, _| 1.0);
        assert_eq!(
            free_response_length(slow.as_ref(), c2.as_ref(), 20_000),
            20_000
        );
    }
}
