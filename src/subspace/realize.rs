//! A and C from a basis of the extended observability range (SLICOT IB01BD, the MOESP route used
//! for both methods): C is the first block row, A solves the shift invariance Γ↑ A = Γ↓.

use crate::error::{Error, Result};
use crate::real::Real;
use crate::solvers::LinAlg;
use faer::{Mat, MatRef};

/// The observability basis Γ = U₁ of order `n` (the first `n` columns of `u_obs`, i·l rows);
/// an error when `n` is zero or above what the shifted blocks (i − 1 block rows) can hold.
fn basis<T: Real>(
    u_obs: MatRef<'_, T>,
    horizon: usize,
    n_outputs: usize,
    n: usize,
) -> Result<MatRef<'_, T>> {
    let (i, l) = (horizon, n_outputs);
    let max = i.saturating_sub(1).saturating_mul(l).min(u_obs.ncols());
    if n == 0 {
        return Err(Error::ZeroOrder);
    }
    if n > max || i.checked_mul(l) != Some(u_obs.nrows()) {
        return Err(Error::OrderTooLarge { requested: n, max });
    }
    Ok(u_obs.subcols(0, n))
}

/// (A, C) of order `n` from the left singular vectors `u_obs` (i·l rows) of the order-revealing SVD;
/// Γ = U₁ as IB01BD, A by least squares (QR) on the shifted blocks.
pub fn ac_from_observability<T: Real>(
    la: &dyn LinAlg<T>,
    u_obs: MatRef<'_, T>,
    horizon: usize,
    n_outputs: usize,
    n: usize,
) -> Result<(Mat<T>, Mat<T>)> {
    let (i, l) = (horizon, n_outputs);
    let gamma = basis(u_obs, horizon, n_outputs, n)?;
    let c = gamma.subrows(0, l).to_owned();
    let g_up = gamma.subrows(0, (i - 1) * l);
    let g_dn = gamma.subrows(l, (i - 1) * l);
    let a = la.lstsq(g_up, g_dn)?;
    Ok((a, c))
}

/// The guaranteed-stable A of order `n` from the same observability basis: Γ A = [Γ↓; 0], the
/// shift invariance solved with the whole Γ against its shifted blocks padded by l zero rows
/// (Maciejowski, "Guaranteed stability with subspace methods", Systems & Control Letters 26
/// (1995) 153–156). With Γ = U₁ (orthonormal columns) A = Γᵀ S Γ for the block shift S, so
/// ‖A‖₂ ≤ 1 and every pole lies in the closed unit disc; the price is a bias of the poles
/// towards the origin, so it replaces an unstable A only (`SubspaceOptions::stable`).
pub fn stable_a_from_observability<T: Real>(
    la: &dyn LinAlg<T>,
    u_obs: MatRef<'_, T>,
    horizon: usize,
    n_outputs: usize,
    n: usize,
) -> Result<Mat<T>> {
    let (i, l) = (horizon, n_outputs);
    let gamma = basis(u_obs, horizon, n_outputs, n)?;
    let shifted = Mat::from_fn(i * l, n, |r, c| {
        if r + l < i * l {
            gamma[(r + l, c)]
        } else {
            T::zero()
        }
    });
    la.lstsq(gamma, shifted.as_ref())
}
