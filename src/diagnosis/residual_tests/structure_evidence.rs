//! What a structure verdict tells the residual analysis: on a multisine record at several levels
//! the best linear approximations of the levels say whether poles move with the level (a
//! nonlinearity in feedback) or zeros do (parallel branches) — evidence the residual of one
//! model at one level cannot give. Made by
//! [`structure_verdict::evidence`](crate::diagnosis::structure_verdict::evidence) and read by the
//! feedback-nonlinearity candidate.

use crate::structure::Verdict;
use serde::Serialize;

/// The structure verdict of a record's levels, as evidence beside the residual.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct StructureEvidence {
    /// The verdict (`linear`, `single-branch`, `parallel`, `feedback`).
    pub verdict: Verdict,
    /// The verdict and its strongest evidence in one line ("feedback: pole at 7.32 Hz moved
    /// to 7.26 Hz, 32.8 s.e.").
    pub line: String,
    /// The p-value of the test behind a `feedback` or `parallel` verdict (poles, or zeros, move
    /// with the level); 1 for the others.
    pub p_value: f64,
}
