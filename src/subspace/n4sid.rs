//! N4SID: Van Overschee & De Moor (1994), "N4SID: Subspace algorithms for the identification of
//! combined deterministic-stochastic systems", Automatica 30(1), 75–93; the data compression is that
//! of SLICOT IB01AD/IB01ND (METH = 'N') and A, C come from the observability range as in IB01BD.
//!
//! With the LQ factorisation of H = [U_f; W_p; Y_f] (W_p = [U_p; Y_p]),
//! L = [L11 0 0; L21 L22 0; L31 L32 L33], the oblique projection of Y_f along U_f onto W_p is
//! O_i = L32 L22⁺ W_p = L32 L22⁺ [L21 L22] Q₁₂. The SVD of the weighted projection W₁ O_i W₂
//! gives the order and Γ_i = U₁ (up to a state basis). Two weightings ([`N4sidWeighting`]):
//! - `Orthogonal` (default): W₁ = I, W₂ = Π⊥ of U_f, the weighting of Van Overschee & De Moor's
//!   robust algorithm (book, 1996, §4.3.3) and of SLICOT IB01ND (METH = 'N'). Then
//!   O_i W₂ = L32 L22⁺ L22 Q₂, which equals MOESP's L32 Q₂ whenever L22 is invertible: SLICOT's
//!   N4SID and MOESP give the same singular values and A, C, and so does this one.
//! - `Unweighted`: W₁ = W₂ = I, the N4SID of the 1994 paper. Consistent, but on coloured inputs
//!   (e.g. DaISy's robot arm sine sweep) its A, C are clearly worse at moderate horizons.

use super::hankel::{Compression, compress};
use super::{Decomposition, SubspaceMethod};
use crate::data::IoView;
use crate::error::Result;
use crate::real::Real;
use crate::solvers::LinAlg;

/// Column weighting W₂ of the oblique projection in N4SID.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum N4sidWeighting {
    /// W₂ = Π⊥ of the future inputs (robust N4SID; SLICOT IB01ND).
    #[default]
    Orthogonal,
    /// W₂ = I (the 1994 paper's N4SID).
    Unweighted,
}

/// N4SID with `horizon` block rows.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct N4sid {
    /// Number of block rows i (the horizon).
    pub horizon: usize,
    /// How the block-Hankel data are compressed (Cholesky with QR fallback by default).
    pub compression: Compression,
    /// Column weighting of the oblique projection.
    pub weighting: N4sidWeighting,
}

impl N4sid {
    /// N4SID with horizon `i` and the default (Cholesky) compression.
    pub fn new(horizon: usize) -> Self {
        Self {
            horizon,
            compression: Compression::default(),
            weighting: N4sidWeighting::default(),
        }
    }
    /// The same method with another weighting.
    pub fn with_weighting(mut self, weighting: N4sidWeighting) -> Self {
        self.weighting = weighting;
        self
    }
    /// The same method with another data compression.
    pub fn with_compression(mut self, compression: Compression) -> Self {
        self.compression = compression;
        self
    }
}

impl<T: Real> SubspaceMethod<T> for N4sid {
    fn name(&self) -> &'static str {
        "n4sid"
    }
    fn horizon(&self) -> usize {
        self.horizon
    }

    fn decompose(&self, la: &dyn LinAlg<T>, data: &[IoView<'_, T>]) -> Result<Decomposition<T>> {
        let i = self.horizon;
        // `compress` validates the experiments (none given, channel counts, lengths, finiteness)
        let (r, n_samples, used) = compress(la, data, i, self.compression)?;
        let (m, l) = (data[0].u.ncols(), data[0].y.ncols());
        let k1 = i * m; // U_f
        let k2 = i * (m + l); // W_p
        let k3 = i * l; // Y_f
        // L = Rᵀ: L22 = R22ᵀ, L32 = R23ᵀ, [L21 L22] = [R12; R22]ᵀ.
        // X = L32 L22⁺ solves X L22 = L32, i.e. R22 Xᵀ = R23 (minimum-norm when R22 is singular).
        let r22 = r.submatrix(k1, k1, k2, k2);
        let r23 = r.submatrix(k1, k1 + k2, k2, k3);
        let xt = la.lstsq(r22, r23)?; // k2 × k3
        let o = match self.weighting {
            // O Π⊥ = L32 L22⁺ [0 L22] (Q₁ part removed) = X L22 = (R22 Xᵀ)ᵀ, k3 × k2
            N4sidWeighting::Orthogonal => (r22 * &xt).transpose().to_owned(),
            // Oᵀ = [R12; R22] Xᵀ ((k1+k2) × k3), O = L32 L22⁺ [L21 L22] in Q-coordinates
            N4sidWeighting::Unweighted => {
                let w = r.submatrix(0, k1, k1 + k2, k2);
                (w * &xt).transpose().to_owned()
            }
        };
        let svd = la.svd(o.as_ref())?;
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
