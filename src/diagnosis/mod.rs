//! Model diagnosis: compare a model with measurements, residual tests, and ranked suggestions of
//! the physical effect the model is missing.
//!
//! Entry points: [`compare()`] (fit %, MSE, NRMSE, residual of a simulation), [`ResidualAnalysis`]
//! (every residual test with its p-value), [`diagnose()`] / [`Diagnoser`] (named missing effects,
//! each checked by a refit), [`TestRegistry`] and [`ResidualTest`] (add your own residual test),
//! [`Registry`] and [`MissingEffect`] (add your own candidate). Tests and candidates are keyed by
//! [`TestId`] and [`CandidateId`]; the size estimates they quote are typed ([`Estimates`]).
//!
//! Layers, bottom to top: `ids`, `estimate`, `checks/`, `regression`, `stats` → `analysis` →
//! `builtin_tests` → `test_registry`; `compare`, `candidate`, `pi_candidate` → `registry` →
//! `outcome` → `whole` → `screen` → `diagnose` → `follow`.

pub mod analysis;
pub mod builtin_tests;
pub mod candidate;
pub mod checks;
pub mod compare;
pub mod confirm;
pub mod diagnose;
pub mod estimate;
pub mod follow;
pub mod follow_options;
pub mod generalisation;
pub mod ids;
pub mod miso;
pub mod outcome;
pub mod pi_candidate;
mod pi_one_sign;
pub mod registry;
pub mod regression;
pub mod screen;
pub mod stats;
pub mod test_registry;
mod whole;

pub use analysis::{AnalysisOptions, ResidualAnalysis, ResidualTest};
pub use builtin_tests::BuiltinTest;
pub use candidate::{Evidence, MissingEffect, Refit, RefitContext};
pub use checks::signature::Domain;
pub use checks::{TestFamily, TestResult};
pub use compare::{Comparison, Metrics, compare, compare_metrics};
pub use confirm::{ConfirmRule, Confirmation};
pub use diagnose::{Diagnoser, diagnose};
pub use estimate::{Estimate, Estimates, Quantity, Source};
pub use follow::{FollowStep, FollowStop, Followed};
pub use follow_options::FollowOptions;
pub use generalisation::Generalisation;
pub use ids::{CandidateId, TestId};
pub use miso::{
    InputDiagnosis, MisoComparison, MisoDiagnosis, MisoFollowStep, MisoFollowed, MisoSuggestion,
    compare_miso,
};
pub use outcome::{Action, CandidateOutcome, Diagnosis, DiagnosisOptions, Suggestion, Unexplained};
pub use pi_candidate::PrandtlIshlinskiiCandidate;
pub use registry::Registry;
pub use test_registry::TestRegistry;
