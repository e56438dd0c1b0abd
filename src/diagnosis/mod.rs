//! Model diagnosis: compare a model with measurements, residual tests, and ranked suggestions of
//! the physical effect the model is missing.
//!
//! Entry points: [`compare()`] (fit %, MSE, NRMSE, residual of a simulation), [`ResidualAnalysis`]
//! (every residual test with its p-value), [`diagnose()`] / [`Diagnoser`] (named missing effects,
//! each checked by a refit), [`TestRegistry`] and [`ResidualTest`] (add your own residual test),
//! [`Registry`] and [`MissingEffect`] (add your own candidate). Tests and candidates are keyed by
//! [`TestId`] and [`CandidateId`]; the size estimates they quote are typed ([`Estimates`]).
//!
//! Rooms, bottom to top (each imports only the ones before it and this level's `ids.rs` and
//! `compare.rs`): `residual_tests/` (the statistics, the residual analysis, the built-in tests
//! and their registry), `candidates/` (the missing-effect candidates, their size estimates and
//! registry), `diagnoser/` (what a diagnosis returns, whether the model carries over, the
//! diagnosis on whole and screened records, the `Diagnoser`), `guided/` (the guided loop of
//! `diagnose --follow`); `miso.rs` diagnoses several-input models input by input,
//! `feedback_model.rs` a model with a nonlinearity in feedback (and follows the suggestion of one).

mod candidates;
pub mod compare;
mod diagnoser;
pub mod feedback_model;
mod guided;
pub mod ids;
pub mod miso;
mod residual_tests;
pub mod structure_verdict;

pub use candidates::{
    candidate, estimate, feedback_candidate, identifiability, pi_candidate, registry,
};
pub use diagnoser::{diagnose, generalisation, outcome, screen};
pub use guided::{confirm, final_check, follow, follow_options};
pub use residual_tests::{
    analysis, builtin_tests, checks, regression, stats, structure_evidence, test_registry,
};

pub use analysis::{AnalysisOptions, ResidualAnalysis, ResidualTest};
pub use builtin_tests::BuiltinTest;
pub use candidate::{Evidence, MissingEffect, Refit, RefitContext};
pub use checks::signature::Domain;
pub use checks::{TestFamily, TestResult};
pub use compare::{Comparison, Metrics, compare, compare_metrics, min_compare_samples};
pub use confirm::{ConfirmRule, Confirmation};
pub use diagnose::{Diagnoser, MIN_VALIDATION_SAMPLES, diagnose};
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
pub use structure_evidence::StructureEvidence;
pub use test_registry::TestRegistry;
