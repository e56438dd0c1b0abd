//! What kind of system is this? Multisine experiments, the best linear approximation and a
//! structure verdict (`linear`, `single-branch`, `parallel`, `feedback`) from BLAs at several
//! amplitudes.
//!
//! Layers, bottom to top: `record.rs` (the record format), `design.rs` (random-phase multisines),
//! `bla.rs` (the BLA per level, robust and fast methods), `parametric.rs` (the rational model's
//! axis, roots and their standard errors), `nested.rs` (joint fits over the levels and their F
//! tests), `verdict.rs` (the verdict and its evidence), `amplitude.rs` (non-periodic records split by
//! the input's local RMS, ARX models per class, the same pole-movement test), `reset.rs` (whether
//! a non-periodic record of one level is nonlinear: the RESET test), `single_branch.rs` (within
//! `single-branch`, Hammerstein, Wiener and Wiener–Hammerstein fitted and ranked by validation
//! error).

pub mod amplitude;
pub mod bla;
pub mod design;
pub mod nested;
pub mod parametric;
pub mod record;
pub mod reset;
pub mod single_branch;
pub mod verdict;

pub use amplitude::{AmplitudeOptions, analyze_by_amplitude};
pub use bla::{Bla, BlaMethod, LevelBla, LineBla, Nonlinearity, bla};
pub use design::{MultisineDesign, MultisineKind};
pub use record::{Block, Record};
pub use single_branch::{CandidateFit, SingleBranchRanking, rank_single_branch};
pub use verdict::{Structure, StructureOptions, Verdict, analyze};
