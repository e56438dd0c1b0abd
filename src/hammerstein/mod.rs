//! The iterative Hammerstein loop: settings, the fitted model, refinement and structure selection.
//! Joins `regressors` and `subspace`.

mod driver;
mod fit_report;
mod init;
mod linear_ls;
mod model;
mod observer;
mod rank_one;
mod refine;
mod settings;

pub use fit_report::{FitReport, IterationRecord, RefineReport, Termination};
pub use model::{HammersteinModel, Simulation, divergence};
pub use observer::{FnObserver, Observer, StderrObserver};
pub use settings::{
    DEFAULT_HORIZON, DEFAULT_MAX_ITER, DEFAULT_TOLERANCE, Hammerstein, Init, Normalization,
};
mod model_file;
mod structure;

pub use model_file::{LinearFile, MODEL_FORMAT_VERSION, ModelFile, SettingsFile};
pub use structure::{Criterion, StructureCandidate, StructureReport, select_structure};
