//! Several inputs, one output (MISO): one Hammerstein branch per input, the branches' outputs
//! summed — y = Σᵢ Gᵢ(Nᵢ(uᵢ(k − nkᵢ))) + c.
//!
//! Each input has its own static nonlinearity (or none: a gain), its own linear block, order and
//! delay; the linear part is their parallel connection (a state-space model with block-diagonal
//! A of order Σ nᵢ, [`MisoModel::linear`]). Any MISO linear system is such a sum; when the inputs
//! share their dynamics the sum has more states than a minimal realisation, and the price is
//! variance, not bias.
//!
//! The fit ([`MisoHammerstein::fit`], `backfit.rs`) is **backfitting** (Hastie & Tibshirani,
//! *Generalized Additive Models*, 1990, ch. 4; for block-oriented systems e.g. Bai 2010): branch i
//! is fitted by the single-input method (loop + refinement) to its **partial residual**
//! rᵢ = y − Σ_{j≠i} ŷⱼ, the others held fixed, and the sweeps over the branches repeat until the
//! total training MSE settles. Each branch fit minimises the same total simulation error over
//! that branch's parameters, so the sweeps are block-coordinate descent on the joint
//! output-error criterion; a branch refit is kept only when the total MSE does not rise. After
//! the sweeps a joint Levenberg–Marquardt refinement of all branches' parameters at once polishes
//! the result (coordinate descent crawls when the branches are coupled).
//!
//! ```
//! use hammerstein::faer::Mat;
//! use hammerstein::miso::MisoHammerstein;
//! use hammerstein::regressors::{EffectSet, StaticNonlinearity, Udn};
//! use hammerstein::{Hammerstein, IoData, StateSpace};
//!
//! // u1 → gain 1 → 0.5/(z − 0.7);  u2 → saturation at ±0.8 → 1/(z − 0.5); outputs summed
//! let mut state = 3u64; // a small LCG: uniform inputs in [−2, 2)
//! let mut uniform = || {
//!     state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
//!     (state >> 11) as f64 / (1u64 << 53) as f64 * 4.0 - 2.0
//! };
//! let n = 1500;
//! let (u1, u2): (Vec<f64>, Vec<f64>) = (0..n).map(|_| (uniform(), uniform())).unzip();
//! let sat = Udn::with_params(EffectSet::parse("saturation")?, &[1.0, 0.8, -0.8])?;
//! let g1 = StateSpace::from_rows(&[&[0.7]], &[&[1.0]], &[&[0.5]], &[&[0.0]])?;
//! let g2 = StateSpace::from_rows(&[&[0.5]], &[&[1.0]], &[&[1.0]], &[&[0.0]])?;
//! let y1 = g1.simulate_siso(&u1, None)?;
//! let y2 = g2.simulate_siso(&sat.eval(&u2), None)?;
//! let data = IoData::with_names(
//!     Mat::from_fn(n, 2, |k, j| if j == 0 { u1[k] } else { u2[k] }),
//!     Mat::from_fn(n, 1, |k, _| y1[k] + y2[k]),
//!     vec!["u1".into(), "u2".into()],
//!     vec!["y".into()],
//! )?;
//!
//! let settings = MisoHammerstein::new(vec![
//!     Hammerstein::linear(),
//!     Hammerstein::udn(EffectSet::parse("saturation")?),
//! ]);
//! let model = settings.fit(&data)?;
//! // noise-free: the fit is exact to 1e-6 of the output's variance (the orders chosen may exceed
//! // the true ones: docs/algorithm.md, "Several inputs")
//! assert!(model.report().train_mse < 1e-6 * 0.5);
//! let p = model.branch("u2").unwrap().parameters(); // p, z1, z2
//! assert!((p[1].1 - 0.8).abs() < 1e-3 && (p[2].1 + 0.8).abs() < 1e-3, "{p:?}");
//! # Ok::<(), hammerstein::Error>(())
//! ```
//!
//! Layering: above [`crate::fit`] (it fits branches with [`crate::fit::Hammerstein`]), below the
//! diagnosis (`diagnosis::miso` diagnoses each input on its partial residual).

mod backfit;
mod horizon;
mod linear_start;
mod model;
mod model_file;
mod partial;
mod report;
mod settings;
#[cfg(test)]
mod streamed_joint;

pub use model::{MisoModel, MisoSimulation};
pub use model_file::{MISO_FORMAT_KIND, MisoBranchFile, MisoModelFile};
pub use partial::partial_record;
pub use report::{MisoReport, SweepRecord};
pub use settings::{DEFAULT_MAX_SWEEPS, DEFAULT_SWEEP_TOLERANCE, MisoHammerstein};
