//! The output offset of a nonlinearity whose regressors span the constant (preload without
//! dead-zone: P1 + P2 = 1): the loop's linear steps drop one of the two columns and estimate an
//! offset instead, which is then folded back into the two columns' gains.
//!
//! Why: with the initial state estimated, a constant input's response is a constant plus a free
//! response, so of the n coefficients the constant's column gets in the r-input least squares
//! only its DC gain is determined (n − 1 directions are collinear with the x0 columns), and the
//! r-input subspace step sees a constant input, which is not persistently exciting. Both left the
//! loop with arbitrary preload gains (e1 ≈ e2 ≈ ±100 on battery records with an output offset)
//! and a spurious mode at z = 1. Dropping the column removes the constant from the basis; the
//! offset c then fixes the preload's common part m through the single-input block's DC gain,
//! m·G(1) = c, since adding m to both gains adds m to v.

use crate::error::Result;
use crate::real::Real;
use crate::solvers::LinAlg;
use faer::{Mat, MatRef};

/// How the loop's linear steps treat the output offset.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum OffsetMode {
    /// No offset: the settings switch it off, or the basis spans the constant in a way the
    /// nonlinearity does not name.
    Absent,
    /// A constant output offset estimated beside the block.
    Fitted,
    /// Columns (i, j) of the regressors sum to the constant: column j is dropped, an offset
    /// estimated and folded into the gains of i and j.
    Folded(usize, usize),
}

/// DC gain C (I − A)⁻¹ b + d of a single-input block; `None` when I − A is singular.
fn dc_gain<T: Real>(
    la: &dyn LinAlg<T>,
    a: MatRef<'_, T>,
    b: MatRef<'_, T>,
    c: MatRef<'_, T>,
    d: T,
) -> Option<T> {
    let n = a.nrows();
    let i_minus_a = Mat::from_fn(n, n, |p, q| {
        let e = if p == q { T::one() } else { T::zero() };
        e - a[(p, q)]
    });
    let x = la.solve(i_minus_a.as_ref(), b).ok()?;
    Some((0..n).fold(d, |s, p| s + c[(0, p)] * x[(p, 0)]))
}

/// The output offset a folded model carries in its gains: the common part g_j (the gain of the
/// dropped column `j`) through the block's DC gain. The subspace step of the next iteration
/// subtracts it, as it subtracts a fitted offset.
pub(crate) fn carried_offset<T: Real>(
    la: &dyn LinAlg<T>,
    gains: &[T],
    j: usize,
    a: MatRef<'_, T>,
    b: &[T],
    c: MatRef<'_, T>,
    d: T,
) -> Option<T> {
    let bm = Mat::from_fn(b.len(), 1, |p, _| b[p]);
    let g = dc_gain(la, a, bm.as_ref(), c, d)?;
    let off = *gains.get(j)? * g;
    off.is_finite().then_some(off)
}

/// `phi` without its column `j`.
pub(crate) fn without_column<T: Real>(phi: MatRef<'_, T>, j: usize) -> Mat<T> {
    Mat::from_fn(phi.nrows(), phi.ncols() - 1, |k, q| {
        phi[(k, if q < j { q } else { q + 1 })]
    })
}

/// The full gain vector from the gains `g` of the basis without column `j`: 0 inserted at `j`,
/// then the common part m = `offset` / G(1) added at `i` and `j`, where G(1) is the DC gain of
/// the single-input block (A, b = B̃g, C, d = D̃g) of the rank-one factorisation (`g` of unit
/// norm). m = 0 when G(1) is not distinguishable from 0 (a block without a DC path).
#[allow(clippy::too_many_arguments)]
pub(crate) fn folded_gains<T: Real>(
    la: &dyn LinAlg<T>,
    a: MatRef<'_, T>,
    b_tilde: MatRef<'_, T>,
    c: MatRef<'_, T>,
    d_tilde: &[T],
    g: &[T],
    offset: T,
    (i, j): (usize, usize),
) -> Result<Vec<T>> {
    let n = a.nrows();
    let b = Mat::from_fn(n, 1, |p, _| {
        (0..g.len()).fold(T::zero(), |s, q| s + b_tilde[(p, q)] * g[q])
    });
    let d = (0..g.len()).fold(T::zero(), |s, q| s + d_tilde[q] * g[q]);
    let dc = dc_gain(la, a, b.as_ref(), c, d).unwrap_or(T::zero());
    let size = (0..n).fold(d.abs(), |s, p| s.max((c[(0, p)] * b[(p, 0)]).abs()));
    let m = if dc.abs() > T::epsilon().sqrt() * size && (offset / dc).is_finite() {
        offset / dc
    } else {
        T::zero()
    };
    let mut full: Vec<T> = g.to_vec();
    full.insert(j, T::zero());
    full[i] += m;
    full[j] += m;
    Ok(full)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::solvers::Faer;

    #[test]
    fn the_offset_becomes_the_common_part_through_the_dc_gain() {
        // one state, pole 0.5, b̃ = [2, 1] for two columns, c = 1, no D: with g = (0.6, 0.8)
        // b = 2·0.6 + 0.8 = 2, G(1) = 2 / (1 − 0.5) = 4, so an offset of 2 is m = 0.5.
        let la = Faer::default();
        let a = Mat::from_fn(1, 1, |_, _| 0.5);
        let bt = Mat::from_fn(1, 2, |_, q| [2.0, 1.0][q]);
        let c = Mat::from_fn(1, 1, |_, _| 1.0);
        let g = [0.6, 0.8];
        let full: Vec<f64> = folded_gains(
            &la,
            a.as_ref(),
            bt.as_ref(),
            c.as_ref(),
            &[0.0, 0.0],
            &g,
            2.0,
            (1, 2),
        )
        .unwrap();
        assert_eq!(full.len(), 3);
        assert!((full[0] - 0.6).abs() < 1e-12);
        assert!((full[1] - (0.8 + 0.5)).abs() < 1e-12);
        assert!((full[2] - 0.5).abs() < 1e-12);
    }

    #[test]
    fn a_block_without_dc_path_gets_no_common_part() {
        // a differentiator-like block: pole 1 − 1e-20 would be unstable; use b cancelling in G(1):
        // two states, A = diag(0.5, 0.5), C = [1, −1], b = B̃g = (1, 1): G(1) = 0.
        let la = Faer::default();
        let a = Mat::from_fn(2, 2, |p, q| if p == q { 0.5 } else { 0.0 });
        let bt = Mat::from_fn(2, 1, |_, _| 1.0);
        let c = Mat::from_fn(1, 2, |_, q| [1.0, -1.0][q]);
        let full = folded_gains(
            &la,
            a.as_ref(),
            bt.as_ref(),
            c.as_ref(),
            &[0.0],
            &[1.0],
            3.0,
            (0, 1),
        )
        .unwrap();
        assert_eq!(full, vec![1.0, 0.0]);
    }

    #[test]
    fn dropping_a_column_keeps_the_others_in_order() {
        let phi = Mat::from_fn(2, 3, |k, q| (10 * k + q) as f64);
        let r = without_column(phi.as_ref(), 1);
        assert_eq!((r[(0, 0)], r[(0, 1)], r[(1, 1)]), (0.0, 2.0, 12.0));
    }
}
