//! Diagnosis: from residual signatures to named, ranked missing effects, each checked by refitting.
//!
//! Decision rule (documented in `docs/`-facing terms in [`Diagnoser::diagnose`]):
//! 1. Compare the model with the training and validation records; run every residual test on the
//!    training residual (Bonferroni over all tests, family-wise level `alpha`, default 1 %).
//! 2. If no test is significant (and no candidate's own evidence is), the residuals are
//!    consistent with noise: `adequate = true`, no refit is made and the suggestion list is empty.
//! 3. Otherwise every applicable candidate is refitted (in parallel) and its validation MSE
//!    measured. A candidate is suggested when its relative validation improvement
//!    (reference − after)/reference is at least `min_improvement` (default 3 %).
//! 4. Score = relative improvement × (1 when the candidate's own test is significant, ½ otherwise):
//!    the refit decides, the evidence breaks near-ties between effects that both help.
//!    Suggestions are sorted by score, best first.
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
use crate::hammerstein::HammersteinModel;
use crate::real::Real;
use rayon::prelude::*;
use serde::Serialize;
use std::collections::BTreeMap;

/// Settings of a diagnosis.
#[derive(Debug, Clone, Serialize)]
pub struct DiagnosisOptions {
    /// Residual-test settings (significance level, bins, lags).
    pub analysis: AnalysisOptions,
    /// Smallest relative validation-MSE improvement that counts as "the effect helps".
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
    /// Validation MSE after adding the effect and refitting.
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
pub struct CandidateOutcome {
    /// Candidate name.
    pub effect: String,
    /// False when the model already has it (no refit).
    pub applicable: bool,
    /// Its evidence in the residuals.
    pub evidence: Option<Evidence>,
    /// The refit, when one was made.
    pub refit: Option<Refit>,
    /// Why the refit failed, when it did.
    pub refit_error: Option<String>,
    /// Relative validation improvement (reference − after)/reference.
    pub improvement: Option<f64>,
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
fn model_classes_for(test: &str) -> Vec<String> {
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
pub struct Diagnosis {
    /// True only when every residual test passes at the stated level (and so nothing is missing).
    pub adequate: bool,
    /// Failing residual tests no candidate explains (empty when adequate or when a suggestion
    /// exists).
    pub unexplained: Vec<Unexplained>,
    /// Suggested effects, best first.
    pub suggestions: Vec<Suggestion>,
    /// Every candidate tried.
    pub candidates: Vec<CandidateOutcome>,
    /// Every residual test (training residual).
    pub tests: Vec<TestResult>,
    /// The model on the training record.
    pub train: Comparison,
    /// The model on the validation record.
    pub validation: Comparison,
    /// One-line summary.
    pub summary: String,
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

    /// Diagnoses `model` (fitted on `train`) with `validation` as hold-out data.
    pub fn diagnose(
        &self,
        model: &HammersteinModel<T>,
        train: &IoData<T>,
        validation: &IoData<T>,
    ) -> Result<Diagnosis> {
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
        };
        let run = |(c, applicable, _): &(&dyn MissingEffect<T>, bool, Option<Evidence>)| {
            if *applicable && any_evidence {
                Some(c.refit(&ctx))
            } else {
                None
            }
        };
        let refits: Vec<Option<Result<Refit>>> = if self.options.parallel {
            entries.par_iter().map(run).collect()
        } else {
            entries.iter().map(run).collect()
        };
        let mut candidates = Vec::new();
        let mut suggestions = Vec::new();
        for ((c, applicable, evidence), refit) in entries.into_iter().zip(refits) {
            let (refit, refit_error) = match refit {
                Some(Ok(r)) => (Some(r), None),
                Some(Err(e)) => (None, Some(e.to_string())),
                None => (None, None),
            };
            let improvement = refit.as_ref().map(|r| {
                if r.reference_mse > 0.0 {
                    (r.reference_mse - r.validation_mse) / r.reference_mse
                } else {
                    0.0
                }
            });
            if let (Some(r), Some(imp)) = (&refit, improvement)
                && imp >= self.options.min_improvement
                && r.validation_mse.is_finite()
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
                suggestions.push(Suggestion {
                    effect: c.name(),
                    score: imp * if own { 1.0 } else { 0.5 },
                    evidence: evidence.as_ref().map_or_else(
                        || format!("refit improves the validation MSE by {:.1} %", 100.0 * imp),
                        |e| e.sentence.clone(),
                    ),
                    estimate,
                    validation_mse_after: r.validation_mse,
                    validation_mse_before: val_c.metrics.mse,
                    p_value: evidence.as_ref().map(|e| e.p_adjusted),
                    change: r.change.clone(),
                    action: c
                        .apply(model, &analysis)
                        .map(|next| Action::between(model.settings(), &next, &c.name()))
                        .unwrap_or_else(|_| Action::Other(c.name())),
                });
            }
            candidates.push(CandidateOutcome {
                effect: c.name(),
                applicable,
                evidence,
                refit,
                refit_error,
                improvement,
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
        let summary = if adequate {
            "no missing effect found: the residuals are consistent with noise".to_string()
        } else if suggestions.is_empty() {
            let names: Vec<&str> = unexplained.iter().map(|u| u.test.as_str()).collect();
            format!(
                "not adequate: residual test(s) {} still fail, and no candidate of this model \
                 class lowers the validation MSE by a meaningful margin (see `unexplained`)",
                if names.is_empty() {
                    "of the candidates".to_string()
                } else {
                    names.join(", ")
                }
            )
        } else {
            let s = &suggestions[0];
            format!(
                "most likely missing: {} (validation MSE {:.4e} → {:.4e})",
                s.effect, s.validation_mse_before, s.validation_mse_after
            )
        };
        Ok(Diagnosis {
            adequate,
            unexplained,
            suggestions,
            candidates,
            tests: analysis.tests.clone(),
            train: train_c,
            validation: val_c,
            summary,
        })
    }
}

/// Diagnoses a model with the built-in candidates and default options.
pub fn diagnose<T: Real>(
    model: &HammersteinModel<T>,
    train: &IoData<T>,
    validation: &IoData<T>,
) -> Result<Diagnosis> {
    Diagnoser::new().diagnose(model, train, validation)
}
