//! The diagnosis of a model on whole records (the rule is documented in `diagnose.rs`): the
//! residual analysis, every candidate's evidence and refit, the judgment of each refit, the
//! suggestions ranked. Also the judgment's pieces the screened diagnosis (`screen.rs`) reuses.

use super::outcome::{
    Action, CandidateOutcome, Diagnosis, DiagnosisOptions, Suggestion, Unexplained, summary_of,
    unexplained_of,
};
use crate::data::IoData;
use crate::diagnosis::candidates::candidate::{Evidence, MissingEffect, Refit, RefitContext};
use crate::diagnosis::candidates::registry::Registry;
use crate::diagnosis::compare::{Comparison, compare};
use crate::diagnosis::residual_tests::analysis::ResidualAnalysis;
use crate::diagnosis::residual_tests::test_registry::TestRegistry;
use crate::error::Result;
use crate::fit::order_selection::{exact_floor_of, training_mse};
use crate::fit::{HammersteinModel, Observer};
use crate::real::Real;
use rayon::prelude::*;

/// What a diagnosis runs with: the candidates, the residual tests and the options.
pub(crate) struct Setup<'a, T: Real> {
    /// The candidates.
    pub registry: &'a Registry<T>,
    /// The residual tests.
    pub tests: &'a TestRegistry,
    /// The options.
    pub options: &'a DiagnosisOptions,
    /// Notified of the stages of a screened diagnosis and by every refit.
    pub observer: Option<&'a dyn Observer>,
}

/// One candidate before its refit: whether it applies to the model, and its evidence.
type Entry<'r, T> = (&'r dyn MissingEffect<T>, bool, Option<Evidence>);

/// The numbers a refit is judged by: the relative training improvement and ΔBIC.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Judgment {
    /// (reference − after)/reference of the training MSE.
    pub improvement: f64,
    /// ΔBIC on the training part (negative: better).
    pub criterion_change: f64,
}

impl Judgment {
    /// The judgment of `r` on a training record of `n_train` samples whose exact-fit MSE level
    /// is `floor` (the MSEs floored there as the order selection floors them).
    pub fn of<T: Real>(r: &Refit<T>, n_train: f64, floor: f64) -> Self {
        let improvement = if r.reference_train_mse > 0.0 {
            (r.reference_train_mse - r.train_mse) / r.reference_train_mse
        } else {
            0.0
        };
        let criterion_change = n_train
            * (r.train_mse.max(floor) / r.reference_train_mse.max(floor)).ln()
            + crate::fit::order_selection::penalty(
                r.added_parameters,
                r.added_states,
                n_train as usize,
            );
        Self {
            improvement,
            criterion_change,
        }
    }

    /// True when the refit is suggested: ΔBIC < 0, the improvement at least `min_improvement`,
    /// its parameters not at their null value, a finite training MSE.
    pub fn passes<T: Real>(&self, r: &Refit<T>, min_improvement: f64) -> bool {
        self.improvement >= min_improvement
            && self.criterion_change < 0.0
            && r.null_parameters.is_none()
            && r.train_mse.is_finite()
    }

    /// The ranking score: the improvement, halved without the candidate's own significant test.
    pub fn score(&self, evidence: Option<&Evidence>) -> f64 {
        let own = evidence.is_some_and(|e| e.significant);
        self.improvement * if own { 1.0 } else { 0.5 }
    }
}

impl<T: Real> Setup<'_, T> {
    /// The residual analysis of `model` on the training record.
    pub fn analysis(
        &self,
        model: &HammersteinModel<T>,
        train: &IoData<T>,
    ) -> Result<ResidualAnalysis> {
        let train_c = compare(model, train)?;
        self.analysis_of(model, &train_c)
    }

    /// The residual analysis of `model` from its training comparison.
    pub fn analysis_of(
        &self,
        model: &HammersteinModel<T>,
        train_c: &Comparison,
    ) -> Result<ResidualAnalysis> {
        let linear = model.linear().cast::<f64>();
        // the analysis works on the input as the nonlinearity sees it: u(k − nk)
        let nk = model.delay();
        let u_delayed = crate::fit::delayed(&train_c.u, nk);
        ResidualAnalysis::with_tests(
            &u_delayed,
            &train_c.y,
            &train_c.y_hat,
            &train_c.v_hat,
            &linear,
            self.options.analysis.clone(),
            self.tests,
        )
    }

    /// The diagnosis on the whole records, without screening; `own_record`: `train` is the
    /// record the model was fitted on (false for a screening window of it).
    pub fn diagnose_whole(
        &self,
        model: &HammersteinModel<T>,
        train: &IoData<T>,
        validation: &IoData<T>,
        own_record: bool,
    ) -> Result<Diagnosis<T>> {
        let train_c = compare(model, train)?;
        let val_c = compare(model, validation)?;
        let analysis = self.analysis_of(model, &train_c)?;
        let entries: Vec<Entry<'_, T>> = self
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
            // the model's own training MSE belongs to its training record: on a screening
            // window the reference is the window's simulation MSE, as the candidates' are (their
            // refits are fitted on the window); the whole record's, when lower than the window's,
            // made every candidate look worse (Silverbox: +75 % for each)
            train_mse: if own_record {
                training_mse(model, train)
            } else {
                train_c.metrics.mse
            },
            observer: self.observer,
        };
        let refits = self.refits(&entries, &ctx, any_evidence);
        let (candidates, mut suggestions) = self.judge_all(&ctx, entries, refits);
        suggestions.sort_by(|a, b| b.score.total_cmp(&a.score));
        // adequate only when the residual tests pass: failing tests that no candidate explains
        // are reported as unexplained, with the model classes that would address them
        let adequate = suggestions.is_empty() && !any_evidence;
        let unexplained: Vec<Unexplained> = if suggestions.is_empty() && any_evidence {
            unexplained_of(&analysis.tests, self.tests)
        } else {
            Vec::new()
        };
        let summary = summary_of(adequate, &unexplained, &suggestions);
        let generalisation =
            super::generalisation::Generalisation::of(&train_c, &val_c, model.delay());
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
            generalisation,
        })
    }

    /// Every applicable candidate's refit (in parallel when the options say so), none when no
    /// test and no evidence is significant.
    fn refits(
        &self,
        entries: &[Entry<'_, T>],
        ctx: &RefitContext<'_, T>,
        any_evidence: bool,
    ) -> Vec<Option<Result<Refit<T>>>> {
        // each finished refit is reported (the command line's spinner counts them and hands
        // the allocator's free memory back between them)
        let total = entries
            .iter()
            .filter(|(_, applicable, _)| *applicable && any_evidence)
            .count();
        let done = std::sync::atomic::AtomicUsize::new(0);
        let run = |(c, applicable, _): &Entry<'_, T>| {
            if *applicable && any_evidence {
                let r = c.refit(ctx).map(|mut r| {
                    r.null_parameters = c.null_parameters(&r, ctx.train);
                    r
                });
                if let Some(o) = self.observer {
                    let k = done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
                    o.progress("refitting the candidates", k, total);
                }
                Some(r)
            } else {
                None
            }
        };
        if self.options.parallel {
            entries.par_iter().map(run).collect()
        } else {
            entries.iter().map(run).collect()
        }
    }

    /// Each candidate's outcome, and the suggestions among them (unsorted).
    fn judge_all(
        &self,
        ctx: &RefitContext<'_, T>,
        entries: Vec<Entry<'_, T>>,
        refits: Vec<Option<Result<Refit<T>>>>,
    ) -> (Vec<CandidateOutcome<T>>, Vec<Suggestion>) {
        let n_train = ctx.train.len().max(1) as f64;
        let floor = exact_floor_of(ctx.train);
        let mut candidates = Vec::new();
        let mut suggestions = Vec::new();
        for ((c, applicable, evidence), refit) in entries.into_iter().zip(refits) {
            let (refit, refit_error) = match refit {
                Some(Ok(r)) => (Some(r), None),
                Some(Err(e)) => (None, Some(e.to_string())),
                None => (None, None),
            };
            let judgment = refit.as_ref().map(|r| Judgment::of(r, n_train, floor));
            if let (Some(r), Some(j)) = (&refit, judgment)
                && j.passes(r, self.options.min_improvement)
            {
                suggestions.push(suggestion(ctx, c, evidence.as_ref(), r, j));
            }
            candidates.push(CandidateOutcome {
                effect: c.id(),
                applicable,
                evidence,
                refit,
                refit_error,
                improvement: judgment.map(|j| j.improvement),
                criterion_change: judgment.map(|j| j.criterion_change),
            });
        }
        (candidates, suggestions)
    }
}

/// The suggestion of candidate `c` whose refit `r` passed with judgment `j`.
fn suggestion<T: Real>(
    ctx: &RefitContext<'_, T>,
    c: &dyn MissingEffect<T>,
    evidence: Option<&Evidence>,
    r: &Refit<T>,
    j: Judgment,
) -> Suggestion {
    let imp = j.improvement;
    let mut estimate = evidence.map(|e| e.estimate.clone()).unwrap_or_default();
    for e in &r.estimate {
        estimate.insert(e.clone());
    }
    let action = match &r.model {
        Some(next) => Action::between(ctx.model.settings(), next.settings(), &c.id()),
        None => Action::Other(c.id()),
    };
    Suggestion {
        effect: c.id(),
        score: j.score(evidence),
        evidence: evidence.map_or_else(
            || format!("refit improves the training MSE by {:.1} %", 100.0 * imp),
            |e| e.sentence.clone(),
        ),
        estimate,
        train_mse_after: r.train_mse,
        train_mse_before: r.reference_train_mse,
        criterion_change: j.criterion_change,
        validation_mse_after: r.validation_mse,
        validation_mse_before: ctx.validation_comparison.metrics.mse,
        p_value: evidence.map(|e| e.p_adjusted),
        change: r.change.clone(),
        action,
    }
}
