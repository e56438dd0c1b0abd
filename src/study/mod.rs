//! Reproducible studies: the paper's Example 1 Monte Carlo runs (Tables 2 and 3) with the
//! Cramér–Rao bound and the paper's own numbers for comparison.

pub mod crlb;
pub mod example1;
pub mod paper_tables;

pub use crlb::{CRLB_PARAMS, Crlb, SnrDefinition, example1_crlb};
pub use example1::{Example1, Example1Data};
pub use paper_tables::{PaperRow, TABLE2, TABLE3, paper_value};
pub mod monte_carlo;
pub use monte_carlo::{
    ParamStats, RunEstimate, Setting, SettingResult, Strategy, StudyConfig, Table, paper_settings,
    run_study,
};
pub mod targets;
pub use targets::{TargetCheck, TargetKind, check_targets};
