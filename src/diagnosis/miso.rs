//! Diagnosis of a several-input model: each input's branch diagnosed on its partial residual,
//! the suggestions of all inputs ranked together, each naming its input.
//!
//! Branch i's partial residual rᵢ = y − Σ_{j≠i} ŷⱼ has the same residual as the whole model
//! (rᵢ − ŷᵢ = y − ŷ), so a candidate's training MSE on it is the whole model's training MSE with
//! that branch changed: the candidates of different inputs are compared on one scale (their
//! scores are relative falls of the same training MSE). The input-related residual tests
//! (direction, amplitude, input correlation) read that input; the others are the same for every
//! input. An output nonlinearity (a map after the sum) lies outside this model class: such a
//! suggestion is moved to [`MisoDiagnosis::outside_class`].

use super::compare::Metrics;
use super::diagnoser::diagnose::Diagnoser;
use super::diagnoser::outcome::{Diagnosis, Suggestion};
use super::ids::CandidateId;
use crate::data::IoData;
use crate::error::{Error, Result};
use crate::fit::divergence;
use crate::miso::{MisoModel, MisoSimulation, partial_record};
use crate::real::Real;
use serde::Serialize;

/// A several-input model on a measured record: the simulation (initial states estimated) and
/// its metrics.
#[derive(Debug, Clone, Serialize)]
pub struct MisoComparison {
    /// Measured output.
    pub y: Vec<f64>,
    /// Simulated output.
    pub y_hat: Vec<f64>,
    /// Each input's contribution to ŷ, in input order.
    pub contributions: Vec<Vec<f64>>,
    /// Fit %, MSE, NRMSE, … of ŷ against y.
    pub metrics: Metrics,
}

/// Simulates `model` on `data` (every branch's initial state estimated) and measures the fit;
/// a diverging simulation is [`Error::Diverged`].
pub fn compare_miso<T: Real>(model: &MisoModel<T>, data: &IoData<T>) -> Result<MisoComparison> {
    comparison_of(model.simulate_on(data)?, data)
}

/// [`compare_miso`] of a simulation already run on `data`.
fn comparison_of<T: Real>(sim: MisoSimulation<T>, data: &IoData<T>) -> Result<MisoComparison> {
    if let Some((index, value)) = divergence(&sim.y_hat) {
        return Err(Error::Diverged { index, value });
    }
    let f = |s: &[T]| -> Vec<f64> { s.iter().map(|x| x.as_f64()).collect() };
    let y = f(data.output_slice(0));
    let y_hat = f(&sim.y_hat);
    let metrics = Metrics::of(&y, &y_hat)?;
    Ok(MisoComparison {
        contributions: sim.contributions.iter().map(|c| f(c)).collect(),
        y,
        y_hat,
        metrics,
    })
}

/// One input's suggestion.
#[derive(Debug, Clone, Serialize)]
pub struct MisoSuggestion {
    /// The input's column name.
    pub input: String,
    /// The suggestion for that input's branch.
    #[serde(flatten)]
    pub suggestion: Suggestion,
}

/// One input's branch diagnosed on its partial residual.
#[derive(Debug, Clone, Serialize)]
#[serde(bound = "")]
pub struct InputDiagnosis<T: Real = f64> {
    /// The input's column name.
    pub input: String,
    /// The branch's diagnosis (its suggestions as found, before the ranking across inputs).
    pub diagnosis: Diagnosis<T>,
}

/// The diagnosis of a several-input model.
#[derive(Debug, Clone, Serialize)]
#[serde(bound = "")]
pub struct MisoDiagnosis<T: Real = f64> {
    /// True only when every input's diagnosis is adequate.
    pub adequate: bool,
    /// Suggestions of every input, best first (by score: the same training MSE's relative fall).
    pub suggestions: Vec<MisoSuggestion>,
    /// Suggestions this model class cannot act on (an output nonlinearity after the sum).
    pub outside_class: Vec<MisoSuggestion>,
    /// Each input's diagnosis.
    pub inputs: Vec<InputDiagnosis<T>>,
    /// The whole model on the training record.
    pub train: Metrics,
    /// The whole model on the validation record.
    pub validation: Metrics,
    /// One-line summary.
    pub summary: String,
}

impl<T: Real> MisoDiagnosis<T> {
    /// The model with `suggestion` acted on: its input's branch replaced by the diagnosis' refit
    /// of that branch, then every branch refitted by backfitting sweeps on `train` with its
    /// structure selected again ([`MisoHammerstein::refit_from`](crate::miso::MisoHammerstein::refit_from): the other branches' orders
    /// were chosen while this branch lacked the effect).
    pub fn apply(
        &self,
        suggestion: &MisoSuggestion,
        model: &MisoModel<T>,
        train: &IoData<T>,
    ) -> Result<MisoModel<T>> {
        let i = model
            .input_names()
            .iter()
            .position(|n| *n == suggestion.input)
            .ok_or_else(|| Error::InvalidParameter(format!("no input '{}'", suggestion.input)))?;
        let d = &self.inputs[i].diagnosis;
        let refit = d
            .refitted(&suggestion.suggestion)
            .ok_or_else(|| Error::NotApplicable {
                effect: suggestion.suggestion.effect.to_string(),
                change: suggestion.suggestion.action.label(),
            })?
            .clone();
        let mut branches = model.branches().to_vec();
        branches[i] = refit;
        let base = MisoModel::from_branches(
            branches,
            model.input_names().to_vec(),
            model.output_name().to_string(),
            model.report().clone(),
        )?;
        let settings = crate::miso::MisoHammerstein::new(
            base.branches()
                .iter()
                .map(|b| b.settings().clone())
                .collect(),
        )
        .max_sweeps(model.settings().max_sweeps)
        .tolerance(model.settings().tolerance);
        settings.refit_from(train, &base)
    }
}

impl<T: Real> Diagnoser<T> {
    /// Diagnoses a several-input model fitted on `train`, with `validation` held out: each input's
    /// branch on its partial residual, the suggestions ranked together.
    pub fn diagnose_miso(
        &self,
        model: &MisoModel<T>,
        train: &IoData<T>,
        validation: &IoData<T>,
    ) -> Result<MisoDiagnosis<T>> {
        let on_train = model.simulate_on(train)?;
        let on_valid = model.simulate_on(validation)?;
        let mut inputs = Vec::new();
        let mut suggestions = Vec::new();
        let mut outside_class = Vec::new();
        for (i, branch) in model.branches().iter().enumerate() {
            let input = model.input_names()[i].clone();
            let tr = partial_record(train, i, &on_train.contributions)?;
            let va = partial_record(validation, i, &on_valid.contributions)?;
            let diagnosis = self.diagnose(branch, &tr, &va)?;
            for s in &diagnosis.suggestions {
                let ms = MisoSuggestion {
                    input: input.clone(),
                    suggestion: s.clone(),
                };
                if s.effect == CandidateId::OutputNonlinearity
                    || s.effect == CandidateId::FeedbackNonlinearity
                {
                    outside_class.push(ms);
                } else {
                    suggestions.push(ms);
                }
            }
            inputs.push(InputDiagnosis { input, diagnosis });
        }
        suggestions.sort_by(|a, b| b.suggestion.score.total_cmp(&a.suggestion.score));
        let adequate = inputs.iter().all(|d| d.diagnosis.adequate);
        let train_m = comparison_of(on_train, train)?.metrics;
        let valid_m = comparison_of(on_valid, validation)?.metrics;
        let summary = match suggestions.first() {
            _ if adequate => "adequate: every residual test passes for every input".to_string(),
            Some(s) => format!(
                "input '{}' misses {} (training MSE −{:.1} %)",
                s.input,
                s.suggestion.action.label(),
                100.0 * (1.0 - s.suggestion.train_mse_after / s.suggestion.train_mse_before)
            ),
            None => "not adequate, and no candidate of this model class helps".to_string(),
        };
        Ok(MisoDiagnosis {
            adequate,
            suggestions,
            outside_class,
            inputs,
            train: train_m,
            validation: valid_m,
            summary,
        })
    }
}

/// One step of a followed several-input sequence.
#[derive(Debug, Clone)]
pub struct MisoFollowStep<T: Real> {
    /// What changed ("start", "u2: + dead-zone", "u1: order 3").
    pub change: String,
    /// The model of this step.
    pub model: MisoModel<T>,
    /// Its diagnosis.
    pub diagnosis: MisoDiagnosis<T>,
}

/// A followed several-input sequence.
#[derive(Debug, Clone)]
pub struct MisoFollowed<T: Real> {
    /// Every step, the starting model first.
    pub steps: Vec<MisoFollowStep<T>>,
    /// Why it stopped.
    pub stop: super::guided::follow::FollowStop,
}

impl<T: Real> Diagnoser<T> {
    /// From `start`, fits, diagnoses and acts on the top suggestion (of any input) up to
    /// `max_steps` times, as [`Diagnoser::follow`] does for one input.
    pub fn follow_miso(
        &self,
        start: &crate::miso::MisoHammerstein<T>,
        train: &IoData<T>,
        validation: &IoData<T>,
        max_steps: usize,
    ) -> Result<MisoFollowed<T>> {
        let (steps, stop) = super::guided::follow::drive(
            start.fit(train)?,
            max_steps,
            |m| self.diagnose_miso(m, train, validation),
            |d| (d.adequate, !d.suggestions.is_empty()),
            |d, m| first_applicable(d, m, train),
        )?;
        let steps = steps
            .into_iter()
            .map(|(change, model, diagnosis)| MisoFollowStep {
                change,
                model,
                diagnosis,
            })
            .collect();
        Ok(MisoFollowed { steps, stop })
    }
}

impl<T: Real> MisoFollowed<T> {
    /// The steps (1-based) whose validation MSE rose over the previous step's.
    pub fn validation_rose(&self) -> Vec<usize> {
        super::guided::follow::rises(self.steps.iter().map(|s| s.diagnosis.validation.mse))
    }
}

/// The model of the best suggestion that can be acted on, with its label; the first error when
/// none can.
fn first_applicable<T: Real>(
    d: &MisoDiagnosis<T>,
    model: &MisoModel<T>,
    train: &IoData<T>,
) -> Result<(MisoModel<T>, String)> {
    let mut first_error = None;
    for s in &d.suggestions {
        match d.apply(s, model, train) {
            Ok(m) => return Ok((m, format!("{}: {}", s.input, s.suggestion.action.label()))),
            Err(e) => {
                first_error.get_or_insert(e);
            }
        }
    }
    Err(first_error.unwrap_or_else(|| Error::InvalidParameter("no suggestion".into())))
}
