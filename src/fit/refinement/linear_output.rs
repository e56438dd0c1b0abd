//! The refinement's linear output y_lin = [b(z) v + q(z) δ]/a(z) (the parametrisation of
//! `refine.rs`), given whole or filtered block by block, and its MSE against a record.
//!
//! Algorithm: the difference equation of [`TfFilter`], run block after block with its last n
//! inputs and outputs carried over. The blocks give the bits of one run over the whole record
//! (`TfFilter`'s own test), so a long record's linear output need not be stored: the MSE of a
//! point and the rows of its Jacobian read it one block at a time, and a refinement on the
//! whole record holds one signal (v) instead of two.

use crate::real::Real;
use crate::solvers::recursion::TfFilter;
use crate::solvers::tsqr::BLOCK_ROWS;
use std::borrow::Cow;

/// The linear output of a point on a record: a given signal, or filtered from v as it is read.
pub(in crate::fit) enum LinearOutput<'a, T: Real> {
    /// The whole signal.
    Given(&'a [T]),
    /// [b(z) v + q(z) δ]/a(z), filtered block by block (the blocks read in order from 0).
    Filtered {
        a: &'a [T],
        b: &'a [T],
        q: &'a [T],
        v: &'a [T],
        filter: TfFilter<T>,
    },
}

impl<'a, T: Real> LinearOutput<'a, T> {
    /// [b(z) v + q(z) δ]/a(z) filtered from rest, block by block.
    pub(in crate::fit) fn filtered(a: &'a [T], b: &'a [T], q: &'a [T], v: &'a [T]) -> Self {
        LinearOutput::Filtered {
            a,
            b,
            q,
            v,
            filter: TfFilter::new(a.len() - 1),
        }
    }

    /// The samples `k0..k1` (a filtered output: the block after the last one read, from 0).
    pub(in crate::fit) fn block(&mut self, k0: usize, k1: usize) -> Cow<'a, [T]> {
        match self {
            LinearOutput::Given(s) => Cow::Borrowed(&s[k0..k1]),
            LinearOutput::Filtered { a, b, q, v, filter } => {
                let mut out = filter.run_with(a, b, q, &v[k0..k1]);
                out.drain(..a.len() - 1);
                Cow::Owned(out)
            }
        }
    }
}

/// Adds Σ_k (y_k − (y_lin,k + c))² over one block to `sse`, in the order of the samples: the
/// blocks of a record summed one after the other give the bits of one sum over it.
pub(in crate::fit) fn add_squares<T: Real>(sse: f64, y: &[T], yl: &[T], c: T) -> f64 {
    y.iter().zip(yl).fold(sse, |s, (&a, &b)| {
        let e = (a - (b + c)).as_f64();
        s + e * e
    })
}

/// (1/N) Σ (y_k − (y_lin,k + c))² of the linear output [b(z) v + q(z) δ]/a(z) against `y`, the
/// output filtered block by block and never stored (the bits of `refine::mse_with_offset` of
/// the whole signal).
pub(in crate::fit) fn mse_filtered<T: Real>(
    a: &[T],
    b: &[T],
    q: &[T],
    c: T,
    v: &[T],
    y: &[T],
) -> f64 {
    let mut yl = LinearOutput::filtered(a, b, q, v);
    let nn = y.len().min(v.len());
    let mut sse = 0.0;
    let mut k0 = 0;
    while k0 < nn {
        let k1 = (k0 + BLOCK_ROWS).min(nn);
        sse = add_squares(sse, &y[k0..k1], &yl.block(k0, k1), c);
        k0 = k1;
    }
    sse / y.len().max(1) as f64
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fit::refinement::refine::{mse_with_offset, simulate_linear};

    /// Uniform numbers on [−0.5, 0.5) from `seed` (a 64-bit LCG, Knuth's MMIX constants).
    fn uniform(seed: u64) -> impl FnMut() -> f64 {
        let mut s = seed;
        move || {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (s >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        }
    }

    /// A record several blocks long: the filtered blocks and their MSE give the bits of the
    /// whole signal's (a second-order block with a free response and an offset).
    #[test]
    fn blocks_give_the_bits_of_the_whole_signal() {
        let nn = 3 * BLOCK_ROWS + 123;
        let mut rnd = uniform(7);
        let v: Vec<f64> = (0..nn).map(|_| rnd()).collect();
        let y: Vec<f64> = (0..nn).map(|_| rnd()).collect();
        let (a, b, q, c) = ([1.0, -1.5, 0.7], [0.0, 1.0, 0.5], [0.3, -0.2], 0.25);
        let whole = simulate_linear(&a, &b, &q, &v);
        let mut out = LinearOutput::filtered(&a, &b, &q, &v);
        let mut k0 = 0;
        for m in [1000, BLOCK_ROWS, 7, 2 * BLOCK_ROWS] {
            let k1 = (k0 + m).min(nn);
            assert_eq!(&out.block(k0, k1)[..], &whole[k0..k1]);
            k0 = k1;
        }
        assert_eq!(&out.block(k0, nn)[..], &whole[k0..]);
        assert_eq!(
            mse_filtered(&a, &b, &q, c, &v, &y).to_bits(),
            mse_with_offset(&y, &whole, c).to_bits()
        );
    }

    /// On a record longer than the refinement's direct limit (the Jacobian streamed in
    /// several blocks), the blocks of [J | r] with y_lin filtered block by block are those with
    /// the whole y_lin given, bit for bit, and so is their R factor.
    #[test]
    fn streamed_jacobian_rows_match_the_given_linear_output() {
        use crate::fit::refinement::refine::{DIRECT_ROWS, JacobianStream, residual_factor_of};
        use crate::regressors::Polynomial;
        use crate::regressors::StaticNonlinearity;
        let nn = DIRECT_ROWS + 3 * BLOCK_ROWS + 17;
        let mut rnd = uniform(3);
        let u: Vec<f64> = (0..nn).map(|_| 2.0 * rnd()).collect();
        let y: Vec<f64> = (0..nn).map(|_| rnd()).collect();
        let mut nl = Polynomial::<f64>::new(3).unwrap();
        nl.set_params(&[1.0, 0.2, -0.1]).unwrap();
        let v = nl.eval(&u);
        let (a, b, q, c) = ([1.0, -1.2, 0.5], [0.0, 1.0, 0.4], [0.1, 0.3], -0.2);
        let whole = simulate_linear(&a, &b, &q, &v);
        let free_b = [1];
        let stream = |yl| JacobianStream::new(&nl, &u, &a, &b, &v, yl, &free_b, true, 0.1, &a);
        let (mut given, mut filtered) = (
            stream(LinearOutput::Given(&whole)),
            stream(LinearOutput::filtered(&a, &b, &q, &v)),
        );
        let mut blocks = 0;
        while let Some((k0, g)) = given.next_block_with_residual(1 << 14, &y, c) {
            let (k1, f) = filtered.next_block_with_residual(1 << 14, &y, c).unwrap();
            assert_eq!(k0, k1);
            assert_eq!(g, f, "block at {k0}");
            blocks += 1;
        }
        assert!(blocks > 4 && filtered.next_block(1).is_none());
        let la = crate::solvers::Faer::default();
        let p = stream(LinearOutput::Given(&whole)).cols();
        let r = |yl| {
            let mut st = stream(yl);
            residual_factor_of(&la, p, nn, |rows| st.next_block_with_residual(rows, &y, c)).unwrap()
        };
        assert_eq!(
            r(LinearOutput::Given(&whole)),
            r(LinearOutput::filtered(&a, &b, &q, &v))
        );
    }
}
