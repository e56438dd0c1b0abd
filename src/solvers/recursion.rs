//! The simulation kernels: one state-space recursion x(k+1) = A x(k) + B u(k) that every
//! simulation of the crate runs (`StateSpace::simulate`, the loop's block outputs and
//! simulations, the Markov parameters, the regressors of the B/D/x0 least squares), and one
//! transfer-function filter y = b(z)/a(z) x (the refinement's simulation and Jacobian).
//!
//! The state recursion hands each sample's state to a readout closure before the update, so the
//! callers differ only in what they read: y = offset + D u + C x (a block's output), the state
//! itself (the regressors), C x (Markov parameters). The sums are formed in one of two orders
//! ([`InputFirst`](SumOrder::InputFirst): B u, then A x; [`StateFirst`](SumOrder::StateFirst):
//! A x, then B u), each caller keeping the order it always had, so the results are bit-identical
//! to the loops this kernel replaced.
//!
//! Row-vector recursions of the least-squares steps that fix A and C (the loop's B/x0 step, the
//! subspace B/D/x0 step): with the output row c, the response of y to a unit entry p of B driven
//! by input f is z(k)_p with z(k+1) = z(k) A + f(k) c, and the free response to a unit initial
//! state j is o(k)_j with o(k+1) = o(k) A, o(0) = c (the rows c A^k; SLICOT IB01CD builds the
//! same regressors by simulation). They are the state recursion with Aᵀ and the input vector cᵀ,
//! reading the whole state.
//!
//! Each recursion is a serial chain of dependent multiply-adds (latency-bound), so up to `WIDE`
//! single-input chains run in one loop, where they overlap in the pipeline (2–3× faster than one
//! by one); orders 1–4 are compiled with fixed-size arrays. A is row-major (`am[i·n + j]`).

use crate::real::Real;

/// Inputs whose recursions run in one pass.
pub(crate) const WIDE: usize = 8;

/// The order in which the kernel sums a state update x(k+1)_i = Σ_j A_ij x_j + Σ_q B_iq u_q.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum SumOrder {
    /// B u first (its first product starting the sum), then A x: the loop's blocks and the row
    /// recursions.
    InputFirst,
    /// From zero, A x first, then B u: `StateSpace::simulate` and the Markov parameters.
    StateFirst,
}

/// The state recursion x(k+1) = A x(k) + B u(k) for any order n = `x.len()` and m =
/// `u.len()` inputs (A n×n and B n×m row-major, `u[q]` input q's samples), from the state `x`
/// (which holds the final state on return): `read(k, x(k), u(k))` sees each sample before the
/// update. The sums are ordered by `order`.
pub(crate) fn state_recursion<T: Real>(
    a: &[T],
    b: &[T],
    u: &[&[T]],
    len: usize,
    order: SumOrder,
    x: &mut [T],
    mut read: impl FnMut(usize, &[T], &[T]),
) {
    let n = x.len();
    let m = u.len();
    let mut cur = x.to_vec();
    let mut next = vec![T::zero(); n];
    let mut uk = vec![T::zero(); m];
    for k in 0..len {
        for (q, v) in uk.iter_mut().enumerate() {
            *v = u[q][k];
        }
        read(k, &cur, &uk);
        for (i, xi) in next.iter_mut().enumerate() {
            let (ar, br) = (&a[i * n..(i + 1) * n], &b[i * m..(i + 1) * m]);
            let mut t = T::zero();
            if order == SumOrder::InputFirst && m > 0 {
                t = br[0] * uk[0];
                for q in 1..m {
                    t += br[q] * uk[q];
                }
            }
            for j in 0..n {
                t += ar[j] * cur[j];
            }
            if order == SumOrder::StateFirst {
                for q in 0..m {
                    t += br[q] * uk[q];
                }
            }
            *xi = t;
        }
        std::mem::swap(&mut cur, &mut next);
    }
    x.copy_from_slice(&cur);
}

/// The kernel's fast path: up to `WIDE` single-input chains x_g(k+1) = A x_g(k) + b f_g(k)
/// (sums in the [`InputFirst`](SumOrder::InputFirst) order) of an order N known at compile
/// time, from the states `x[g]`; `read(g, k, x_g(k), f_g(k))` sees each sample before the
/// update. The chains are interleaved sample by sample.
fn chains<T: Real, const N: usize>(
    a: &[[T; N]; N],
    b: &[T; N],
    f: &[&[T]],
    x: &mut [[T; N]],
    mut read: impl FnMut(usize, usize, &[T; N], T),
) {
    let g_count = f.len().min(WIDE).min(x.len());
    let len = f.first().map_or(0, |c| c.len());
    let fs: Vec<&[T]> = f[..g_count].iter().map(|c| &c[..len]).collect();
    for k in 0..len {
        for g in 0..g_count {
            let fk = fs[g][k];
            read(g, k, &x[g], fk);
            let xg = x[g];
            x[g] = std::array::from_fn(|i| {
                let mut t = b[i] * fk;
                for j in 0..N {
                    t += a[i][j] * xg[j];
                }
                t
            });
        }
    }
}

/// A single-input single-output block (A row-major, b, c, d) plus an output offset.
pub(crate) struct SisoBlock<'a, T> {
    /// A, n×n row-major.
    pub a: &'a [T],
    /// The input vector, n.
    pub b: &'a [T],
    /// The output row, n.
    pub c: &'a [T],
    /// Feed-through.
    pub d: T,
    /// Added to every output.
    pub offset: T,
}

impl<T: Real> SisoBlock<'_, T> {
    /// Simulates the block from the state `x0` once per input `f[g]` into `out[g]`:
    /// out_g(k) = offset + d f_g(k) + C x_g(k), x_g(k+1) = b f_g(k) + A x_g(k).
    pub(crate) fn run_many(&self, x0: &[T], f: &[&[T]], out: &mut [&mut [T]]) {
        match self.b.len() {
            1 => self.run::<1>(x0, f, out),
            2 => self.run::<2>(x0, f, out),
            3 => self.run::<3>(x0, f, out),
            4 => self.run::<4>(x0, f, out),
            _ => {
                for (f, o) in f.iter().zip(out.iter_mut()) {
                    let mut x = x0.to_vec();
                    state_recursion(
                        self.a,
                        self.b,
                        &[f],
                        f.len().min(o.len()),
                        SumOrder::InputFirst,
                        &mut x,
                        |k, x, uk| o[k] = self.output(x, uk[0]),
                    );
                }
            }
        }
    }

    /// `run_many` of one input whose output overwrites it: `buf` holds f on entry and the output
    /// on return, from the state `x0`. The samples are copied out block by block and the state
    /// carried from block to block, so the bits are those of `run_many` and the record needs
    /// one signal, not two.
    pub(crate) fn run_in_place(&self, x0: &[T], buf: &mut [T]) {
        const BLOCK: usize = 4096;
        let mut x = x0.to_vec();
        let mut f = vec![T::zero(); BLOCK.min(buf.len())];
        for out in buf.chunks_mut(BLOCK) {
            let f = &mut f[..out.len()];
            f.copy_from_slice(out);
            match self.b.len() {
                1 => self.carry::<1>(&mut x, f, out),
                2 => self.carry::<2>(&mut x, f, out),
                3 => self.carry::<3>(&mut x, f, out),
                4 => self.carry::<4>(&mut x, f, out),
                _ => state_recursion(
                    self.a,
                    self.b,
                    &[f],
                    f.len(),
                    SumOrder::InputFirst,
                    &mut x,
                    |k, x, uk| out[k] = self.output(x, uk[0]),
                ),
            }
        }
    }

    /// One block of `run_in_place` for an order known at compile time (the sums of `run`),
    /// from the state `x`, which holds the state after the block on return.
    fn carry<const N: usize>(&self, x: &mut [T], f: &[T], out: &mut [T]) {
        let a: [[T; N]; N] = std::array::from_fn(|i| std::array::from_fn(|j| self.a[i * N + j]));
        let b: [T; N] = std::array::from_fn(|i| self.b[i]);
        let c: [T; N] = std::array::from_fn(|i| self.c[i]);
        let mut xs = [std::array::from_fn::<T, N, _>(|i| x[i])];
        chains(&a, &b, &[f], &mut xs, |_, k, xg, fk| {
            let mut s = self.offset + self.d * fk;
            for j in 0..N {
                s += c[j] * xg[j];
            }
            out[k] = s;
        });
        x.copy_from_slice(&xs[0]);
    }

    /// offset + d·f + C x, summed in that order.
    fn output(&self, x: &[T], f: T) -> T {
        let mut s = self.offset + self.d * f;
        for (cj, xj) in self.c.iter().zip(x) {
            s += *cj * *xj;
        }
        s
    }

    /// `run_many` for an order known at compile time, `WIDE` inputs per pass.
    fn run<const N: usize>(&self, x0: &[T], f: &[&[T]], out: &mut [&mut [T]]) {
        let a: [[T; N]; N] = std::array::from_fn(|i| std::array::from_fn(|j| self.a[i * N + j]));
        let b: [T; N] = std::array::from_fn(|i| self.b[i]);
        let c: [T; N] = std::array::from_fn(|i| self.c[i]);
        for (f, out) in f.chunks(WIDE).zip(out.chunks_mut(WIDE)) {
            let mut x = [[T::zero(); N]; WIDE];
            for xg in x.iter_mut().take(f.len()) {
                *xg = std::array::from_fn(|i| x0[i]);
            }
            chains(&a, &b, f, &mut x, |g, k, xg, fk| {
                let mut s = self.offset + self.d * fk;
                for j in 0..N {
                    s += c[j] * xg[j];
                }
                out[g][k] = s;
            });
        }
    }
}

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
    match n {
        1 => rows_fixed::<T, 1>(am, c, f, z, out),
        2 => rows_fixed::<T, 2>(am, c, f, z, out),
        3 => rows_fixed::<T, 3>(am, c, f, z, out),
        4 => rows_fixed::<T, 4>(am, c, f, z, out),
        _ => {
            // the row recursion is the state recursion with Aᵀ (products commute: the sums are
            // those of z A term by term)
            let at: Vec<T> = (0..n * n).map(|k| am[(k % n) * n + k / n]).collect();
            for ((f, z), o) in f.iter().zip(z.chunks_mut(n)).zip(out.chunks_mut(n)) {
                state_recursion(&at, c, &[f], f.len(), SumOrder::InputFirst, z, |k, z, _| {
                    for p in 0..n {
                        o[p][k] = z[p];
                    }
                });
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

/// `row_responses` for an order known at compile time, `WIDE` inputs per pass.
fn rows_fixed<T: Real, const N: usize>(
    am: &[T],
    cv: &[T],
    f: &[&[T]],
    z0: &mut [T],
    out: &mut [&mut [T]],
) {
    // Aᵀ: the row recursion z A is the state recursion Aᵀ z (products commute)
    let at: [[T; N]; N] = std::array::from_fn(|j| std::array::from_fn(|i| am[i * N + j]));
    let c: [T; N] = std::array::from_fn(|j| cv[j]);
    for ((f, z0), out) in f
        .chunks(WIDE)
        .zip(z0.chunks_mut(WIDE * N))
        .zip(out.chunks_mut(WIDE * N))
    {
        let g_count = f.len().min(out.len() / N).min(z0.len() / N);
        let mut z = [[T::zero(); N]; WIDE];
        for g in 0..g_count {
            z[g] = std::array::from_fn(|p| z0[g * N + p]);
        }
        chains(&at, &c, &f[..g_count], &mut z, |g, k, zg, _| {
            for p in 0..N {
                out[g * N + p][k] = zg[p];
            }
        });
        for g in 0..g_count {
            z0[g * N..(g + 1) * N].copy_from_slice(&z[g]);
        }
    }
}

/// The transfer-function filter y = b(z)/a(z) x (coefficients in powers of z⁻¹, a₀ = 1, b with
/// at most n + 1 entries) as the difference equation
/// y(k) = Σ_i b_i x(k−i) [+ q(k)] − Σ_{i≥1} a_i y(k−i), run block after block with its last n
/// inputs and outputs carried over (zero before the record); q(k) is an optional additive
/// sequence (the free response's numerator, entered as q(z)·δ).
pub(crate) struct TfFilter<T: Real> {
    x_hist: Vec<T>,
    y_hist: Vec<T>,
    /// Samples filtered so far (the index of q).
    done: usize,
}

impl<T: Real> TfFilter<T> {
    /// A filter of order n at rest.
    pub(crate) fn new(n: usize) -> Self {
        Self {
            x_hist: vec![T::zero(); n],
            y_hist: vec![T::zero(); n],
            done: 0,
        }
    }

    /// The outputs for the next block of inputs `x`, preceded by the n outputs before it (oldest
    /// first): entry n + t is the output at the block's sample t.
    pub(crate) fn run(&mut self, a: &[T], b: &[T], x: &[T]) -> Vec<T> {
        self.run_with(a, b, &[], x)
    }

    /// [`run`](Self::run) with q(k) added after the numerator's sum at the samples k <
    /// `q.len()` (counted from the record's start).
    pub(crate) fn run_with(&mut self, a: &[T], b: &[T], q: &[T], x: &[T]) -> Vec<T> {
        match a.len() - 1 {
            1 => self.run_fixed::<1>(a, b, q, x),
            2 => self.run_fixed::<2>(a, b, q, x),
            3 => self.run_fixed::<3>(a, b, q, x),
            4 => self.run_fixed::<4>(a, b, q, x),
            _ => self.run_dyn(a, b, q, x),
        }
    }

    /// [`run_with`](Self::run_with) for the order `N` known at compile time: the denominator
    /// and the last `N` outputs in registers, the same sums in the same order as
    /// [`run_dyn`](Self::run_dyn) (the same bits).
    fn run_fixed<const N: usize>(&mut self, a: &[T], b: &[T], q: &[T], x: &[T]) -> Vec<T> {
        let m = x.len();
        let av: [T; N] = std::array::from_fn(|i| a[i + 1]);
        // yh[i] = y(k − 1 − i)
        let mut yh: [T; N] = std::array::from_fn(|i| self.y_hist[N - 1 - i]);
        let mut ye = Vec::with_capacity(N + m);
        ye.extend_from_slice(&self.y_hist);
        let nb = b.len().min(N + 1);
        // the samples at which q(k) is added
        let qn = q.len().saturating_sub(self.done).min(m);
        let q = &q[q.len().min(self.done)..];
        let head = N.min(m);
        let xh = &self.x_hist;
        for t in 0..m {
            let mut s = T::zero();
            if t < head {
                for (i, &bi) in b[..nb].iter().enumerate() {
                    let k = N + t - i;
                    s += bi * if k < N { xh[k] } else { x[k - N] };
                }
            } else if nb == 1 {
                s += b[0] * x[t];
            } else {
                for (i, &bi) in b[..nb].iter().enumerate() {
                    s += bi * x[t - i];
                }
            }
            if t < qn {
                s += q[t];
            }
            for i in 0..N {
                s -= av[i] * yh[i];
            }
            for i in (1..N).rev() {
                yh[i] = yh[i - 1];
            }
            yh[0] = s;
            ye.push(s);
        }
        let hist: [T; N] = std::array::from_fn(|i| {
            let k = m + i;
            if k < N { self.x_hist[k] } else { x[k - N] }
        });
        self.x_hist.copy_from_slice(&hist);
        self.y_hist.copy_from_slice(&ye[m..m + N]);
        self.done += m;
        ye
    }

    /// [`run_with`](Self::run_with) for any order.
    fn run_dyn(&mut self, a: &[T], b: &[T], q: &[T], x: &[T]) -> Vec<T> {
        let n = a.len() - 1;
        let m = x.len();
        // the input is read in place (no copy behind its history: long records keep one
        // signal less); entry k of the extended input [history, x] is `xe(k)`
        let xe = |k: usize| if k < n { self.x_hist[k] } else { x[k - n] };
        let mut ye = Vec::with_capacity(n + m);
        ye.extend_from_slice(&self.y_hist);
        ye.resize(n + m, T::zero());
        let nb = b.len().min(n + 1);
        // the first n samples reach into the history, the others read x alone (the same sums,
        // in the same order)
        let head = n.min(m);
        for t in 0..head {
            let k = n + t;
            let mut s = T::zero();
            for i in 0..nb {
                s += b[i] * xe(k - i);
            }
            if let Some(&qk) = q.get(self.done + t) {
                s += qk;
            }
            for i in 1..=n {
                s -= a[i] * ye[k - i];
            }
            ye[k] = s;
        }
        for t in head..m {
            let k = n + t;
            let mut s = T::zero();
            for i in 0..nb {
                s += b[i] * x[t - i];
            }
            if let Some(&qk) = q.get(self.done + t) {
                s += qk;
            }
            for i in 1..=n {
                s -= a[i] * ye[k - i];
            }
            ye[k] = s;
        }
        let hist: Vec<T> = (m..m + n).map(xe).collect();
        self.x_hist.copy_from_slice(&hist);
        self.y_hist.copy_from_slice(&ye[m..m + n]);
        self.done += m;
        ye
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The in-place run, its blocks carrying the state, gives the bits of `run_many` for the
    /// fixed-size orders and the general one, over several blocks and a ragged last one.
    #[test]
    fn the_in_place_run_gives_the_bits_of_run_many() {
        let len = 3 * 4096 + 77;
        let f: Vec<f64> = (0..len)
            .map(|k| ((k * k) as f64 * 0.011 + k as f64 * 0.3).sin())
            .collect();
        for n in [1usize, 2, 4, 6] {
            // a stable A: 0.9 on the diagonal, small couplings
            let a: Vec<f64> = (0..n * n)
                .map(|k| {
                    if k / n == k % n {
                        0.9
                    } else {
                        0.05 * ((k % 7) as f64 - 3.0) / 3.0
                    }
                })
                .collect();
            let b: Vec<f64> = (0..n).map(|i| 1.0 + 0.1 * i as f64).collect();
            let c: Vec<f64> = (0..n).map(|i| 0.5 - 0.2 * i as f64).collect();
            let x0: Vec<f64> = (0..n).map(|i| 0.3 * i as f64 - 0.1).collect();
            let blk = SisoBlock {
                a: &a,
                b: &b,
                c: &c,
                d: 0.25,
                offset: -0.4,
            };
            let mut whole = vec![0.0; len];
            blk.run_many(&x0, &[&f], &mut [whole.as_mut_slice()]);
            let mut buf = f.clone();
            blk.run_in_place(&x0, &mut buf);
            assert!(
                whole
                    .iter()
                    .zip(&buf)
                    .all(|(p, q)| p.to_bits() == q.to_bits()),
                "order {n}"
            );
        }
    }

    /// `TfFilter::run_with` as written before it read its input in place (the input copied
    /// behind its history): the filter must give the same bits, whatever the block sizes.
    fn old_tf(a: &[f64], b: &[f64], q: &[f64], x: &[f64]) -> Vec<f64> {
        let n = a.len() - 1;
        let mut xe = vec![0.0; n];
        xe.extend_from_slice(x);
        let mut ye = vec![0.0; n + x.len()];
        let nb = b.len().min(n + 1);
        for t in 0..x.len() {
            let k = n + t;
            let mut s = 0.0;
            for i in 0..nb {
                s += b[i] * xe[k - i];
            }
            if let Some(&qk) = q.get(t) {
                s += qk;
            }
            for i in 1..=n {
                s -= a[i] * ye[k - i];
            }
            ye[k] = s;
        }
        ye
    }

    #[test]
    fn tf_filter_blocks_match_the_whole_run_bit_for_bit() {
        let a_all = [1.0, -0.7, 0.2, -0.05, 0.01, -0.003];
        let b_all = [0.3, 1.0, -0.4, 0.25, 0.1, -0.05];
        let x: Vec<f64> = (0..50)
            .map(|k| ((k * 7919) % 13) as f64 / 3.0 - 2.0)
            .collect();
        // orders 0 to 5 (the fixed-order paths 1–4 and the general one), full numerators and
        // the single-coefficient one of the Jacobian's filters, with and without q
        for n in 0..=5 {
            let a = &a_all[..=n];
            let q: Vec<f64> = (0..n).map(|i| 0.5 - 0.2 * i as f64).collect();
            for b in [&b_all[..=n], &[1.0][..]] {
                for q in [&q[..], &[][..]] {
                    let whole = old_tf(a, b, q, &x);
                    for block in [1, 2, 3, 4, 7, 50] {
                        let mut f = TfFilter::<f64>::new(n);
                        let mut got = Vec::new();
                        for chunk in x.chunks(block) {
                            let out = f.run_with(a, b, q, chunk);
                            got.extend_from_slice(&out[n..]);
                        }
                        assert_eq!(got.len(), x.len());
                        for (g, w) in got.iter().zip(&whole[n..]) {
                            assert_eq!(g.to_bits(), w.to_bits(), "order {n}, block {block}");
                        }
                    }
                }
            }
        }
    }

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

    /// The loops the kernel replaced, as written before (`linear_ls::SiBlock::run_dyn`,
    /// `rows_dyn`, `StateSpace::simulate`'s body for one input and output): the kernel must
    /// give the same bits.
    fn old_block(
        am: &[f64],
        b: &[f64],
        c: &[f64],
        d: f64,
        off: f64,
        x0: &[f64],
        v: &[f64],
    ) -> Vec<f64> {
        let n = b.len();
        let (mut x, mut xn, mut out) = (x0.to_vec(), vec![0.0; n], vec![0.0; v.len()]);
        for (o, &vk) in out.iter_mut().zip(v) {
            let mut s = off + d * vk;
            for j in 0..n {
                s += c[j] * x[j];
            }
            *o = s;
            for (i, xi) in xn.iter_mut().enumerate() {
                let mut t = b[i] * vk;
                for j in 0..n {
                    t += am[i * n + j] * x[j];
                }
                *xi = t;
            }
            std::mem::swap(&mut x, &mut xn);
        }
        out
    }

    fn old_rows(am: &[f64], c: &[f64], f: &[f64], z: &mut [f64], out: &mut [Vec<f64>]) {
        let n = c.len();
        let mut zn = vec![0.0; n];
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

    fn old_state_space(
        am: &[f64],
        b: &[f64],
        c: &[f64],
        d: f64,
        x0: &[f64],
        u: &[f64],
    ) -> Vec<f64> {
        let n = b.len();
        let (mut x, mut xn, mut y) = (x0.to_vec(), vec![0.0; n], vec![0.0; u.len()]);
        for k in 0..u.len() {
            let mut s = 0.0;
            for j in 0..n {
                s += c[j] * x[j];
            }
            s += d * u[k];
            y[k] = s;
            for i in 0..n {
                let mut s = 0.0;
                for j in 0..n {
                    s += am[i * n + j] * x[j];
                }
                s += b[i] * u[k];
                xn[i] = s;
            }
            std::mem::swap(&mut x, &mut xn);
        }
        y
    }

    #[test]
    fn the_kernel_gives_the_bits_of_the_loops_it_replaced() {
        for n in 1..=7 {
            let am: Vec<f64> = (0..n * n)
                .map(|k| 0.31 * ((k * 7 % 5) as f64 - 2.03) / n as f64)
                .collect();
            let b: Vec<f64> = (0..n).map(|j| 0.7 + 0.13 * j as f64).collect();
            let c: Vec<f64> = (0..n).map(|j| 1.0 - 0.21 * j as f64).collect();
            let x0: Vec<f64> = (0..n).map(|j| 0.1 * j as f64 - 0.17).collect();
            let v: Vec<f64> = (0..300)
                .map(|k| ((k * 31 % 17) as f64 - 8.0) / 3.0)
                .collect();
            let blk = SisoBlock {
                a: &am,
                b: &b,
                c: &c,
                d: 0.3,
                offset: 0.7,
            };
            let mut out = vec![vec![0.0; v.len()]; 3];
            let mut outs: Vec<&mut [f64]> = out.iter_mut().map(|o| o.as_mut_slice()).collect();
            blk.run_many(&x0, &[&v, &v, &v], &mut outs);
            let want = old_block(&am, &b, &c, 0.3, 0.7, &x0, &v);
            assert!(out.iter().all(|o| *o == want), "block, n {n}");
            // the row recursion
            let (mut z, mut z_old) = (x0.clone(), x0.clone());
            let mut cols = vec![vec![0.0; v.len()]; n];
            let mut outs: Vec<&mut [f64]> = cols.iter_mut().map(|c| c.as_mut_slice()).collect();
            row_responses(&am, &c, &[&v], &mut z, &mut outs);
            let mut want = vec![vec![0.0; v.len()]; n];
            old_rows(&am, &c, &v, &mut z_old, &mut want);
            assert!(cols == want && z == z_old, "rows, n {n}");
            // the state-space order
            let mut x = x0.clone();
            let mut y = vec![0.0; v.len()];
            state_recursion(
                &am,
                &b,
                &[&v],
                v.len(),
                SumOrder::StateFirst,
                &mut x,
                |k, x, uk| {
                    let mut s = 0.0;
                    for j in 0..n {
                        s += c[j] * x[j];
                    }
                    s += 0.3 * uk[0];
                    y[k] = s;
                },
            );
            assert!(
                y == old_state_space(&am, &b, &c, 0.3, &x0, &v),
                "state space, n {n}"
            );
        }
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
