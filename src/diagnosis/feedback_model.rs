//! The diagnosis of a model with a nonlinearity in feedback, and the guided step that adds one.
//!
//! [`diagnose_feedback`]: the residual tests of a feedback model (`crate::feedback`) on its
//! training record — the same built-in tests as a Hammerstein model's, the input-side columns
//! filtered through the model's linear block from u to y, the block's input as v̂ (N(u) with
//! an input nonlinearity before the loop, else u) — with the verdict: adequate when every test passes at the family-wise
//! level, else the failing tests. No candidate is refitted: the candidates extend Hammerstein
//! models.
//!
//! [`feedback_step`]: the `feedback-nonlinearity` suggestion followed — the feedback model of
//! the suggested basis and variable fitted on the training record at the model's order — and
//! confirmed as every guided step is (`guided::confirm`): the training record's last and first
//! quarters held back in turn, the model before the step (its structure, order fixed) and the
//! feedback model each fitted on the other three quarters and simulated on the held-back one
//! (initial state estimated there), the Diebold–Mariano statistic of the loss differential
//! below `ConfirmRule::z`.

use crate::data::IoData;
use crate::diagnosis::candidates::feedback_candidate::{feedback_command, fit_loop, loop_settings};
use crate::diagnosis::compare::compare;
use crate::diagnosis::confirm::{ConfirmRule, Confirmation, diebold_mariano};
use crate::diagnosis::diagnose::Diagnoser;
use crate::diagnosis::ids::CandidateId;
use crate::diagnosis::outcome::{Diagnosis, Unexplained, unexplained_of};
use crate::diagnosis::residual_tests::analysis::{AnalysisOptions, ResidualAnalysis};
use crate::diagnosis::residual_tests::checks::TestResult;
use crate::diagnosis::residual_tests::checks::feedback_signature::feedback_signature;
use crate::diagnosis::residual_tests::stats::normal_cdf;
use crate::diagnosis::residual_tests::test_registry::TestRegistry;
use crate::error::{Error, Result};
use crate::feedback::{FeedbackFit, FeedbackKind, FeedbackModel, FeedbackOn, FeedbackSettings};
use crate::fit::HammersteinModel;
use crate::real::Real;
use serde::Serialize;

/// The residual tests of a feedback model.
#[derive(Debug, Clone, Serialize)]
pub struct FeedbackDiagnosis {
    /// True when every residual test passes at the family-wise level.
    pub adequate: bool,
    /// Every residual test (training residual, Bonferroni-adjusted).
    pub tests: Vec<TestResult>,
    /// The failing tests and the model classes that would address them.
    pub unexplained: Vec<Unexplained>,
    /// Training RMS error (initial state estimated).
    pub train_rms: f64,
    /// Validation RMS error (initial state estimated on the validation record).
    pub validation_rms: f64,
    /// Validation fit in per cent.
    pub validation_fit_percent: f64,
    /// One-line summary.
    pub summary: String,
}

/// The model's linear block from u to y (the loop's input column left out), normalised units.
fn input_block(model: &FeedbackModel) -> Result<crate::StateSpace<f64>> {
    let l = model.linear()?;
    let n = model.order();
    crate::StateSpace::new(
        l.a.clone(),
        faer::Mat::from_fn(n, 1, |i, _| l.b[(i, 0)]),
        l.c.clone(),
        faer::Mat::from_fn(1, 1, |_, _| l.d[(0, 0)]),
    )
}

/// The residual tests of `model` on `train` and its errors on `validation` (the module's text).
pub fn diagnose_feedback(
    model: &FeedbackModel,
    train: &IoData<f64>,
    validation: &IoData<f64>,
    options: &AnalysisOptions,
) -> Result<FeedbackDiagnosis> {
    let tc = model.compare(train)?;
    let vc = model.compare(validation)?;
    let u = train.input(0);
    let y = train.output(0);
    let v_hat = model.eval_input(&u).unwrap_or_else(|| u.clone());
    let tests = TestRegistry::builtin();
    let a = ResidualAnalysis::with_tests(
        &u,
        &y,
        &tc.simulated,
        &v_hat,
        &input_block(model)?,
        options.clone(),
        &tests,
    )?;
    let adequate = !a.any_significant();
    let unexplained = unexplained_of(&a.tests, &tests);
    let summary = if adequate {
        "no missing effect found: the feedback model's residuals are consistent with noise".into()
    } else {
        let names: Vec<&str> = unexplained.iter().map(|u| u.test.as_str()).collect();
        format!(
            "not adequate: residual test(s) {} fail for the feedback model",
            names.join(", ")
        )
    };
    Ok(FeedbackDiagnosis {
        adequate,
        tests: a.tests,
        unexplained,
        train_rms: tc.rms,
        validation_rms: vc.rms,
        validation_fit_percent: vc.fit_percent,
        summary,
    })
}

/// The guided step that replaces a Hammerstein model by a feedback model.
#[derive(Debug, Clone)]
pub struct FeedbackStep {
    /// The basis.
    pub kind: FeedbackKind,
    /// What z is.
    pub on: FeedbackOn,
    /// The options that fit it ("--feedback-nonlinearity coulomb --feedback-on velocity").
    pub command: String,
    /// The feedback model fitted on the whole training record.
    pub fit: FeedbackFit,
    /// Its validation MSE (initial state estimated on the validation record).
    pub validation_mse: f64,
    /// The check on the held-back quarters of the training record (`None`: not asked for).
    pub confirmation: Option<Confirmation>,
}

impl FeedbackStep {
    /// True when the step is taken: confirmed, or not asked to be.
    pub fn taken(&self) -> bool {
        self.confirmation.as_ref().is_none_or(|c| c.confirmed)
    }
}

/// True when `d`'s top suggestion is the `feedback-nonlinearity` candidate.
pub fn suggests_feedback<T: Real>(d: &Diagnosis<T>) -> bool {
    d.suggestions
        .first()
        .is_some_and(|s| s.effect == CandidateId::FeedbackNonlinearity)
}

/// Follows a `feedback-nonlinearity` suggestion for `model` (fitted on `train`): the basis and
/// variable from the residual signature, the feedback model fitted, its validation MSE, and —
/// with `rule` — its confirmation on held-back quarters of `train` (the module's text).
pub fn feedback_step<T: Real>(
    diagnoser: &Diagnoser<T>,
    model: &HammersteinModel<T>,
    train: &IoData<T>,
    validation: &IoData<T>,
    rule: Option<ConfirmRule>,
) -> Result<FeedbackStep> {
    let a = diagnoser.analysis(model, train)?;
    let sig = feedback_signature(&a).ok_or_else(|| {
        Error::Identification("the feedback signature could not be computed".into())
    })?;
    let on = sig.on;
    let n = model.linear().order();
    let with_d = on == FeedbackOn::Output && model.has_feedthrough();
    let train64: IoData<f64> = train.cast();
    let (kind, fit) = fit_loop(sig.kind, on, n, with_d, &train64)?;
    let s = loop_settings(kind, on, n, with_d);
    let validation_mse = fit
        .model
        .compare(&validation.cast())
        .map_or(f64::INFINITY, |c| c.rms * c.rms);
    let confirmation = rule.map(|r| confirm(r, model, train, &s));
    Ok(FeedbackStep {
        kind,
        on,
        command: feedback_command(kind, on),
        fit,
        validation_mse,
        confirmation,
    })
}

/// The feedback step's check on the held-back quarters (`guided::confirm`'s algorithm, the
/// after-model a feedback model).
fn confirm<T: Real>(
    rule: ConfirmRule,
    model: &HammersteinModel<T>,
    train: &IoData<T>,
    s: &FeedbackSettings,
) -> Confirmation {
    let n = train.len();
    let held = ((n as f64) * rule.hold_back.clamp(0.0, 0.5)).round() as usize;
    if held < rule.min_held_back || n - held < rule.min_held_back {
        return Confirmation::unchecked(format!(
            "the training record ({n} samples) is too short to hold back {} of them",
            rule.min_held_back.max(held)
        ));
    }
    let settings = model.settings().clone().at_structure_of(model);
    let bounds = [(0, n - held, n - held, n), (held, n, 0, held)];
    let (mut before, mut after) = (Vec::new(), Vec::new());
    for &(a, b, c, d) in bounds.iter().take(rule.folds.clamp(1, 2)) {
        let fold = (|| -> Result<(Vec<f64>, Vec<f64>)> {
            let fit_part = train.slice(a, b)?;
            let held_part = train.slice(c, d)?;
            let current = settings.fit(&fit_part)?;
            let e_before = compare(&current, &held_part)?.residual;
            let fb = crate::feedback::fit(s, &fit_part.cast())?;
            let h64: IoData<f64> = held_part.cast();
            let sim = fb.model.compare(&h64)?.simulated;
            let e_after = h64
                .output(0)
                .iter()
                .zip(&sim)
                .map(|(y, yh)| y - yh)
                .collect();
            Ok((e_before, e_after))
        })();
        match fold {
            Ok((b, a)) => {
                before.extend(b);
                after.extend(a);
            }
            Err(e) => {
                return Confirmation::unchecked(format!("its refit on a fitting part failed: {e}"));
            }
        }
    }
    let mse = |e: &[f64]| e.iter().map(|x| x * x).sum::<f64>() / e.len().max(1) as f64;
    let (_, statistic) = diebold_mariano(&before, &after);
    let (mse_before, mse_after) = (mse(&before), mse(&after));
    Confirmation {
        confirmed: statistic < rule.z && mse_after.is_finite(),
        held_back: before.len(),
        mse_before,
        mse_after,
        statistic,
        p_value: normal_cdf(statistic),
        note: None,
    }
}
