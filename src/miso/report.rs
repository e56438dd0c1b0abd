//! What a several-input fit reports: its sweeps, whether they settled, the joint refinement.

use crate::fit::RefineReport;
use serde::{Deserialize, Serialize};

/// One sweep over the branches.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct SweepRecord {
    /// Total training MSE after the sweep.
    pub train_mse: f64,
    /// Whether each branch's refit was kept in this sweep (input order).
    pub kept: Vec<bool>,
}

/// What the backfitting did.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq, Default)]
pub struct MisoReport {
    /// Every sweep, in order.
    pub sweeps: Vec<SweepRecord>,
    /// True when the sweeps stopped because the total MSE settled (not at the sweep limit).
    pub converged: bool,
    /// Total training MSE of the returned model.
    pub train_mse: f64,
    /// The joint refinement of all branches after the sweeps (`None` when it did not run:
    /// switched off, a branch not refined, one branch, or the fit already exact).
    #[serde(default)]
    pub joint_refinement: Option<RefineReport>,
}
