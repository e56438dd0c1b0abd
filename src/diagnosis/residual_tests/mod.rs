//! The residual tests: their statistics (`stats.rs`, `regression.rs`, `checks/`), the residual
//! analysis and the `ResidualTest` trait (`analysis.rs`), the built-in tests (`builtin_tests.rs`)
//! and their registry (`test_registry.rs`); the structure verdict as evidence beside the
//! residual (`structure_evidence.rs`).

pub mod analysis;
pub mod builtin_tests;
pub mod checks;
pub mod regression;
pub mod stats;
pub mod structure_evidence;
pub mod test_registry;
