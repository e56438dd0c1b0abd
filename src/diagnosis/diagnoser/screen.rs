//! The diagnosis of a long record: residual tests and candidate refits on a window of the
//! training record (the leading one unless its input barely moves: `fit::screening`), then the
//! suggested candidates re-checked on the whole record.
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

use super::outcome::{Diagnosis, summary_of, unexplained_of};
use super::whole::{Judgment, Setup};
use crate::data::IoData;
use crate::diagnosis::candidates::candidate::{Refit, RefitContext};
use crate::diagnosis::candidates::estimate::{Estimate, Quantity};
use crate::diagnosis::compare::{Comparison, check_length, metrics_of, simulate_and_measure};
use crate::diagnosis::ids::CandidateId;
use crate::diagnosis::residual_tests::analysis::ResidualAnalysis;
use crate::error::Result;
use crate::fit::MemoryStart;
use crate::fit::order_selection::{exact_floor_of, training_mse_of};
use crate::fit::{HammersteinModel, Screening, polish_on};
use crate::real::Real;

/// Most suggestions of the window re-checked on the whole record.
pub const RECHECKED: usize = 2;

/// Samples of the window a long record's candidates are screened on when its model was fitted
/// on the whole record (no screening window carried over): four default windows.
pub const WHOLE_FIT_WINDOW: usize = 4 * crate::fit::DEFAULT_SCREEN_WINDOW;

/// Most samples of the series of a screened diagnosis' comparisons `train` and `validation`
/// (the leading ones, for plots); their metrics are the whole record's.
pub const SERIES_KEPT: usize = 100_000;

/// The comparison of `model` on the whole of `data`: metrics of the whole record, series of
/// its leading [`SERIES_KEPT`] samples.
fn whole_comparison<T: Real>(model: &HammersteinModel<T>, data: &IoData<T>) -> Result<Comparison> {
    let k = data.len().min(SERIES_KEPT);
    let f64s = |s: &[T]| -> Vec<f64> { s[..k].iter().map(|x| x.as_f64()).collect() };
    let (y_hat, v_hat, metrics) = if model.delay() > 0 {
        // the intermediate values before the record are estimated with x0: the simulation's
        // own v, its leading samples taken before it is dropped
        let (sim, metrics) = simulate_and_measure(model, data)?;
        (f64s(&sim.y_hat), f64s(&sim.v), metrics)
    } else {
        // the simulation consumed as it is produced (one signal of the record at a time), its
        // leading samples kept; v of the start it took made again on those samples alone
        check_length(model, data)?;
        let y = data.output_slice(0);
        let (metrics, y_hat, start) = model.on_simulated_with(data, |y_hat, _, start| {
            if let Some((index, value)) = crate::fit::divergence(y_hat) {
                return Err(crate::error::Error::Diverged { index, value });
            }
            Ok((metrics_of(y, y_hat)?, f64s(y_hat), start))
        })??;
        let start = start.unwrap_or(MemoryStart::Rising);
        let v = model.intermediate_of(&data.input_slice(0)[..k], start)?;
        (y_hat, f64s(&v), metrics)
    };
    let y = f64s(data.output_slice(0));
    let residual = y.iter().zip(&y_hat).map(|(a, b)| a - b).collect();
    Ok(Comparison {
        u: f64s(data.input_slice(0)),
        y,
        y_hat,
        residual,
        v_hat,
        metrics,
    })
}

/// The metrics of `model` on the whole of `data` (a comparison without series: what the
/// re-checks are judged against) and the training MSE the selection criterion sees
/// (`order_selection::training_mse_of`, from the same simulation), the simulation not kept.
fn whole_metrics<T: Real>(
    model: &HammersteinModel<T>,
    data: &IoData<T>,
) -> Result<(Comparison, f64)> {
    let y = data.output_slice(0);
    let (metrics, train_mse) = model.on_simulated(data, |y_hat| {
        if let Some((index, value)) = crate::fit::divergence(y_hat) {
            return Err(crate::error::Error::Diverged { index, value });
        }
        Ok((
            crate::diagnosis::compare::metrics_of(y, y_hat)?,
            training_mse_of(model, data, y_hat),
        ))
    })??;
    let comparison = Comparison {
        u: Vec::new(),
        y: Vec::new(),
        y_hat: Vec::new(),
        residual: Vec::new(),
        v_hat: Vec::new(),
        metrics,
    };
    Ok((comparison, train_mse))
}

/// [`Diagnoser::diagnose`](crate::diagnosis::Diagnoser::diagnose) of a training record longer than the
/// screening threshold.
pub(crate) fn diagnose_screened<T: Real>(
    setup: &Setup<'_, T>,
    model: &HammersteinModel<T>,
    train: &IoData<T>,
    validation: &IoData<T>,
    s: Screening,
) -> Result<Diagnosis<T>> {
    let progress = |stage: &str, done: usize, total: usize| {
        if let Some(o) = setup.observer {
            o.progress(stage, done, total);
        }
    };
    let w = s.window.min(train.len());
    let t0 = crate::fit::screening_window_start(train, w);
    let train_w = train.slice(t0, t0 + w)?;
    let wv = validation.len().min(w);
    let v0 = crate::fit::screening_window_start(validation, wv);
    let val_w = validation.slice(v0, v0 + wv)?;
    progress("screening the candidates on the screening window", 0, 1);
    let mut d = setup.diagnose_whole(model, &train_w, &val_w, false)?;
    d.screening_window = Some(w);
    // the window's comparison would describe the windows, not the whole records
    d.generalisation = None;
    progress("comparing on the whole record", 0, 1);
    // the metrics first, the series after the re-checks: a long record's series would
    // otherwise be held through the re-checks' own simulations (the peak of the memory)
    let (_, train_mse) = whole_metrics(model, train)?;
    let (val_m, _) = whole_metrics(model, validation)?;
    let analysis: ResidualAnalysis = setup.analysis(model, &train_w)?;
    let ctx = RefitContext {
        model,
        train,
        validation,
        validation_comparison: &val_m,
        analysis: &analysis,
        train_mse,
        observer: setup.observer,
    };
    let ids: Vec<CandidateId> = d
        .suggestions
        .iter()
        .take(RECHECKED)
        .map(|x| x.effect.clone())
        .collect();
    // one after the other: in parallel on the two cores they took longer (2.75 against 2.5 s at
    // 1e6 samples; the polish is bound by memory bandwidth) and needed twice the memory
    progress("re-checking the best suggestions on the whole record", 0, 1);
    let rechecks: Vec<(CandidateId, Option<Result<Refit<T>>>)> = ids
        .iter()
        .map(|id| (id.clone(), recheck(setup, &ctx, &d, id, s)))
        .collect();
    let judge = JudgeOn {
        n_train: train.len().max(1) as f64,
        floor: exact_floor_of(train),
        min_improvement: setup.options.min_improvement,
    };
    let mut rejected = Vec::new();
    for (id, recheck) in rechecks {
        if let Some(recheck) = recheck
            && !judge.apply(&mut d, &id, recheck)
        {
            rejected.push(id);
        }
    }
    d.suggestions.retain(|x| !rejected.contains(&x.effect));
    for sg in d.suggestions.iter_mut() {
        sg.validation_mse_before = val_m.metrics.mse;
    }
    d.suggestions.sort_by(|a, b| b.score.total_cmp(&a.score));
    if d.suggestions.is_empty() && !d.adequate && d.unexplained.is_empty() {
        d.unexplained = unexplained_of(&d.tests, setup.tests);
    }
    d.train = whole_comparison(model, train)?;
    d.validation = whole_comparison(model, validation)?;
    d.summary = summary_of(d.adequate, &d.unexplained, &d.suggestions);
    progress("diagnosed", 1, 1);
    Ok(d)
}

/// The window refit of candidate `id` polished on the whole record and measured there; `None`
/// for a change outside the model (the output map): its window numbers stand.
fn recheck<T: Real>(
    setup: &Setup<'_, T>,
    ctx: &RefitContext<'_, T>,
    d: &Diagnosis<T>,
    id: &CandidateId,
    s: Screening,
) -> Option<Result<Refit<T>>> {
    let r_w = d
        .candidates
        .iter()
        .find(|c| &c.effect == id)
        .and_then(|c| c.refit.as_ref())?;
    let m_w = r_w.model.as_ref()?;
    let candidate = setup.registry.get(id);
    let recheck = polish_on(m_w, ctx.train, s.polish_iterations).and_then(|m| {
        let params: Vec<String> = m.parameters().into_iter().map(|(k, _)| k).collect();
        let keep: Vec<&str> = r_w
            .estimate
            .iter()
            .filter_map(|e| match &e.quantity {
                Quantity::Parameter(n) if params.contains(n) => Some(n.as_str()),
                _ => None,
            })
            .collect();
        let mut r = Refit::of_model(ctx, m, &keep)?;
        // the window's other estimates (order, delay, output map) by value: their window
        // standard errors are not the whole record's
        for e in &r_w.estimate {
            r.estimate.insert_missing(Estimate {
                standard_error: None,
                ..e.clone()
            });
        }
        r.change = r_w.change.clone();
        r.null_parameters = candidate.and_then(|c| c.null_parameters(&r, ctx.train));
        Ok(r)
    });
    Some(recheck)
}

/// The judgment of a re-check on the whole record.
struct JudgeOn {
    n_train: f64,
    floor: f64,
    min_improvement: f64,
}

impl JudgeOn {
    /// Puts the re-check of `id` into the diagnosis (its outcome and suggestion); false when the
    /// re-check failed or does not pass on the whole record.
    fn apply<T: Real>(
        &self,
        d: &mut Diagnosis<T>,
        id: &CandidateId,
        recheck: Result<Refit<T>>,
    ) -> bool {
        let Some(outcome) = d.candidates.iter_mut().find(|c| &c.effect == id) else {
            return true;
        };
        let r = match recheck {
            Ok(r) => r,
            Err(e) => {
                outcome.refit_error = Some(format!("re-check on the whole record: {e}"));
                return false;
            }
        };
        let j = Judgment::of(&r, self.n_train, self.floor);
        let ok = j.passes(&r, self.min_improvement);
        if let Some(sg) = d.suggestions.iter_mut().find(|x| &x.effect == id) {
            sg.score = j.score(outcome.evidence.as_ref());
            sg.train_mse_after = r.train_mse;
            sg.train_mse_before = r.reference_train_mse;
            sg.criterion_change = j.criterion_change;
            sg.validation_mse_after = r.validation_mse;
            sg.change = r.change.clone();
            for e in &r.estimate {
                sg.estimate.insert(e.clone());
            }
        }
        outcome.improvement = Some(j.improvement);
        outcome.criterion_change = Some(j.criterion_change);
        outcome.refit = Some(r);
        ok
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::regressors::{Effect, EffectSet, StaticNonlinearity, Udn};
    use crate::subspace::Order;

    /// A record of a hysteresis with saturation behind a second-order block (a fixed
    /// pseudo-random input, no noise but the model's own misfit).
    fn record(seed: u64, n: usize) -> IoData<f64> {
        let set = EffectSet::of(&[Effect::Hysteresis, Effect::Saturation]);
        let truth = Udn::<f64>::with_params(set, &[2.0, 0.5, 1.5, -1.0]).unwrap();
        let u: Vec<f64> = (0..n)
            .map(|k| 3.0 * ((k as f64 * 0.37 + seed as f64).sin() * (k as f64 * 0.011).cos()))
            .collect();
        let v = truth.eval(&u);
        let mut y = vec![0.0; n];
        for k in 2..n {
            y[k] = 1.2 * y[k - 1] - 0.5 * y[k - 2] + 0.3 * v[k - 1] + 0.01 * (k as f64).sin();
        }
        IoData::siso(&u, &y).unwrap()
    }

    /// The screened diagnosis' comparison, its simulation consumed as it is produced and v of
    /// the start it kept made again, gives the series and metrics of `compare` (the full
    /// simulation) bit for bit, for a hysteresis (two starts) and a memoryless saturation.
    #[test]
    fn the_whole_comparison_gives_the_full_simulations_series() {
        let train = record(1, 900);
        for set in [
            EffectSet::of(&[Effect::Hysteresis, Effect::Saturation]),
            EffectSet::of(&[Effect::Saturation]),
        ] {
            let model = crate::Hammerstein::<f64>::udn(set)
                .order(Order::Fixed(2))
                .with_d(false)
                .fit(&train)
                .unwrap();
            for seed in [2, 3] {
                let data = record(seed, 600);
                let full = crate::diagnosis::compare(&model, &data).unwrap();
                let lean = whole_comparison(&model, &data).unwrap();
                assert_eq!(full.metrics, lean.metrics);
                assert_eq!(full.y_hat, lean.y_hat);
                assert_eq!(full.v_hat, lean.v_hat);
                assert_eq!(full.residual, lean.residual);
                assert_eq!(full.u, lean.u);
            }
        }
    }
}
