//! The rank-one factorisation of the r-input linear block into a single-input block and the gain
//! vector g, and the normalisation that fixes their common scale.
//!
//! The paper (Section 3.3, eq. 16–19) factors Θ = [B̃; D̃] by its SVD. That factorisation depends
//! on the state basis the subspace step happened to return (B̃ is only defined up to an n×n
//! similarity), and NOTES.md records that it derails from some starts when D is estimated. Here
//! the factored matrix is the basis-independent Markov-parameter matrix
//! H = [D̃; C B̃; C A B̃; …; C A^(K-1) B̃] (K×r): an input-output quantity, so its best rank-one
//! approximation σ₁u₁v₁ᵀ (Eckart–Young, by SVD) gives g = v₁ and the single-input block's impulse
//! response σ₁u₁ whatever the realisation. With K large this is the rank-one approximation in the
//! (truncated) H2 norm of the r-input system.

use crate::error::{Error, Result};
use crate::fit::settings::Normalization;
use crate::real::Real;
use crate::solvers::LinAlg;
use crate::solvers::columns::row_major;
use crate::solvers::recursion::{SumOrder, state_recursion};
use faer::{Mat, MatRef};

/// Number of Markov parameters in H: enough to cover the impulse response of the orders the
/// horizon allows (at least 20 samples, four horizons).
pub(crate) fn markov_rows(horizon: usize, order: usize) -> usize {
    (4 * horizon).max(4 * order).max(20)
}

/// A rank-one factorisation: g (unit norm before normalisation) and the Markov parameters
/// h_0 = D, h_1 = CB, … of the single-input block, with h ⊗ g ≈ H.
#[derive(Debug, Clone)]
pub(crate) struct RankOne<T: Real> {
    /// Gain vector g, length r.
    pub g: Vec<T>,
    /// Markov parameters h_0 (= D, zero without D), h_1, …, h_K.
    pub markov: Vec<T>,
}

/// Best rank-one approximation of the Markov-parameter matrix of (A, B̃, C, D̃).
pub(crate) fn factor<T: Real>(
    la: &dyn LinAlg<T>,
    a: MatRef<'_, T>,
    b_tilde: MatRef<'_, T>,
    c: MatRef<'_, T>,
    d_tilde: &[T],
    k_rows: usize,
) -> Result<RankOne<T>> {
    let r = b_tilde.ncols();
    let n = a.nrows();
    let mut h = Mat::<T>::zeros(k_rows + 1, r);
    for q in 0..r {
        h[(0, q)] = d_tilde[q];
    }
    // row vector o = C A^k, updated in place
    let mut o: Vec<T> = (0..n).map(|j| c[(0, j)]).collect();
    let mut o_next = vec![T::zero(); n];
    for k in 0..k_rows {
        for q in 0..r {
            let mut s = T::zero();
            for j in 0..n {
                s += o[j] * b_tilde[(j, q)];
            }
            h[(k + 1, q)] = s;
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
    let svd = la.svd(h.as_ref())?;
    let s1 = svd.s.first().copied().unwrap_or(T::zero());
    if !s1.is_finite() || s1 <= T::zero() {
        return Err(Error::Identification(
            "the estimated linear block has no response to the nonlinearity's regressors".into(),
        ));
    }
    let g: Vec<T> = (0..r).map(|q| svd.v[(q, 0)]).collect();
    let markov: Vec<T> = (0..=k_rows).map(|k| svd.u[(k, 0)] * s1).collect();
    Ok(RankOne { g, markov })
}

/// Relative size below which a Markov parameter counts as negligible for [`Normalization::MarkovOne`]
/// (5 % of the largest: a noisy estimate of a zero parameter must not set the scale).
pub(crate) const MARKOV_NEGLIGIBLE: f64 = 0.05;

/// The factor s such that (g·s, h/s) satisfies the normalisation, from the gains and the Markov
/// parameters h_0 (= D), h_1, … of the single-input block.
pub(crate) fn scale_for<T: Real>(rule: Normalization, g: &[T], markov: &[T]) -> Result<T> {
    let s = match rule {
        Normalization::MarkovOne => {
            let max = markov.iter().fold(T::zero(), |m, h| m.max(h.abs()));
            let tol = max * T::lit(MARKOV_NEGLIGIBLE);
            markov
                .iter()
                .copied()
                .find(|h| h.abs() > tol)
                .unwrap_or(T::zero())
        }
        Normalization::GainOne => {
            let g0 = g.first().copied().unwrap_or(T::zero());
            if g0 == T::zero() {
                T::zero()
            } else {
                T::one() / g0
            }
        }
        Normalization::UnitGainVector => {
            let norm = g.iter().fold(T::zero(), |s, x| s + *x * *x).sqrt();
            let sign = if g.first().copied().unwrap_or(T::one()) < T::zero() {
                -T::one()
            } else {
                T::one()
            };
            if norm == T::zero() {
                T::zero()
            } else {
                sign / norm
            }
        }
    };
    if s == T::zero() || !s.is_finite() {
        return Err(Error::Identification(format!(
            "cannot normalise ({rule:?}): the reference gain or Markov parameter is zero"
        )));
    }
    Ok(s)
}

/// Markov parameters h_0 = d, h_k = C A^(k-1) b (k = 1..=count) of a single-input block.
pub(crate) fn markov_of<T: Real>(
    a: MatRef<'_, T>,
    b: &[T],
    c: MatRef<'_, T>,
    d: T,
    count: usize,
) -> Vec<T> {
    let mut out = Vec::with_capacity(count + 1);
    out.push(d);
    // h_k = C x(k−1) with x(0) = b, x(k+1) = A x(k): the state kernel without inputs
    let am = row_major(a);
    let cv = row_major(c);
    let mut x = b.to_vec();
    state_recursion(
        &am,
        &[],
        &[],
        count,
        SumOrder::StateFirst,
        &mut x,
        |_, x, _| {
            let mut s = T::zero();
            for (cj, xj) in cv.iter().zip(x) {
                s += *cj * *xj;
            }
            out.push(s);
        },
    );
    out
}
