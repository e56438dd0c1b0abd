//! The uncertainty of the fitted f(z): its value over the range z visits with a standard
//! error.
//!
//! Method (the delta method on the output-error estimate; Pintelon & Schoukens, *System
//! Identification*, 2nd ed., 2012, §7.2 and §9.15): the covariance of all parameters is
//! σ² (JᵀJ)⁺, J the exact output sensitivities at the fitted model on the training record
//! ([`super::simulate`]), σ² the residual variance with N − rank(J) degrees of freedom. The
//! pseudo-inverse (through the SVD of J's QR factor, singular values below 10⁻⁷ of the largest
//! dropped) leaves out the directions the full parametrisation does not identify: any
//! similarity transform of (A, B, C, E) and the exchange of E's scale against f's gains; E's
//! normalisation fixes the latter's gauge. The block of f's coefficients θ (and the viscous
//! term for `velocity`) is propagated to w(z) = f(z; θ) + c_v z by its gradient:
//! var w(z) = φ(z)ᵀ Σ_θ φ(z), φ = ∂w/∂θ.

use super::model::FeedbackModel;
use super::simulate::{Layout, run_z};
use super::{FeedbackOn, siso};
use crate::data::IoData;
use crate::error::{Error, Result};
use crate::solvers::{Faer, LinAlg};
use faer::Mat;

/// f over the visited z range with its standard error, in the record's units.
#[derive(Debug, Clone, PartialEq)]
pub struct FeedbackBand {
    /// z on a grid over the visited range (the output's units; per sample for `velocity`).
    pub z: Vec<f64>,
    /// w(z) = f(z) (+ the viscous term c_v z for `velocity`), as an equivalent input.
    pub w: Vec<f64>,
    /// The standard error of w(z).
    pub se: Vec<f64>,
    /// The feedback variable along the training record (simulated: the model's own z).
    pub data_z: Vec<f64>,
}

impl FeedbackModel {
    /// f(z) over the range z visits on `train` (the training record) with its standard error
    /// (see the module's method), `points` grid points.
    pub fn nonlinearity_band(&self, train: &IoData<f64>, points: usize) -> Result<FeedbackBand> {
        let (u, y) = siso(train)?;
        let us: Vec<f64> = u.iter().map(|v| v / self.u_scale).collect();
        let ys: Vec<f64> = y.iter().map(|v| v / self.y_scale).collect();
        let lay = Layout::of(self, true);
        let np = lay.len();
        let nn = us.len();
        if nn <= np + 1 {
            return Err(Error::InvalidParameter(format!(
                "the record ({nn} samples) is too short for the covariance of {np} parameters"
            )));
        }
        let mut jr = Mat::<f64>::zeros(nn, np + 1);
        let mut zbuf = Vec::new();
        let yh = run_z(self, &us, &self.x0, Some((&lay, &mut jr)), Some(&mut zbuf))?;
        let sse: f64 = ys.iter().zip(&yh).map(|(a, b)| (a - b).powi(2)).sum();
        for k in 0..nn {
            jr[(k, np)] = 0.0;
        }
        let la = Faer::default();
        let r = la.qr_r(jr.as_ref())?;
        let rows = r.nrows().min(np);
        let rj = Mat::from_fn(rows, np, |i, j| r[(i, j)]);
        let svd = la.svd(rj.as_ref())?;
        let smax = svd.s.first().copied().unwrap_or(0.0);
        let keep: Vec<usize> = (0..svd.s.len())
            .filter(|&i| svd.s[i] > 1e-7 * smax && svd.s[i] > 0.0)
            .collect();
        let dof = (nn - keep.len()).max(1) as f64;
        let sigma2 = sse / dof;
        // Σ_θ = σ² Σ_i v_i v_iᵀ / s_i² over the θ rows of V
        let o = lay.offsets();
        let q = lay.q;
        let th: Vec<usize> = (o[5]..o[5] + q).collect();
        let mut cov = vec![vec![0.0; q]; q];
        for &i in &keep {
            let s2 = svd.s[i] * svd.s[i];
            for (a, &ja) in th.iter().enumerate() {
                for (b, &jb) in th.iter().enumerate() {
                    cov[a][b] += sigma2 * svd.v[(ja, i)] * svd.v[(jb, i)] / s2;
                }
            }
        }
        // the model's own z along the record
        let zs = super::z_along(self, &yh, &us, zbuf);
        let (lo, hi) = super::range(&zs);
        if hi.partial_cmp(&lo) != Some(std::cmp::Ordering::Greater) {
            return Err(Error::InvalidParameter(
                "z does not vary along the record: f cannot be drawn".into(),
            ));
        }
        let m = points.max(2);
        let grid: Vec<f64> = (0..m)
            .map(|i| lo + (hi - lo) * i as f64 / (m - 1) as f64)
            .collect();
        let fz = self.f.eval(&grid);
        let phi = self.f.param_jacobian(&grid);
        let velocity = self.on == FeedbackOn::Velocity;
        let nf = q - usize::from(velocity);
        let mut w = Vec::with_capacity(m);
        let mut se = Vec::with_capacity(m);
        for k in 0..m {
            let g: Vec<f64> = (0..q)
                .map(|j| if j < nf { phi[(k, j)] } else { grid[k] })
                .collect();
            let var: f64 = (0..q)
                .map(|a| (0..q).map(|b| g[a] * cov[a][b] * g[b]).sum::<f64>())
                .sum();
            w.push(
                (fz[k]
                    + if velocity {
                        self.viscous * grid[k]
                    } else {
                        0.0
                    })
                    * self.u_scale,
            );
            se.push(var.max(0.0).sqrt() * self.u_scale);
        }
        Ok(FeedbackBand {
            z: grid.iter().map(|z| z * self.y_scale).collect(),
            w,
            se,
            data_z: zs.iter().map(|z| z * self.y_scale).collect(),
        })
    }
}
