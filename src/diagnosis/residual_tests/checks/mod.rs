//! Residual tests with confidence bounds: each gives a statistic and a p-value.
//!
//! Linear tests: whiteness (Ljung–Box and per-lag bounds) and cross-correlation with the input.
//! Nonlinear ("signature") tests: the residual regressed on functions of the input filtered
//! through the model's linear block (input level, direction of motion, extremes, small |u|, the
//! sign step at u = 0, u², u³) or on functions of the predicted output, by prewhitened F tests.

pub mod cross_correlation;
pub mod feedback_signature;
pub mod signature;
pub mod whiteness;

use crate::diagnosis::ids::TestId;
use serde::Serialize;

/// Which kind of model deficit a test looks for.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum TestFamily {
    /// Linear-dynamics deficits (order, delay, noise colour).
    Linear,
    /// Static-nonlinearity deficits (a function of the input or of the output left in the residual).
    Nonlinear,
}

/// The outcome of one residual test.
#[derive(Debug, Clone, Serialize)]
pub struct TestResult {
    /// Which test ("whiteness", "input-direction", … in the output).
    pub name: TestId,
    /// What the test checks, in one sentence.
    pub description: String,
    /// Linear or nonlinear family.
    pub family: TestFamily,
    /// Name of the statistic ("Q", "F", "max|z|").
    pub statistic_name: String,
    /// Value of the statistic.
    pub statistic: f64,
    /// Degrees of freedom of its reference distribution (empty for a Bonferroni-combined z).
    pub df: Vec<f64>,
    /// p-value of this test alone.
    pub p_value: f64,
    /// p-value after the multiple-testing correction over all tests of the analysis.
    pub p_adjusted: f64,
    /// True when `p_adjusted` is below the analysis' significance level.
    pub significant: bool,
    /// Test-specific numbers for the evidence sentence (e.g. input-referred coefficients).
    pub coefficients: Vec<f64>,
    /// One line with the numbers that matter.
    pub detail: String,
}

impl TestResult {
    /// A result with the adjusted fields still unset (filled in by the analysis).
    pub fn new(
        name: impl Into<TestId>,
        description: &str,
        family: TestFamily,
        statistic_name: &str,
        statistic: f64,
        df: Vec<f64>,
        p_value: f64,
    ) -> Self {
        Self {
            name: name.into(),
            description: description.to_string(),
            family,
            statistic_name: statistic_name.to_string(),
            statistic,
            df,
            p_value: if p_value.is_nan() { 1.0 } else { p_value },
            p_adjusted: 1.0,
            significant: false,
            coefficients: Vec::new(),
            detail: String::new(),
        }
    }
}
