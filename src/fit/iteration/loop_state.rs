//! The iterative subspace loop (paper Section 3.3, corrected as in NOTES.md) as a state and one
//! step: [`LoopState`] carries what passes from one iteration to the next, [`step`] runs one
//! iteration and says whether and why the loop ends ([`Termination`]), [`run_loop`] steps until
//! it does.
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
//!    diverged (far above it); the iteration limit → max-iterations. The best iterate is always
//!    the one returned.
//!
//! Steps 1–6 are `Problem::pass` (`search.rs`, `problem.rs`); this file is step 7 and the
//! bookkeeping between iterations.

use super::initial_direction::try_other_direction;
use super::problem::{Iterate, Problem, Workspace, normalise_iterate};
use super::search::SearchWidths;
use crate::error::{Error, Result};
use crate::fit::fit_report::{FitReport, IterationRecord, Termination};
use crate::real::Real;
use crate::regressors::StaticNonlinearity;
use faer::Mat;

/// Iterations without a new best MSE after which the loop stops (oscillating or diverged).
pub(crate) const PATIENCE: usize = 5;
/// An MSE above best·(1 + DIVERGED_BAND) after `PATIENCE` fruitless iterations counts as diverged.
pub(crate) const DIVERGED_BAND: f64 = 0.5;
/// Halvings of a θ step that raised the MSE.
pub(crate) const DAMPING_STEPS: usize = 3;
/// Least relative MSE change at which a loop the refinement follows counts as settled: its
/// iterate is only the refinement's start, and the last loop iterations' gains below 0.1 % are
/// what the refinement makes anyway (measured: `docs/performance.md`).
pub(crate) const REFINED_SETTLE_TOLERANCE: f64 = 1e-3;

/// The settled-MSE tolerance of the loop: the settings' λ, at least
/// `REFINED_SETTLE_TOLERANCE` when the refinement follows.
fn settle_tolerance(options: &crate::fit::settings::FitOptions) -> f64 {
    if options.refine {
        options.tolerance.max(REFINED_SETTLE_TOLERANCE)
    } else {
        options.tolerance
    }
}

/// What the loop carries from one iteration to the next (the current θ lives in the
/// nonlinearity the steps update).
#[derive(Debug, Clone)]
pub(crate) struct LoopState<T: Real> {
    /// Index of the next iteration (0-based); the iterations run so far.
    pub iteration: usize,
    /// The best iterate so far and the iteration that produced it.
    pub best: Option<(Iterate<T>, usize)>,
    /// MSE of the last iterate.
    pub last_mse: Option<f64>,
    /// Model order, chosen at the first iteration and kept afterwards.
    pub order: Option<usize>,
    /// Singular values of the first subspace step.
    pub singular_values: Vec<f64>,
    /// Iterations since the last significant improvement of the best MSE.
    pub since_best: usize,
    /// Offset the next subspace step removes from y (the last iterate's; `None` at first).
    pub offset_hint: Option<T>,
    /// True when the first iteration left the regressors unchanged (they do not depend on θ).
    pub phi_static: bool,
    /// Regressors of the current θ, computed at the end of the last iteration.
    pub phi_next: Option<Mat<T>>,
    /// Half-widths of the local search brackets.
    pub widths: SearchWidths,
    /// Every iterate's record, in order.
    pub records: Vec<IterationRecord>,
    /// The nonlinearity's initial direction (falling) at the best iterate.
    pub best_falling: bool,
}

impl<T: Real> LoopState<T> {
    /// A state before the first iteration, with the search brackets `widths` (those the
    /// initialisation's trial passes left).
    pub fn new(widths: SearchWidths) -> Self {
        Self {
            iteration: 0,
            best: None,
            last_mse: None,
            order: None,
            singular_values: Vec::new(),
            since_best: 0,
            offset_hint: None,
            phi_static: false,
            phi_next: None,
            widths,
            records: Vec::new(),
            best_falling: false,
        }
    }

    /// The best iterate and the report of a loop that ended with `termination` (without
    /// refinement); an error when no iteration produced an iterate.
    pub fn finish(self, termination: Termination) -> Result<(Iterate<T>, FitReport)> {
        let (best, best_iteration) = self
            .best
            .ok_or_else(|| Error::Identification("the loop produced no iterate".into()))?;
        let report = FitReport {
            iterations: self.records,
            best_iteration,
            termination,
            converged: matches!(
                termination,
                Termination::Converged | Termination::SinglePass
            ),
            order: best.a.nrows(),
            singular_values: self.singular_values,
            train_mse: best.mse,
            refinement: None,
            order_selection: Vec::new(),
            standard_errors: Vec::new(),
            covariance: None,
            horizon_raised_from: None,
            screening_window: None,
            stabilised: None,
            departs_from_rest: None,
        };
        Ok((best, report))
    }
}

/// Steps from `state` until the loop terminates; returns the best iterate and the report
/// (without refinement), `nl` left at the best iterate's initial direction.
pub(crate) fn run_loop<T: Real>(
    problem: &Problem<'_, T>,
    nl: &mut dyn StaticNonlinearity<T>,
    mut state: LoopState<T>,
    ws: &mut Workspace<T>,
) -> Result<(Iterate<T>, FitReport)> {
    let termination = loop {
        if state.iteration >= problem.settings.options.max_iter {
            break Termination::MaxIterations;
        }
        if let Some(t) = step(problem, nl, &mut state, ws)? {
            break t;
        }
    };
    // the best iterate's initial direction (the last iteration's may differ)
    nl.set_initial_falling(state.best_falling);
    state.finish(termination)
}

/// One iteration of the loop from the θ of `nl`: steps 1–6, damping when the MSE rose, the
/// record, then the stopping rules. `Some` names why the loop ends (the iteration limit
/// included); `None`: go on. An error only when the very first iteration fails (a later failure
/// ends the loop as diverged, keeping the best iterate).
pub(crate) fn step<T: Real>(
    problem: &Problem<'_, T>,
    nl: &mut dyn StaticNonlinearity<T>,
    state: &mut LoopState<T>,
    ws: &mut Workspace<T>,
) -> Result<Option<Termination>> {
    let s = state.iteration;
    let theta_before = nl.params();
    let phi_before = match state.phi_next.take() {
        Some(phi) => phi,
        None => nl.regressors(&problem.u),
    };
    let pass = problem.pass_from(
        ws,
        &mut state.widths,
        nl,
        phi_before.as_ref(),
        state.order,
        state.offset_hint,
    );
    let (mut it, n, sv) = match pass {
        Ok(x) => x,
        // a failed step after a usable iterate: stop and keep the best
        Err(_) if state.best.is_some() => return Ok(Some(Termination::Diverged)),
        Err(e) => return Err(e),
    };
    if state.order.is_none() {
        state.order = Some(n);
        state.singular_values = sv;
    }
    // the initial direction that fits this θ and block better (a nuisance parameter, like x0)
    try_other_direction(problem, ws, nl, &mut it);
    let damped = match state.last_mse {
        Some(pm) if it.mse > pm => damp(problem, ws, nl, &mut it, &theta_before, pm)?,
        _ => false,
    };
    let record = IterationRecord {
        mse: it.mse,
        params: it.theta.iter().map(|t| t.as_f64()).collect(),
        damped,
    };
    if let Some(obs) = problem.observer {
        obs.observe_iteration(s, &record);
    }
    state.records.push(record);
    let phi_new = nl.regressors(&problem.u);
    let same_phi = phi_new == phi_before;
    state.phi_next = Some(phi_new);
    // the next step would repeat this one when φ and the offset it subtracts are unchanged
    let offset_settled = !problem.fits_offset(nl)
        || state
            .offset_hint
            .is_some_and(|c| (it.offset - c).abs().as_f64() <= problem.offset_tol);
    if s == 0 && same_phi {
        state.phi_static = true;
    }
    let (cur, new_offset) = (it.mse, problem.next_offset_hint(nl, &it));
    state.accept(it, nl.initial_falling(), problem.settings.options.tolerance);
    if let Some(t) = stopping(problem, nl, state, ws, cur, same_phi && offset_settled)? {
        return Ok(Some(t));
    }
    state.last_mse = Some(cur);
    if new_offset.is_some() {
        state.offset_hint = new_offset;
    }
    state.iteration += 1;
    Ok(
        (state.iteration >= problem.settings.options.max_iter)
            .then_some(Termination::MaxIterations),
    )
}

impl<T: Real> LoopState<T> {
    /// Takes iterate `it` of the current iteration (the nonlinearity's initial direction
    /// `falling`): the new best when its MSE is lower, and the patience counter reset when it is
    /// lower by more than the tolerance `lambda`.
    fn accept(&mut self, it: Iterate<T>, falling: bool, lambda: f64) {
        let cur = it.mse;
        let (improved, significant) = match &self.best {
            None => (true, true),
            Some((b, _)) => (cur < b.mse, cur < b.mse * (1.0 - lambda.max(1e-9))),
        };
        if improved {
            self.best = Some((it, self.iteration));
            self.best_falling = falling;
        }
        if significant {
            self.since_best = 0;
        } else {
            self.since_best += 1;
        }
    }
}

/// Damping of a step that raised the MSE above `prev`: θ moved back half-way towards
/// `theta_before` (up to `DAMPING_STEPS` halvings) until the MSE falls below `prev`, the block
/// (A, C) kept. True (and `nl`, `it` updated) when one did.
fn damp<T: Real>(
    problem: &Problem<'_, T>,
    ws: &mut Workspace<T>,
    nl: &mut dyn StaticNonlinearity<T>,
    it: &mut Iterate<T>,
    theta_before: &[T],
    prev: f64,
) -> Result<bool> {
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
            && let Ok(t) = problem.evaluate(ws, trial.as_ref(), it.a.as_ref(), it.c.as_ref())
            && t.mse < prev
        {
            nl.set_params(&theta_h)?;
            *it = t;
            normalise_iterate(problem, nl, it);
            return Ok(true);
        }
        frac *= T::lit(0.5);
    }
    Ok(false)
}

/// The stopping rules after an iteration whose MSE is `cur` (`fixed_point`: φ and the offset
/// unchanged, so the next iteration would repeat this one), in order: an exact fit (preferring
/// the searched parameters at their lower ends), regressors independent of θ, a fixed point,
/// a settled MSE, no improvement for `PATIENCE` iterations.
fn stopping<T: Real>(
    problem: &Problem<'_, T>,
    nl: &mut dyn StaticNonlinearity<T>,
    state: &mut LoopState<T>,
    ws: &mut Workspace<T>,
    cur: f64,
    fixed_point: bool,
) -> Result<Option<Termination>> {
    let s = state.iteration;
    let lambda = settle_tolerance(&problem.settings.options);
    if cur <= problem.floor {
        // among exact fits prefer the searched parameters at their lower end (b = 0, no
        // dead-zone): on a finite record a small b can fit exactly too (no sample inside the
        // band), and the fixed point the loop reached need not be the simpler one
        if let Some(alt) = problem.exact_at_lower_end(ws, nl, state.order, state.offset_hint)
            && let Some((b, s_best)) = state.best.as_mut()
        {
            nl.set_params(&alt.theta)?;
            *b = alt;
            *s_best = s;
            state.best_falling = nl.initial_falling();
        }
        return Ok(Some(Termination::Converged));
    }
    if state.phi_static && (s == 1 || !problem.fits_offset(nl)) {
        // regressors independent of θ: one pass (plus the offset pass) is the answer
        return Ok(Some(Termination::SinglePass));
    }
    if fixed_point {
        return Ok(Some(Termination::Converged));
    }
    let (best_mse, best_at) = state
        .best
        .as_ref()
        .map_or((f64::INFINITY, 0), |b| (b.0.mse, b.1));
    if let Some(pm) = state.last_mse
        && (cur - pm).abs() <= lambda * pm
    {
        // settled, but settled above the best iterate: a loop that never improved on its
        // first iterate has diverged from it, one that did is oscillating around its best
        return Ok(Some(if cur <= best_mse * (1.0 + 10.0 * lambda.max(1e-9)) {
            Termination::Converged
        } else if best_at == 0 {
            Termination::Diverged
        } else {
            Termination::Oscillating
        }));
    }
    if state.since_best >= PATIENCE {
        return Ok(Some(if cur <= best_mse * (1.0 + DIVERGED_BAND) {
            Termination::Oscillating
        } else {
            Termination::Diverged
        }));
    }
    Ok(None)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::data::IoData;
    use crate::fit::Hammerstein;
    use crate::regressors::Udn;
    use crate::statespace::StateSpace;
    use crate::subspace::Order;

    /// The paper's Example 1 truth θ = (p, a, z1, z2) of saturation with hysteresis.
    const TRUTH: [f64; 4] = [2.0, 0.5, 1.5, -1.0];

    /// 600 samples of Example 1 (u uniform in [−3, 3) from a small LCG), plus `noise` times a
    /// deterministic pseudo-random sequence in [−1, 1).
    fn example1(noise: f64) -> IoData<f64> {
        let mut state = 7u64;
        let mut uniform = || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (state >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
        };
        let u: Vec<f64> = (0..600).map(|_| 3.0 * uniform()).collect();
        let effects = Hammerstein::<f64>::sh().effects().unwrap();
        let truth = Udn::with_params(effects, &TRUTH).unwrap();
        let g = StateSpace::from_rows(
            &[&[0.2, 1.0], &[-0.35, 0.0]],
            &[&[1.0], &[0.5]],
            &[&[1.0, 0.0]],
            &[&[0.0]],
        )
        .unwrap();
        let y: Vec<f64> = g
            .simulate_siso(&truth.eval(&u), None)
            .unwrap()
            .into_iter()
            .map(|v| v + noise * uniform())
            .collect();
        IoData::siso(&u, &y).unwrap()
    }

    fn settings() -> Hammerstein<f64> {
        Hammerstein::sh().order(Order::Fixed(2)).with_d(false)
    }

    /// Runs `f` with the problem of fitting `data` with `settings`, a nonlinearity at `theta`
    /// (the quantile start when `None`) and a fresh workspace.
    fn with_problem<R>(
        settings: &Hammerstein<f64>,
        data: &IoData<f64>,
        theta: Option<&[f64]>,
        f: impl FnOnce(&Problem<'_, f64>, &mut dyn StaticNonlinearity<f64>, &mut Workspace<f64>) -> R,
    ) -> R {
        let la = settings.linalg_backend().unwrap();
        let method = settings.subspace_at(settings.options.horizon).unwrap();
        let problem = Problem::new(la.as_ref(), method.as_ref(), settings, data);
        let mut nl = settings.build_nonlinearity().unwrap();
        match theta {
            Some(t) => nl.set_params(t).unwrap(),
            None => nl.initialize(&problem.u),
        }
        f(&problem, nl.as_mut(), &mut Workspace::default())
    }

    /// A stand-in best iterate with MSE `mse` (only its MSE matters to the stopping rules).
    fn iterate(mse: f64) -> Iterate<f64> {
        Iterate {
            theta: TRUTH.to_vec(),
            a: Mat::zeros(2, 2),
            b: vec![0.0; 2],
            c: Mat::zeros(1, 2),
            d: 0.0,
            x0: vec![0.0; 2],
            offset: 0.0,
            mse,
        }
    }

    #[test]
    fn one_step_from_the_truth_stays_there_and_converges() {
        let data = example1(0.0);
        let s = settings();
        with_problem(&s, &data, Some(&TRUTH), |problem, nl, ws| {
            let mut state = LoopState::new(SearchWidths::default());
            let t = step(problem, nl, &mut state, ws).unwrap();
            assert_eq!(t, Some(Termination::Converged));
            let (best, at) = state.best.as_ref().unwrap();
            assert_eq!(*at, 0);
            assert!(best.mse <= problem.floor, "mse {}", best.mse);
            for (p, q) in best.theta.iter().zip(TRUTH) {
                assert!((p - q).abs() < 1e-6, "{:?}", best.theta);
            }
            assert_eq!(state.records.len(), 1);
            assert_eq!(state.order, Some(2));
            let (_, report) = state.finish(Termination::Converged).unwrap();
            assert!(report.converged && report.order == 2);
        });
    }

    #[test]
    fn the_iteration_limit_terminates_as_max_iterations() {
        let data = example1(0.3);
        let s = settings().max_iter(1);
        with_problem(&s, &data, None, |problem, nl, ws| {
            let mut state = LoopState::new(SearchWidths::default());
            let t = step(problem, nl, &mut state, ws).unwrap();
            assert_eq!(t, Some(Termination::MaxIterations));
            assert_eq!(state.iteration, 1);
            assert_eq!(state.records.len(), 1);
            let (_, report) = state.finish(t.unwrap()).unwrap();
            assert_eq!(report.termination.name(), "max-iterations");
            assert!(!report.converged);
        });
        // the same start with room to go on does not stop after one iteration
        let s = settings();
        with_problem(&s, &data, None, |problem, nl, ws| {
            let mut state = LoopState::new(SearchWidths::default());
            assert_eq!(step(problem, nl, &mut state, ws).unwrap(), None);
            assert_eq!(state.iteration, 1);
            assert!(state.last_mse.is_some() && state.offset_hint.is_some());
        });
    }

    #[test]
    fn a_step_whose_mse_rose_past_the_patience_terminates_as_diverged() {
        let data = example1(0.3);
        let s = settings();
        let theta = [1.0, 0.2, 2.5, -2.5];
        with_problem(&s, &data, Some(&theta), |problem, nl, ws| {
            let mut state = LoopState::new(SearchWidths::default());
            // an earlier best far below what this start can reach, no improvement since
            state.iteration = 3;
            state.order = Some(2);
            state.best = Some((iterate(1e-9), 1));
            state.since_best = PATIENCE - 1;
            state.last_mse = Some(1e-9);
            let t = step(problem, nl, &mut state, ws).unwrap();
            assert_eq!(t, Some(Termination::Diverged));
            // the best iterate is kept
            assert_eq!(state.best.as_ref().unwrap().1, 1);
            assert_eq!(state.best.as_ref().unwrap().0.mse, 1e-9);
            assert!(state.records[0].mse > 1e-9 * (1.0 + DIVERGED_BAND));
        });
    }

    #[test]
    fn a_loop_the_refinement_follows_settles_at_the_looser_tolerance() {
        let tight = settings().tolerance(1e-5);
        assert_eq!(
            settle_tolerance(&tight.clone().refine(true).options),
            REFINED_SETTLE_TOLERANCE
        );
        assert_eq!(settle_tolerance(&tight.refine(false).options), 1e-5);
        let loose = settings().tolerance(1e-2).refine(true);
        assert_eq!(settle_tolerance(&loose.options), 1e-2);
    }

    #[test]
    fn the_stopping_rules_name_their_termination() {
        let data = example1(0.3);
        let s = settings();
        with_problem(&s, &data, None, |problem, nl, ws| {
            let lambda = settle_tolerance(&problem.settings.options);
            let mut stop = |best_at: usize, since: usize, last: Option<f64>, cur: f64, fixed| {
                let mut state = LoopState::new(SearchWidths::default());
                state.iteration = 6;
                state.best = Some((iterate(1.0), best_at));
                state.since_best = since;
                state.last_mse = last;
                stopping(problem, nl, &mut state, ws, cur, fixed).unwrap()
            };
            // going on: no rule applies
            assert_eq!(stop(2, 0, Some(3.0), 2.0, false), None);
            // a fixed point of φ and the offset
            assert_eq!(
                stop(2, 0, Some(3.0), 2.0, true),
                Some(Termination::Converged)
            );
            // settled at the best MSE
            assert_eq!(
                stop(2, 0, Some(1.0), 1.0, false),
                Some(Termination::Converged)
            );
            // settled above the best: oscillating after an improvement, diverged without one
            let above = 1.0 + 20.0 * lambda;
            assert_eq!(
                stop(2, 1, Some(above), above, false),
                Some(Termination::Oscillating)
            );
            assert_eq!(
                stop(0, 1, Some(above), above, false),
                Some(Termination::Diverged)
            );
            // patience exhausted near the best, and far above it
            assert_eq!(
                stop(2, PATIENCE, Some(3.0), 1.2, false),
                Some(Termination::Oscillating)
            );
            assert_eq!(
                stop(2, PATIENCE, Some(3.0), 2.0, false),
                Some(Termination::Diverged)
            );
            // an exact fit
            assert_eq!(
                stop(2, 0, Some(3.0), problem.floor, false),
                Some(Termination::Converged)
            );
        });
    }

    #[test]
    fn an_observer_attached_at_fit_time_sees_every_iteration() {
        use crate::fit::{FitReport, IterationRecord, Observer};
        use std::sync::atomic::{AtomicUsize, Ordering};
        #[derive(Default)]
        struct Count(AtomicUsize, AtomicUsize);
        impl Observer for Count {
            fn observe_iteration(&self, _: usize, _: &IterationRecord) {
                self.0.fetch_add(1, Ordering::Relaxed);
            }
            fn observe_final(&self, _: &FitReport) {
                self.1.fetch_add(1, Ordering::Relaxed);
            }
        }
        let data = example1(0.3);
        let count = Count::default();
        let model = settings().fit_observed(&data, &count).unwrap();
        let iterations = model.report().iterations.len();
        assert!(iterations > 1);
        assert_eq!(count.0.load(Ordering::Relaxed), iterations);
        assert_eq!(count.1.load(Ordering::Relaxed), 1);
    }
}
