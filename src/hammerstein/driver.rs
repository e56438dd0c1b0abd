//! The iterative subspace loop (paper Section 3.3, corrected as in NOTES.md).
//!
//! One iteration, for the current nonlinearity parameters θ:
//! 1. φ = N.regressors(u(k − nk))  (N×r);
//! 2. (A, C) by the subspace method from (φ, y) (means removed when an offset is estimated); the
//!    order is chosen by the `Order` rule at the first iteration and kept afterwards;
//! 3. B̃ (n×r), D̃, x0 and the offset by linear least squares given (A, C);
//! 4. g from the best rank-one approximation of the Markov-parameter matrix of (A, B̃, C, D̃)
//!    (basis independent, see `rank_one.rs`), scaled by the normalisation rule;
//! 5. θ ← N.update_from_gains(g, u) (the nonlinearity's zone guard keeps thresholds inside the
//!    data); parameters g cannot determine (`searched_params`) by a bounded 1-D search of the
//!    simulation MSE, the rest of the step (3–5) redone for every candidate;
//! 6. B, D, x0 and offset re-estimated by least squares for the single input v = N(u; θ) given
//!    (A, C) (the brief's "re-estimate B, D for v = φ·g", done with the updated θ so that the
//!    iterate's model is self-consistent), simulation and MSE;
//! 7. stopping: |ΔMSE| ≤ λ·MSE_prev, an exact fit (MSE below a round-off floor) or a fixed point
//!    of φ → converged; the MSE rising → the θ step is halved towards the previous θ (up to three
//!    times); no new best for `PATIENCE` iterations → oscillating (still near the best MSE) or
//!    diverged (far above it). The best iterate is always the one returned.

use super::fit_report::{FitReport, IterationRecord, Termination};
use super::init::initialize;
use super::linear_ls::{
    LsTerms, LsWork, delayed, fit_gains_given_block, fit_given_ac, mse, simulate_into,
};
use super::model::{HammersteinModel, check_siso};
use super::rank_one::{factor, markov_of, markov_rows, scale_for};
use super::refine;
use super::scaling::Scaling;
use super::settings::Hammerstein;
use crate::data::{IoData, IoView, min_samples_for_horizon};
use crate::error::{Error, Result};
use crate::real::Real;
use crate::regressors::StaticNonlinearity;
use crate::solvers::LinAlg;
use crate::statespace::StateSpace;
use crate::subspace::{SubspaceMethod, max_order, select_order};
use faer::{Mat, MatRef};

/// Iterations without a new best MSE after which the loop stops (oscillating or diverged).
pub(crate) const PATIENCE: usize = 5;
/// An MSE above best·(1 + DIVERGED_BAND) after `PATIENCE` fruitless iterations counts as diverged.
pub(crate) const DIVERGED_BAND: f64 = 0.5;
/// Halvings of a θ step that raised the MSE.
pub(crate) const DAMPING_STEPS: usize = 3;
/// Grid points of the 1-D search of a searched parameter before golden-section refinement.
pub(crate) const SEARCH_GRID: usize = 9;
/// Golden-section steps after the grid.
pub(crate) const SEARCH_GOLDEN: usize = 6;
/// Golden-section steps of the local search of later iterations (the first iteration searches the
/// whole range).
pub(crate) const SEARCH_GOLDEN_LOCAL: usize = 4;
/// Iterations with the searched parameters fixed at their lower ends tried after an exact fit.
pub(crate) const LOWER_END_ITERATIONS: usize = 4;
/// Horizon of the single-input re-identification of the linear block before the refinement.
pub(crate) const RESTART_HORIZON: usize = 20;
/// Factor by which the local bracket shrinks after a search whose best point was inside it (it
/// doubles when the best point was at its edge).
pub(crate) const SEARCH_SHRINK: f64 = 0.25;

/// One iterate: nonlinearity parameters and the single-input linear block with its x0 and offset.
#[derive(Debug, Clone)]
pub(crate) struct Iterate<T: Real> {
    pub theta: Vec<T>,
    pub a: Mat<T>,
    pub b: Vec<T>,
    pub c: Mat<T>,
    pub d: T,
    pub x0: Vec<T>,
    pub offset: T,
    pub mse: f64,
}

/// The fixed data of one fit: the delayed input, the output, the solvers and the settings.
pub(crate) struct Problem<'a, T: Real> {
    pub la: &'a dyn LinAlg<T>,
    pub method: &'a dyn SubspaceMethod<T>,
    pub settings: &'a Hammerstein<T>,
    pub u: Vec<T>,
    pub y: Vec<T>,
    pub k_rows: usize,
    /// MSE at or below which the fit counts as exact (round-off level of var(y)).
    pub floor: f64,
    /// Change of the offset below which it counts as settled (√ε·std(y)).
    pub offset_tol: f64,
    /// Half-width of the next local search bracket per searched parameter (NaN: not set yet).
    pub search_width: std::cell::RefCell<Vec<f64>>,
    /// Regression matrix of the least-squares steps, reused from call to call.
    pub ls_work: std::cell::RefCell<LsWork<T>>,
}

impl<'a, T: Real> Problem<'a, T> {
    /// The problem of fitting `data` with `settings` (the input delayed by the settings' delay).
    pub fn new(
        la: &'a dyn LinAlg<T>,
        method: &'a dyn SubspaceMethod<T>,
        settings: &'a Hammerstein<T>,
        data: &IoData<T>,
    ) -> Self {
        let y = data.output(0);
        let var = variance(&y);
        Problem {
            la,
            method,
            settings,
            u: delayed(data.input_slice(0), settings.delay),
            y,
            k_rows: markov_rows(settings.horizon, max_order(settings.horizon, 1)),
            floor: exact_floor::<T>(var),
            offset_tol: T::epsilon().as_f64().sqrt() * var.sqrt(),
            search_width: Default::default(),
            ls_work: Default::default(),
        }
    }

    /// Whether the loop estimates its own output offset: not when the nonlinearity's regressors
    /// already span the constant (preload without dead-zone), where an offset column would make
    /// the linear step rank deficient and the preload steps absorb the offset.
    pub fn fits_offset(&self, nl: &dyn StaticNonlinearity<T>) -> bool {
        self.settings.offset && !nl.spans_constant()
    }

    fn terms(&self, nl: &dyn StaticNonlinearity<T>) -> LsTerms {
        LsTerms {
            with_d: self.settings.with_d,
            x0: true,
            offset: self.fits_offset(nl),
        }
    }

    /// Step 2: (A, C) from (φ, y); the order by the rule when `order` is `None`.
    ///
    /// Offsets: with `offset_hint = Some(c)` (the previous iterate's offset) the subspace step sees
    /// the raw φ and y − c, which is exactly LTI (with an initial state) once c is right; without a
    /// hint (first iteration) it sees first differences of φ and y, exactly LTI whatever the
    /// offset (the differenced noise is coloured, so later iterations switch to the hint).
    #[allow(clippy::type_complexity)]
    pub fn identify_ac(
        &self,
        phi: MatRef<'_, T>,
        order: Option<usize>,
        offset_hint: Option<T>,
        fit_offset: bool,
    ) -> Result<(Mat<T>, Mat<T>, Vec<f64>, usize)> {
        let nn = self.y.len();
        let r = phi.ncols();
        let (mut phic, mut yc) = (phi.to_owned(), Mat::from_fn(nn, 1, |k, _| self.y[k]));
        if let (true, Some(c)) = (fit_offset, offset_hint) {
            for k in 0..nn {
                yc[(k, 0)] -= c;
            }
        } else if fit_offset {
            // first iteration: no offset estimate yet. First differences remove any constant
            // exactly and leave an LTI system with the same (A, C): Δy = G(Δφ·g) + a free
            // response. (Removing the means instead leaves the mean of the transients, which a
            // noise-free record turns into a spurious mode at z = 1.)
            phic = Mat::from_fn(nn - 1, r, |k, q| phi[(k + 1, q)] - phi[(k, q)]);
            yc = Mat::from_fn(nn - 1, 1, |k, _| self.y[k + 1] - self.y[k]);
        }
        let view = IoView::new(phic.as_ref(), yc.as_ref())?;
        let dec = self.method.decompose(self.la, &[view])?;
        let sv: Vec<f64> = dec.singular_values.iter().map(|s| s.as_f64()).collect();
        let n = match order {
            Some(n) => n,
            None => select_order(
                &dec.singular_values,
                &self.settings.order,
                max_order(dec.horizon, 1),
            )?,
        };
        let (a, c) = self.method.realize_ac(self.la, &dec, n)?;
        Ok((stabilised(a), c, sv, n))
    }

    /// The linear block of order `n` re-identified from (v, y) with v = N(u; θ) held fixed: a
    /// single-input subspace step with the longer horizon `RESTART_HORIZON` (the loop's r-input
    /// steps use the settings' short one, which leaves slow and high-order blocks far from their
    /// optimum), then B, D, x0 and the offset by least squares (step 6). The refinement starts
    /// from it when its MSE is lower. `None` when the record is too short or a step fails.
    pub fn restart_linear(
        &self,
        nl: &dyn StaticNonlinearity<T>,
        n: usize,
        offset: T,
    ) -> Option<Iterate<T>> {
        let nn = self.y.len();
        let mut h = RESTART_HORIZON.max(self.settings.horizon).max(n + 1);
        while h > n + 1 && min_samples_for_horizon(h, 1, 1) > nn {
            h -= 1;
        }
        if min_samples_for_horizon(h, 1, 1) > nn || max_order(h, 1) < n {
            return None;
        }
        let method = self.settings.subspace_at(h).ok()?;
        let v = nl.eval(&self.u);
        let vm = Mat::from_fn(nn, 1, |k, _| v[k]);
        let c = if self.fits_offset(nl) {
            offset
        } else {
            T::zero()
        };
        let yc = Mat::from_fn(nn, 1, |k, _| self.y[k] - c);
        let view = IoView::new(vm.as_ref(), yc.as_ref()).ok()?;
        let dec = method.decompose(self.la, &[view]).ok()?;
        let (a, c) = method.realize_ac(self.la, &dec, n).ok()?;
        let a = stabilised(a);
        let it = self.evaluate(nl, a.as_ref(), c.as_ref()).ok()?;
        it.mse.is_finite().then_some(it)
    }

    /// Steps 3–5 without the search: g by least squares and rank-one factorisation given (A, C),
    /// then θ from g.
    pub fn update_gains(
        &self,
        nl: &mut dyn StaticNonlinearity<T>,
        phi: MatRef<'_, T>,
        a: MatRef<'_, T>,
        c: MatRef<'_, T>,
    ) -> Result<()> {
        let fit = fit_given_ac(
            self.la,
            a,
            c,
            phi,
            &self.y,
            self.terms(nl),
            &mut self.ls_work.borrow_mut(),
        )?;
        let ro = factor(self.la, a, fit.b.as_ref(), c, &fit.d, self.k_rows)?;
        let s = scale_for(self.settings.normalization, &ro.g, &ro.markov)?;
        let g: Vec<T> = ro.g.iter().map(|&x| x * s).collect();
        match nl.update_from_gains(&g, &self.u) {
            Ok(()) => Ok(()),
            Err(e) => {
                // MarkovOne fixes the first Markov parameter to +1, which may give a negative gain
                // the nonlinearity refuses (a UDN needs p > 0): then it is −1 instead.
                let neg: Vec<T> = g.iter().map(|&x| -x).collect();
                let mut trial = nl.clone_box();
                if trial.update_from_gains(&neg, &self.u).is_ok() {
                    nl.set_params(&trial.params())
                } else {
                    Err(e)
                }
            }
        }
    }

    /// Step 6: the single-input block for v = N(u; θ) given (A, C), simulated.
    pub fn evaluate(
        &self,
        nl: &dyn StaticNonlinearity<T>,
        a: MatRef<'_, T>,
        c: MatRef<'_, T>,
    ) -> Result<Iterate<T>> {
        let v = nl.eval(&self.u);
        let vm = Mat::from_fn(v.len(), 1, |k, _| v[k]);
        let fit = fit_given_ac(
            self.la,
            a,
            c,
            vm.as_ref(),
            &self.y,
            self.terms(nl),
            &mut self.ls_work.borrow_mut(),
        )?;
        let b: Vec<T> = (0..a.nrows()).map(|i| fit.b[(i, 0)]).collect();
        let mut y_hat = Vec::with_capacity(v.len());
        simulate_into(a, &b, c, fit.d[0], &fit.x0, fit.offset, &v, &mut y_hat);
        let e = mse(&self.y, &y_hat);
        Ok(Iterate {
            theta: nl.params(),
            a: a.to_owned(),
            b,
            c: c.to_owned(),
            d: fit.d[0],
            x0: fit.x0,
            offset: fit.offset,
            mse: if e.is_finite() { e } else { f64::INFINITY },
        })
    }

    /// MSE after fixing parameter `j` at `t`, given (A, C); `None` when the value is
    /// inadmissible. The gains come from the gain step of alternating least squares — the
    /// current single-input block `base` (A, b, C, d) fixed, g, x0 and the offset free (m + n + 1
    /// unknowns, against the m·n + n + 1 of the loop's relaxed step 3, which made every candidate
    /// 2× dearer and, in the paper's loop, biased b, e1, e2 more: Table 2's b RMSE 0.068 against
    /// 0.046 now); then θ from g and step 6 (the block refitted for v = N(u; θ)).
    #[allow(clippy::too_many_arguments)]
    fn searched_value(
        &self,
        nl: &dyn StaticNonlinearity<T>,
        j: usize,
        t: T,
        phi_cols: usize,
        a: MatRef<'_, T>,
        c: MatRef<'_, T>,
        base: &Iterate<T>,
    ) -> Option<Iterate<T>> {
        let mut trial = nl.clone_box();
        let mut theta = trial.params();
        theta[j] = t;
        trial.set_params(&theta).ok()?;
        let phi = trial.regressors(&self.u);
        if phi.ncols() != phi_cols {
            return None;
        }
        let mut work = self.ls_work.borrow_mut();
        let fit = fit_gains_given_block(
            self.la,
            a,
            &base.b,
            c,
            base.d,
            phi.as_ref(),
            &self.y,
            self.terms(trial.as_ref()),
            &mut work,
        )
        .ok()?;
        drop(work);
        let g: Vec<T> = (0..phi_cols).map(|q| fit.b[(0, q)]).collect();
        trial.update_from_gains(&g, &self.u).ok()?;
        let mut theta = trial.params();
        if theta[j] != t {
            theta[j] = t;
            trial.set_params(&theta).ok()?;
        }
        self.evaluate(trial.as_ref(), a, c).ok()
    }

    /// Bounded 1-D search over each searched parameter; θ is set to the best candidate found (or
    /// left unchanged) and, with one searched parameter, its iterate is returned. `global` (first
    /// iteration): a grid over the whole range, then golden-section refinement around the best
    /// grid point; otherwise the lower range end, the current value and golden section on the
    /// adaptive bracket kept in `search_width` (see `docs/algorithm.md`).
    fn search(
        &self,
        nl: &mut dyn StaticNonlinearity<T>,
        a: MatRef<'_, T>,
        c: MatRef<'_, T>,
        global: bool,
    ) -> Result<Option<Iterate<T>>> {
        let r = nl.n_regressors();
        let mut chosen = None;
        // the single-input block the candidates' gain steps hold fixed
        let base = self.evaluate(nl, a, c)?;
        for j in nl.searched_params() {
            let (lo, hi) = nl.search_range(j, &self.u);
            let (lo, hi) = (lo.as_f64(), hi.as_f64());
            if !(lo.is_finite() && hi.is_finite() && hi >= lo) {
                continue;
            }
            let current = nl.params()[j].as_f64();
            let mut best: Option<(f64, f64, Iterate<T>)> = None;
            let shared: &dyn StaticNonlinearity<T> = &*nl;
            // MSEs at the exact-fit level count as equal: the first such candidate (the range's
            // lower end, "no effect", is tried first) is kept
            let consider = |x: f64, best: &mut Option<(f64, f64, Iterate<T>)>| -> f64 {
                match self.searched_value(shared, j, T::lit(x), r, a, c, &base) {
                    Some(it) => {
                        let m = it.mse.max(self.floor);
                        if best.as_ref().is_none_or(|b| m < b.0) {
                            *best = Some((m, x, it));
                        }
                        m
                    }
                    None => f64::INFINITY,
                }
            };
            let step = (hi - lo) / (SEARCH_GRID - 1) as f64;
            let in_range = current.is_finite() && current >= lo && current <= hi;
            let stored = self
                .search_width
                .borrow()
                .get(j)
                .copied()
                .unwrap_or(f64::NAN);
            let local = !global && in_range && stored.is_finite() && stored > 0.0;
            // bracket half-width: one grid step after the grid, the stored width afterwards
            let width = if local { stored.min(hi - lo) } else { step };
            let golden_steps = if !local {
                // grid (including the current value)
                let mut grid: Vec<f64> = (0..SEARCH_GRID).map(|i| lo + step * i as f64).collect();
                if in_range {
                    grid.push(current);
                }
                for &x in &grid {
                    consider(x, &mut best);
                }
                SEARCH_GOLDEN
            } else {
                // the lower end (b = 0: no dead-zone) is always tried exactly, and first; the
                // upper end when it lies inside the bracket
                if lo != current {
                    consider(lo, &mut best);
                }
                consider(current, &mut best);
                if (hi - current).abs() <= width && hi != current {
                    consider(hi, &mut best);
                }
                SEARCH_GOLDEN_LOCAL
            };
            let Some(x_best) = best.as_ref().map(|b| b.1) else {
                continue;
            };
            // golden section on [x_best − width, x_best + width] ∩ [lo, hi]
            let (mut l, mut h) = ((x_best - width).max(lo), (x_best + width).min(hi));
            let gr = (5f64.sqrt() - 1.0) / 2.0;
            let mut x1 = h - gr * (h - l);
            let mut x2 = l + gr * (h - l);
            let mut f1 = consider(x1, &mut best);
            let mut f2 = consider(x2, &mut best);
            for _ in 0..golden_steps {
                if f1 <= f2 {
                    h = x2;
                    x2 = x1;
                    f2 = f1;
                    x1 = h - gr * (h - l);
                    f1 = consider(x1, &mut best);
                } else {
                    l = x1;
                    x1 = x2;
                    f1 = f2;
                    x2 = l + gr * (h - l);
                    f2 = consider(x2, &mut best);
                }
            }
            // next bracket: shrink around an interior optimum, widen when it hit the bracket edge
            let x_final = best.as_ref().map_or(x_best, |b| b.1);
            // (golden section never evaluates the bracket ends: "at the edge" = in its outer 20 %)
            let at_edge = (x_final - (x_best - width)).abs() < 0.2 * width
                || (x_final - (x_best + width)).abs() < 0.2 * width;
            let next = if at_edge {
                (2.0 * width).min(hi - lo)
            } else {
                (SEARCH_SHRINK * width).max(f64::EPSILON * (hi - lo).max(f64::MIN_POSITIVE))
            };
            {
                let mut widths = self.search_width.borrow_mut();
                if widths.len() <= j {
                    widths.resize(j + 1, f64::NAN);
                }
                widths[j] = next;
            }
            if let Some((_, _, it)) = best {
                nl.set_params(&it.theta)?;
                chosen = Some(it);
            }
        }
        // the chosen candidate's iterate is the step's evaluation when one parameter was searched
        Ok(if nl.searched_params().len() == 1 {
            chosen
        } else {
            None
        })
    }

    /// When the searched parameters are above their lower ends: up to `LOWER_END_ITERATIONS`
    /// iterations with them fixed at the lower ends (steps 1–6, no search); the iterate when it
    /// fits exactly (MSE at the floor).
    fn exact_at_lower_end(
        &self,
        nl: &dyn StaticNonlinearity<T>,
        order: Option<usize>,
        offset_hint: Option<T>,
    ) -> Option<Iterate<T>> {
        let searched = nl.searched_params();
        let mut trial = nl.clone_box();
        let mut theta = trial.params();
        let mut moved = false;
        for &j in &searched {
            let lo = nl.search_range(j, &self.u).0;
            if theta[j] != lo {
                theta[j] = lo;
                moved = true;
            }
        }
        if !moved {
            return None;
        }
        trial.set_params(&theta).ok()?;
        for _ in 0..LOWER_END_ITERATIONS {
            let phi = trial.regressors(&self.u);
            let fit_offset = self.fits_offset(trial.as_ref());
            let (a, c, _, _) = self
                .identify_ac(phi.as_ref(), order, offset_hint, fit_offset)
                .ok()?;
            self.update_gains(trial.as_mut(), phi.as_ref(), a.as_ref(), c.as_ref())
                .ok()?;
            let mut th = trial.params();
            for &j in &searched {
                th[j] = theta[j];
            }
            trial.set_params(&th).ok()?;
            let mut it = self.evaluate(trial.as_ref(), a.as_ref(), c.as_ref()).ok()?;
            normalise_iterate(self, trial.as_mut(), &mut it);
            if it.mse <= self.floor {
                return Some(it);
            }
        }
        None
    }

    /// One complete iteration from the current θ (steps 1–6). Returns the iterate, the order and
    /// the singular values of the subspace step.
    pub fn step(
        &self,
        nl: &mut dyn StaticNonlinearity<T>,
        order: Option<usize>,
        offset_hint: Option<T>,
    ) -> Result<(Iterate<T>, usize, Vec<f64>)> {
        let phi = nl.regressors(&self.u);
        self.step_from(nl, phi.as_ref(), order, offset_hint)
    }

    /// `step` with the regressors of the current θ already computed.
    pub fn step_from(
        &self,
        nl: &mut dyn StaticNonlinearity<T>,
        phi: MatRef<'_, T>,
        order: Option<usize>,
        offset_hint: Option<T>,
    ) -> Result<(Iterate<T>, usize, Vec<f64>)> {
        let fit_offset = self.fits_offset(nl);
        let (a, c, sv, n) = self.identify_ac(phi, order, offset_hint, fit_offset)?;
        self.update_gains(nl, phi, a.as_ref(), c.as_ref())?;
        let searched = if nl.searched_params().is_empty() {
            None
        } else {
            self.search(nl, a.as_ref(), c.as_ref(), order.is_none())?
        };
        let mut it = match searched {
            Some(it) => it,
            None => self.evaluate(nl, a.as_ref(), c.as_ref())?,
        };
        normalise_iterate(self, nl, &mut it);
        Ok((it, n, sv))
    }
}

/// Fits a Hammerstein model (the body of [`Hammerstein::fit`]): with `Order::Auto` every
/// candidate order is fitted and compared (`order_selection.rs`), otherwise one fit.
pub(crate) fn fit<T: Real>(
    settings: &Hammerstein<T>,
    data: &IoData<T>,
) -> Result<HammersteinModel<T>> {
    settings.validate()?;
    check_siso(data)?;
    if settings.screening.applies(data.len()) {
        return super::screening::fit_screened(settings, data);
    }
    let scaling = Scaling::of(settings, data)?;
    let scaled_data;
    let scaled_settings;
    let (s, d) = if scaling.is_identity() {
        (settings, data)
    } else {
        scaled_data = scaling.data(data)?;
        scaled_settings = scaling.settings(settings)?;
        (&scaled_settings, &scaled_data)
    };
    let model = if matches!(settings.order, crate::subspace::Order::Auto) || settings.d_auto {
        super::order_selection::fit_selecting_order(s, d)?
    } else {
        fit_fixed(s, d)?
    };
    // Hammerstein–Wiener: the output map is fitted on top of the Hammerstein model
    let model = match &s.output_map {
        Some(map) => super::output_fit::fit_output_map(s, d, model, map.as_ref())?,
        None => model,
    };
    let mut model = scaling.unscale(model, settings)?;
    model.report.standard_errors =
        super::uncertainty::standard_errors(&model, data).unwrap_or_default();
    Ok(model)
}

/// One fit with the settings' order rule (fixed, gap or threshold; `Auto` acts as `Gap` here).
pub(crate) fn fit_fixed<T: Real>(
    settings: &Hammerstein<T>,
    data: &IoData<T>,
) -> Result<HammersteinModel<T>> {
    fit_fixed_from(settings, data, None)
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
}

/// `fit_fixed`, or with `start`: θ held from the start, the linear block of the settings'
/// (fixed) order re-identified from (v, y) (`restart_linear`), then the refinement — no loop.
/// Falls back to the loop when the re-identification fails.
pub(crate) fn fit_fixed_from<T: Real>(
    settings: &Hammerstein<T>,
    data: &IoData<T>,
    start: Option<&SharedStart<T>>,
) -> Result<HammersteinModel<T>> {
    settings.validate()?;
    check_siso(data)?;
    let la = settings.linalg_backend()?;
    let method = settings.subspace_at(settings.horizon)?;
    let mut nl = settings.build_nonlinearity()?;
    let r = nl.n_regressors();
    if r == 0 {
        return Err(Error::InvalidParameter(format!(
            "the nonlinearity '{}' has no regressors",
            nl.name()
        )));
    }
    let needed = min_samples_for_horizon(settings.horizon, r, 1).saturating_add(settings.delay);
    if data.len() < needed {
        return Err(Error::TooFewSamples {
            needed,
            got: data.len(),
            reason: format!(
                "horizon {} with {r} regressor(s) of '{}' and delay {}",
                settings.horizon,
                nl.name(),
                settings.delay
            ),
        });
    }
    if settings.delay >= data.len() / 2 {
        return Err(Error::InvalidParameter(format!(
            "input delay {} is not shorter than half the record ({} samples)",
            settings.delay,
            data.len()
        )));
    }
    if let crate::subspace::Order::Fixed(n) = settings.order {
        let max = max_order(settings.horizon, 1);
        if n > max {
            return Err(Error::OrderTooLarge { requested: n, max });
        }
    }
    let problem = Problem::new(la.as_ref(), method.as_ref(), settings, data);
    let shared = match (start, &settings.order) {
        (Some(st), crate::subspace::Order::Fixed(n)) if nl.set_params(&st.theta).is_ok() => problem
            .restart_linear(nl.as_ref(), *n, st.offset)
            .map(|it| {
                let mut rep = st.report.clone();
                rep.order = *n;
                rep.train_mse = it.mse;
                rep.refinement = None;
                rep.order_selection = Vec::new();
                (it, rep)
            }),
        _ => None,
    };
    let looped = shared.is_none();
    let (best, report) = match shared {
        Some(x) => x,
        None => {
            initialize(&problem, nl.as_mut())?;
            run_loop(&problem, nl.as_mut())?
        }
    };
    nl.set_params(&best.theta)?;
    let mut it = best;
    normalise_iterate(&problem, nl.as_mut(), &mut it);
    let mut report = report;
    let mut linear = to_statespace(&it)?;
    linear.ts = data.sample_time();
    let mut x0 = it.x0.clone();
    let mut offset = it.offset;
    if settings.refine {
        // two starts: the loop's iterate and the same θ with the linear block re-identified;
        // the refinement from each, the lowest training MSE kept
        let mut candidates: Vec<Iterate<T>> = Vec::new();
        let (from_loop, mut rep) = refine::refine(&problem, nl.as_ref(), &it)?;
        candidates.extend(from_loop);
        // (a shared start's iterate is already the re-identified block)
        let restart = if looped {
            problem.restart_linear(nl.as_ref(), it.a.nrows(), it.offset)
        } else {
            None
        };
        if let Some(restart) = restart {
            let (from_restart, rep2) = refine::refine(&problem, nl.as_ref(), &restart)?;
            rep.iterations += rep2.iterations;
            candidates.extend(from_restart);
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
        if let Some(mut rf) = refined {
            nl.set_params(&rf.theta)?;
            normalise_iterate(&problem, nl.as_mut(), &mut rf);
            linear = to_statespace(&rf)?;
            linear.ts = data.sample_time();
            x0 = rf.x0.clone();
            offset = rf.offset;
            report.train_mse = rf.mse;
        }
        report.refinement = Some(rep);
    }
    if let Some(obs) = &settings.observer {
        obs.observe_final(&report);
    }
    Ok(HammersteinModel {
        nl,
        linear,
        offset,
        x0,
        settings: settings.clone(),
        report,
        output_map: None,
    })
}

/// Largest pole radius an intermediate linear block of the loop may have.
pub(crate) const MAX_POLE_RADIUS: f64 = 0.9995;

/// A with its poles pulled inside the circle of radius `MAX_POLE_RADIUS` (a uniform shrink,
/// A·r/ρ(A)) when the subspace step returned an unstable block: its free response over the
/// record would overflow the B/D/x0 least squares and the simulation (a subspace estimate of a
/// stable plant is unstable only when it is poor, e.g. an order far above the plant's on noise;
/// the iterations and the refinement then move from there). Unchanged when stable or when its
/// eigenvalues cannot be computed.
pub(crate) fn stabilised<T: Real>(a: Mat<T>) -> Mat<T> {
    let n = a.nrows();
    let Ok(rho) = crate::statespace::spectral_radius_of(a.as_ref()) else {
        return a;
    };
    if !(rho.is_finite() && rho > MAX_POLE_RADIUS) {
        return a;
    }
    let s = T::lit(MAX_POLE_RADIUS / rho);
    Mat::from_fn(n, n, |i, j| a[(i, j)] * s)
}

/// MSE at or below which a fit of an output with variance `var` counts as exact: 10·ε^1.5·var
/// (relative RMS error ≈ 2e-12 in f64, 1e-5 in f32), the level the loop's round-off reaches.
pub(crate) fn exact_floor<T: Real>(var: f64) -> f64 {
    let eps = T::epsilon().as_f64();
    var.max(f64::MIN_POSITIVE) * 10.0 * eps * eps.sqrt()
}

/// Variance of a signal (population), in f64.
pub(crate) fn variance<T: Real>(y: &[T]) -> f64 {
    let nn = y.len().max(1) as f64;
    let mean = y.iter().map(|v| v.as_f64()).sum::<f64>() / nn;
    y.iter().map(|v| (v.as_f64() - mean).powi(2)).sum::<f64>() / nn
}

/// The iterations; returns the best iterate and the report (without refinement).
pub(crate) fn run_loop<T: Real>(
    problem: &Problem<'_, T>,
    nl: &mut dyn StaticNonlinearity<T>,
) -> Result<(Iterate<T>, FitReport)> {
    let settings = problem.settings;
    let lambda = settings.tolerance;
    let mut records: Vec<IterationRecord> = Vec::new();
    let mut best: Option<(Iterate<T>, usize)> = None;
    let mut order: Option<usize> = None;
    let mut singular_values = Vec::new();
    let mut prev_mse: Option<f64> = None;
    let mut since_best = 0usize;
    let mut offset_hint: Option<T> = None;
    let mut phi_static = false;
    // regressors of the current θ, computed at the end of the previous iteration
    let mut phi_next: Option<Mat<T>> = None;
    let mut termination = Termination::MaxIterations;
    for s in 0..settings.max_iter {
        let theta_before = nl.params();
        let phi_before = match phi_next.take() {
            Some(phi) => phi,
            None => nl.regressors(&problem.u),
        };
        let step = problem.step_from(nl, phi_before.as_ref(), order, offset_hint);
        let (mut it, n, sv) = match step {
            Ok(x) => x,
            Err(e) => {
                if best.is_none() {
                    return Err(e);
                }
                // a failed step after a usable iterate: stop and keep the best
                termination = Termination::Diverged;
                break;
            }
        };
        if order.is_none() {
            order = Some(n);
            singular_values = sv;
        }
        // damping: when the MSE rose, halve the θ step towards the previous θ
        let mut damped = false;
        if let Some(pm) = prev_mse
            && it.mse > pm
        {
            let theta_new = it.theta.clone();
            let mut frac = T::lit(0.5);
            for _ in 0..DAMPING_STEPS {
                let theta_h: Vec<T> = theta_before
                    .iter()
                    .zip(&theta_new)
                    .map(|(&p, &q)| p + (q - p) * frac)
                    .collect();
                let mut trial = nl.clone_box();
                if trial.set_params(&theta_h).is_ok()
                    && let Ok(t) = problem.evaluate(trial.as_ref(), it.a.as_ref(), it.c.as_ref())
                    && t.mse < pm
                {
                    nl.set_params(&theta_h)?;
                    it = t;
                    normalise_iterate(problem, nl, &mut it);
                    damped = true;
                    break;
                }
                frac *= T::lit(0.5);
            }
        }
        let record = IterationRecord {
            mse: it.mse,
            params: it.theta.iter().map(|t| t.as_f64()).collect(),
            damped,
        };
        if let Some(obs) = &settings.observer {
            obs.observe_iteration(s, &record);
        }
        records.push(record);
        let cur = it.mse;
        let improved = match &best {
            None => true,
            Some((b, _)) => cur < b.mse,
        };
        let significant = match &best {
            None => true,
            Some((b, _)) => cur < b.mse * (1.0 - lambda.max(1e-9)),
        };
        let phi_new = nl.regressors(&problem.u);
        let same_phi = phi_new == phi_before;
        phi_next = Some(phi_new);
        // the next step would repeat this one when φ and the offset it subtracts are unchanged
        let offset_settled = !problem.fits_offset(nl)
            || offset_hint.is_some_and(|c| (it.offset - c).abs().as_f64() <= problem.offset_tol);
        let fixed_point = same_phi && offset_settled;
        if s == 0 && same_phi {
            phi_static = true;
        }
        let new_offset = it.offset;
        if improved {
            best = Some((it, s));
        }
        if significant {
            since_best = 0;
        } else {
            since_best += 1;
        }
        // stopping rules
        if cur <= problem.floor {
            // among exact fits prefer the searched parameters at their lower end (b = 0, no
            // dead-zone): on a finite record a small b can fit exactly too (no sample inside the
            // band), and the fixed point the loop reached need not be the simpler one
            if let Some(alt) = problem.exact_at_lower_end(nl, order, offset_hint)
                && let Some((b, s_best)) = best.as_mut()
            {
                nl.set_params(&alt.theta)?;
                *b = alt;
                *s_best = s;
            }
            termination = Termination::Converged;
            break;
        }
        if phi_static && (s == 1 || !problem.fits_offset(nl)) {
            // regressors independent of θ: one pass (plus the offset pass) is the answer
            termination = Termination::SinglePass;
            break;
        }
        if fixed_point {
            termination = Termination::Converged;
            break;
        }
        if let Some(pm) = prev_mse
            && (cur - pm).abs() <= lambda * pm
        {
            // settled, but settled above the best iterate: a loop that never improved on its
            // first iterate has diverged from it, one that did is oscillating around its best
            let (best_mse, best_at) = best.as_ref().map_or((f64::INFINITY, 0), |b| (b.0.mse, b.1));
            termination = if cur <= best_mse * (1.0 + 10.0 * lambda.max(1e-9)) {
                Termination::Converged
            } else if best_at == 0 {
                Termination::Diverged
            } else {
                Termination::Oscillating
            };
            break;
        }
        if since_best >= PATIENCE {
            let best_mse = best.as_ref().map_or(f64::INFINITY, |b| b.0.mse);
            termination = if cur <= best_mse * (1.0 + DIVERGED_BAND) {
                Termination::Oscillating
            } else {
                Termination::Diverged
            };
            break;
        }
        prev_mse = Some(cur);
        if problem.fits_offset(nl) {
            offset_hint = Some(new_offset);
        }
    }
    let (best, best_iteration) =
        best.ok_or_else(|| Error::Identification("the loop produced no iterate".into()))?;
    let report = FitReport {
        iterations: records,
        best_iteration,
        termination,
        converged: matches!(
            termination,
            Termination::Converged | Termination::SinglePass
        ),
        order: best.a.nrows(),
        singular_values,
        train_mse: best.mse,
        refinement: None,
        order_selection: Vec::new(),
        standard_errors: Vec::new(),
    };
    Ok((best, report))
}

/// Rescales an iterate so that its own linear block satisfies the normalisation exactly (its B was
/// re-estimated after θ was normalised from the rank-one factor, so it is close but not exact
/// under noise); θ absorbs the factor. Skipped when the nonlinearity cannot absorb it (its output
/// would not scale exactly).
pub(crate) fn normalise_iterate<T: Real>(
    problem: &Problem<'_, T>,
    nl: &mut dyn StaticNonlinearity<T>,
    it: &mut Iterate<T>,
) {
    let markov = markov_of(it.a.as_ref(), &it.b, it.c.as_ref(), it.d, problem.k_rows);
    let g = nl.gains();
    let Ok(s) = scale_for(problem.settings.normalization, &g, &markov) else {
        return;
    };
    if s == T::one() {
        return;
    }
    let v_old = nl.eval(&problem.u);
    // +s first; −s when the nonlinearity refuses the sign (see `update_gains`)
    let mut accepted = None;
    for s in [s, -s] {
        let mut trial = nl.clone_box();
        let gs: Vec<T> = g.iter().map(|&x| x * s).collect();
        if trial.update_from_gains(&gs, &problem.u).is_err() {
            continue;
        }
        let v_new = trial.eval(&problem.u);
        let scale = v_old.iter().fold(T::zero(), |m, v| m.max((*v * s).abs()));
        let tol = scale * T::epsilon().sqrt();
        if v_old
            .iter()
            .zip(&v_new)
            .all(|(&a, &b)| (a * s - b).abs() <= tol)
        {
            accepted = Some((s, trial.params()));
            break;
        }
    }
    let Some((s, theta)) = accepted else {
        return;
    };
    if nl.set_params(&theta).is_err() {
        return;
    }
    for bi in it.b.iter_mut() {
        *bi /= s;
    }
    it.d /= s;
    it.theta = theta;
}

/// The iterate's linear block as a state-space model.
pub(crate) fn to_statespace<T: Real>(it: &Iterate<T>) -> Result<StateSpace<T>> {
    let n = it.a.nrows();
    StateSpace::new(
        it.a.clone(),
        Mat::from_fn(n, 1, |i, _| it.b[i]),
        it.c.clone(),
        Mat::from_fn(1, 1, |_, _| it.d),
    )
}
