//! The feedback-nonlinearity candidate: a static nonlinearity acting inside the loop, on the
//! output (stiffness, a clearance) or on its first difference (friction on the velocity), that a
//! Hammerstein model cannot express (`crate::feedback`: x(k+1) = A x + B u + E f(z)).
//!
//! Signature (`residual_tests::checks::feedback_signature`): an odd function of the simulated
//! output ŷ or of Δŷ — z³, tanh(z/δ), clip(z, ±d) — filtered through the model's linear block
//! explains part of the residual beyond the input-level bins, their rising/falling split and z
//! itself; the best of the six shapes (three bases × output/velocity) names the basis and the
//! variable, its p-value Bonferroni-corrected over the shapes.
//!
//! Rule against input nonlinearities: the candidate is refitted (and so can be offered) only when
//! its shape explains more of the held-out last third of the residual than the input-side shapes
//! (the columns of the dead-zone, saturation, hysteresis, preload and level tests, u², u³)
//! explain together, each regression fitted on the first two thirds. Otherwise it is reported as
//! not credited, with both shares. A structure verdict at hand
//! ([`AnalysisOptions::structure`](crate::diagnosis::residual_tests::analysis::AnalysisOptions):
//! a multisine record at several levels) is cited in the evidence; a `feedback` verdict — poles
//! that move with the level, which no input nonlinearity produces — offers the candidate
//! whatever the held-out shares, and its p-value joins the signature's (Bonferroni over the
//! two).
//!
//! Refit: [`crate::feedback::fit`] of the chosen basis and variable at the model's order (a
//! feedback loop added does not change the number of states, as a static effect does not); the
//! training MSE with the initial state estimated, as the other candidates'; the validation MSE
//! from an initial state estimated on the validation record (`FeedbackModel::compare`).

use super::candidate::{Evidence, MissingEffect, Refit, RefitContext, readable};
use super::estimate::{Estimate, Estimates, Quantity};
use crate::data::IoData;
use crate::diagnosis::ids::{CandidateId, TestId};
use crate::diagnosis::residual_tests::analysis::ResidualAnalysis;
use crate::diagnosis::residual_tests::checks::feedback_signature::{
    FeedbackSignature, feedback_signature, kind_name,
};
use crate::diagnosis::residual_tests::checks::{TestFamily, TestResult};
use crate::diagnosis::residual_tests::structure_evidence::StructureEvidence;
use crate::error::Result;
use crate::feedback::{FeedbackKind, FeedbackOn, FeedbackSettings};
use crate::fit::{Hammerstein, HammersteinModel};
use crate::real::Real;
use crate::structure::Verdict;
use crate::subspace::Order;

/// A nonlinearity in feedback on the output or its difference.
#[derive(Debug, Clone, Copy, Default)]
pub struct FeedbackNonlinearity;

/// The options a user types to fit the feedback model of this basis and variable.
pub fn feedback_command(kind: FeedbackKind, on: FeedbackOn) -> String {
    format!(
        "--feedback-nonlinearity {} --feedback-on {}",
        kind_name(kind),
        on.name()
    )
}

/// The basis and variable a diagnosis' feedback suggestion stands for, read from the
/// residual analysis it was made on (`None`: no shape could be tested).
pub fn feedback_choice(a: &ResidualAnalysis) -> Option<(FeedbackKind, FeedbackOn)> {
    feedback_signature(a).map(|s| (s.kind, s.on))
}

/// The structure verdict at hand when it is `feedback`: poles that move with the level.
fn moving_poles(a: &ResidualAnalysis) -> Option<&StructureEvidence> {
    a.options
        .structure
        .as_ref()
        .filter(|v| v.verdict == Verdict::Feedback)
}

/// Whether the candidate is refitted: its shape explains more of the held-out residual than
/// the input side, or the levels' poles move.
fn offered(s: &FeedbackSignature, a: &ResidualAnalysis) -> bool {
    s.offered() || moving_poles(a).is_some()
}

fn test_of(s: &FeedbackSignature, m: usize, alpha: f64) -> TestResult {
    let mut t = TestResult::new(
        TestId::FeedbackNonlinearity,
        "odd functions of the simulated output or of its difference, filtered through the linear \
         block, beyond the input-level bins and their rising/falling split (feedback signature)",
        TestFamily::Nonlinear,
        "F",
        s.f,
        vec![1.0],
        s.p_value,
    );
    t.p_adjusted = (s.p_value * m as f64).min(1.0);
    t.significant = t.p_adjusted < alpha;
    t.detail = format!(
        "best shape {} on the {}; held-out residual variance explained: feedback {:.1} %, input \
         side {:.1} %",
        kind_name(s.kind),
        s.on.name(),
        100.0 * s.held_out_feedback,
        100.0 * s.held_out_input
    );
    t
}

/// The settings of a feedback refit of `kind` on `on` at the order `n`.
pub fn loop_settings(
    kind: FeedbackKind,
    on: FeedbackOn,
    n: usize,
    with_d: bool,
) -> FeedbackSettings {
    let mut settings = FeedbackSettings::new(kind, on);
    settings.order = Order::Fixed(n);
    settings.horizon = settings.horizon.max(2 * n + 1);
    settings.with_d = with_d;
    settings
}

/// The feedback model of the signature's `kind` on `on` at order `n`, fitted on `train`; on the
/// velocity both friction shapes (`coulomb` and `dead-zone`, whose force with the viscous term is
/// a saturating ramp) are fitted and the lower training error kept (they have as many
/// parameters): the residual of a linear model, read through its ŷ, does not tell a smooth sign
/// from a ramp reliably. Returns the kind kept and its fit.
pub fn fit_loop(
    kind: FeedbackKind,
    on: FeedbackOn,
    n: usize,
    with_d: bool,
    train: &IoData<f64>,
) -> Result<(FeedbackKind, crate::feedback::FeedbackFit)> {
    let mut kinds = vec![kind];
    if on == FeedbackOn::Velocity {
        for k in [FeedbackKind::Coulomb, FeedbackKind::DeadZone] {
            if k != kind {
                kinds.push(k);
            }
        }
    }
    let mut best: Option<(FeedbackKind, crate::feedback::FeedbackFit)> = None;
    let mut first_err = None;
    for k in kinds {
        match crate::feedback::fit(&loop_settings(k, on, n, with_d), train) {
            Ok(f) => {
                if best.as_ref().is_none_or(|b| f.rms < b.1.rms) {
                    best = Some((k, f));
                }
            }
            Err(e) => {
                first_err.get_or_insert(e);
            }
        }
    }
    best.ok_or_else(|| {
        first_err.unwrap_or_else(|| crate::error::Error::Identification("no feedback fit".into()))
    })
}

/// The number of free parameters the feedback model adds to a linear model of the same order:
/// f's gains, and the viscous term for `velocity`.
fn loop_parameters(m: &crate::feedback::FeedbackModel) -> i64 {
    m.nonlinearity().gains().len() as i64 + i64::from(m.feedback_on() == FeedbackOn::Velocity)
}

impl<T: Real> MissingEffect<T> for FeedbackNonlinearity {
    fn id(&self) -> CandidateId {
        CandidateId::FeedbackNonlinearity
    }
    /// Single-input single-output models only (the feedback model has one input and one output).
    fn applies_to(&self, model: &HammersteinModel<T>) -> bool {
        model.linear().n_inputs() == 1 && model.linear().n_outputs() == 1
    }
    fn evidence(&self, a: &ResidualAnalysis) -> Option<Evidence> {
        let s = feedback_signature(a)?;
        let mut t = test_of(&s, a.tests.len() + 1, a.options.alpha);
        if let Some(v) = moving_poles(a) {
            t.p_adjusted = (2.0 * t.p_adjusted.min(v.p_value)).min(1.0);
            t.significant = t.p_adjusted < a.options.alpha;
        }
        let verdict = a.options.structure.as_ref().map_or(String::new(), |v| {
            format!(
                "; the levels' best linear approximations: {}{}",
                v.line,
                if v.verdict == Verdict::Feedback {
                    ", which a loop produces and an input nonlinearity does not"
                } else {
                    ""
                }
            )
        });
        let sentence = format!(
            "an odd function of the simulated {} ({}) explains part of the residual beyond the \
             input's level bins (F = {:.1}, p = {}); on the held-out last third it explains {:.1} % \
             of the residual variance against {:.1} % for the input-side shapes together{verdict}{}",
            if s.on == FeedbackOn::Output {
                "output"
            } else {
                "output's difference (velocity)"
            },
            kind_name(s.kind),
            s.f,
            readable(t.p_value),
            100.0 * s.held_out_feedback,
            100.0 * s.held_out_input,
            if offered(&s, a) {
                format!(
                    ": a nonlinearity in feedback ({})",
                    feedback_command(s.kind, s.on)
                )
            } else {
                ": an input nonlinearity explains it as well".into()
            }
        );
        let estimate = Estimates::residual([
            (
                Quantity::User("held_out_feedback".into()),
                Some(s.held_out_feedback),
            ),
            (
                Quantity::User("held_out_input".into()),
                Some(s.held_out_input),
            ),
        ]);
        Some(Evidence::from_test(&t, sentence, estimate))
    }
    /// The model's own settings: the change lies outside the Hammerstein class (a feedback
    /// model, fitted by [`refit`](MissingEffect::refit)).
    fn apply(&self, model: &HammersteinModel<T>, _a: &ResidualAnalysis) -> Result<Hammerstein<T>> {
        Ok(model.settings().clone())
    }
    /// The feedback model of the signature's basis and variable at the model's order, or — when
    /// the input side explains the held-out residual as well — no refit (its MSEs not a number,
    /// the reason in `null_parameters`).
    fn refit(&self, ctx: &RefitContext<'_, T>) -> Result<Refit<T>> {
        let s = feedback_signature(ctx.analysis).ok_or_else(|| {
            crate::error::Error::Identification(
                "the feedback signature could not be computed".into(),
            )
        })?;
        let mut r = Refit {
            train_mse: f64::NAN,
            reference_train_mse: ctx.train_mse,
            added_parameters: 0,
            added_states: 0,
            validation_mse: f64::NAN,
            reference_mse: ctx.validation_comparison.metrics.mse,
            change: format!(
                "nonlinearity in feedback {} on the {} ({})",
                kind_name(s.kind),
                s.on.name(),
                feedback_command(s.kind, s.on)
            ),
            estimate: Estimates::new(),
            null_parameters: None,
            model: None,
        };
        if !offered(&s, ctx.analysis) {
            r.change = format!("not refitted: {}", r.change);
            r.null_parameters = Some(format!(
                "an input nonlinearity explains the held-out residual as well (held-out variance \
                 explained: feedback {:.1} %, input side {:.1} %)",
                100.0 * s.held_out_feedback,
                100.0 * s.held_out_input
            ));
            return Ok(r);
        }
        let train: IoData<f64> = ctx.train.cast();
        let with_d = s.on == FeedbackOn::Output && ctx.model.has_feedthrough();
        let (kind, fit) = fit_loop(s.kind, s.on, ctx.model.linear().order(), with_d, &train)?;
        let n = ctx.model.linear().order();
        if kind != s.kind {
            r.change = format!(
                "nonlinearity in feedback {} on the {} ({})",
                kind_name(kind),
                s.on.name(),
                feedback_command(kind, s.on)
            );
        }
        r.train_mse = fit.rms * fit.rms;
        r.validation_mse = match fit.model.compare(&ctx.validation.cast()) {
            Ok(c) => c.rms * c.rms,
            Err(e) => {
                r.change = format!("{}; on the validation record: {e}", r.change);
                f64::INFINITY
            }
        };
        // the loop's parameters (the input nonlinearity's, which the feedback model drops, are
        // not credited back: the criterion errs on the side of the model under diagnosis)
        r.added_parameters = loop_parameters(&fit.model).max(1);
        r.added_states = fit.model.state_len() as i64 - n as i64;
        for (j, g) in fit.model.nonlinearity().gains().iter().enumerate() {
            r.estimate.insert(Estimate::refit(
                Quantity::User(format!("feedback.g{}", j + 1)),
                *g,
                None,
            ));
        }
        Ok(r)
    }
    /// Null value: the loop's parameters together not distinguishable from 0 by the F test of
    /// the refit against the model (level 1 %, as for the play weights).
    fn null_parameters(&self, refit: &Refit<T>, train: &IoData<T>) -> Option<String> {
        if refit.null_parameters.is_some() || !refit.train_mse.is_finite() {
            return refit.null_parameters.clone();
        }
        let k = refit.added_parameters.max(1) as usize;
        let p = super::pi_candidate::joint_p_value(refit, train.len(), k);
        (p.is_nan() || p >= super::pi_candidate::JOINT_LEVEL).then(|| {
            format!(
                "the feedback loop does not lower the training error distinguishably from 0 (F test p = {})",
                readable(p)
            )
        })
    }
}
