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
//! output-error criterion; a branch refit is kept only when the total MSE does not rise.
//!
//! Layering: above [`crate::fit`] (it fits branches with [`crate::fit::Hammerstein`]), below the
//! diagnosis (`diagnosis::miso` diagnoses each input on its partial residual).

mod backfit;
mod linear_start;
mod model;
mod model_file;
mod partial;
mod settings;

pub use backfit::{MisoReport, SweepRecord};
pub use model::{MisoModel, MisoSimulation};
pub use model_file::{MISO_FORMAT_KIND, MisoBranchFile, MisoModelFile};
pub use partial::partial_record;
pub use settings::{DEFAULT_MAX_SWEEPS, DEFAULT_SWEEP_TOLERANCE, MisoHammerstein};
