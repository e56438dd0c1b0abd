//! What a diagnosis returns: the suggestions with their typed settings change, what happened to
//! every candidate, the failing tests no candidate explains, and the diagnosis itself; the
//! options of a diagnosis.

use crate::diagnosis::candidates::candidate::{Evidence, Refit};
use crate::diagnosis::candidates::estimate::Estimates;
use crate::diagnosis::compare::Comparison;
use crate::diagnosis::ids::{CandidateId, TestId};
use crate::diagnosis::residual_tests::analysis::AnalysisOptions;
use crate::diagnosis::residual_tests::checks::TestResult;
use crate::diagnosis::residual_tests::test_registry::TestRegistry;
use crate::error::Result;
use crate::fit::{Hammerstein, HammersteinModel};
use crate::real::Real;
use serde::Serialize;

/// Settings of a diagnosis.
#[derive(Debug, Clone, Serialize)]
pub struct DiagnosisOptions {
    /// Residual-test settings (significance level, bins, lags).
    pub analysis: AnalysisOptions,
    /// Smallest relative training-MSE improvement that counts as "the effect helps" (besides a
    /// lower information criterion).
    pub min_improvement: f64,
    /// Refit the candidates in parallel (rayon).
    pub parallel: bool,
}

impl Default for DiagnosisOptions {
    fn default() -> Self {
        Self {
            analysis: AnalysisOptions::default(),
            min_improvement: 0.03,
            parallel: true,
        }
    }
}

/// One suggested missing effect.
#[derive(Debug, Clone, Serialize)]
pub struct Suggestion {
    /// Which effect (shown as "hysteresis", "dead-zone", "saturation", "preload",
    /// "prandtl-ishlinskii", "dynamics", "delay", "output-nonlinearity", or a user's name).
    pub effect: CandidateId,
    /// Ranking score (relative validation improvement weighted by the evidence).
    pub score: f64,
    /// One sentence of evidence with numbers.
    pub evidence: String,
    /// Size estimates: from the residual (named "residual_…") and from the refitted model
    /// (serialised as the map name → value).
    pub estimate: Estimates,
    /// Training MSE after adding the effect and refitting (what the selection compares).
    pub train_mse_after: f64,
    /// Training MSE of the reference (the current model, or a fairer one the candidate names).
    pub train_mse_before: f64,
    /// Change of the information criterion on the training part (negative: better).
    pub criterion_change: f64,
    /// Validation MSE after adding the effect and refitting (reported, not used to select).
    pub validation_mse_after: f64,
    /// Validation MSE of the current model.
    pub validation_mse_before: f64,
    /// p-value of the candidate's own test (Bonferroni-adjusted), when it has one.
    pub p_value: Option<f64>,
    /// What the refit changed.
    pub change: String,
    /// The settings change the suggestion stands for, typed (what `Diagnoser::next_settings`
    /// applies).
    pub action: Action,
}

/// The settings change a suggestion stands for.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Action {
    /// Add these UDN effects (at the model's order and feed-through).
    AddEffects(Vec<crate::regressors::Effect>),
    /// Fit with this model order.
    Order(usize),
    /// Fit with this input delay.
    Delay(usize),
    /// Estimate (true) or drop (false) the direct feed-through.
    Feedthrough(bool),
    /// A change outside the current settings (an output nonlinearity, a user candidate): the
    /// candidate.
    Other(CandidateId),
}

impl Action {
    /// The typed difference between two settings (the first difference found), `Other(name)`
    /// when none of the typed ones applies.
    pub fn between<T: Real>(
        from: &crate::fit::Hammerstein<T>,
        to: &crate::fit::Hammerstein<T>,
        candidate: &CandidateId,
    ) -> Self {
        if let (Some(a), Some(b)) = (from.effects(), to.effects()) {
            let added: Vec<_> = b
                .effects()
                .into_iter()
                .filter(|&e| !a.contains(e))
                .collect();
            if !added.is_empty() {
                return Action::AddEffects(added);
            }
        }
        // another nonlinearity outside the UDN's effects (a Prandtl–Ishlinskii subset of plays):
        // the candidate's change, not the order its settings fix at the model's
        if from.effects().zip(to.effects()).is_none()
            && from.nonlinearity_name() != to.nonlinearity_name()
        {
            return match candidate {
                CandidateId::Effect(e) => Action::AddEffects(vec![*e]),
                other => Action::Other(other.clone()),
            };
        }
        // an output map added or swapped: the candidate's change, even when it also fixes the
        // order at the model's (an `Auto` order becomes `Fixed(n)` without changing n)
        let map_name = |h: &crate::fit::Hammerstein<T>| h.output_map().map(|m| m.name());
        if map_name(from) != map_name(to) {
            return Action::Other(candidate.clone());
        }
        if from.options().delay != to.options().delay {
            return Action::Delay(to.options().delay);
        }
        if let crate::subspace::Order::Fixed(n) = to.options().order
            && from.options().order != to.options().order
        {
            return Action::Order(n);
        }
        if from.options().feedthrough() != to.options().feedthrough()
            && to.options().feedthrough() != crate::fit::Feedthrough::Auto
        {
            return Action::Feedthrough(to.options().with_d);
        }
        Action::Other(candidate.clone())
    }

    /// Short label of the change: "+ hysteresis", "order 3", "delay 2", "feed-through on", or
    /// the candidate's name.
    pub fn label(&self) -> String {
        match self {
            Action::AddEffects(e) => format!(
                "+ {}",
                e.iter()
                    .map(|e| e.to_string())
                    .collect::<Vec<_>>()
                    .join(" + ")
            ),
            Action::Order(n) => format!("order {n}"),
            Action::Delay(d) => format!("delay {d}"),
            Action::Feedthrough(on) => format!("feed-through {}", if *on { "on" } else { "off" }),
            Action::Other(c) => c.to_string(),
        }
    }
}

/// What happened to one candidate (suggested or not).
#[derive(Debug, Clone, Serialize)]
#[serde(bound = "")]
pub struct CandidateOutcome<T: Real = f64> {
    /// Which candidate.
    pub effect: CandidateId,
    /// False when the model already has it (no refit).
    pub applicable: bool,
    /// Its evidence in the residuals.
    pub evidence: Option<Evidence>,
    /// The refit, when one was made.
    pub refit: Option<Refit<T>>,
    /// Why the refit failed, when it did.
    pub refit_error: Option<String>,
    /// Relative training improvement (reference − after)/reference.
    pub improvement: Option<f64>,
    /// Change of the information criterion on the training part (negative: better).
    pub criterion_change: Option<f64>,
}

/// A residual test that still fails when no candidate helps, and the model classes beyond the
/// current one that would address it.
#[derive(Debug, Clone, Serialize)]
pub struct Unexplained {
    /// The failing residual test.
    pub test: TestId,
    /// Its Bonferroni-adjusted p-value.
    pub p_adjusted: f64,
    /// Model classes that would address it (output nonlinearity, a second input, dynamic
    /// hysteresis, nonlinear feedback, …).
    pub model_classes: Vec<String>,
}

/// The diagnosis of a model.
#[derive(Debug, Clone, Serialize)]
#[serde(bound = "")]
pub struct Diagnosis<T: Real = f64> {
    /// True only when every residual test passes at the stated level (and so nothing is missing).
    pub adequate: bool,
    /// Failing residual tests no candidate explains (empty when adequate or when a suggestion
    /// exists).
    pub unexplained: Vec<Unexplained>,
    /// Suggested effects, best first.
    pub suggestions: Vec<Suggestion>,
    /// Every candidate tried.
    pub candidates: Vec<CandidateOutcome<T>>,
    /// Every residual test (training residual).
    pub tests: Vec<TestResult>,
    /// The model on the training record (screened: series of the leading
    /// `screen::SERIES_KEPT` samples, metrics of the whole record).
    pub train: Comparison,
    /// The model on the validation record (screened: as `train`).
    pub validation: Comparison,
    /// One-line summary.
    pub summary: String,
    /// With a long record: the training samples (from the start) the residual tests ran on and
    /// the candidates were screened on; the suggested candidates were then re-checked on the
    /// whole record (`diagnosis::screen`). `None`: everything on the whole record.
    pub screening_window: Option<usize>,
    /// The validation error against the training error, and the validation samples beyond the
    /// training input's range (`generalisation.rs`); `None` for a screened diagnosis or when it
    /// cannot be computed.
    pub generalisation: Option<super::generalisation::Generalisation>,
}

impl<T: Real> Diagnosis<T> {
    /// The model refitted for `suggestion` (kept from the diagnosis, not fitted again); `None` for
    /// a suggestion whose change lies outside the model (an output map).
    pub fn refitted(&self, suggestion: &Suggestion) -> Option<&HammersteinModel<T>> {
        self.candidates
            .iter()
            .find(|c| c.effect == suggestion.effect)
            .and_then(|c| c.refit.as_ref())
            .and_then(|r| r.model.as_ref())
    }

    /// The settings that act on `suggestion`: the refitted model's own settings (the effect
    /// added at the model's order, the order or delay the refit chose, …).
    pub fn apply(&self, suggestion: &Suggestion) -> Result<Hammerstein<T>> {
        self.refitted(suggestion)
            .map(|m| m.settings().clone())
            .ok_or_else(|| crate::error::Error::NotApplicable {
                effect: suggestion.effect.to_string(),
                change: suggestion.action.label(),
            })
    }
}

/// The failing tests of `tests`, each with the model classes that would address it (as the
/// test in `registry` says).
pub(crate) fn unexplained_of(tests: &[TestResult], registry: &TestRegistry) -> Vec<Unexplained> {
    tests
        .iter()
        .filter(|t| t.significant)
        .map(|t| Unexplained {
            test: t.name.clone(),
            p_adjusted: t.p_adjusted,
            model_classes: registry.model_classes(&t.name),
        })
        .collect()
}

/// The one-line summary of a diagnosis.
pub(crate) fn summary_of(
    adequate: bool,
    unexplained: &[Unexplained],
    suggestions: &[Suggestion],
) -> String {
    if adequate {
        "no missing effect found: the residuals are consistent with noise".to_string()
    } else if suggestions.is_empty() {
        let names: Vec<&str> = unexplained.iter().map(|u| u.test.as_str()).collect();
        format!(
            "not adequate: residual test(s) {} still fail, and no candidate of this model \
             class lowers the training error by a meaningful margin (see `unexplained`)",
            if names.is_empty() {
                "of the candidates".to_string()
            } else {
                names.join(", ")
            }
        )
    } else {
        let s = &suggestions[0];
        format!(
            "most likely missing: {} (training MSE {:.4e} → {:.4e}; validation {:.4e} → {:.4e})",
            s.effect,
            s.train_mse_before,
            s.train_mse_after,
            s.validation_mse_before,
            s.validation_mse_after
        )
    }
}
