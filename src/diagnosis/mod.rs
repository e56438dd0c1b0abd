//! Model diagnosis: compare a model with measurements, residual tests, and ranked suggestions of
//! the physical effect the model is missing.

pub mod analysis;
pub mod regression;
pub mod stats;
pub mod tests;

pub use analysis::{AnalysisOptions, ResidualAnalysis};
pub use tests::signature::Domain;
pub use tests::{TestFamily, TestResult};
