//! Model-order selection with the nonlinearity in the model (issue "Right by default"): every
//! candidate order is fitted completely (loop + refinement) and the orders are compared by the
//! Bayesian information criterion of the training simulation error,
//!
//!   BIC(n) = N·ln(MSE_n) + k_n·ln(N),   k_n = n_θ + 3n − 1 + d + c + n_k,
//!
//! (n_θ nonlinearity parameters; n poles, n numerator coefficients less the one the scale
//! normalisation fixes, plus the feed-through d; n initial states; the offset c; the n_k
//! intermediate values before the record of an input delay). MSE_n is the training simulation
//! error with the initial conditions estimated ([`training_mse`]). The criterion
//! uses the training record only; the validation part stays for reporting. Candidates run upwards
//! from order 1 and stop after `PATIENCE` orders without a new best (or at `MAX_CANDIDATE_ORDER`,
//! or where the record is too short for the candidate's horizon). The horizon grows with the
//! candidate order (at least 2n block rows) when the settings' one is too short.
//!
//! Why BIC on the simulation error and not the singular-value gap of the first linear pass: the
//! gap sees the r-input relaxed problem before the nonlinearity is known and chose order 1 for
//! 8 of 25 random records of order 2–3 (`docs/battery.md`). Why BIC and not AIC: AIC's 2k
//! penalty let orders above the truth through on long records in the battery.

use super::fixed::{SharedStart, fit_fixed_from};
use super::observer::Observer;
use super::settings::Hammerstein;
use super::{HammersteinModel, OrderCandidate};
use crate::data::{IoData, min_samples_for_horizon};
use crate::error::Result;
use crate::real::Real;
use crate::subspace::Order;
use rayon::prelude::*;

/// Orders tried after the last new best before the search stops.
pub const PATIENCE: usize = 2;
/// The highest order the automatic selection tries.
pub const MAX_CANDIDATE_ORDER: usize = 10;

/// Number of free parameters of a fitted model (the k of the criterion).
pub fn free_parameters<T: Real>(model: &HammersteinModel<T>) -> usize {
    let n = model.linear().order();
    let n_theta = model.nonlinearity().params().len();
    let d = usize::from(model.settings().options().with_d);
    let c = usize::from(model.offset_fitted());
    let w = model.output_map().map_or(0, |g| g.params().len());
    n_theta + 3 * n + d + c + w - 1
}

/// Training MSE of a model as the criterion sees it: the simulation on the training record with
/// the initial state (and, with an input delay, the intermediate values before the record, and
/// the nonlinearity's initial direction) estimated, as `compare` does. The loop's own MSE fills
/// the delay line with N(u(0)), which favours orders whose extra states absorb that transient.
pub fn training_mse<T: Real>(model: &HammersteinModel<T>, train: &IoData<T>) -> f64 {
    // the simulation is consumed as it is produced (no copy of ŷ kept beside the record)
    let own = model.report().train_mse;
    let y = train.output_slice(0);
    let Ok(mse) = model.on_simulated(train, |y_hat| super::linear_ls::mse(y, y_hat)) else {
        return own;
    };
    if mse.is_finite() { mse.min(own) } else { own }
}

/// [`training_mse`] from the simulation `y_hat` of `model` on `train` already run
/// ([`HammersteinModel::simulate_on`]): its MSE, the model's own when lower or when it is not
/// finite.
pub fn training_mse_of<T: Real>(
    model: &HammersteinModel<T>,
    train: &IoData<T>,
    y_hat: &[T],
) -> f64 {
    let own = model.report().train_mse;
    let mse = super::linear_ls::mse(train.output_slice(0), y_hat);
    if mse.is_finite() { mse.min(own) } else { own }
}

/// BIC of a model whose training MSE is `mse` on `n_samples` samples of an output with
/// variance `var`. MSEs at the round-off level of an exact fit count as equal (the lowest order
/// that fits a noise-free record exactly wins, not the one with the smallest round-off).
pub fn criterion<T: Real>(
    model: &HammersteinModel<T>,
    mse: f64,
    n_samples: usize,
    var: f64,
) -> f64 {
    let nn = n_samples.max(1) as f64;
    let k = free_parameters(model) + model.delay();
    let floor = super::problem::exact_floor::<T>(var).max(f64::MIN_POSITIVE);
    nn * mse.max(floor).ln() + k as f64 * nn.ln()
}

/// The MSE at or below which a fit of `data`'s output counts as exact (the criterion's floor).
pub fn exact_floor_of<T: Real>(data: &IoData<T>) -> f64 {
    super::problem::exact_floor::<T>(output_variance(data)).max(f64::MIN_POSITIVE)
}

/// Horizon used for a candidate of order `n`: the settings' one, raised to 2n when shorter.
pub fn candidate_horizon(settings_horizon: usize, n: usize) -> usize {
    settings_horizon.max(2 * n)
}

/// Variance of the record's output.
fn output_variance<T: Real>(data: &IoData<T>) -> f64 {
    super::problem::variance(&data.output(0))
}

/// The model of one candidate and its row of the table; with `start`, the candidate starts
/// from its θ (no loop of its own).
fn candidate<T: Real>(
    settings: &Hammerstein<T>,
    data: &IoData<T>,
    n: usize,
    d: bool,
    start: Option<&SharedStart<T>>,
    observer: Option<&dyn Observer>,
) -> Result<(OrderCandidate, HammersteinModel<T>)> {
    let h = candidate_horizon(settings.options.horizon, n);
    let s = settings.clone().order(Order::Fixed(n)).horizon(h).with_d(d);
    let model = fit_fixed_from(&s, data, start, observer)?;
    Ok((row(&model, data, d), model))
}

/// The table row of a fitted candidate.
fn row<T: Real>(model: &HammersteinModel<T>, data: &IoData<T>, d: bool) -> OrderCandidate {
    let mse = training_mse(model, data);
    OrderCandidate {
        order: model.linear().order(),
        feedthrough: d,
        criterion: criterion(model, mse, data.len(), output_variance(data)),
        train_mse: mse,
    }
}

/// The start the other candidates share: the fitted model's θ and offset.
fn start_of<T: Real>(model: &HammersteinModel<T>) -> SharedStart<T> {
    SharedStart {
        theta: model.nonlinearity().params(),
        offset: model.offset,
        report: model.report().clone(),
    }
}

/// Fits every candidate (orders upwards from 1 when the order is automatic, the settings' fixed
/// order otherwise; without D, and at the chosen order with D too when the feed-through is
/// automatic) and returns the model with the lowest criterion, its report carrying the table.
pub(crate) fn fit_selecting_order<T: Real>(
    settings: &Hammerstein<T>,
    data: &IoData<T>,
    observer: Option<&dyn Observer>,
) -> Result<HammersteinModel<T>> {
    let d_first = settings.options.with_d && !settings.options.d_auto;
    let mut sel = Selection {
        table: Vec::new(),
        best: None,
        first_error: None,
    };
    // the first candidate runs the loop at the order of the singular-value gap (or the
    // settings' rule); the others start from its refined θ with their own linear block
    let first_settings = match settings.options.order {
        Order::Auto => settings.clone().order(Order::Gap),
        _ => settings.clone(),
    };
    let first = super::fixed::fit_fixed(&first_settings.with_d(d_first), data, observer)
        .map(|m| (row(&m, data, d_first), m));
    let (n0, start) = match &first {
        Ok((_, m)) => (m.linear().order(), Some(start_of(m))),
        Err(_) => (0, None),
    };
    sel.keep(first);
    if matches!(settings.options.order, Order::Auto) {
        sel.orders(settings, data, (d_first, n0), start.as_ref(), observer);
    }
    if settings.options.d_auto
        && let Some((_, m)) = &sel.best
    {
        let n = m.linear().order();
        let st = start_of(m);
        sel.keep(candidate(settings, data, n, true, Some(&st), observer));
    }
    sel.finish()
}

/// The candidates fitted so far: the table, the best model by its criterion, the first error.
struct Selection<T: Real> {
    table: Vec<OrderCandidate>,
    best: Option<(f64, HammersteinModel<T>)>,
    first_error: Option<crate::error::Error>,
}

impl<T: Real> Selection<T> {
    /// Records a candidate's outcome; true when it is the new best.
    fn keep(&mut self, res: Result<(OrderCandidate, HammersteinModel<T>)>) -> bool {
        match res {
            Ok((row, model)) => {
                let crit = row.criterion;
                self.table.push(row);
                if self.best.as_ref().is_none_or(|(b, _)| crit < *b) {
                    self.best = Some((crit, model));
                    true
                } else {
                    false
                }
            }
            Err(e) => {
                if self.first_error.is_none() {
                    self.first_error = Some(e);
                }
                false
            }
        }
    }

    /// The automatic order's candidates 1, 2, … (with D when `d_first`; `n0`, fitted first,
    /// skipped), two at a time
    /// (the two cores), processed in order until `PATIENCE` candidates above the best brought no
    /// improvement; each starts from `start`.
    fn orders(
        &mut self,
        settings: &Hammerstein<T>,
        data: &IoData<T>,
        (d_first, n0): (bool, usize),
        start: Option<&SharedStart<T>>,
        observer: Option<&dyn Observer>,
    ) {
        let nn = data.len();
        let fits_record = |k: usize| {
            k == 1
                || min_samples_for_horizon(candidate_horizon(settings.options.horizon, k), 1, 1)
                    .saturating_add(settings.options.delay)
                    <= nn
        };
        let mut since_best = 0;
        let mut n = 1;
        while n <= MAX_CANDIDATE_ORDER {
            let batch: Vec<usize> = [n, n + 1]
                .into_iter()
                .filter(|&k| k <= MAX_CANDIDATE_ORDER && fits_record(k))
                .collect();
            if batch.is_empty() {
                break;
            }
            let fitted: Vec<(usize, Option<Result<(OrderCandidate, HammersteinModel<T>)>>)> = batch
                .par_iter()
                .map(|&k| {
                    (
                        k,
                        (k != n0).then(|| candidate(settings, data, k, d_first, start, observer)),
                    )
                })
                .collect();
            for (k, res) in fitted {
                let improved = match res {
                    None => self
                        .best
                        .as_ref()
                        .is_some_and(|(_, m)| m.linear().order() == n0),
                    Some(res) => self.keep(res),
                };
                if improved {
                    since_best = 0;
                } else {
                    since_best += 1;
                    if since_best >= PATIENCE
                        && self
                            .best
                            .as_ref()
                            .is_some_and(|(_, m)| m.linear().order() < k)
                    {
                        return;
                    }
                }
            }
            if batch.len() < 2 {
                break;
            }
            n += 2;
        }
    }

    /// The best model with the table (sorted by feed-through, then order) in its report; the
    /// first error when no candidate could be fitted.
    fn finish(mut self) -> Result<HammersteinModel<T>> {
        self.table.sort_by_key(|r| (r.feedthrough, r.order));
        match self.best {
            Some((_, mut model)) => {
                model.report.order_selection = self.table;
                Ok(model)
            }
            None => Err(self.first_error.unwrap_or_else(|| {
                crate::error::Error::Identification("no candidate order could be fitted".into())
            })),
        }
    }
}

/// Variance of a signal (population), in f64 (what the criterion's exact-fit floor scales with).
pub(crate) fn variance_of<T: Real>(y: &[T]) -> f64 {
    super::problem::variance(y)
}

/// MSE of `y_hat` against `y` (the sum formed as the loop forms it; infinite when it overflows).
pub(crate) fn mse_between<T: Real>(y: &[T], y_hat: &[T]) -> f64 {
    super::linear_ls::mse(y, y_hat)
}
