//! One fit of a fixed structure: the settings' order rule and feed-through, the loop (or a
//! start shared from another fit), then the refinement from the loop's iterate and from the
//! linear block re-identified for the same θ; and the fit's final model redone at the horizon
//! its slowest time constant asks for when its block is slow for the horizon (`slow_horizon.rs`,
//! `refit_if_slow`, called by the driver after the order selection).

use super::fit_report::FitReport;
use super::fitted::model::{HammersteinModel, check_siso};
use super::iteration::init::initialize;
use super::iteration::initial_direction::try_other_direction;
use super::iteration::loop_state::{LoopState, run_loop};
use super::iteration::problem::{Iterate, Problem, Workspace, normalise_iterate, to_statespace};
use super::iteration::search::SearchWidths;
use super::observer::Observer;
use super::refinement::refine;
use super::settings::Hammerstein;
use crate::data::{IoData, min_samples_for_horizon};
use crate::error::{Error, Result};
use crate::real::Real;
use crate::regressors::StaticNonlinearity;
use crate::subspace::{Order, max_order};
use faer::Mat;

/// One fit with the settings' order rule (fixed, gap or threshold; `Auto` acts as `Gap` here),
/// `observer` notified after every iteration and at the end.
pub(crate) fn fit_fixed<T: Real>(
    settings: &Hammerstein<T>,
    data: &IoData<T>,
    observer: Option<&dyn Observer>,
) -> Result<HammersteinModel<T>> {
    fit_fixed_from(settings, data, None, observer)
}

/// A start for a fixed-order fit that skips the loop: the nonlinearity's θ and the offset of
/// another fit of the same record (the order selection's first candidate), with its report.
#[derive(Debug, Clone)]
pub(crate) struct SharedStart<T: Real> {
    /// Nonlinearity parameters θ.
    pub theta: Vec<T>,
    /// Output offset.
    pub offset: T,
    /// The report of the fit the start comes from (its loop's iterations).
    pub report: FitReport,
    /// A lower-order block (A, C) of the same fit to extend (`Problem::nested_start`) instead of
    /// re-identifying the block.
    pub nest: Option<(Mat<T>, Mat<T>)>,
    /// A higher-order block (A, B, C) of the same fit to truncate (`Problem::reduced_start`)
    /// instead of re-identifying the block.
    pub reduce: Option<(Mat<T>, Mat<T>, Mat<T>)>,
}

/// `fit_fixed`, or with `start`: θ held from the start, the linear block of the settings'
/// (fixed) order re-identified from (v, y) (`restart_linear`), then the refinement — no loop.
/// Falls back to the loop when the re-identification fails. `observer` is notified after every
/// iteration and at the end.
pub(crate) fn fit_fixed_from<T: Real>(
    settings: &Hammerstein<T>,
    data: &IoData<T>,
    start: Option<&SharedStart<T>>,
    observer: Option<&dyn Observer>,
) -> Result<HammersteinModel<T>> {
    on_pool(|| fit_fixed_here(settings, data, start, observer))
}

/// A fit's final `model` (fixed order, or the order selection's choice) redone at the horizon
/// its block's slowest time constant asks for (`slow_horizon.rs`), at its order and
/// feed-through, when that horizon is longer than the one it was fitted at; the refit is
/// returned (with the model's settings and order-selection table) when its training MSE is
/// clearly lower (`slow_horizon::clearly_lower`). Done once, after the order selection: its
/// candidates are compared with each other fitted the same way (applied to the candidates that
/// run their own loop, it moved the search on held-out records, `docs/battery.md`). The refit
/// runs without the observer (the caller's fit already ended).
pub(crate) fn refit_if_slow<T: Real>(
    settings: &Hammerstein<T>,
    data: &IoData<T>,
    mut model: HammersteinModel<T>,
) -> HammersteinModel<T> {
    let at = settings.clone().at_structure_of(&model);
    let Some(h) = slow_horizon_of(&at, data, &model) else {
        return model;
    };
    let n = model.linear.order();
    let slow = at.raise_horizon(h).order(Order::Fixed(n));
    match on_pool(|| fit_fixed_here(&slow, data, None, None)) {
        Ok(mut m)
            if super::numerics::slow_horizon::clearly_lower(
                m.report.train_mse,
                model.report.train_mse,
                data.len(),
            ) =>
        {
            m.settings = model.settings.clone();
            m.report.order_selection = std::mem::take(&mut model.report.order_selection);
            m
        }
        _ => model,
    }
}

/// The horizon the slowest pole of `model`'s block asks for when it is longer than the settings'
/// one (`slow_horizon::slow_horizon`); `None` otherwise.
fn slow_horizon_of<T: Real>(
    settings: &Hammerstein<T>,
    data: &IoData<T>,
    model: &HammersteinModel<T>,
) -> Option<usize> {
    let poles = model.linear.poles().ok()?;
    let rho = super::numerics::slow_horizon::spectral_radius(&poles);
    let r = model.nl.n_regressors();
    super::numerics::slow_horizon::slow_horizon(rho, settings.options.horizon, data.len(), r)
}

/// Runs `f` on a thread of rayon's pool (in place when already on one): the fit's
/// `rayon::join`s (the search's candidates, the two refinements) then hand their second half to
/// the pool's other thread directly, instead of each waking a pool thread for the whole join
/// while the caller waits.
fn on_pool<R: Send>(f: impl FnOnce() -> R + Send) -> R {
    if rayon::current_thread_index().is_some() {
        f()
    } else {
        rayon::scope(|_| f())
    }
}

/// [`fit_fixed_from`] on the calling thread.
fn fit_fixed_here<T: Real>(
    settings: &Hammerstein<T>,
    data: &IoData<T>,
    start: Option<&SharedStart<T>>,
    observer: Option<&dyn Observer>,
) -> Result<HammersteinModel<T>> {
    settings.validate()?;
    check_siso(data)?;
    let la = settings.linalg_backend()?;
    let method = settings.subspace_at(settings.options.horizon)?;
    let mut nl = settings.build_nonlinearity()?;
    check_record(settings, data, nl.as_ref())?;
    let problem = Problem::new(la.as_ref(), method.as_ref(), settings, data).observed(observer);
    let mut ws = Workspace::default();
    let shared = start.and_then(|st| shared_start(&problem, &mut ws, nl.as_mut(), st));
    let looped = shared.is_none();
    let (best, report) = match shared {
        Some(x) => x,
        None => {
            let mut widths = SearchWidths::default();
            initialize(&problem, &mut ws, &mut widths, nl.as_mut())?;
            run_loop(&problem, nl.as_mut(), LoopState::new(widths), &mut ws)?
        }
    };
    nl.set_params(&best.theta)?;
    let mut it = best;
    normalise_iterate(&problem, nl.as_mut(), &mut it);
    let mut report = report;
    let mut chosen = it.clone();
    if settings.options.refine {
        let (refined, rep) = refine_both(&problem, &mut ws, nl.as_ref(), &it, looped)?;
        if let Some(mut rf) = refined {
            nl.set_params(&rf.theta)?;
            normalise_iterate(&problem, nl.as_mut(), &mut rf);
            report.train_mse = rf.mse;
            chosen = rf;
        }
        report.refinement = Some(rep);
    }
    let mut linear = to_statespace(&chosen)?;
    linear.ts = data.sample_time();
    if let Some(obs) = observer {
        obs.observe_final(&report);
    }
    Ok(HammersteinModel {
        nl,
        linear,
        offset: chosen.offset,
        x0: chosen.x0,
        settings: settings.clone(),
        report,
        output_map: None,
    })
}

/// Checks that `data` can be fitted with `settings` and the nonlinearity `nl`: regressors at all,
/// enough samples for the horizon, a delay shorter than half the record, a fixed order the
/// horizon allows.
fn check_record<T: Real>(
    settings: &Hammerstein<T>,
    data: &IoData<T>,
    nl: &dyn StaticNonlinearity<T>,
) -> Result<()> {
    let r = nl.n_regressors();
    if r == 0 {
        return Err(Error::InvalidParameter(format!(
            "the nonlinearity '{}' has no regressors",
            nl.name()
        )));
    }
    let needed = min_samples_for_horizon(settings.options.horizon, r, 1)
        .saturating_add(settings.options.delay);
    if data.len() < needed {
        // the way out when there is one: the longest horizon the record allows (above the
        // fixed order, which a horizon must exceed)
        let lowest = match settings.options.order {
            Order::Fixed(n) => n + 1,
            _ => 2,
        };
        let fits = (lowest..settings.options.horizon).rev().find(|&h| {
            min_samples_for_horizon(h, r, 1).saturating_add(settings.options.delay) <= data.len()
        });
        let way_out = fits.map_or_else(String::new, |h| {
            format!("; horizon {h} fits this record (--horizon {h})")
        });
        return Err(Error::TooFewSamples {
            needed,
            got: data.len(),
            reason: format!(
                "horizon {} with {r} regressor(s) of '{}' and delay {}{way_out}",
                settings.options.horizon,
                nl.name(),
                settings.options.delay
            ),
        });
    }
    if settings.options.delay >= data.len() / 2 {
        return Err(Error::InvalidParameter(format!(
            "input delay {} is not shorter than half the record ({} samples)",
            settings.options.delay,
            data.len()
        )));
    }
    if let Order::Fixed(n) = settings.options.order {
        let max = max_order(settings.options.horizon, 1);
        if n > max {
            return Err(Error::OrderTooLarge { requested: n, max });
        }
    }
    Ok(())
}

/// The iterate of a shared start: θ from `start` (set on `nl`), the linear block of the fixed
/// order re-identified, with `start`'s report; `None` when the order is not fixed, θ is
/// refused or the re-identification fails.
fn shared_start<T: Real>(
    problem: &Problem<'_, T>,
    ws: &mut Workspace<T>,
    nl: &mut dyn StaticNonlinearity<T>,
    start: &SharedStart<T>,
) -> Option<(Iterate<T>, FitReport)> {
    let Order::Fixed(n) = problem.settings.options.order else {
        return None;
    };
    nl.set_params(&start.theta).ok()?;
    let mut it = match (&start.nest, &start.reduce) {
        (Some((a, c)), _) => problem.nested_start(ws, nl, (a.as_ref(), c.as_ref()), n)?,
        (None, Some((a, b, c))) => {
            problem.reduced_start(ws, nl, (a.as_ref(), b.as_ref(), c.as_ref()), n)?
        }
        (None, None) => problem.restart_linear(ws, nl, n, start.offset)?,
    };
    // the start's θ at the initial direction that fits the block better (`nl` starts rising)
    try_other_direction(problem, ws, nl, &mut it);
    let mut rep = start.report.clone();
    rep.order = n;
    rep.train_mse = it.mse;
    rep.refinement = None;
    rep.order_selection = Vec::new();
    Some((it, rep))
}

/// Longest record whose two refinements run side by side (two TSQR blocks).
const PARALLEL_REFINE_ROWS: usize = 8192;

/// The refinement from two starts: the loop's iterate `it` and (when `looped`; a shared start's
/// iterate is already the re-identified block) the same θ with the linear block re-identified,
/// also a candidate itself. The candidate with the lowest training MSE below `it`'s, if any, and
/// the refinement's report. The two refinements are independent and run side by side
/// (`rayon::join`: the two cores) on records of at most `PARALLEL_REFINE_ROWS` samples; the
/// result is the one of running them in turn.
fn refine_both<T: Real>(
    problem: &Problem<'_, T>,
    ws: &mut Workspace<T>,
    nl: &dyn StaticNonlinearity<T>,
    it: &Iterate<T>,
    looped: bool,
) -> Result<(Option<Iterate<T>>, super::fit_report::RefineReport)> {
    let first = || refine::refine(problem, nl, it);
    let mut second = || {
        let restart = if looped {
            problem.restart_linear(ws, nl, it.a.nrows(), it.offset)
        } else {
            None
        };
        restart.map(|r| refine::refine(problem, nl, &r).map(|x| (x, r)))
    };
    // side by side on short records only: on a long one two refinements at once hold two
    // Jacobians (a screened diagnosis at 1e6 samples peaked at 3.0× its record instead of 2.8×)
    let (from_loop, from_restart) = if problem.y.len() <= PARALLEL_REFINE_ROWS {
        rayon::join(first, second)
    } else {
        (first(), second())
    };
    let (from_loop, mut rep) = from_loop?;
    let mut candidates: Vec<Iterate<T>> = Vec::new();
    candidates.extend(from_loop);
    if let Some(res) = from_restart {
        let ((refined, rep2), restart) = res?;
        rep.iterations += rep2.iterations;
        candidates.extend(refined);
        candidates.push(restart);
    }
    let refined = candidates
        .into_iter()
        .filter(|c| c.mse < it.mse)
        .min_by(|a, b| a.mse.total_cmp(&b.mse));
    if let Some(rf) = &refined {
        rep.mse_before = it.mse;
        rep.mse_after = rf.mse;
        rep.accepted = true;
    }
    Ok((refined, rep))
}
