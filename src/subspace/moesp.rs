//! PO-MOESP (past inputs and outputs as instruments): Verhaegen (1994), "Identification of the
//! deterministic part of MIMO state space models given in innovations form from input-output data",
//! Automatica 30(1); as SLICOT IB01AD/IB01ND with METH = 'M'.

use super::hankel::{Compression, compress};
use super::{Decomposition, SubspaceMethod};
use crate::data::IoView;
use crate::error::Result;
use crate::real::Real;
use crate::solvers::LinAlg;
use faer::Mat;

/// PO-MOESP with `horizon` block rows.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Moesp {
    /// Number of block rows i (the horizon).
    pub horizon: usize,
    /// How the block-Hankel data are compressed (Cholesky with QR fallback by default).
    pub compression: Compression,
}

impl Moesp {
    /// PO-MOESP with horizon `i` and the default (Cholesky) compression.
    pub fn new(horizon: usize) -> Self {
        Self {
            horizon,
            compression: Compression::default(),
        }
    }
    /// The same method with another data compression.
    pub fn with_compression(mut self, compression: Compression) -> Self {
        self.compression = compression;
        self
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
        // `compress` validates the experiments (none given, channel counts, lengths, finiteness)
        let (r, n_samples, used) = compress(la, data, i, self.compression)?;
        let (m, l) = (data[0].u.ncols(), data[0].y.ncols());
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
            compression: used,
        })
    }

    fn with_horizon(&self, horizon: usize) -> Option<Box<dyn SubspaceMethod<T>>> {
        Some(Box::new(Self { horizon, ..*self }))
    }
}
