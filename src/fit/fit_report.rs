//! What a fit reports about itself: the iterates, why it stopped, the order, the refinement.

use serde::{Deserialize, Serialize};

/// One iterate of the loop.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct IterationRecord {
    /// Simulation MSE on the training record (initial state and offset by least squares).
    pub mse: f64,
    /// Physical parameters θ of the nonlinearity after the iteration (normalised).
    pub params: Vec<f64>,
    /// True when the θ step was damped (halved towards the previous θ) because the MSE rose.
    #[serde(default)]
    pub damped: bool,
}

/// Why the loop stopped.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Termination {
    /// |ΔMSE| < λ·MSE, or the fit is exact to round-off.
    Converged,
    /// The iteration limit was reached.
    MaxIterations,
    /// The MSE cycled near its minimum without settling; the best iterate was kept.
    Oscillating,
    /// The MSE kept rising despite damping; the best iterate was kept.
    Diverged,
    /// The regressors do not depend on θ (a linear gain, a polynomial): one pass (plus one pass
    /// with the estimated offset removed) is the answer, nothing to iterate.
    SinglePass,
}

impl Termination {
    /// Name as reports print it.
    pub fn name(self) -> &'static str {
        match self {
            Self::Converged => "converged",
            Self::MaxIterations => "max-iterations",
            Self::Oscillating => "oscillating",
            Self::Diverged => "diverged",
            Self::SinglePass => "single-pass",
        }
    }
}

impl std::fmt::Display for Termination {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// What the Levenberg–Marquardt refinement did.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RefineReport {
    /// Training MSE before the refinement (the loop's best iterate).
    pub mse_before: f64,
    /// Training MSE after (equal to `mse_before` when not accepted).
    pub mse_after: f64,
    /// LM iterations run.
    pub iterations: usize,
    /// True when the refined model replaced the loop's result (only if the MSE fell).
    pub accepted: bool,
}

/// Report of a complete fit.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FitReport {
    /// Every iterate, in order.
    pub iterations: Vec<IterationRecord>,
    /// Index of the iterate returned (the one with the lowest MSE).
    pub best_iteration: usize,
    /// Why the loop stopped.
    pub termination: Termination,
    /// True for `Converged` and `SinglePass`.
    pub converged: bool,
    /// Model order n.
    pub order: usize,
    /// Singular values of the first subspace step (from which the order was chosen).
    pub singular_values: Vec<f64>,
    /// Training simulation MSE of the returned model.
    pub train_mse: f64,
    /// The refinement's report, when it ran.
    pub refinement: Option<RefineReport>,
    /// Every candidate (order, feed-through) the automatic selection fitted (empty when both
    /// were fixed).
    #[serde(default)]
    pub order_selection: Vec<OrderCandidate>,
    /// Standard errors of the nonlinearity's parameters θ on the training record (same order as
    /// θ; `+∞` for a parameter the record does not determine; empty when not computed). See
    /// [`crate::fit::uncertainty`].
    #[serde(default, with = "infinite_as_null")]
    pub standard_errors: Vec<f64>,
    /// The covariance of the same parameters, for the standard error of a combination
    /// ([`crate::fit::ParameterCovariance::standard_error`]); computed with the standard errors,
    /// not saved in model files (`None` for a loaded model).
    #[serde(skip)]
    pub covariance: Option<super::fitted::covariance::ParameterCovariance>,
    /// The default horizon the fit raised for a fixed order it could not hold (the horizon used
    /// is the model's `settings().options().horizon`); `None` when no such raise happened.
    /// Written to model files only when set.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub horizon_raised_from: Option<usize>,
    /// The length of the window a screened fit chose the structure on (the record's own length
    /// when no window's model carried over to the whole record and the record was fitted
    /// whole); `None` when the fit was not screened. A screened diagnosis screens on a window
    /// at least this long. Written to model files only when set.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub screening_window: Option<usize>,
    /// When the stability constraint (`Hammerstein::stable`) replaced an unstable fitted block:
    /// that block's spectral radius and training MSE; `None` otherwise. Written to model files
    /// only when set.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stabilised: Option<Stabilised>,
    /// When the returned model's simulation from rest departs from its fit with the estimated
    /// initial state by more than [`REST_LIMIT`](crate::fit::from_rest::REST_LIMIT) times the
    /// output's excursion on the training record: that departure ([`crate::fit::from_rest`]),
    /// for `simulate` to say; `None` otherwise. Written to model files only when set.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub departs_from_rest: Option<f64>,
}

/// The unstable block the stability constraint replaced (`FitReport::stabilised`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Stabilised {
    /// Spectral radius of the unconstrained fit's block (≥ 1).
    pub spectral_radius: f64,
    /// That fit's training MSE (the constrained model's is `FitReport::train_mse`).
    pub train_mse: f64,
}

/// A vector of numbers whose non-finite entries (an undetermined parameter's +∞) are written as
/// JSON `null` and read back as +∞ (JSON has no infinity).
mod infinite_as_null {
    use serde::{Deserialize, Deserializer, Serialize, Serializer};

    pub fn serialize<S: Serializer>(v: &[f64], s: S) -> Result<S::Ok, S::Error> {
        v.iter()
            .map(|x| x.is_finite().then_some(*x))
            .collect::<Vec<Option<f64>>>()
            .serialize(s)
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Vec<f64>, D::Error> {
        let v = Vec::<Option<f64>>::deserialize(d)?;
        Ok(v.into_iter().map(|x| x.unwrap_or(f64::INFINITY)).collect())
    }
}

/// One candidate of the automatic order selection.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct OrderCandidate {
    /// Model order n.
    pub order: usize,
    /// Whether the candidate has a direct feed-through D.
    #[serde(default)]
    pub feedthrough: bool,
    /// Information criterion on the training record (lower is better).
    pub criterion: f64,
    /// Training simulation MSE of the candidate's fit.
    pub train_mse: f64,
    /// When the selection refused the candidate because its simulation from rest departs from
    /// its fit with the estimated initial state by more than
    /// [`REST_LIMIT`](crate::fit::from_rest::REST_LIMIT) times the output's excursion: that
    /// departure ([`crate::fit::from_rest`]); `None` for a candidate the selection could choose.
    /// Written to model files only when set.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub refused_from_rest: Option<f64>,
}

impl OrderCandidate {
    /// Whether the selection refused the candidate (`refused_from_rest`).
    pub fn refused(&self) -> bool {
        self.refused_from_rest.is_some()
    }

    /// The selection's order of preference: a candidate it could choose before a refused one,
    /// then the lower criterion.
    pub fn preference(&self, other: &Self) -> std::cmp::Ordering {
        self.refused()
            .cmp(&other.refused())
            .then(self.criterion.total_cmp(&other.criterion))
    }
}
