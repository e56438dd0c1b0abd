//! PO-MOESP (past inputs and outputs as instruments): Verhaegen (1994), "Identification of the
//! deterministic part of MIMO state space models given in innovations form from input-output data",
//! Automatica 30(1); as SLICOT IB01AD/IB01ND with METH = 'M'.

use super::hankel::accumulate_r;
use super::{Decomposition, SubspaceMethod};
use crate::data::IoView;
use crate::error::{Error, Result};
use crate::real::Real;
use crate::solvers::LinAlg;
use faer::Mat;

/// PO-MOESP with `horizon` block rows.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Moesp {
    /// Number of block rows i (the horizon).
    pub horizon: usize,
}

impl Moesp {
    /// PO-MOESP with horizon `i`.
    pub fn new(horizon: usize) -> Self {
        Self { horizon }
    }
}

impl<T: Real> SubspaceMethod<T> for Moesp {
    fn name(&self) -> &'static str {
        "moesp"
    }
    fn horizon(&self) -> usize {
        self.horizon
    }

    fn decompose(&self, la: &dyn LinAlg<T>, data: &[IoView<'_, T>]) -> Result<Decomposition<T>> {
        let i = self.horizon;
        if data.is_empty() {
            return Err(Error::InvalidParameter("no experiment given".into()));
        }
        let (m, l) = (data[0].u.ncols(), data[0].y.ncols());
        let (r, n_samples) = accumulate_r(la, data, i)?;
        // R = Lᵀ; the block of L that maps the instruments W_p onto Y_f after removing U_f:
        // rows Y_f (cols i(2m+l)..), cols W_p (i·m .. i(2m+l)) of L, i.e. R[W_p rows, Y_f cols]ᵀ.
        let k1 = i * m;
        let k2 = i * (m + l);
        let k3 = i * l;
        let l32 = Mat::from_fn(k3, k2, |a, b| r[(k1 + b, k1 + k2 + a)]);
        let svd = la.svd(l32.as_ref())?;
        Ok(Decomposition {
            singular_values: svd.s,
            horizon: i,
            n_inputs: m,
            n_outputs: l,
            n_samples,
            r,
            u_obs: svd.u,
        })
    }

    fn realize_ac(
        &self,
        la: &dyn LinAlg<T>,
        dec: &Decomposition<T>,
        n: usize,
    ) -> Result<(Mat<T>, Mat<T>)> {
        let (i, l) = (dec.horizon, dec.n_outputs);
        if n == 0 || n > dec.u_obs.ncols() || n > (i - 1) * l {
            return Err(Error::OrderTooLarge {
                requested: n,
                max: ((i - 1) * l).min(dec.u_obs.ncols()),
            });
        }
        // Γ = U₁ (SLICOT IB01BD uses U₁ directly); C = first block row, A from the shift invariance
        // Γ↑ A = Γ↓ solved by least squares (QR).
        let gamma = dec.u_obs.subcols(0, n);
        let c = gamma.subrows(0, l).to_owned();
        let g_up = gamma.subrows(0, (i - 1) * l);
        let g_dn = gamma.subrows(l, (i - 1) * l);
        let a = la.lstsq(g_up, g_dn)?;
        Ok((a, c))
    }
}
