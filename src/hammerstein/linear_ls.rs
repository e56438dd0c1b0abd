//! The linear least-squares steps of the loop: B (and D), the initial state and the output offset
//! for fixed A and C, and simulation on slices.
//!
//! Once A and C are fixed the output y(k) = C A^k x0 + Σ_j C A^(k-1-j) B φ(j) + D φ(k) + c is linear
//! in (vec B, D, x0, c); the regressors are the simulated responses to unit entries (as SLICOT
//! IB01CD does), and the problem is solved by QR (SVD when rank deficient) through the backend.

use crate::error::{Error, Result};
use crate::real::Real;
use crate::solvers::LinAlg;
use faer::{Mat, MatRef};

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

/// Solves min ‖y − ŷ(B, D, x0, c)‖ for fixed A (n×n), C (1×n) and inputs `phi` (N×m).
///
/// The B columns are the output responses to each entry of B, computed by a row-vector recursion
/// per input (see the body); cost O(N·m·n²) plus the QR solve.
pub(crate) fn fit_given_ac<T: Real>(
    la: &dyn LinAlg<T>,
    a: MatRef<'_, T>,
    c: MatRef<'_, T>,
    phi: MatRef<'_, T>,
    y: &[T],
    terms: LsTerms,
) -> Result<LinearFit<T>> {
    let n = a.nrows();
    let m = phi.ncols();
    let nn = y.len();
    if phi.nrows() != nn {
        return Err(Error::LengthMismatch {
            what: format!("regressors have {} rows, output {}", phi.nrows(), nn),
        });
    }
    let nb = n * m;
    let nd = if terms.with_d { m } else { 0 };
    let nx = if terms.x0 { n } else { 0 };
    let no = usize::from(terms.offset);
    let np = nb + nd + nx + no;
    if nn < np + 1 {
        return Err(Error::TooFewSamples {
            needed: np + 1,
            got: nn,
            reason: "estimating B, D, the initial state and the offset".into(),
        });
    }
    // A and C copied row-major for the inner loops
    let am: Vec<T> = (0..n * n).map(|ij| a[(ij / n, ij % n)]).collect();
    let cv: Vec<T> = (0..n).map(|j| c[(0, j)]).collect();
    let mut reg = Mat::<T>::zeros(nn, np);
    // B columns: the response of y to B's entry (p, q) is z_q(k)_p, where the row vector
    // z_q(k) = Σ_{j<k} φ_q(j) C A^(k−1−j) obeys z_q(k+1) = z_q(k) A + φ_q(k) C, z_q(0) = 0
    // (O(N·m·n²); the n responses of one input in one pass).
    let mut phiq = vec![T::zero(); nn];
    let mut zcols = vec![T::zero(); n * nn];
    for q in 0..m {
        for (k, v) in phiq.iter_mut().enumerate() {
            *v = phi[(k, q)];
        }
        match n {
            1 => responses::<T, 1>(&am, &cv, &phiq, &mut zcols),
            2 => responses::<T, 2>(&am, &cv, &phiq, &mut zcols),
            3 => responses::<T, 3>(&am, &cv, &phiq, &mut zcols),
            4 => responses::<T, 4>(&am, &cv, &phiq, &mut zcols),
            _ => responses_dyn(n, &am, &cv, &phiq, &mut zcols),
        }
        for p in 0..n {
            col_slice(&mut reg, q * n + p).copy_from_slice(&zcols[p * nn..(p + 1) * nn]);
        }
        if terms.with_d {
            col_slice(&mut reg, nb + q).copy_from_slice(&phiq);
        }
    }
    // x0 columns: row k is C A^k, propagated as o ← o A
    if terms.x0 {
        let mut o = cv.clone();
        let mut o_next = vec![T::zero(); n];
        for k in 0..nn {
            for j in 0..n {
                reg[(k, nb + nd + j)] = o[j];
            }
            for j in 0..n {
                let mut s = T::zero();
                for i in 0..n {
                    s += o[i] * am[i * n + j];
                }
                o_next[j] = s;
            }
            std::mem::swap(&mut o, &mut o_next);
        }
    }
    if terms.offset {
        reg.col_mut(np - 1).fill(T::one());
    }
    let mut rhs = Mat::from_fn(nn, 1, |k, _| y[k]);
    let theta = la.lstsq_in_place(reg.as_mut(), rhs.as_mut())?;
    let b = Mat::from_fn(n, m, |p, q| theta[(q * n + p, 0)]);
    let d = (0..m)
        .map(|q| {
            if terms.with_d {
                theta[(nb + q, 0)]
            } else {
                T::zero()
            }
        })
        .collect();
    let x0 = (0..n)
        .map(|j| {
            if terms.x0 {
                theta[(nb + nd + j, 0)]
            } else {
                T::zero()
            }
        })
        .collect();
    let offset = if terms.offset {
        theta[(np - 1, 0)]
    } else {
        T::zero()
    };
    Ok(LinearFit { b, d, x0, offset })
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
    let mut reg = Mat::<T>::zeros(nn, np);
    let mut o = (0..n).map(|j| c[(0, j)]).collect::<Vec<T>>();
    let mut o_next = vec![T::zero(); n];
    for k in 0..nn {
        for j in 0..n {
            reg[(k, j)] = o[j];
        }
        if fit_offset {
            reg[(k, n)] = T::one();
        }
        for j in 0..n {
            let mut s = T::zero();
            for i in 0..n {
                s += o[i] * a[(i, j)];
            }
            o_next[j] = s;
        }
        std::mem::swap(&mut o, &mut o_next);
    }
    let rhs = Mat::from_fn(nn, 1, |k, _| {
        y[k] - y_forced[k] - if fit_offset { T::zero() } else { offset }
    });
    let theta = la.lstsq(reg.as_ref(), rhs.as_ref())?;
    let x0 = (0..n).map(|j| theta[(j, 0)]).collect();
    let off = if fit_offset { theta[(n, 0)] } else { offset };
    Ok((x0, off))
}

/// The n output responses z(k)_p of one input f (see `fit_given_ac`), order n known at compile
/// time: z(k+1) = z(k) A + f(k) C, written to `out[p·N + k]`.
fn responses<T: Real, const N: usize>(am: &[T], cv: &[T], f: &[T], out: &mut [T]) {
    let nn = f.len();
    let mut a = [[T::zero(); N]; N];
    let mut c = [T::zero(); N];
    for i in 0..N {
        c[i] = cv[i];
        for j in 0..N {
            a[i][j] = am[i * N + j];
        }
    }
    let mut z = [T::zero(); N];
    for (k, &fk) in f.iter().enumerate() {
        for p in 0..N {
            out[p * nn + k] = z[p];
        }
        let mut zn = [T::zero(); N];
        for j in 0..N {
            let mut s = fk * c[j];
            for i in 0..N {
                s += z[i] * a[i][j];
            }
            zn[j] = s;
        }
        z = zn;
    }
}

/// `responses` for any order.
fn responses_dyn<T: Real>(n: usize, am: &[T], cv: &[T], f: &[T], out: &mut [T]) {
    let nn = f.len();
    let mut x = vec![T::zero(); n];
    let mut xn = vec![T::zero(); n];
    for (k, &fk) in f.iter().enumerate() {
        for p in 0..n {
            out[p * nn + k] = x[p];
        }
        for (j, xj) in xn.iter_mut().enumerate() {
            let mut s = fk * cv[j];
            for (i, &xi) in x.iter().enumerate() {
                s += xi * am[i * n + j];
            }
            *xj = s;
        }
        std::mem::swap(&mut x, &mut xn);
    }
}

/// Column `j` of an owned matrix as a slice (owned faer matrices are column-major, contiguous).
fn col_slice<T: Real>(m: &mut Mat<T>, j: usize) -> &mut [T] {
    m.col_mut(j)
        .try_as_col_major_mut()
        .expect("owned faer columns are contiguous")
        .as_slice_mut()
}

/// Output of the single-input block (A, b, C, d) driven by `v` from `x0`, plus `offset`, into `out`.
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
    let n = a.nrows();
    let mut x = x0.to_vec();
    let mut xn = vec![T::zero(); n];
    out.clear();
    out.reserve(v.len());
    for &vk in v {
        let mut s = offset + d * vk;
        for j in 0..n {
            s += c[(0, j)] * x[j];
        }
        out.push(s);
        for i in 0..n {
            let mut t = b[i] * vk;
            for j in 0..n {
                t += a[(i, j)] * x[j];
            }
            xn[i] = t;
        }
        std::mem::swap(&mut x, &mut xn);
    }
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

/// The input delayed by `nk` samples, the first sample held before the record starts.
pub(crate) fn delayed<T: Real>(u: &[T], nk: usize) -> Vec<T> {
    (0..u.len()).map(|k| u[k.saturating_sub(nk)]).collect()
}
