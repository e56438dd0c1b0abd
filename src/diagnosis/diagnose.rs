//! Diagnosis: from residual signatures to named, ranked missing effects, each checked by refitting.
//!
//! Decision rule (documented in `docs/`-facing terms in [`Diagnoser::diagnose`]):
//! 1. Compare the model with the training and validation records; run every residual test on the
//!    training residual (Bonferroni over all tests, family-wise level `alpha`, default 1 %).
//! 2. If no test is significant (and no candidate's own evidence is), the residuals are
//!    consistent with noise: `adequate = true`, no refit is made and the suggestion list is empty.
//! 3. Otherwise every applicable candidate is refitted (in parallel; refinement included, as the
//!    current model's own fit) and judged **on the training part only**: it is suggested when
//!    its refit lowers the Bayesian information criterion of the training simulation error,
//!    ΔBIC = N·ln(MSE_after/MSE_before) + Δk·ln N < 0 (the criterion of the order selection,
//!    `hammerstein::order_selection`), its relative training improvement is at least
//!    `min_improvement` (default 3 %), and its own parameters are not at their null value
//!    within two standard errors (`MissingEffect::null_parameters`: a hysteresis width a ≈ 0,
//!    saturation limits outside the input's range, …). The validation part is only reported.
//! 4. Score = relative training improvement × (1 when the candidate's own test is significant,
//!    ½ otherwise): the refit decides, the evidence breaks near-ties between effects that both
//!    help. Suggestions are sorted by score, best first.
//! 5. Adequate only when every residual test passes (step 2). When tests fail and no candidate
//!    helps, `adequate = false`, no suggestion, and `unexplained` lists the failing tests with
//!    the model classes beyond this one that would address them.

use super::analysis::{AnalysisOptions, ResidualAnalysis};
use super::candidate::{Evidence, MissingEffect, Refit, RefitContext};
use super::compare::{Comparison, compare};
use super::registry::Registry;
use super::tests::TestResult;
use crate::data::IoData;
use crate::error::Result;
use crate::hammerstein::order_selection::training_mse;
use crate::hammerstein::{Hammerstein, HammersteinModel};
use crate::real::Real;
use rayon::prelude::*;
use serde::Serialize;
use std::collections::BTreeMap;

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
    /// Effect name ("hysteresis", "dead-zone", "saturation", "preload", "dynamics", "delay",
    /// "output-nonlinearity", or a user's).
    pub effect: String,
    /// Ranking score (relative validation improvement weighted by the evidence).
    pub score: f64,
    /// One sentence of evidence with numbers.
    pub evidence: String,
    /// Size estimates: from the residual and from the refitted model.
    pub estimate: BTreeMap<String, f64>,
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
    /// A change outside the current settings (an output nonlinearity, a user candidate), by name.
    Other(String),
}

impl Action {
    /// The typed difference between two settings (the first difference found), `Other(name)`
    /// when none of the typed ones applies.
    pub fn between<T: Real>(
        from: &crate::hammerstein::Hammerstein<T>,
        to: &crate::hammerstein::Hammerstein<T>,
        name: &str,
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
        if from.delay_value() != to.delay_value() {
            return Action::Delay(to.delay_value());
        }
        if let crate::subspace::Order::Fixed(n) = to.order_value()
            && from.order_value() != to.order_value()
        {
            return Action::Order(*n);
        }
        if from.feedthrough_value() != to.feedthrough_value()
            && to.feedthrough_value() != crate::hammerstein::Feedthrough::Auto
        {
            return Action::Feedthrough(to.with_d_value());
        }
        Action::Other(name.to_string())
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
            Action::Other(name) => name.clone(),
        }
    }
}

/// What happened to one candidate (suggested or not).
#[derive(Debug, Clone, Serialize)]
#[serde(bound = "")]
pub struct CandidateOutcome<T: Real = f64> {
    /// Candidate name.
    pub effect: String,
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
    pub test: String,
    /// Its Bonferroni-adjusted p-value.
    pub p_adjusted: f64,
    /// Model classes that would address it (output nonlinearity, a second input, dynamic
    /// hysteresis, nonlinear feedback, …).
    pub model_classes: Vec<String>,
}

/// Model classes that address a failing residual test when no built-in candidate does.
pub(crate) fn model_classes_for(test: &str) -> Vec<String> {
    let classes: &[&str] = match test {
        "whiteness" | "dynamics" => &[
            "nonlinear feedback or dynamics the static nonlinearity cannot carry",
            "coloured noise (a noise model)",
        ],
        "input-cross-correlation" | "delay" => &["a second input", "nonlinear feedback"],
        "input-direction" => &["dynamic hysteresis (Prandtl–Ishlinskii, Bouc–Wen)"],
        "input-level" | "input-extremes" | "input-near-zero" | "input-zero-step"
        | "input-square" | "input-cube" => &[
            "an input nonlinearity outside the UDN family (a user basis)",
            "dynamic hysteresis (Prandtl–Ishlinskii, Bouc–Wen)",
        ],
        "output-level" => &["an output nonlinearity (Hammerstein–Wiener)"],
        _ => &["a model class beyond the Hammerstein structure"],
    };
    classes.iter().map(|c| c.to_string()).collect()
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
            .ok_or_else(|| {
                crate::error::Error::InvalidParameter(format!(
                    "the suggestion '{}' ({}) changes something outside this model class; \
                     it cannot be applied to the settings",
                    suggestion.effect,
                    suggestion.action.label()
                ))
            })
    }
}

/// Runs diagnoses with a registry of candidates.
pub struct Diagnoser<T: Real> {
    registry: Registry<T>,
    options: DiagnosisOptions,
}

impl<T: Real> Default for Diagnoser<T> {
    fn default() -> Self {
        Self::new()
    }
}

impl<T: Real> Diagnoser<T> {
    /// The built-in candidates with default options.
    pub fn new() -> Self {
        Self {
            registry: Registry::builtin(),
            options: DiagnosisOptions::default(),
        }
    }
    /// Uses another registry.
    pub fn registry(mut self, registry: Registry<T>) -> Self {
        self.registry = registry;
        self
    }
    /// Adds a user's candidate to the registry.
    pub fn register(mut self, c: Box<dyn MissingEffect<T>>) -> Self {
        self.registry.register(c);
        self
    }
    /// Sets the options.
    pub fn options(mut self, options: DiagnosisOptions) -> Self {
        self.options = options;
        self
    }
    /// The registry in use.
    pub fn candidates(&self) -> &Registry<T> {
        &self.registry
    }

    /// The residual analysis of `model` on the training record (what the candidates read their
    /// evidence and settings changes from).
    pub fn analysis(
        &self,
        model: &HammersteinModel<T>,
        train: &IoData<T>,
    ) -> Result<ResidualAnalysis> {
        let train_c = compare(model, train)?;
        self.analysis_of(model, &train_c)
    }

    fn analysis_of(
        &self,
        model: &HammersteinModel<T>,
        train_c: &Comparison,
    ) -> Result<ResidualAnalysis> {
        let linear = model.linear().cast::<f64>();
        // the analysis works on the input as the nonlinearity sees it: u(k − nk)
        let nk = model.delay();
        let u_delayed: Vec<f64> = (0..train_c.u.len())
            .map(|k| {
                if k >= nk {
                    train_c.u[k - nk]
                } else {
                    train_c.u[0]
                }
            })
            .collect();
        ResidualAnalysis::new(
            &u_delayed,
            &train_c.y,
            &train_c.y_hat,
            &train_c.v_hat,
            &linear,
            self.options.analysis.clone(),
        )
    }

    /// Diagnoses `model` (fitted on `train`) with `validation` as hold-out data; a training
    /// record longer than the model's screening threshold is screened on its leading window
    /// ([`super::screen`]).
    pub fn diagnose(
        &self,
        model: &HammersteinModel<T>,
        train: &IoData<T>,
        validation: &IoData<T>,
    ) -> Result<Diagnosis<T>> {
        let s = model.settings().screening_value();
        if s.applies(train.len()) {
            return super::screen::diagnose_screened(self, model, train, validation, s);
        }
        self.diagnose_whole(model, train, validation)
    }

    /// The options in use.
    pub(crate) fn options_value(&self) -> &DiagnosisOptions {
        &self.options
    }

    /// [`diagnose`](Self::diagnose) on the whole records, without screening.
    pub(crate) fn diagnose_whole(
        &self,
        model: &HammersteinModel<T>,
        train: &IoData<T>,
        validation: &IoData<T>,
    ) -> Result<Diagnosis<T>> {
        let train_c = compare(model, train)?;
        let val_c = compare(model, validation)?;
        let analysis = self.analysis_of(model, &train_c)?;
        let entries: Vec<(&dyn MissingEffect<T>, bool, Option<Evidence>)> = self
            .registry
            .candidates()
            .iter()
            .map(|c| {
                let c = c.as_ref();
                (c, c.applies_to(model), c.evidence(&analysis))
            })
            .collect();
        let any_evidence = analysis.any_significant()
            || entries
                .iter()
                .any(|(_, _, e)| e.as_ref().is_some_and(|e| e.significant));
        let ctx = RefitContext {
            model,
            train,
            validation,
            validation_comparison: &val_c,
            analysis: &analysis,
            train_mse: training_mse(model, train),
        };
        let run = |(c, applicable, _): &(&dyn MissingEffect<T>, bool, Option<Evidence>)| {
            if *applicable && any_evidence {
                Some(c.refit(&ctx).map(|mut r| {
                    r.null_parameters = c.null_parameters(&r, train);
                    r
                }))
            } else {
                None
            }
        };
        let refits: Vec<Option<Result<Refit<T>>>> = if self.options.parallel {
            entries.par_iter().map(run).collect()
        } else {
            entries.iter().map(run).collect()
        };
        let n_train = train.len().max(1) as f64;
        let mut candidates = Vec::new();
        let mut suggestions = Vec::new();
        for ((c, applicable, evidence), refit) in entries.into_iter().zip(refits) {
            let (refit, refit_error) = match refit {
                Some(Ok(r)) => (Some(r), None),
                Some(Err(e)) => (None, Some(e.to_string())),
                None => (None, None),
            };
            let improvement = refit.as_ref().map(|r| {
                if r.reference_train_mse > 0.0 {
                    (r.reference_train_mse - r.train_mse) / r.reference_train_mse
                } else {
                    0.0
                }
            });
            // ΔBIC on the training part; MSEs floored at the exact-fit level as the order
            // selection floors them
            let floor = crate::hammerstein::order_selection::exact_floor_of(train);
            let criterion_change = refit.as_ref().map(|r| {
                n_train * (r.train_mse.max(floor) / r.reference_train_mse.max(floor)).ln()
                    + r.added_parameters as f64 * n_train.ln()
            });
            if let (Some(r), Some(imp), Some(dc)) = (&refit, improvement, criterion_change)
                && imp >= self.options.min_improvement
                && dc < 0.0
                && r.null_parameters.is_none()
                && r.train_mse.is_finite()
            {
                let own = evidence.as_ref().is_some_and(|e| e.significant);
                let mut estimate = evidence
                    .as_ref()
                    .map(|e| {
                        e.estimate
                            .iter()
                            .map(|(k, v)| (format!("residual_{k}"), *v))
                            .collect::<BTreeMap<_, _>>()
                    })
                    .unwrap_or_default();
                estimate.extend(r.estimate.iter().map(|(k, v)| (k.clone(), *v)));
                let action = match &r.model {
                    Some(next) => Action::between(model.settings(), next.settings(), &c.name()),
                    None => Action::Other(c.name()),
                };
                suggestions.push(Suggestion {
                    effect: c.name(),
                    score: imp * if own { 1.0 } else { 0.5 },
                    evidence: evidence.as_ref().map_or_else(
                        || format!("refit improves the training MSE by {:.1} %", 100.0 * imp),
                        |e| e.sentence.clone(),
                    ),
                    estimate,
                    train_mse_after: r.train_mse,
                    train_mse_before: r.reference_train_mse,
                    criterion_change: dc,
                    validation_mse_after: r.validation_mse,
                    validation_mse_before: val_c.metrics.mse,
                    p_value: evidence.as_ref().map(|e| e.p_adjusted),
                    change: r.change.clone(),
                    action,
                });
            }
            candidates.push(CandidateOutcome {
                effect: c.name(),
                applicable,
                evidence,
                refit,
                refit_error,
                improvement,
                criterion_change,
            });
        }
        suggestions.sort_by(|a, b| b.score.total_cmp(&a.score));
        // adequate only when the residual tests pass: failing tests that no candidate explains
        // are reported as unexplained, with the model classes that would address them
        let adequate = suggestions.is_empty() && !any_evidence;
        let unexplained: Vec<Unexplained> = if suggestions.is_empty() && any_evidence {
            analysis
                .tests
                .iter()
                .filter(|t| t.significant)
                .map(|t| Unexplained {
                    test: t.name.clone(),
                    p_adjusted: t.p_adjusted,
                    model_classes: model_classes_for(&t.name),
                })
                .collect()
        } else {
            Vec::new()
        };
        let summary = summary_of(adequate, &unexplained, &suggestions);
        Ok(Diagnosis {
            adequate,
            unexplained,
            suggestions,
            candidates,
            tests: analysis.tests.clone(),
            train: train_c,
            validation: val_c,
            summary,
            screening_window: None,
        })
    }
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

/// Diagnoses a model with the built-in candidates and default options.
pub fn diagnose<T: Real>(
    model: &HammersteinModel<T>,
    train: &IoData<T>,
    validation: &IoData<T>,
) -> Result<Diagnosis<T>> {
    Diagnoser::new().diagnose(model, train, validation)
}
