//! Row-vector state recursions shared by the least-squares steps that fix A and C (the loop's B/x0
//! step, the subspace B/D/x0 step): with the output row c, the response of y to a unit entry p of
//! B driven by input f is z(k)_p with z(k+1) = z(k) A + f(k) c, and the free response to a unit
//! initial state j is o(k)_j with o(k+1) = o(k) A, o(0) = c (the rows c A^k; SLICOT IB01CD builds
//! the same regressors by simulation).
//!
//! Each recursion is a serial chain of dependent multiply-adds (latency-bound), so up to `WIDE`
//! inputs run in one loop, where their chains overlap in the pipeline (2–3× faster than one by
//! one); orders 1–4 are compiled with fixed-size arrays. A is row-major (`am[i·n + j]`).

use crate::real::Real;

/// Inputs whose recursions run in one pass.
pub(crate) const WIDE: usize = 8;

/// For each input `f[g]`: z_g(k+1) = z_g(k) A + f_g(k) c from the state `z[g·n..(g+1)·n]`,
/// writing z_g(k)_p to `out[g·n + p][k]` (k < f_g.len()); `z` holds the final states on return
/// (so a long record can be processed in chunks).
pub(crate) fn row_responses<T: Real>(
    am: &[T],
    c: &[T],
    f: &[&[T]],
    z: &mut [T],
    out: &mut [&mut [T]],
) {
    let n = c.len();
    if n == 0 {
        return;
    }
    for ((fs, zs), outs) in f
        .chunks(WIDE)
        .zip(z.chunks_mut(WIDE * n))
        .zip(out.chunks_mut(WIDE * n))
    {
        match n {
            1 => rows_fixed::<T, 1>(am, c, fs, zs, outs),
            2 => rows_fixed::<T, 2>(am, c, fs, zs, outs),
            3 => rows_fixed::<T, 3>(am, c, fs, zs, outs),
            4 => rows_fixed::<T, 4>(am, c, fs, zs, outs),
            _ => {
                for ((f, z), o) in fs.iter().zip(zs.chunks_mut(n)).zip(outs.chunks_mut(n)) {
                    rows_dyn(am, c, f, z, o);
                }
            }
        }
    }
}

/// o(k+1) = o(k) A from the row `o` (length n), writing o(k)_j to `out[j][k]` for
/// k < out[0].len(); `o` holds the next row on return.
pub(crate) fn free_rows<T: Real>(am: &[T], o: &mut [T], out: &mut [&mut [T]]) {
    let n = o.len();
    let len = out.first().map_or(0, |c| c.len());
    let zeros = vec![T::zero(); len];
    let c = vec![T::zero(); n];
    row_responses(am, &c, &[&zeros], o, out);
}

/// `row_responses` for up to `WIDE` inputs and an order known at compile time.
fn rows_fixed<T: Real, const N: usize>(
    am: &[T],
    cv: &[T],
    f: &[&[T]],
    z0: &mut [T],
    out: &mut [&mut [T]],
) {
    let g_count = f.len().min(WIDE).min(out.len() / N).min(z0.len() / N);
    let len = f.first().map_or(0, |c| c.len());
    let a: [[T; N]; N] = std::array::from_fn(|i| std::array::from_fn(|j| am[i * N + j]));
    let c: [T; N] = std::array::from_fn(|j| cv[j]);
    let fs: Vec<&[T]> = f[..g_count].iter().map(|c| &c[..len]).collect();
    let mut z = [[T::zero(); N]; WIDE];
    for g in 0..g_count {
        z[g] = std::array::from_fn(|p| z0[g * N + p]);
    }
    for k in 0..len {
        for g in 0..g_count {
            for p in 0..N {
                out[g * N + p][k] = z[g][p];
            }
            let fk = fs[g][k];
            z[g] = std::array::from_fn(|j| {
                let mut s = fk * c[j];
                for i in 0..N {
                    s += z[g][i] * a[i][j];
                }
                s
            });
        }
    }
    for g in 0..g_count {
        z0[g * N..(g + 1) * N].copy_from_slice(&z[g]);
    }
}

/// `row_responses` of one input for any order.
fn rows_dyn<T: Real>(am: &[T], c: &[T], f: &[T], z: &mut [T], out: &mut [&mut [T]]) {
    let n = c.len();
    let mut zn = vec![T::zero(); n];
    for (k, &fk) in f.iter().enumerate() {
        for p in 0..n {
            out[p][k] = z[p];
        }
        for (j, zj) in zn.iter_mut().enumerate() {
            let mut s = fk * c[j];
            for (i, &zi) in z.iter().enumerate() {
                s += zi * am[i * n + j];
            }
            *zj = s;
        }
        z.copy_from_slice(&zn);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The same recursions by plain loops, for comparison.
    fn reference(am: &[f64], c: &[f64], f: &[f64], z0: &[f64]) -> (Vec<Vec<f64>>, Vec<f64>) {
        let n = c.len();
        let mut z = z0.to_vec();
        let mut out = vec![vec![0.0; f.len()]; n];
        for (k, &fk) in f.iter().enumerate() {
            for p in 0..n {
                out[p][k] = z[p];
            }
            z = (0..n)
                .map(|j| fk * c[j] + (0..n).map(|i| z[i] * am[i * n + j]).sum::<f64>())
                .collect();
        }
        (out, z)
    }

    #[test]
    fn grouped_chunked_recursions_match_plain_loops() {
        for n in 1..=6 {
            let am: Vec<f64> = (0..n * n)
                .map(|k| 0.3 * ((k * 7 % 5) as f64 - 2.0) / n as f64)
                .collect();
            let c: Vec<f64> = (0..n).map(|j| 1.0 - 0.2 * j as f64).collect();
            // 11 inputs: a full group of 8 and a partial one
            let inputs: Vec<Vec<f64>> = (0..11)
                .map(|g| (0..50).map(|k| ((k * (g + 3)) % 13) as f64 - 6.0).collect())
                .collect();
            let z0: Vec<f64> = (0..11 * n).map(|k| 0.1 * k as f64).collect();
            // in two chunks of 30 and 20 samples, the state carried
            let mut z = z0.clone();
            let mut cols = vec![vec![0.0; 50]; 11 * n];
            for (lo, hi) in [(0, 30), (30, 50)] {
                let fs: Vec<&[f64]> = inputs.iter().map(|f| &f[lo..hi]).collect();
                let mut outs: Vec<&mut [f64]> = cols.iter_mut().map(|c| &mut c[lo..hi]).collect();
                row_responses(&am, &c, &fs, &mut z, &mut outs);
            }
            for (g, f) in inputs.iter().enumerate() {
                let (out, zend) = reference(&am, &c, f, &z0[g * n..(g + 1) * n]);
                for p in 0..n {
                    for k in 0..50 {
                        assert!((cols[g * n + p][k] - out[p][k]).abs() < 1e-12, "n {n}");
                    }
                    assert!((z[g * n + p] - zend[p]).abs() < 1e-12);
                }
            }
            // free rows: c A^k
            let mut o = c.clone();
            let mut cols = vec![vec![0.0; 40]; n];
            let mut outs: Vec<&mut [f64]> = cols.iter_mut().map(|c| c.as_mut_slice()).collect();
            free_rows(&am, &mut o, &mut outs);
            let (out, _) = reference(&am, &vec![0.0; n], &[0.0; 40], &c);
            for p in 0..n {
                for k in 0..40 {
                    assert!((cols[p][k] - out[p][k]).abs() < 1e-12);
                }
            }
        }
    }
}
