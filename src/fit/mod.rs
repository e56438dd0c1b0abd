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

// The files in layers, bottom to top; each imports only files listed before it, so the file
// graph is acyclic (docs/architecture.md, "The loop's files"):
// 1. covariance, fit_report, observer, linear_ls, settings, golden, slow_horizon — reports,
//    callbacks, least squares, the builder, golden section's bracket, the horizon a slow block
//    asks for;
// 2. rank_one, model, model_file — the rank-one factor, the fitted model and its file;
// 3. problem — one fit's data, one iterate, the workspace, the steps that do not search;
// 4. search — one pass of steps 1–6 with the 1-D search;
// 5. init, initial_direction, loop_state, refine — the start, the nonlinearity's initial
//    direction estimated, the loop (state, step, termination), the refinement;
// 6. output_fit, scaling, fixed, stability — the output map's fit, normalisation, one
//    fixed-structure fit, the stability constraint's last step;
// 7. uncertainty, screening, nested, order_selection, joint_refine — standard errors, the
//    polish, fits from a model, the order candidates, several branches refined jointly (the
//    several-input fit's polish);
// 8. driver — `Hammerstein::fit`; 9. structure — fits compared across effect sets.
mod centring;
mod covariance;
mod driver;
mod fit_report;
mod fixed;
mod golden;
mod init;
mod initial_direction;
mod joint_refine;
mod jump_centre;
mod jump_scan;
mod kink_scan;
mod linear_ls;
mod linear_nested;
mod loop_state;
mod model;
mod nested;
mod observer;
mod offset_fold;
pub mod order_selection;
mod output_fit;
mod problem;
mod rank_one;
mod refine;
pub(crate) mod scaling;
mod screening;
mod search;
mod settings;
mod slow_horizon;
mod stability;
pub mod uncertainty;

pub use covariance::{NULL_SHARE, ParameterCovariance};
pub use fit_report::{
    FitReport, IterationRecord, OrderCandidate, RefineReport, Stabilised, Termination,
};
pub(crate) use joint_refine::refine_jointly;
#[cfg(test)]
pub(crate) use joint_refine::refine_jointly_whole;
pub(crate) use linear_ls::delayed;
pub use model::{HammersteinModel, Simulation, divergence};
pub use observer::{FnObserver, Observer, StderrObserver};
pub use problem::STABLE_RADIUS;
pub use scaling::anchored_effects_far_from_input;
pub(crate) use screening::{polish_on, window_start as screening_window_start};
pub use settings::{
    DEFAULT_HORIZON, DEFAULT_MAX_ITER, DEFAULT_POLISH_ITERATIONS, DEFAULT_SCREEN_THRESHOLD,
    DEFAULT_SCREEN_WINDOW, DEFAULT_TOLERANCE, Feedthrough, FitOptions, Hammerstein, Init,
    Normalization, Screening,
};
mod model_file;
mod structure;

pub use model_file::{
    ColumnNames, LinearFile, MODEL_FORMAT_VERSION, ModelFile, OLDEST_MODEL_FORMAT_VERSION,
    SettingsFile,
};
pub use structure::{Criterion, StructureCandidate, StructureReport, select_structure};
