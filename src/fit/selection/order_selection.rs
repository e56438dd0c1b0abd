//! Model-order selection with the nonlinearity in the model (issue "Right by default"): every
//! candidate order is fitted completely (loop + refinement) and the orders are compared by the
//! Bayesian information criterion of the training simulation error,
//!
//!   BIC(n) = N·ln(MSE_n) + (k_n − n)·ln(N) + 2n,   k_n = n_θ + 3n − 1 + d + c + n_k,
//!
//! (n_θ nonlinearity parameters; n poles, n numerator coefficients less the one the scale
//! normalisation fixes, plus the feed-through d; n initial states; the offset c; the n_k
//! intermediate values before the record of an input delay). The n initial states are charged
//! 2 each instead of ln N: their information does not grow with N ([`penalty`]). MSE_n is the
//! training simulation error with the initial conditions estimated ([`training_mse`]). The criterion
//! uses the training record only; the validation part stays for reporting. Candidates run upwards
//! from order 1 and stop after `PATIENCE` orders without a new best (or at `MAX_CANDIDATE_ORDER`,
//! or where the record is too short for the candidate's horizon). The horizon grows with the
//! candidate order (at least 2n block rows) when the settings' one is too short.
//!
//! Where the candidates start (the search, `Selection::search`): the first runs the loop at the
//! singular-value gap's order; every other order starts from its refined θ with its own block
//! re-identified (a sweep). One θ is not enough: when the gap order is wrong its θ can be a poor
//! start for the others (on the development battery, seeds 201–400, a record of order 3 ended
//! at 170× the noise this way while the loop at order 3 reached 1.2×). So (1) the loop of its own
//! runs at the best order once, (2) a new best whose training MSE is `RESEED_GAIN` below every
//! earlier seed's starts a new sweep of all orders, and (3) a candidate that ends more than
//! `RESEED_GAIN` above a lower order's training MSE — a local minimum, since the higher order
//! nests the lower one — is fitted again from that lower model extended by a real pole
//! (`Problem::nested_start`), so that the search is not stopped by orders that merely failed.
//! (4) After the search, every order below the best is fitted again from the best model's block
//! truncated to it (balanced truncation, `Problem::reduced_start`) when the truncation moves the
//! block's output by at most the fit's residual RMS (`reducible_orders`): a higher order that fits
//! better than a lower one's own fits is often the lower order's local minimum plus states that
//! absorb its error, and the truncated block starts the lower order in the better basin (on the
//! development battery, seeds 201–600, orders above the truth 13 → 7, order right 316 → 317;
//! `docs/battery.md`).
//!
//! Why BIC on the simulation error and not the singular-value gap of the first linear pass: the
//! gap sees the r-input relaxed problem before the nonlinearity is known and chose order 1 for
//! 8 of 25 random records of order 2–3 (`docs/battery.md`). Why BIC and not AIC: AIC's 2k
//! penalty let orders above the truth through on long records in the battery.

use crate::data::{IoData, min_samples_for_horizon};
use crate::error::Result;
use crate::fit::fixed::{SharedStart, fit_fixed_from};
use crate::fit::observer::Observer;
use crate::fit::settings::Hammerstein;
use crate::fit::{HammersteinModel, OrderCandidate};
use crate::real::Real;
use crate::subspace::Order;
use rayon::prelude::*;

/// Orders tried after the last new best before the search stops.
pub const PATIENCE: usize = 2;
/// The highest order the automatic selection tries.
pub const MAX_CANDIDATE_ORDER: usize = 10;
/// The refinement's relative stopping tolerance for the candidates (the chosen one is then
/// refined on to the default tolerance): the criteria of the orders differ by far more than
/// what the last iterations of a candidate's refinement change (N·ln of a 1e-7 relative
/// decrease is 2e-4 at N = 2000, against a penalty of ln N per parameter).
pub const CANDIDATE_LM_TOL: f64 = 1e-7;

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
    let own = model.report().train_mse;
    simulated_mse(model, train).map_or(own, |mse| mse.min(own))
}

/// The MSE of `model`'s simulation on `train` alone ([`training_mse`] without the model's own
/// report): for a model whose report belongs to another record (a start built from a base
/// fitted elsewhere, a screened fit's window). `None` when the simulation fails or is not
/// finite.
pub fn simulated_mse<T: Real>(model: &HammersteinModel<T>, train: &IoData<T>) -> Option<f64> {
    // the simulation is consumed as it is produced (no copy of ŷ kept beside the record)
    let y = train.output_slice(0);
    model
        .on_simulated(train, |y_hat| {
            crate::fit::numerics::linear_ls::mse(y, y_hat)
        })
        .ok()
        .filter(|m| m.is_finite())
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
    let mse = crate::fit::numerics::linear_ls::mse(train.output_slice(0), y_hat);
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
    let floor = crate::fit::iteration::problem::exact_floor::<T>(var).max(f64::MIN_POSITIVE);
    nn * mse.max(floor).ln() + penalty(k as i64, model.linear().order() as i64, n_samples)
}

/// Penalty per initial state in [`penalty`] (AIC's constant).
pub const INITIAL_STATE_PENALTY: f64 = 2.0;

/// The criterion's penalty for `parameters` free parameters of which `initial_states` are the
/// block's initial state, on `n_samples` training samples (differences of both give the
/// penalty of a change).
///
/// Schwarz's ln N per parameter is the Laplace approximation's term for a parameter whose
/// Fisher information grows in proportion to N. An initial state's does not: its free response
/// decays geometrically, so its information stays bounded however long the record, and the
/// approximation leaves it an O(1) term. It is charged AIC's constant 2 instead of ln N
/// (`docs/algorithm.md`, "The default fit", step 2; measured on the battery, `docs/battery.md`).
pub fn penalty(parameters: i64, initial_states: i64, n_samples: usize) -> f64 {
    let ln_n = (n_samples.max(1) as f64).ln();
    (parameters - initial_states) as f64 * ln_n + INITIAL_STATE_PENALTY * initial_states as f64
}

/// The MSE at or below which a fit of `data`'s output counts as exact (the criterion's floor).
pub fn exact_floor_of<T: Real>(data: &IoData<T>) -> f64 {
    crate::fit::iteration::problem::exact_floor::<T>(output_variance(data)).max(f64::MIN_POSITIVE)
}

/// Horizon used for a candidate of order `n`: the settings' one, raised to 2n when shorter.
pub fn candidate_horizon(settings_horizon: usize, n: usize) -> usize {
    settings_horizon.max(2 * n)
}

/// Variance of the record's output.
fn output_variance<T: Real>(data: &IoData<T>) -> f64 {
    crate::fit::iteration::problem::variance(&data.output(0))
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
    let mut s = settings
        .clone()
        .order(Order::Fixed(n))
        .raise_horizon(h)
        .with_d(d);
    // a candidate's refinement stops early; the chosen one is polished on (`finish`)
    s.lm_tol = Some(CANDIDATE_LM_TOL);
    let model = fit_fixed_from(&s, data, start, observer)?;
    Ok((row(&model, data, d), model))
}

/// The table row of a fitted candidate; refused (`refused_from_rest`) when its simulation from
/// rest departs from its fit with the estimated initial state by more than
/// [`REST_LIMIT`](super::from_rest::REST_LIMIT) times the output's excursion (`from_rest.rs`).
fn row<T: Real>(model: &HammersteinModel<T>, data: &IoData<T>, d: bool) -> OrderCandidate {
    let mse = training_mse(model, data);
    let departure = super::from_rest::departure(model, data);
    OrderCandidate {
        order: model.linear().order(),
        feedthrough: d,
        criterion: criterion(model, mse, data.len(), output_variance(data)),
        train_mse: mse,
        refused_from_rest: departure.filter(|_| super::from_rest::departs(departure)),
    }
}

/// The start the other candidates share: the fitted model's θ and offset.
fn start_of<T: Real>(model: &HammersteinModel<T>) -> SharedStart<T> {
    SharedStart {
        theta: model.nonlinearity().params(),
        offset: model.offset,
        report: model.report().clone(),
        nest: None,
        reduce: None,
    }
}

/// The nested start from a fitted model: its θ and its block, extended by the candidate.
fn nested_of<T: Real>(model: &HammersteinModel<T>) -> SharedStart<T> {
    let lin = model.linear();
    SharedStart {
        nest: Some((lin.a.clone(), lin.c.clone())),
        ..start_of(model)
    }
}

/// The reduced start from a fitted model: its θ and its block, truncated to the candidate's order.
fn reduced_of<T: Real>(model: &HammersteinModel<T>) -> SharedStart<T> {
    let lin = model.linear();
    SharedStart {
        reduce: Some((lin.a.clone(), lin.b.clone(), lin.c.clone())),
        ..start_of(model)
    }
}

/// How far, in RMS, a truncated block's output may lie from the fitted one's, in units of the
/// fit's residual RMS, for the truncation to be a start worth refining (`reducible_orders`).
pub const REDUCTION_REACH: f64 = 1.0;

/// The orders k below `model`'s whose balanced truncation moves its output by at most
/// `REDUCTION_REACH` times the fit's residual RMS (`mse` its training MSE), by the truncation's
/// error bound 2·Σ_{j>k} σ_j (Glover 1984: the H∞ norm of the error; σ the Hankel singular
/// values) times the RMS of the block's centred input v = N(u; θ). A lower order whose
/// truncation moves the output by far more than the residual drops a mode the record shows:
/// refitting it from there would only repeat the lower order's own fit.
fn reducible_orders<T: Real>(
    ctx: &Context<'_, T>,
    model: &HammersteinModel<T>,
    mse: f64,
) -> Vec<usize> {
    let lin = model.linear();
    let Ok(la) = ctx.settings.linalg_backend() else {
        return Vec::new();
    };
    let Some(hsv) = crate::subspace::hankel_singular_values(
        la.as_ref(),
        lin.a.as_ref(),
        lin.b.as_ref(),
        lin.c.as_ref(),
    ) else {
        return Vec::new();
    };
    let v = model.nl.eval(ctx.data.input_slice(0));
    let rms_v = variance_of(&v).sqrt();
    let reach = REDUCTION_REACH * mse.max(0.0).sqrt();
    (1..lin.order())
        .filter(|&k| {
            let tail: f64 = hsv[k..].iter().map(|s| s.as_f64()).sum();
            2.0 * tail * rms_v <= reach
        })
        .collect()
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
        fits: Vec::new(),
        looped: Vec::new(),
        first_error: None,
        spare: None,
    };
    // the first candidate runs the loop at the order of the singular-value gap (or the
    // settings' rule); the others start from its refined θ with their own linear block
    let first_settings = match settings.options.order {
        Order::Auto => settings.clone().order(Order::Gap),
        _ => settings.clone(),
    };
    let first = crate::fit::fixed::fit_fixed(&first_settings.with_d(d_first), data, observer)
        .map(|m| (row(&m, data, d_first), m));
    if let Ok((_, m)) = &first {
        sel.looped.push(m.linear().order());
        if settings.options.d_auto && !d_first {
            sel.spare = Some(Spare {
                order: m.linear().order(),
                start: start_of(m),
                result: None,
            });
        }
    }
    if sel.keep(first)
        && let Some(e) = sel.fits.first_mut()
    {
        e.first = true;
    }
    if matches!(settings.options.order, Order::Auto) {
        sel.search(&Context {
            settings,
            data,
            d: d_first,
            observer,
        });
        sel.reduce(&Context {
            settings,
            data,
            d: d_first,
            observer,
        });
    }
    if settings.options.d_auto {
        let spare = sel.spare_for_best();
        let res = match spare {
            Some(res) => {
                // the speculative fit ran without the observer: it sees its end now
                if let (Some(obs), Ok((_, m))) = (observer, &res) {
                    obs.observe_final(m.report());
                }
                Some(res)
            }
            None => sel.best().map(|e| {
                let m = &e.model;
                let st = start_of(m);
                candidate(
                    settings,
                    data,
                    m.linear().order(),
                    true,
                    Some(&st),
                    observer,
                )
            }),
        };
        if let Some(res) = res {
            sel.keep(res);
        }
    }
    sel.finish(data)
}

/// What every candidate of one selection shares: the settings, the record, the feed-through of
/// the order search and the observer.
struct Context<'a, T: Real> {
    settings: &'a Hammerstein<T>,
    data: &'a IoData<T>,
    d: bool,
    observer: Option<&'a dyn Observer>,
}

impl<T: Real> Context<'_, T> {
    /// Whether a candidate of order `k` fits the record with its horizon.
    fn fits_record(&self, k: usize) -> bool {
        let h = candidate_horizon(self.settings.options.horizon, k);
        k == 1
            || min_samples_for_horizon(h, 1, 1).saturating_add(self.settings.options.delay)
                <= self.data.len()
    }

    /// The feed-through candidate of the spare slot: order `spare.order` with D, from
    /// `spare.start`, without the observer (it may not be used; `fit_selecting_order` notifies
    /// the observer when it is).
    fn fit_spare(&self, spare: &Spare<T>) -> Result<(OrderCandidate, HammersteinModel<T>)> {
        candidate(
            self.settings,
            self.data,
            spare.order,
            true,
            Some(&spare.start),
            None,
        )
    }

    /// The orders of the automatic search in pairs (1, 2), (3, 4), …: the orders that fit the
    /// record, up to `MAX_CANDIDATE_ORDER`, ending with the first pair that is not whole.
    fn order_batches(&self) -> Vec<Vec<usize>> {
        let mut out = Vec::new();
        let mut n = 1;
        while n <= MAX_CANDIDATE_ORDER {
            let batch: Vec<usize> = [n, n + 1]
                .into_iter()
                .filter(|&k| k <= MAX_CANDIDATE_ORDER && self.fits_record(k))
                .collect();
            let whole = batch.len() == 2;
            if !batch.is_empty() {
                out.push(batch);
            }
            if !whole {
                break;
            }
            n += 2;
        }
        out
    }

    /// The candidate of order `k`: from `start` (None: its own loop).
    fn fit(
        &self,
        k: usize,
        start: Option<&SharedStart<T>>,
    ) -> Result<(OrderCandidate, HammersteinModel<T>)> {
        candidate(self.settings, self.data, k, self.d, start, self.observer)
    }
}

/// Rounds of the search (`Selection::search`): sweeps from a new best's θ and loops at the best
/// order.
pub const SEARCH_ROUNDS: usize = 6;

/// The relative training-MSE gain on every model that seeded a sweep so far above which a new
/// best model seeds one too (a smaller gain is the same basin: the other orders would not move).
pub const RESEED_GAIN: f64 = 0.05;

/// The best fit of one order and feed-through.
struct Entry<T: Real> {
    row: OrderCandidate,
    model: HammersteinModel<T>,
    /// Whether the other orders have been fitted from this model's θ.
    seeded: bool,
    /// Whether this is the first candidate's fit (the loop at the gap order).
    first: bool,
}

/// The feed-through decision's candidate fitted ahead, in a slot of the order search that would
/// otherwise leave a core idle: order `order` with D from the first candidate's θ (`start`).
/// It is the candidate `fit_selecting_order` fits after the search when the first candidate is
/// still the best; otherwise it is dropped (speculation on the second core: the same result as
/// fitting it afterwards, since the fit is deterministic).
struct Spare<T: Real> {
    order: usize,
    start: SharedStart<T>,
    result: Option<Result<(OrderCandidate, HammersteinModel<T>)>>,
}

/// The candidates fitted so far (the best fit of each order and feed-through), the orders whose
/// own loop has run, the first error.
struct Selection<T: Real> {
    fits: Vec<Entry<T>>,
    looped: Vec<usize>,
    first_error: Option<crate::error::Error>,
    /// The feed-through candidate fitted ahead, if any.
    spare: Option<Spare<T>>,
}

impl<T: Real> Selection<T> {
    /// The preferred entry ([`OrderCandidate::preference`]): the lowest criterion among the
    /// candidates not refused, the lowest of all when every one was.
    fn best(&self) -> Option<&Entry<T>> {
        self.fits.iter().min_by(|a, b| a.row.preference(&b.row))
    }

    /// The spare slot's result when it is the feed-through candidate of the best entry (the
    /// first candidate's fit, still the best: the same start and order); the spare is consumed.
    fn spare_for_best(&mut self) -> Option<Result<(OrderCandidate, HammersteinModel<T>)>> {
        let order = self.best().filter(|e| e.first)?.row.order;
        let spare = self.spare.take()?;
        if spare.order != order {
            return None;
        }
        spare.result
    }

    /// The best model's row, to tell whether a candidate improved on it.
    fn best_row(&self) -> Option<OrderCandidate> {
        self.best().map(|e| e.row.clone())
    }

    /// Records a candidate's outcome, replacing a worse fit of the same order and feed-through;
    /// true when it is the new best of its order.
    fn keep(&mut self, res: Result<(OrderCandidate, HammersteinModel<T>)>) -> bool {
        let (row, model) = match res {
            Ok(x) => x,
            Err(e) => {
                self.first_error.get_or_insert(e);
                return false;
            }
        };
        let entry = Entry {
            row,
            model,
            seeded: false,
            first: false,
        };
        let same = self.fits.iter().position(|e| {
            e.row.order == entry.row.order && e.row.feedthrough == entry.row.feedthrough
        });
        match same {
            Some(i) if self.fits[i].row.preference(&entry.row).is_le() => false,
            Some(i) => {
                self.fits[i] = entry;
                true
            }
            None => {
                self.fits.push(entry);
                true
            }
        }
    }

    /// The automatic order's search, in rounds: while the best model's θ has not seeded the
    /// other orders, every order is fitted from it (`orders`) — when its training MSE is
    /// `RESEED_GAIN` below every earlier seed's; otherwise the loop of its own runs at the best
    /// order (once per order), whose improvement seeds the next round. Stops when a round
    /// changes nothing (or after `SEARCH_ROUNDS`).
    fn search(&mut self, ctx: &Context<'_, T>) {
        for _ in 0..SEARCH_ROUNDS {
            let Some(i) = self
                .fits
                .iter()
                .enumerate()
                .min_by(|a, b| a.1.row.preference(&b.1.row))
                .map(|(i, _)| i)
            else {
                return;
            };
            let nb = self.fits[i].row.order;
            if !self.fits[i].seeded {
                self.fits[i].seeded = true;
                let seeded_mse = self
                    .fits
                    .iter()
                    .filter(|e| e.seeded && e.row.order != nb)
                    .map(|e| e.row.train_mse)
                    .fold(f64::INFINITY, f64::min);
                if self.fits[i].row.train_mse < (1.0 - RESEED_GAIN) * seeded_mse {
                    let start = start_of(&self.fits[i].model);
                    self.orders(ctx, nb, &start);
                }
                continue;
            }
            if nb > MAX_CANDIDATE_ORDER || !ctx.fits_record(nb) || self.looped.contains(&nb) {
                return;
            }
            self.looped.push(nb);
            let res = ctx.fit(nb, None);
            self.keep(res);
        }
    }

    /// The automatic order's candidates 1, 2, … (`n0`, where `start` comes from, skipped),
    /// each from `start`, processed in order until `PATIENCE` candidates above the best brought
    /// no improvement of the best criterion. They are fitted in the pairs of
    /// `Context::order_batches`, except that the pairs up to order `n0 + PATIENCE` — what the
    /// search needs when `n0` stays the best — are fitted at once, so that the two cores share
    /// them unevenly sized as they come (the same candidates, processed in the same order).
    fn orders(&mut self, ctx: &Context<'_, T>, n0: usize, start: &SharedStart<T>) {
        let batches = ctx.order_batches();
        let first = batches
            .iter()
            .take_while(|b| b.first().is_some_and(|&k| k <= n0 + PATIENCE))
            .count()
            .max(1)
            .min(batches.len());
        let windows = std::iter::once(batches[..first].concat())
            .chain(batches[first..].iter().cloned())
            .filter(|w| !w.is_empty());
        let mut since_best = 0;
        for window in windows {
            let fitted = self.batch(ctx, &window, n0, start);
            for (k, res) in fitted {
                let before = self.best_row();
                if let Some(res) = res {
                    let mse = res.as_ref().map_or(f64::INFINITY, |(r, _)| r.train_mse);
                    self.keep(res);
                    self.nest_if_above(ctx, k, mse);
                }
                let best_order = self.best().map_or(0, |e| e.row.order);
                let improved = match (self.best_row(), &before) {
                    (Some(now), Some(before)) => now.preference(before).is_lt(),
                    (now, None) => now.is_some(),
                    (None, Some(_)) => false,
                };
                if improved || best_order == k {
                    since_best = 0;
                } else {
                    since_best += 1;
                    if since_best >= PATIENCE && best_order < k {
                        return;
                    }
                }
            }
        }
    }

    /// The candidates of the orders `batch` (`n0` skipped) from `start`, side by side (the two
    /// cores); when `n0` leaves a slot free, the spare feed-through candidate fills it.
    #[allow(clippy::type_complexity)]
    fn batch(
        &mut self,
        ctx: &Context<'_, T>,
        batch: &[usize],
        n0: usize,
        start: &SharedStart<T>,
    ) -> Vec<(usize, Option<Result<(OrderCandidate, HammersteinModel<T>)>>)> {
        let spare = self
            .spare
            .as_ref()
            .filter(|s| s.result.is_none() && !ctx.d && batch.contains(&n0));
        // one job per slot: an order (`Some`) or the spare (`None`)
        let jobs: Vec<Option<usize>> = batch
            .iter()
            .filter_map(|&k| {
                if k != n0 {
                    Some(Some(k))
                } else {
                    spare.map(|_| None)
                }
            })
            .collect();
        let mut results: Vec<(Option<usize>, Result<(OrderCandidate, HammersteinModel<T>)>)> = jobs
            .par_iter()
            .filter_map(|&job| match (job, spare) {
                (Some(k), _) => Some((job, ctx.fit(k, Some(start)))),
                (None, Some(sp)) => Some((job, ctx.fit_spare(sp))),
                (None, None) => None,
            })
            .collect();
        if let Some(pos) = results.iter().position(|(job, _)| job.is_none()) {
            let (_, res) = results.remove(pos);
            if let Some(sp) = self.spare.as_mut() {
                sp.result = Some(res);
            }
        }
        let mut by_order = results.into_iter();
        batch
            .iter()
            .map(|&k| {
                (
                    k,
                    (k != n0).then(|| by_order.next().map(|(_, r)| r)).flatten(),
                )
            })
            .collect()
    }

    /// The lower orders fitted again from the best model's block truncated to them (balanced
    /// truncation: `Problem::reduced_start`), side by side: a higher order that fits better
    /// than a lower one's own fit may be a local minimum of the lower order, not the order.
    fn reduce(&mut self, ctx: &Context<'_, T>) {
        let Some(best) = self.best().filter(|e| e.row.feedthrough == ctx.d) else {
            return;
        };
        let top = best.row.order;
        if top < 2 {
            return;
        }
        let orders = reducible_orders(ctx, &best.model, best.row.train_mse);
        if orders.is_empty() {
            return;
        }
        let start = reduced_of(&best.model);
        let results: Vec<_> = orders
            .par_iter()
            .map(|&k| ctx.fit(k, Some(&start)))
            .collect();
        for res in results {
            self.keep(res);
        }
    }

    /// When the candidate of order `k` (training MSE `mse`) ended above a lower order's training
    /// MSE — a higher order nests the lower one, so that is a local minimum, not the order — it
    /// is fitted again from the nested start of the lower order with the lowest MSE.
    fn nest_if_above(&mut self, ctx: &Context<'_, T>, k: usize, mse: f64) {
        let lower = self
            .fits
            .iter()
            .filter(|e| e.row.order < k && e.row.feedthrough == ctx.d)
            .min_by(|a, b| a.row.train_mse.total_cmp(&b.row.train_mse));
        let Some(e) = lower else {
            return;
        };
        if mse.is_finite() && mse <= (1.0 + RESEED_GAIN) * e.row.train_mse {
            return;
        }
        let start = nested_of(&e.model);
        let res = ctx.fit(k, Some(&start));
        self.keep(res);
    }

    /// The best model with the table (sorted by feed-through, then order) in its report,
    /// refined on to the default tolerance on `data` (its row updated); the first error when no
    /// candidate could be fitted.
    fn finish(self, data: &IoData<T>) -> Result<HammersteinModel<T>> {
        let mut table: Vec<OrderCandidate> = self.fits.iter().map(|e| e.row.clone()).collect();
        table.sort_by_key(|r| (r.feedthrough, r.order));
        let best = self
            .fits
            .into_iter()
            .min_by(|a, b| a.row.preference(&b.row));
        match best {
            Some(mut e) => {
                // the chosen candidate refined on at the default tolerance (when the settings
                // refine at all: the paper's loop alone is left as it ended)
                e.model.settings.lm_tol = None;
                let polished = if e.model.settings.options.refine {
                    super::screening::polish(
                        &e.model,
                        data,
                        crate::fit::refinement::refine::MAX_LM_ITER,
                    )
                    .ok()
                } else {
                    None
                };
                if let Some(m) = polished {
                    let row = row(&m, data, e.row.feedthrough);
                    if let Some(r) = table
                        .iter_mut()
                        .find(|r| r.order == row.order && r.feedthrough == row.feedthrough)
                    {
                        *r = row;
                    }
                    e.model = m;
                }
                e.model.report.order_selection = table;
                Ok(e.model)
            }
            None => Err(self.first_error.unwrap_or_else(|| {
                crate::error::Error::Identification("no candidate order could be fitted".into())
            })),
        }
    }
}

/// Variance of a signal (population), in f64 (what the criterion's exact-fit floor scales with).
pub(crate) fn variance_of<T: Real>(y: &[T]) -> f64 {
    crate::fit::iteration::problem::variance(y)
}

/// MSE of `y_hat` against `y` (the sum formed as the loop forms it; infinite when it overflows).
pub(crate) fn mse_between<T: Real>(y: &[T], y_hat: &[T]) -> f64 {
    crate::fit::numerics::linear_ls::mse(y, y_hat)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_initial_state_costs_a_constant_and_other_parameters_ln_n() {
        for n in [100usize, 2000, 1_000_000] {
            let ln_n = (n as f64).ln();
            // one more order: a pole, a numerator coefficient and an initial state
            let step = penalty(3, 1, n);
            assert!((step - (2.0 * ln_n + INITIAL_STATE_PENALTY)).abs() < 1e-12);
            // the initial states' share does not grow with the record
            assert_eq!(penalty(4, 4, n), 4.0 * INITIAL_STATE_PENALTY);
            // differences of penalties are the penalties of differences (the diagnosis' ΔBIC)
            let d = penalty(11, 3, n) - penalty(8, 2, n);
            assert!((d - penalty(3, 1, n)).abs() < 1e-9);
        }
    }
}
