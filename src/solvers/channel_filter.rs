//! Several signals through one transfer function b(z)/a(z) at once: the refinement's Jacobian
//! columns of the nonlinearity's parameters, ∂ŷ/∂θ_j = (b/a)·∂v/∂θ_j, all share the block's
//! filter. The difference equation is a serial recursion whose speed is bound by the latency of
//! each output's dependence on the previous ones; interleaving independent channels sample by
//! sample lets the processor overlap them. Every channel's sums are formed exactly as
//! `solvers/recursion.rs::TfFilter` forms them (numerator terms in order, then the denominator's
//! in order, from zero), so the columns are the same bits as one `TfFilter` per column.

use crate::real::Real;
use crate::solvers::recursion::TfFilter;

/// Filters of order n for several channels, run block after block with each channel's last n
/// inputs and outputs carried over (zero before the record).
pub(crate) struct ChannelFilter<T: Real> {
    n: usize,
    /// Per channel: the last n inputs, then the last n outputs (oldest first).
    hist: Vec<(Vec<T>, Vec<T>)>,
    /// Orders above 4: one `TfFilter` per channel.
    fallback: Vec<TfFilter<T>>,
}

impl<T: Real> ChannelFilter<T> {
    /// `channels` filters of order `n` at rest.
    pub(crate) fn new(n: usize, channels: usize) -> Self {
        let fixed = (1..=4).contains(&n);
        Self {
            n,
            hist: if fixed {
                vec![(vec![T::zero(); n], vec![T::zero(); n]); channels]
            } else {
                Vec::new()
            },
            fallback: if fixed {
                Vec::new()
            } else {
                (0..channels).map(|_| TfFilter::new(n)).collect()
            },
        }
    }

    /// Filters the next block of every channel: `input(c)` is channel c's block (all of the
    /// same length m) and `out(c, t, y)` receives its output at the block's sample t.
    pub(crate) fn run<'x>(
        &mut self,
        a: &[T],
        b: &[T],
        input: impl Fn(usize) -> &'x [T],
        out: impl FnMut(usize, usize, T),
    ) where
        T: 'x,
    {
        match self.n {
            1 => self.run_fixed::<1>(a, b, input, out),
            2 => self.run_fixed::<2>(a, b, input, out),
            3 => self.run_fixed::<3>(a, b, input, out),
            4 => self.run_fixed::<4>(a, b, input, out),
            _ => self.run_each(a, b, input, out),
        }
    }

    /// [`run`](Self::run) returning every channel's outputs preceded by its n outputs before
    /// the block (oldest first), as `TfFilter::run` does.
    pub(crate) fn run_extended<'x>(
        &mut self,
        a: &[T],
        b: &[T],
        input: impl Fn(usize) -> &'x [T],
    ) -> Vec<Vec<T>>
    where
        T: 'x,
    {
        if !self.fallback.is_empty() {
            return (self.fallback.iter_mut().enumerate())
                .map(|(c, f)| f.run(a, b, input(c)))
                .collect();
        }
        let n = self.n;
        let mut ys: Vec<Vec<T>> = (self.hist.iter().enumerate())
            .map(|(c, (_, yh))| {
                let mut y = Vec::with_capacity(n + input(c).len());
                y.extend_from_slice(yh);
                y.resize(n + input(c).len(), T::zero());
                y
            })
            .collect();
        self.run(a, b, input, |c, t, v| ys[c][n + t] = v);
        ys
    }

    /// Orders above 4: each channel by its own `TfFilter`.
    fn run_each<'x>(
        &mut self,
        a: &[T],
        b: &[T],
        input: impl Fn(usize) -> &'x [T],
        mut out: impl FnMut(usize, usize, T),
    ) where
        T: 'x,
    {
        let n = self.n;
        for (c, f) in self.fallback.iter_mut().enumerate() {
            let x = input(c);
            let y = f.run(a, b, x);
            for t in 0..x.len() {
                out(c, t, y[n + t]);
            }
        }
    }

    /// The channels interleaved sample by sample, order `N` known at compile time: channel c's
    /// output at sample t is Σ_i b_i x_c(t − i) − Σ_{i≥1} a_i y_c(t − i), summed from zero in
    /// that order (`TfFilter::run_with`'s sums).
    fn run_fixed<'x, const N: usize>(
        &mut self,
        a: &[T],
        b: &[T],
        input: impl Fn(usize) -> &'x [T],
        mut out: impl FnMut(usize, usize, T),
    ) where
        T: 'x,
    {
        let chans = self.hist.len();
        if chans == 0 {
            return;
        }
        let av: [T; N] = std::array::from_fn(|i| a[i + 1]);
        let nb = b.len().min(N + 1);
        let xs: Vec<&[T]> = (0..chans).map(&input).collect();
        let m = xs[0].len();
        // per channel: yh[i] = y(k − 1 − i)
        let mut yh: Vec<[T; N]> = self
            .hist
            .iter()
            .map(|(_, y)| std::array::from_fn(|i| y[N - 1 - i]))
            .collect();
        for t in 0..m {
            for (c, x) in xs.iter().enumerate() {
                let xh = &self.hist[c].0;
                let mut s = T::zero();
                for (i, &bi) in b[..nb].iter().enumerate() {
                    let xv = if t >= i { x[t - i] } else { xh[N + t - i] };
                    s += bi * xv;
                }
                let y = &mut yh[c];
                for i in 0..N {
                    s -= av[i] * y[i];
                }
                for i in (1..N).rev() {
                    y[i] = y[i - 1];
                }
                y[0] = s;
                out(c, t, s);
            }
        }
        for (c, (xh, yhist)) in self.hist.iter_mut().enumerate() {
            let x = xs[c];
            let next: [T; N] = std::array::from_fn(|i| {
                let k = m + i;
                if k < N { xh[k] } else { x[k - N] }
            });
            xh.copy_from_slice(&next);
            for i in 0..N {
                yhist[i] = yh[c][N - 1 - i];
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The channels' outputs are `TfFilter`'s bit for bit, over two blocks (history carried),
    /// for orders 1–5.
    #[test]
    fn same_bits_as_one_filter_per_channel() {
        let sig =
            |c: usize, k: usize| ((k * 7 + c * 13) % 17) as f64 * 0.37 - 2.0 + (k as f64).sin();
        for n in 1..=5 {
            let a: Vec<f64> = (0..=n)
                .map(|i| if i == 0 { 1.0 } else { 0.3 / i as f64 - 0.1 })
                .collect();
            let b: Vec<f64> = (0..=n).map(|i| 0.5 - 0.2 * i as f64).collect();
            let x: Vec<Vec<f64>> = (0..3)
                .map(|c| (0..50).map(|k| sig(c, k)).collect())
                .collect();
            let mut cf = ChannelFilter::new(n, 3);
            let mut got = vec![vec![0.0; 50]; 3];
            for (k0, k1) in [(0, 2), (2, 50)] {
                cf.run(&a, &b, |c| &x[c][k0..k1], |c, t, y| got[c][k0 + t] = y);
            }
            for c in 0..3 {
                let mut f = TfFilter::new(n);
                let mut want = f.run(&a, &b, &x[c][..2]);
                want.drain(..n);
                let mut w2 = f.run(&a, &b, &x[c][2..]);
                want.extend(w2.drain(n..));
                assert_eq!(got[c], want, "order {n}, channel {c}");
            }
            // the extended form: the outputs before each block first, as `TfFilter::run`
            let mut cf = ChannelFilter::new(n, 3);
            let mut fs: Vec<TfFilter<f64>> = (0..3).map(|_| TfFilter::new(n)).collect();
            for (k0, k1) in [(0, 2), (2, 50)] {
                let got = cf.run_extended(&a, &b, |c| &x[c][k0..k1]);
                for (c, f) in fs.iter_mut().enumerate() {
                    assert_eq!(
                        got[c],
                        f.run(&a, &b, &x[c][k0..k1]),
                        "order {n}, channel {c}"
                    );
                }
            }
        }
    }
}
