//! The iterative Hammerstein loop: settings, the fitted model, refinement and structure selection.
//! Joins `regressors` and `subspace`.
//!
//! [`Hammerstein`] holds the settings (nonlinearity, method, horizon, order, …);
//! [`Hammerstein::fit`] runs the loop on a record and returns a [`HammersteinModel`]:
//!
//! ```
//! use hammerstein::regressors::{StaticNonlinearity, Udn};
//! use hammerstein::{Hammerstein, IoData, StateSpace};
//!
//! // the paper's Example 1: saturation with hysteresis (p, a, z1, z2) into a second-order block
//! let truth = Udn::with_params(Hammerstein::<f64>::sh().effects().unwrap(), &[2.0, 0.5, 1.5, -1.0])?;
//! let g = StateSpace::from_rows(&[&[0.2, 1.0], &[-0.35, 0.0]], &[&[1.0], &[0.5]], &[&[1.0, 0.0]], &[&[0.0]])?;
//! let mut state = 1u64; // a small LCG: uniform input in [-3, 3)
//! let mut uniform = || {
//!     state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
//!     (state >> 11) as f64 / (1u64 << 53) as f64 * 6.0 - 3.0
//! };
//! let u: Vec<f64> = (0..1000).map(|_| uniform()).collect();
//! let y = g.simulate_siso(&truth.eval(&u), None)?;
//!
//! let model = Hammerstein::sh().fit(&IoData::siso(&u, &y)?)?;
//! assert!(model.report().train_mse < 1e-12);
//! let p: Vec<f64> = model.parameters().iter().map(|(_, v)| *v).collect();
//! assert!(p.iter().zip([2.0, 0.5, 1.5, -1.0]).all(|(a, b)| (a - b).abs() < 1e-6), "{p:?}");
//! let tf = model.transfer_function()?; // z⁻¹(1 + 0.5z⁻¹) / (1 − 0.2z⁻¹ + 0.35z⁻²)
//! assert!((tf.denominator[1] + 0.2).abs() < 1e-6 && (tf.numerator[2] - 0.5).abs() < 1e-6);
//! # Ok::<(), hammerstein::Error>(())
//! ```

// The fit's vocabulary and orchestration stay at this level: the settings (`settings.rs`), the
// callbacks (`observer.rs`), what a fit reports (`fit_report.rs`), one fixed-structure fit
// (`fixed.rs`), the record's normalisation (`scaling.rs`), standard errors (`uncertainty.rs`) and
// the entry `Hammerstein::fit` (`driver.rs`). The rooms, bottom to top (each imports only the
// rooms before it and this level's files; docs/architecture.md has the map):
// - `numerics/`: the B/D/x0 least squares, golden section, the jump and kink scans, the offset
//   fold, the slow-block horizon, the rank-one factor;
// - `fitted/`: the fitted model, its file, the parameters' covariance;
// - `iteration/`: the paper's iterative loop — one fit's data, the 1-D search, the start, the
//   loop's state, step and termination;
// - `refinement/`: the Levenberg–Marquardt refinement, the joint refinement of several branches,
//   the jump centring, the stability constraint, the output map's fit;
// - `selection/`: the order and feed-through candidates, fits nested in a fitted model, the
//   linear check, screening of long records, the effect subsets ranked.
mod driver;
mod fit_report;
mod fitted;
mod fixed;
mod iteration;
mod numerics;
mod observer;
mod refinement;
pub(crate) mod scaling;
mod selection;
mod settings;
pub mod uncertainty;

pub use selection::from_rest;
pub use selection::order_selection;

pub use fit_report::{
    FitReport, IterationRecord, OrderCandidate, RefineReport, Stabilised, Termination,
};
pub use fitted::covariance::{NULL_SHARE, ParameterCovariance};
pub(crate) use fitted::model::MemoryStart;
pub use fitted::model::{HammersteinModel, Simulation, divergence};
pub use fitted::model_file::{
    ColumnNames, LinearFile, MODEL_FORMAT_VERSION, ModelFile, OLDEST_MODEL_FORMAT_VERSION,
    SettingsFile,
};
pub use iteration::problem::STABLE_RADIUS;
pub(crate) use numerics::linear_ls::delayed;
pub use observer::{FnObserver, Observer, StderrObserver};
pub(crate) use refinement::joint_refine::refine_jointly;
#[cfg(test)]
pub(crate) use refinement::joint_refine::refine_jointly_whole;
pub use scaling::anchored_effects_far_from_input;
pub(crate) use selection::screening::{polish_on, window_start as screening_window_start};
pub use selection::structure::{Criterion, StructureCandidate, StructureReport, select_structure};
pub use settings::{
    DEFAULT_HORIZON, DEFAULT_MAX_ITER, DEFAULT_POLISH_ITERATIONS, DEFAULT_SCREEN_THRESHOLD,
    DEFAULT_SCREEN_WINDOW, DEFAULT_TOLERANCE, Feedthrough, FitOptions, Hammerstein, Init,
    Normalization, Screening,
};
