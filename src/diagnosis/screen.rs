//! The diagnosis of a long record: residual tests and candidate refits on a leading window of
//! the training record, then the suggested candidates re-checked on the whole record.
//!
//! Why: every candidate is a complete refit and the residual tests regress the residual on
//! dozens of filtered input functions; on a record of millions of samples both would cost
//! minutes and gigabytes while a window of tens of thousands of samples already has the power
//! to rank the candidates. What is approximated: the test statistics, p-values and the evidence
//! are those of the window; the candidates that were not suggested on the window are not
//! refitted on the whole record (their numbers in `candidates` are the window's). The suggested
//! ones (at most [`RECHECKED`], best first) are refitted on the whole record — their window
//! refit polished by chunked Levenberg–Marquardt steps (`hammerstein::screening`) — and judged
//! there by the rule of `diagnose.rs` (ΔBIC < 0, improvement ≥ `min_improvement`, parameters
//! not at their null value); the comparisons `train` and `validation` are on the whole records
//! (their metrics), their series cut to the leading [`SERIES_KEPT`] samples (the memory of a
//! long record's comparisons would otherwise be five times the record's).

use super::analysis::ResidualAnalysis;
use super::candidate::{Refit, RefitContext};
use super::compare::{Comparison, simulate_and_measure};
use super::diagnose::{Diagnoser, Diagnosis, Unexplained, model_classes_for, summary_of};
use crate::data::IoData;
use crate::error::Result;
use crate::hammerstein::order_selection::exact_floor_of;
use crate::hammerstein::{HammersteinModel, Screening, polish_on};
use crate::real::Real;

/// Most suggestions of the window re-checked on the whole record.
pub const RECHECKED: usize = 2;

/// Most samples of the series of a screened diagnosis' comparisons `train` and `validation`
/// (the leading ones, for plots); their metrics are the whole record's.
pub const SERIES_KEPT: usize = 100_000;

/// The comparison of `model` on the whole of `data` (metrics of the whole record, series of its
/// leading [`SERIES_KEPT`] samples) and the training MSE the selection criterion sees
/// (`order_selection::training_mse`, from the same simulation).
fn whole_comparison<T: Real>(
    model: &HammersteinModel<T>,
    data: &IoData<T>,
) -> Result<(Comparison, f64)> {
    let (sim, metrics) = simulate_and_measure(model, data)?;
    let y = data.output_slice(0);
    // as `training_mse`: the simulation's MSE (`linear_ls::mse`), the model's own when lower
    let own = model.report().train_mse;
    let sse = y
        .iter()
        .zip(&sim.y_hat)
        .map(|(&a, &b)| {
            let e = (a - b).as_f64();
            e * e
        })
        .sum::<f64>();
    let m = sse / y.len().max(1) as f64;
    let train_mse = if m.is_finite() { m.min(own) } else { own };
    let k = data.len().min(SERIES_KEPT);
    let f64s = |s: &[T]| -> Vec<f64> { s[..k].iter().map(|x| x.as_f64()).collect() };
    let y = f64s(y);
    let y_hat = f64s(&sim.y_hat);
    let residual = y.iter().zip(&y_hat).map(|(a, b)| a - b).collect();
    let comparison = Comparison {
        u: f64s(data.input_slice(0)),
        y,
        y_hat,
        residual,
        v_hat: f64s(&sim.v),
        metrics,
    };
    Ok((comparison, train_mse))
}

/// [`Diagnoser::diagnose`] of a training record longer than the screening threshold.
pub(crate) fn diagnose_screened<T: Real>(
    diagnoser: &Diagnoser<T>,
    model: &HammersteinModel<T>,
    train: &IoData<T>,
    validation: &IoData<T>,
    s: Screening,
) -> Result<Diagnosis<T>> {
    let observer = model.settings().observer.clone();
    let progress = |stage: &str, done: usize, total: usize| {
        if let Some(o) = &observer {
            o.progress(stage, done, total);
        }
    };
    let w = s.window.min(train.len());
    let train_w = train.slice(0, w)?;
    let val_w = validation.slice(0, validation.len().min(w))?;
    progress("screening the candidates on the leading window", 0, 1);
    let mut d = diagnoser.diagnose_whole(model, &train_w, &val_w)?;
    d.screening_window = Some(w);
    progress("comparing on the whole record", 0, 1);
    let (train_c, train_mse) = whole_comparison(model, train)?;
    let (val_c, _) = whole_comparison(model, validation)?;
    let analysis: ResidualAnalysis = diagnoser.analysis(model, &train_w)?;
    let ctx = RefitContext {
        model,
        train,
        validation,
        validation_comparison: &val_c,
        analysis: &analysis,
        train_mse,
    };
    let n_train = train.len().max(1) as f64;
    let floor = exact_floor_of(train);
    let min_improvement = diagnoser.options_value().min_improvement;
    let names: Vec<String> = d
        .suggestions
        .iter()
        .take(RECHECKED)
        .map(|x| x.effect.clone())
        .collect();
    // one after the other: in parallel on the two cores they took longer (2.75 against 2.5 s at
    // 1e6 samples; the polish is bound by memory bandwidth) and needed twice the memory
    progress("re-checking the best suggestions on the whole record", 0, 1);
    let rechecks: Vec<(String, Option<Result<Refit<T>>>)> = names
        .iter()
        .map(|name| {
            let r_w = d
                .candidates
                .iter()
                .find(|c| &c.effect == name)
                .and_then(|c| c.refit.as_ref());
            // a change outside the model (the output map) has no model: its window numbers stand
            let Some((r_w, m_w)) = r_w.and_then(|r| r.model.as_ref().map(|m| (r, m))) else {
                return (name.clone(), None);
            };
            let candidate = diagnoser
                .candidates()
                .candidates()
                .iter()
                .find(|c| &c.name() == name);
            let recheck = polish_on(m_w, train, s.polish_iterations).and_then(|m| {
                let params: Vec<String> = m.parameters().into_iter().map(|(k, _)| k).collect();
                let keep: Vec<&str> = r_w
                    .estimate
                    .keys()
                    .filter(|k| params.contains(k))
                    .map(|k| k.as_str())
                    .collect();
                let mut r = Refit::of_model(&ctx, m, &keep)?;
                for (k, v) in &r_w.estimate {
                    r.estimate.entry(k.clone()).or_insert(*v);
                }
                r.change = r_w.change.clone();
                r.null_parameters = candidate.and_then(|c| c.null_parameters(&r, train));
                Ok(r)
            });
            (name.clone(), Some(recheck))
        })
        .collect();
    let mut rejected = Vec::new();
    for (name, recheck) in rechecks {
        let Some(recheck) = recheck else { continue };
        let Some(outcome) = d.candidates.iter_mut().find(|c| c.effect == name) else {
            continue;
        };
        let r = match recheck {
            Ok(r) => r,
            Err(e) => {
                outcome.refit_error = Some(format!("re-check on the whole record: {e}"));
                rejected.push(name.clone());
                continue;
            }
        };
        let imp = if r.reference_train_mse > 0.0 {
            (r.reference_train_mse - r.train_mse) / r.reference_train_mse
        } else {
            0.0
        };
        let dc = n_train * (r.train_mse.max(floor) / r.reference_train_mse.max(floor)).ln()
            + r.added_parameters as f64 * n_train.ln();
        let ok = imp >= min_improvement
            && dc < 0.0
            && r.null_parameters.is_none()
            && r.train_mse.is_finite();
        let own = outcome.evidence.as_ref().is_some_and(|e| e.significant);
        if let Some(sg) = d.suggestions.iter_mut().find(|x| x.effect == name) {
            sg.score = imp * if own { 1.0 } else { 0.5 };
            sg.train_mse_after = r.train_mse;
            sg.train_mse_before = r.reference_train_mse;
            sg.criterion_change = dc;
            sg.validation_mse_after = r.validation_mse;
            sg.change = r.change.clone();
            for (k, v) in &r.estimate {
                sg.estimate.insert(k.clone(), *v);
            }
        }
        outcome.improvement = Some(imp);
        outcome.criterion_change = Some(dc);
        outcome.refit = Some(r);
        if !ok {
            rejected.push(name.clone());
        }
    }
    d.suggestions.retain(|x| !rejected.contains(&x.effect));
    for sg in d.suggestions.iter_mut() {
        sg.validation_mse_before = val_c.metrics.mse;
    }
    d.suggestions.sort_by(|a, b| b.score.total_cmp(&a.score));
    if d.suggestions.is_empty() && !d.adequate && d.unexplained.is_empty() {
        d.unexplained = d
            .tests
            .iter()
            .filter(|t| t.significant)
            .map(|t| Unexplained {
                test: t.name.clone(),
                p_adjusted: t.p_adjusted,
                model_classes: model_classes_for(&t.name),
            })
            .collect();
    }
    d.train = train_c;
    d.validation = val_c;
    d.summary = summary_of(d.adequate, &d.unexplained, &d.suggestions);
    progress("diagnosed", 1, 1);
    Ok(d)
}
