//! Model diagnosis: compare a model with measurements, residual tests, and ranked suggestions of
//! the physical effect the model is missing.
//!
//! Entry points: [`compare()`] (fit %, MSE, NRMSE, residual of a simulation), [`ResidualAnalysis`]
//! (every residual test with its p-value), [`diagnose()`] / [`Diagnoser`] (named missing effects,
//! each checked by a refit), [`Registry`] and [`MissingEffect`] (add your own candidate).

pub mod analysis;
pub mod candidate;
pub mod compare;
pub mod diagnose;
pub mod follow;
pub mod pi_candidate;
pub mod registry;
pub mod regression;
pub mod screen;
pub mod stats;
pub mod tests;

pub use analysis::{AnalysisOptions, ResidualAnalysis};
pub use candidate::{Evidence, MissingEffect, Refit, RefitContext};
pub use compare::{Comparison, Metrics, compare, compare_metrics};
pub use diagnose::{
    Action, CandidateOutcome, Diagnoser, Diagnosis, DiagnosisOptions, Suggestion, Unexplained,
    diagnose,
};
pub use follow::{FollowStep, FollowStop, Followed};
pub use pi_candidate::PrandtlIshlinskiiCandidate;
pub use registry::Registry;
pub use tests::signature::Domain;
pub use tests::{TestFamily, TestResult};
