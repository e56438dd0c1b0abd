//! The options of the guided loop ([`crate::diagnosis::Diagnoser::follow_with`]): the step limit, the rule
//! each step is confirmed by on the held-back part of the training record, and a time budget.

use super::confirm::ConfirmRule;
use std::time::Duration;

/// How the guided loop runs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FollowOptions {
    /// Most changes the loop makes.
    pub max_steps: usize,
    /// The rule each step is confirmed by before it is taken ([`super::confirm`]); `None`:
    /// every step the training criterion chooses is taken.
    pub confirm: Option<ConfirmRule>,
    /// Stop after the step in progress once this much time has passed since the loop started
    /// (its last model is kept; [`crate::diagnosis::FollowStop::TimeBudget`]); `None`: no limit.
    pub time_budget: Option<Duration>,
}

impl Default for FollowOptions {
    /// Six steps, each confirmed by the default [`ConfirmRule`], no time budget.
    fn default() -> Self {
        Self {
            max_steps: 6,
            confirm: Some(ConfirmRule::default()),
            time_budget: None,
        }
    }
}

impl FollowOptions {
    /// The default options with at most `max_steps` steps.
    pub fn steps(max_steps: usize) -> Self {
        Self {
            max_steps,
            ..Self::default()
        }
    }
}
