//! The automatic fit of a UDN with effects held to the linear model it contains: the linear
//! model is fitted too (its own order selection), extended by the effects at their null values
//! (half-widths, dead-zone and preload steps 0, saturation limits at the input's extremes, and
//! at its 2nd and 98th percentiles) and refined from there (`fit_nested`); the lower information
//! criterion wins.
//!
//! Why: the UDN's default start puts its thresholds at input quantiles, and on records where the
//! effects are small or absent the loop and the refinement can end in a basin far worse than the
//! linear model the UDN contains. On the F-16 ground vibration record (force → acceleration 2,
//! the first 10 000 samples) the full UDN ended at 64.43 % training fit against 81.88 % for the
//! linear model; dead-zone with preload at 59.04 % (`docs/algorithm.md`, "The default fit",
//! step 8). Done with the automatic order only (the diagnosis' refits at a fixed order have their
//! own nested start from the model they extend) and with the refinement on.

use super::nested::fit_nested;
use super::order_selection::{criterion, fit_selecting_order, training_mse};
use crate::data::IoData;
use crate::error::{Error, Result};
use crate::fit::settings::Hammerstein;
use crate::fit::{HammersteinModel, OrderCandidate};
use crate::real::Real;
use crate::regressors::{Effect, EffectSet};
use crate::subspace::Order;

/// Whether `settings` are an automatic-order UDN with effects (not dynamic hysteresis, whose
/// weights have no null start here), refined, without an output map and not a several-input
/// fit's branch: the fits this module serves.
fn applies<T: Real>(settings: &Hammerstein<T>) -> bool {
    settings
        .effects()
        .is_some_and(|set| set != EffectSet::empty() && !set.contains(Effect::PrandtlIshlinskii))
        && matches!(settings.options.order, Order::Auto)
        && settings.options.refine
        && settings.output_map.is_none()
        && settings.linear_check
}

/// The linear model of `data` with `settings`' options (its own order selection); `None` when it
/// cannot be fitted.
fn linear_of<T: Real>(settings: &Hammerstein<T>, data: &IoData<T>) -> Option<HammersteinModel<T>> {
    fit_selecting_order(&settings.with_effects(EffectSet::empty()).ok()?, data, None).ok()
}

/// The linear model the automatic fit of `settings` is held to (`linear_of`), fitted when the
/// settings are those this module serves; `None` otherwise or when it cannot be fitted. The
/// driver fits it beside the UDN's own fit (it depends on the record and the settings alone),
/// so that it runs on the core the UDN's fit leaves idle.
pub(crate) fn linear_for<T: Real>(
    settings: &Hammerstein<T>,
    data: &IoData<T>,
) -> Option<HammersteinModel<T>> {
    if applies(settings) {
        linear_of(settings, data)
    } else {
        None
    }
}

/// The UDN of `settings` fitted from `linear` (a linear model of `data`) with every effect at its
/// null value, refined and centred; `None` when the nested fits fail.
fn nested_from<T: Real>(
    settings: &Hammerstein<T>,
    data: &IoData<T>,
    linear: &HammersteinModel<T>,
) -> Option<HammersteinModel<T>> {
    let names = settings.build_nonlinearity().ok()?.param_names();
    let at = settings
        .clone()
        .order(Order::Fixed(linear.linear().order()))
        .with_d(linear.has_feedthrough());
    // two starts, side by side: the saturation limits at the input's extremes (no sample
    // clipped: the start is the linear model, so the fit cannot end above it) and at its 2nd and
    // 98th percentiles (the diagnosis' nested start: a limit inside the range, where the
    // refinement's step sees the samples it clips; on the F-16 excerpt this start alone ended
    // 5.5 % above the linear model's MSE, on development record 448 it reached the floor)
    let from = |(hi, lo): (f64, f64)| -> Option<HammersteinModel<T>> {
        let theta = null_theta(&names, linear, hi, lo)?;
        fit_nested(&at, data, linear, &theta).ok()
    };
    let q = quantile_of(data);
    let (min, max) = (q(0.0)?, q(1.0)?);
    let (outer, inner) = rayon::join(|| from((max, min)), || from((q(0.98)?, q(0.02)?)));
    let best = [outer, inner]
        .into_iter()
        .flatten()
        .min_by(|a, b| a.report.train_mse.total_cmp(&b.report.train_mse))?;
    crate::fit::refinement::centring::centred(&at, data, best).ok()
}

/// The input's quantile function on `data` (nearest rank).
fn quantile_of<T: Real>(data: &IoData<T>) -> impl Fn(f64) -> Option<f64> {
    let mut u: Vec<f64> = data.input_slice(0).iter().map(|x| x.as_f64()).collect();
    u.sort_by(f64::total_cmp);
    move |f: f64| {
        u.get(((u.len().checked_sub(1)?) as f64 * f).round() as usize)
            .copied()
    }
}

/// The fit of `settings` on `data` when the automatic fit failed with `error` (a first
/// iteration whose gains do not give the nonlinearity's parameters: a UDN's gain p at zero
/// against its other columns, seen at f32 on the Dyke MR damper record): the fit nested from
/// `linear` (`linear_for` of the same settings and record); `error` when that does not apply
/// or fails too.
pub(crate) fn instead_of_failure<T: Real>(
    settings: &Hammerstein<T>,
    data: &IoData<T>,
    linear: Option<&HammersteinModel<T>>,
    error: Error,
) -> Result<HammersteinModel<T>> {
    if !applies(settings) {
        return Err(error);
    }
    linear
        .and_then(|linear| nested_from(settings, data, linear))
        .ok_or(error)
}

/// `model` (the automatic fit of `settings` on `data`) or, when its criterion is lower, the fit
/// nested from the linear model `linear` (`linear_for` of the same settings and record) — tried
/// only when `model` does not fit the training record better than the linear model (whose order
/// is selected too: a UDN holds it, so it ended in a worse basin); `model` unchanged when the
/// settings are not those `applies` names.
pub(crate) fn no_worse_than_linear<T: Real>(
    settings: &Hammerstein<T>,
    data: &IoData<T>,
    linear: &HammersteinModel<T>,
    model: HammersteinModel<T>,
) -> Result<HammersteinModel<T>> {
    if !applies(settings) {
        return Ok(model);
    }
    // the linear model (its own order selection): a UDN that fits the training record better has
    // not ended in a basin worse than the linear model it contains, and nothing more is fitted
    if training_mse(&model, data) < training_mse(linear, data) {
        return Ok(model);
    }
    let Some(nested) = nested_from(settings, data, linear) else {
        return Ok(model);
    };
    let var = crate::fit::iteration::problem::variance(data.output_slice(0));
    let score = |m: &HammersteinModel<T>| criterion(m, training_mse(m, data), data.len(), var);
    let nested_score = score(&nested);
    // a nested fit whose simulation from rest departs from its fit is not preferred to one
    // whose does not (`from_rest.rs`)
    let departs =
        |m: &HammersteinModel<T>| super::from_rest::departs(super::from_rest::departure(m, data));
    if nested_score >= score(&model) || (departs(&nested) && !departs(&model)) {
        return Ok(model);
    }
    let mut nested = nested;
    // the selection's table, with the nested fit's row (its order and feed-through are the
    // linear model's choice), so that the table's lowest criterion is the returned model's
    let (n, d) = (nested.linear.order(), nested.has_feedthrough());
    let row = OrderCandidate {
        order: n,
        feedthrough: d,
        criterion: nested_score,
        train_mse: training_mse(&nested, data),
        refused_from_rest: None,
    };
    let mut table = model.report.order_selection;
    match table
        .iter_mut()
        .find(|r| r.order == n && r.feedthrough == d)
    {
        Some(r) => *r = row,
        None => table.push(row),
    }
    table.sort_by_key(|r| (r.feedthrough, r.order));
    nested.report.order_selection = table;
    nested.settings = model.settings.order(Order::Fixed(n)).with_d(d);
    Ok(nested)
}

/// θ of the UDN whose parameters are `names`, with the gain of `linear`, every effect at its
/// null value and the saturation limits at `hi` and `lo`; `None` when a parameter is not the
/// UDN's or the limits are not ordered.
fn null_theta<T: Real>(
    names: &[String],
    linear: &HammersteinModel<T>,
    hi: f64,
    lo: f64,
) -> Option<Vec<f64>> {
    let p = linear
        .parameters()
        .into_iter()
        .find(|(k, _)| k == "p")
        .map(|(_, v)| v)?;
    if hi <= lo {
        return None;
    }
    names
        .iter()
        .map(|k| match k.as_str() {
            "p" => Some(p),
            "a" | "b" | "e1" | "e2" => Some(0.0),
            "z1" => Some(hi),
            "z2" => Some(lo),
            _ => None,
        })
        .collect()
}
