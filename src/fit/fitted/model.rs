//! The fitted Hammerstein model: nonlinearity, normalised linear block, optional static output map
//! (Hammerstein–Wiener), output offset, the settings it was fitted with and the fit's report. Simulates, reports parameters, saves and loads.

use crate::data::IoData;
use crate::error::{Error, Result};
use crate::fit::fit_report::FitReport;
use crate::fit::fitted::initial_map::{MapProblem, Regressors};
use crate::fit::numerics::linear_ls::{
    delayed, fit_x0, free_response_length, mse, observability_columns, simulate_in_place,
    simulate_into,
};
use crate::fit::settings::Hammerstein;
use crate::real::Real;
use crate::regressors::{OutputMap, StaticNonlinearity};
use crate::solvers::columns::row_major;
use crate::statespace::{StateSpace, TransferFunction};
use faer::Mat;

/// A simulation on a measured record.
#[derive(Debug, Clone)]
pub struct Simulation<T: Real> {
    /// Simulated output (offset included).
    pub y_hat: Vec<T>,
    /// Initial state estimated by least squares on the record.
    pub x0: Vec<T>,
    /// Intermediate signal v = N(u) (after the input delay).
    pub v: Vec<T>,
}

/// The first sample at which a simulated output diverges, with its value: non-finite, or beyond
/// √(largest value of `T`) in magnitude (≈1.3e154 in f64, 1.8e19 in f32), past which its square
/// (every error metric) overflows. `None` when the whole output is usable.
pub fn divergence<T: Real>(y: &[T]) -> Option<(usize, f64)> {
    let limit = T::max_value().sqrt();
    y.iter()
        .position(|v| !v.is_finite() || v.abs() > limit)
        .map(|k| (k, y[k].as_f64()))
}

/// A fitted Hammerstein model y = G(N(u(k − nk))) + c, or with an output map
/// y = g(G(N(u(k − nk)))) + c (Hammerstein–Wiener).
#[derive(Debug, Clone)]
pub struct HammersteinModel<T: Real> {
    pub(crate) nl: Box<dyn StaticNonlinearity<T>>,
    pub(crate) linear: StateSpace<T>,
    pub(crate) offset: T,
    pub(crate) x0: Vec<T>,
    pub(crate) settings: Hammerstein<T>,
    pub(crate) report: FitReport,
    pub(crate) output_map: Option<Box<dyn OutputMap<T>>>,
}

impl<T: Real> HammersteinModel<T> {
    /// Assembles a model from its parts (used by loading and by callers that build models by hand).
    pub fn from_parts(
        nl: Box<dyn StaticNonlinearity<T>>,
        linear: StateSpace<T>,
        offset: T,
        settings: Hammerstein<T>,
        report: FitReport,
    ) -> Result<Self> {
        if linear.n_inputs() != 1 || linear.n_outputs() != 1 {
            return Err(Error::Dimension(format!(
                "a Hammerstein model needs a single-input single-output linear block, got {}×{}",
                linear.n_outputs(),
                linear.n_inputs()
            )));
        }
        for (what, m) in [
            ("A", &linear.a),
            ("B", &linear.b),
            ("C", &linear.c),
            ("D", &linear.d),
        ] {
            let cols = m.ncols();
            if let Some(k) = (0..m.nrows() * cols).find(|&k| !m[(k / cols, k % cols)].is_finite()) {
                return Err(Error::NonFinite {
                    what: format!("the linear block's {what} matrix (row-major entry)"),
                    index: k,
                });
            }
        }
        if !offset.is_finite() {
            return Err(Error::NonFinite {
                what: "the output offset".into(),
                index: 0,
            });
        }
        if let Some(k) = nl.params().iter().position(|p| !p.is_finite()) {
            return Err(Error::NonFinite {
                what: format!("the parameters of the nonlinearity '{}'", nl.name()),
                index: k,
            });
        }
        let n = linear.order();
        Ok(Self {
            nl,
            linear,
            offset,
            x0: vec![T::zero(); n],
            settings,
            report,
            output_map: None,
        })
    }

    /// The model with a static output map y = g(x) + c after the linear block (`None` removes
    /// it); errors on non-finite map parameters.
    pub fn with_output_map(mut self, map: Option<Box<dyn OutputMap<T>>>) -> Result<Self> {
        if let Some(g) = &map
            && let Some(k) = g.params().iter().position(|p| !p.is_finite())
        {
            return Err(Error::NonFinite {
                what: format!("the parameters of the output map '{}'", g.name()),
                index: k,
            });
        }
        self.output_map = map;
        Ok(self)
    }

    /// The static output map after the linear block (`None`: a plain Hammerstein model).
    pub fn output_map(&self) -> Option<&dyn OutputMap<T>> {
        self.output_map.as_deref()
    }

    /// Output-map parameters by name with their standard errors on the training record (empty
    /// without a map; errors `None` when not computed).
    pub fn output_map_parameters_with_errors(&self) -> Vec<(String, f64, Option<f64>)> {
        let Some(g) = &self.output_map else {
            return Vec::new();
        };
        let n_theta = self.nl.params().len();
        let se = &self.report.standard_errors;
        g.param_names()
            .into_iter()
            .zip(g.params())
            .enumerate()
            .map(|(j, (name, v))| (name, v.as_f64(), se.get(n_theta + j).copied()))
            .collect()
    }

    /// The static nonlinearity.
    pub fn nonlinearity(&self) -> &dyn StaticNonlinearity<T> {
        self.nl.as_ref()
    }
    /// The linear block, normalised as the settings ask.
    pub fn linear(&self) -> &StateSpace<T> {
        &self.linear
    }
    /// The settings the model was fitted with.
    pub fn settings(&self) -> &Hammerstein<T> {
        &self.settings
    }
    /// The fit's report.
    pub fn report(&self) -> &FitReport {
        &self.report
    }
    /// Nonlinearity parameters θ by name.
    pub fn parameters(&self) -> Vec<(String, f64)> {
        self.nl
            .param_names()
            .into_iter()
            .zip(self.nl.params().into_iter().map(|t| t.as_f64()))
            .collect()
    }
    /// Nonlinearity parameters θ by name with their standard errors on the training record
    /// (`None` when not computed, e.g. a model assembled by hand; `+∞` when the record does not
    /// determine the parameter).
    pub fn parameters_with_errors(&self) -> Vec<(String, f64, Option<f64>)> {
        let se = &self.report.standard_errors;
        self.parameters()
            .into_iter()
            .enumerate()
            .map(|(j, (name, v))| (name, v, se.get(j).copied()))
            .collect()
    }
    /// The standard error of the combination Σ wᵢθᵢ of the nonlinearity's parameters named in
    /// `weights` on the training record (e.g. `[("e1", 1.0), ("e2", -1.0)]`: a preload's jump);
    /// `None` when the covariance was not computed (a loaded or hand-made model) or a name is
    /// not a parameter; `+∞` when the record does not determine the combination.
    pub fn standard_error_of_combination(&self, weights: &[(&str, f64)]) -> Option<f64> {
        let cov = self.report.covariance.as_ref()?;
        Some(cov.standard_error(&self.weights_of(weights, cov.len())?))
    }
    /// [`standard_error_of_combination`](Self::standard_error_of_combination) with the
    /// combination `held` fixed at its estimate
    /// ([`ParameterCovariance::standard_error_given`](crate::fit::ParameterCovariance::standard_error_given),
    /// e.g. the nonlinearity's gains: its scale).
    pub fn standard_error_given(
        &self,
        weights: &[(&str, f64)],
        held: &[(&str, f64)],
    ) -> Option<f64> {
        let cov = self.report.covariance.as_ref()?;
        let w = self.weights_of(weights, cov.len())?;
        let h = self.weights_of(held, cov.len())?;
        Some(cov.standard_error_given(&w, &h))
    }
    /// The weight vector over the reported parameters of named nonlinearity parameters.
    fn weights_of(&self, weights: &[(&str, f64)], len: usize) -> Option<Vec<f64>> {
        let names = self.nl.param_names();
        let mut w = vec![0.0; len];
        for (name, wi) in weights {
            let j = names.iter().position(|n| n == name)?;
            *w.get_mut(j)? += wi;
        }
        Some(w)
    }
    /// The constant output offset c.
    pub fn output_offset(&self) -> f64 {
        self.offset.as_f64()
    }
    /// Initial state estimated on the training record.
    pub fn training_x0(&self) -> &[T] {
        &self.x0
    }
    /// Whether the linear block has a direct feed-through (D ≠ 0), as fitted or decided by the
    /// automatic feed-through rule.
    pub fn has_feedthrough(&self) -> bool {
        self.linear.d[(0, 0)] != T::zero()
    }
    /// Whether the fit estimated its own output offset (not when the nonlinearity's regressors
    /// span the constant, e.g. preload without dead-zone, whose steps carry it).
    pub fn offset_fitted(&self) -> bool {
        self.settings.options.offset && !self.nl.spans_constant()
    }
    /// Input delay nk in samples.
    pub fn delay(&self) -> usize {
        self.settings.options.delay
    }

    /// The intermediate signal v = N(u(k − nk)).
    pub fn intermediate(&self, u: &[T]) -> Result<Vec<T>> {
        check_input(u)?;
        Ok(self.nl.eval(&delayed(u, self.settings.options.delay)))
    }

    /// Simulates from a zero initial state (offset added).
    pub fn simulate(&self, u: &[T]) -> Result<Vec<T>> {
        let v = self.intermediate(u)?;
        Ok(self.run(&vec![T::zero(); self.linear.order()], self.offset, &v))
    }

    /// [`simulate`](Self::simulate) that fails with [`Error::Diverged`] when the output diverges
    /// (see [`divergence`]): for callers that need a finite answer.
    pub fn simulate_finite(&self, u: &[T]) -> Result<Vec<T>> {
        let y = self.simulate(u)?;
        match divergence(&y) {
            Some((index, value)) => Err(Error::Diverged { index, value }),
            None => Ok(y),
        }
    }

    /// The linear block's output x for the intermediate signal `v` from the state `x0` (before
    /// the output map and the offset; e.g. with a [`Simulation`]'s `v` and `x0`).
    pub fn linear_output(&self, v: &[T], x0: &[T]) -> Vec<T> {
        self.run_linear(x0, T::zero(), v)
    }

    /// The model's output for `v` from `x0`: the linear block, the output map if any, plus
    /// `offset`.
    fn run(&self, x0: &[T], offset: T, v: &[T]) -> Vec<T> {
        match &self.output_map {
            None => self.run_linear(x0, offset, v),
            Some(g) => g
                .eval(&self.run_linear(x0, T::zero(), v))
                .into_iter()
                .map(|y| y + offset)
                .collect(),
        }
    }

    /// The linear block driven by `v` from `x0`, plus `offset` (no output map).
    fn run_linear(&self, x0: &[T], offset: T, v: &[T]) -> Vec<T> {
        let mut y = Vec::new();
        simulate_into(
            self.linear.a.as_ref(),
            &self.b_vec(),
            self.linear.c.as_ref(),
            self.linear.d[(0, 0)],
            x0,
            offset,
            v,
            &mut y,
        );
        y
    }

    /// Simulates on a measured record with the initial state estimated by least squares on it.
    ///
    /// With an input delay nk > 0 the first nk values of v = N(u(k − nk)) act before the record
    /// starts and are unknown; they are estimated together with x0 (the initial state of the
    /// delay line, which is part of the delayed system's state) and returned in `v`.
    /// The nonlinearity's own memory at the first sample (the hysteresis direction) is
    /// estimated: the rising and the falling starts are both simulated and the better fit kept.
    /// Nonlinearities with a longer memory (play operators) are also simulated behind the input
    /// histories they name ([`StaticNonlinearity::memory_histories`]) and the best fit kept.
    pub fn simulate_on(&self, data: &IoData<T>) -> Result<Simulation<T>> {
        check_siso(data)?;
        // the record's columns borrowed, not copied (long records)
        let u = data.input_slice(0);
        let y = data.output_slice(0);
        let mut best = self.simulate_on_directions(u, y)?;
        let mut best_mse = mse(y, &best.y_hat);
        for h in self.histories(u) {
            let Ok(sim) = self.simulate_on_v(y, self.intermediate_behind(u, &h)?) else {
                continue;
            };
            let m = mse(y, &sim.y_hat);
            if m < best_mse {
                (best, best_mse) = (sim, m);
            }
        }
        Ok(best)
    }

    /// The nonlinearity's memory histories before the record (none for an empty one).
    fn histories(&self, u: &[T]) -> Vec<Vec<T>> {
        u.first()
            .map_or_else(Vec::new, |&u0| self.nl.memory_histories(u0))
    }

    /// `simulate_on` with the rising and the falling start only.
    fn simulate_on_directions(&self, u: &[T], y: &[T]) -> Result<Simulation<T>> {
        // the nonlinearity's memory at the first sample (the direction of motion before the
        // record) is unknown: both starts are simulated and the better fit kept (the falling
        // one evaluated first: its extended input is gone before the rising one is made)
        let falling = self.intermediate_falling(u)?;
        let rising = self.intermediate_rising(u)?;
        if falling == rising {
            drop(falling);
            return self.simulate_on_v(y, rising);
        }
        let mut first = self.simulate_on_v(y, rising)?;
        // without a delay the first start's v is the rising intermediate signal itself: it is
        // dropped while the second start runs and evaluated again if the first wins (long
        // records hold three signals at a time, not four)
        let again = self.settings.options.delay == 0;
        if again {
            first.v = Vec::new();
        }
        let second = self.simulate_on_v(y, falling)?;
        if mse(y, &second.y_hat) < mse(y, &first.y_hat) {
            return Ok(second);
        }
        drop(second);
        if again {
            first.v = self.intermediate_rising(u)?;
        }
        Ok(first)
    }

    /// `f` of the output ŷ of [`simulate_on`](Self::simulate_on) (the same start chosen, the
    /// same numbers) without keeping the simulation. Without an input delay each start of the
    /// nonlinearity's memory is simulated in one signal of the record's length, written over its
    /// intermediate signal ([`output_in_place`](Self::output_in_place)), and dropped before the
    /// next (the metrics of a long record: one signal beside the record, not two).
    pub(crate) fn on_simulated<R>(&self, data: &IoData<T>, f: impl Fn(&[T]) -> R) -> Result<R> {
        self.on_simulated_with(data, |y_hat, _, _| f(y_hat))
    }

    /// The initial state x0 [`simulate_on`](Self::simulate_on) estimates on `data` (of the
    /// start it keeps), without keeping its simulation (one signal of the record's length at a
    /// time without an input delay).
    pub(crate) fn initial_state_on(&self, data: &IoData<T>) -> Result<Vec<T>> {
        self.on_simulated_with(data, |_, x0, _| x0.to_vec())
    }

    /// [`on_simulated`](Self::on_simulated) with `f` also given the simulation's initial state
    /// and the start of the nonlinearity's memory it kept (`None` with an input delay, whose
    /// intermediate values before the record are estimated with x0).
    pub(crate) fn on_simulated_with<R>(
        &self,
        data: &IoData<T>,
        f: impl Fn(&[T], &[T], Option<MemoryStart>) -> R,
    ) -> Result<R> {
        check_siso(data)?;
        if self.settings.options.delay > 0 {
            let sim = self.simulate_on(data)?;
            return Ok(f(&sim.y_hat, &sim.x0, None));
        }
        let u = data.input_slice(0);
        let y = data.output_slice(0);
        // the rising start, then (a nonlinearity with a memory) the falling one and the
        // longer memories' histories, each simulated and dropped before the next; a start
        // replaces the best only when it fits better (a falling start equal to the rising one
        // is not taken). The errors of the rising and falling starts are the simulation's, as
        // in `simulate_on`; a history whose simulation fails is skipped
        let histories = if self.nl.memoryless() {
            0
        } else {
            self.histories(u).len()
        };
        let rising = MemoryStart::Rising;
        let (y_hat, x0) = self.output_in_place(y, || self.intermediate_of(u, rising))?;
        let mut best = (mse(y, &y_hat), f(&y_hat, &x0, Some(rising)));
        drop(y_hat);
        let others = (!self.nl.memoryless())
            .then_some(MemoryStart::Falling)
            .into_iter()
            .chain((0..histories).map(MemoryStart::History));
        for start in others {
            let (y_hat, x0) = match self.output_in_place(y, || self.intermediate_of(u, start)) {
                Ok(sim) => sim,
                Err(_) if matches!(start, MemoryStart::History(_)) => continue,
                Err(e) => return Err(e),
            };
            let m = mse(y, &y_hat);
            if m < best.0 {
                best = (m, f(&y_hat, &x0, Some(start)));
            }
        }
        Ok(best.1)
    }

    /// v = N(u(k)) from the start `start` of the nonlinearity's memory (no input delay): the
    /// intermediate signal of a simulation [`on_simulated_with`](Self::on_simulated_with) kept.
    /// The nonlinearity is causal, so on the leading samples of a record it gives the leading
    /// samples of the record's v.
    pub(crate) fn intermediate_of(&self, u: &[T], start: MemoryStart) -> Result<Vec<T>> {
        match start {
            MemoryStart::Rising => self.intermediate_rising(u),
            MemoryStart::Falling => self.intermediate_falling(u),
            MemoryStart::History(i) => match self.histories(u).get(i) {
                Some(h) => self.intermediate_behind(u, h),
                None => self.intermediate_rising(u),
            },
        }
    }

    /// The output ŷ and initial state of `simulate_on_v` (no input delay) for the intermediate
    /// signal `make_v` gives, in one signal: the forced response is written over v, the initial
    /// state fitted to it, then v made again and the simulation from that state written over
    /// it (the same bits as `simulate_on_v`, whose v and ŷ are two signals; v is evaluated
    /// twice).
    fn output_in_place(
        &self,
        y: &[T],
        make_v: impl Fn() -> Result<Vec<T>>,
    ) -> Result<(Vec<T>, Vec<T>)> {
        let (a, c) = (self.linear.a.as_ref(), self.linear.c.as_ref());
        let b = self.b_vec();
        let d = self.linear.d[(0, 0)];
        let mut forced = make_v()?;
        let zeros = vec![T::zero(); self.linear.order()];
        simulate_in_place(a, &b, c, d, &zeros, T::zero(), &mut forced);
        if let Some((index, value)) = divergence(&forced) {
            return Err(Error::Diverged { index, value });
        }
        let x0 = self.initial_state_for(y, &forced)?;
        drop(forced);
        let mut out = make_v()?;
        match &self.output_map {
            None => simulate_in_place(a, &b, c, d, &x0, self.offset, &mut out),
            Some(g) => {
                simulate_in_place(a, &b, c, d, &x0, T::zero(), &mut out);
                // the map is evaluated sample by sample: block by block, the same values
                for block in out.chunks_mut(4096) {
                    let mapped = g.eval(block);
                    for (o, m) in block.iter_mut().zip(mapped) {
                        *o = m + self.offset;
                    }
                }
            }
        }
        Ok((out, x0))
    }

    /// The initial state of the simulation on `y` given the forced response (no input delay):
    /// least squares on the free response, then through the output map when there is one.
    fn initial_state_for(&self, y: &[T], forced: &[T]) -> Result<Vec<T>> {
        let la = self.settings.linalg_backend()?;
        let (x0, _) = fit_x0(
            la.as_ref(),
            self.linear.a.as_ref(),
            self.linear.c.as_ref(),
            forced,
            y,
            self.offset,
            false,
        )?;
        if self.output_map.is_none() {
            return Ok(x0);
        }
        // the free response's rows only while it has not decayed below round-off
        // (`free_response_length`): the later rows of the regressors are zero, and the
        // Gauss–Newton steps need the leading rows only (an n × N matrix on a long record
        // cost gigabytes)
        let n = self.linear.order();
        let (a, c) = (self.linear.a.as_ref(), self.linear.c.as_ref());
        let reg = Regressors::Free {
            am: row_major(a),
            c: row_major(c),
            head: free_response_length(a, c, y.len()),
        };
        debug_assert_eq!(reg.ncols(), n);
        self.best_initial_through_map(y, forced, &reg, x0)
    }

    /// v = N(u(k − nk)) with the input taken as rising before the record (the nonlinearity's
    /// own initial direction when it is rising, as in `eval`).
    fn intermediate_rising(&self, u: &[T]) -> Result<Vec<T>> {
        // a nonlinearity taken as falling has a direction memory, so `Some`
        match self.intermediate_started(u, false)? {
            Some(v) => Ok(v),
            None => self.intermediate(u),
        }
    }

    /// v = N(u(k − nk)) with the input taken as falling before the record: the
    /// nonlinearity's own falling start (`set_initial_falling`, the start the fit estimates)
    /// when it has one; otherwise the record evaluated behind one extra leading sample above
    /// u(0), which is then dropped.
    fn intermediate_falling(&self, u: &[T]) -> Result<Vec<T>> {
        if let Some(v) = self.intermediate_started(u, true)? {
            return Ok(v);
        }
        let Some(&u0) = u.first() else {
            return Ok(Vec::new());
        };
        self.intermediate_behind(u, &[u0 + u0.abs().max(T::one())])
    }

    /// v = N(u(k − nk)) with the nonlinearity's initial direction set to `falling` (itself when
    /// it is already there, a copy otherwise); `None` when it has no direction memory to set.
    fn intermediate_started(&self, u: &[T], falling: bool) -> Result<Option<Vec<T>>> {
        if self.nl.initial_falling() == falling {
            return self.intermediate(u).map(Some);
        }
        check_input(u)?;
        let mut nl = self.nl.clone_box();
        if !nl.set_initial_falling(falling) {
            return Ok(None);
        }
        Ok(Some(nl.eval(&delayed(u, self.settings.options.delay))))
    }

    /// v = N(u(k − nk)) with the input `history` before the record: the record is evaluated
    /// behind it, whose values are then dropped.
    fn intermediate_behind(&self, u: &[T], history: &[T]) -> Result<Vec<T>> {
        check_input(u)?;
        let mut ext = Vec::with_capacity(u.len() + history.len());
        ext.extend_from_slice(history);
        ext.extend_from_slice(u);
        let mut v = self.nl.eval(&delayed(&ext, self.settings.options.delay));
        drop(ext);
        v.drain(..history.len().min(v.len()));
        Ok(v)
    }

    /// `simulate_on` for a given intermediate signal.
    fn simulate_on_v(&self, y: &[T], v: Vec<T>) -> Result<Simulation<T>> {
        let nk = self.settings.options.delay.min(v.len());
        if nk > 0 {
            return self.simulate_on_delayed(y, v, nk);
        }
        let forced = self.run_linear(&vec![T::zero(); self.linear.order()], T::zero(), &v);
        if let Some((index, value)) = divergence(&forced) {
            return Err(Error::Diverged { index, value });
        }
        let x0 = self.initial_state_for(y, &forced)?;
        drop(forced);
        let y_hat = self.run(&x0, self.offset, &v);
        Ok(Simulation { y_hat, x0, v })
    }

    /// `simulate_on` with the first `nk` intermediate values unknown: least squares for
    /// (x0, v(0..nk)) on y − offset − (forced response to the known v), then the simulation.
    fn simulate_on_delayed(&self, y: &[T], v: Vec<T>, nk: usize) -> Result<Simulation<T>> {
        let n = self.linear.order();
        let nn = y.len();
        let np = n + nk;
        if nn < np + 1 {
            return Err(Error::TooFewSamples {
                needed: np + 1,
                got: nn,
                reason: format!(
                    "estimating the initial state and the {nk} intermediate value(s) before the record (input delay {nk})"
                ),
            });
        }
        let zeros = vec![T::zero(); n];
        let mut known = v.clone();
        known[..nk].fill(T::zero());
        let forced = self.run_linear(&zeros, T::zero(), &known);
        if let Some((index, value)) = divergence(&forced) {
            return Err(Error::Diverged { index, value });
        }
        // regressors: the free responses C A^k e_j, then the responses to a unit v at j < nk —
        // on the leading rows only, while they have not decayed below round-off (the unit
        // responses are free responses shifted by at most nk samples, `free_response_length`):
        // the later rows are zero and add nothing to the least squares
        let (a, c) = (self.linear.a.as_ref(), self.linear.c.as_ref());
        let head = (free_response_length(a, c, nn) + nk).min(nn);
        let mut reg = Mat::<T>::zeros(head, np);
        let free = observability_columns(a, c, head);
        for j in 0..n {
            for k in 0..head {
                reg[(k, j)] = free[j * head + k];
            }
        }
        drop(free);
        for j in 0..nk {
            let mut imp = vec![T::zero(); head];
            imp[j] = T::one();
            let col = self.run_linear(&zeros, T::zero(), &imp);
            for k in 0..head {
                reg[(k, n + j)] = col[k];
            }
        }
        let rhs = Mat::from_fn(head, 1, |k, _| y[k] - self.offset - forced[k]);
        let la = self.settings.linalg_backend()?;
        let theta = la.lstsq(reg.as_ref(), rhs.as_ref())?;
        let mut theta: Vec<T> = (0..np).map(|j| theta[(j, 0)]).collect();
        if self.output_map.is_some() {
            theta = self.best_initial_through_map(y, &forced, &Regressors::Dense(&reg), theta)?;
        }
        let x0: Vec<T> = theta[..n].to_vec();
        let mut v_est = v;
        v_est[..nk].copy_from_slice(&theta[n..n + nk]);
        let y_hat = self.run(&x0, self.offset, &v_est);
        Ok(Simulation {
            y_hat,
            x0,
            v: v_est,
        })
    }

    /// The unknowns z (initial state, then the intermediate values before the record) through
    /// the output map, by Gauss–Newton from `z` and from the model's own fitted initial state
    /// (`initial_map.rs`); `z` itself without a map.
    fn best_initial_through_map(
        &self,
        y: &[T],
        forced: &[T],
        reg: &Regressors<'_, T>,
        z: Vec<T>,
    ) -> Result<Vec<T>> {
        let Some(g) = &self.output_map else {
            return Ok(z);
        };
        let n = self.linear.order();
        let la = self.settings.linalg_backend()?;
        let problem = MapProblem {
            g: g.as_ref(),
            y,
            forced,
            offset: self.offset,
        };
        let own = (self.x0.len() == n).then_some(self.x0.as_slice());
        problem.best_initial(la.as_ref(), reg, z, own)
    }

    /// Transfer function of the linear block in powers of z⁻¹.
    pub fn transfer_function(&self) -> Result<TransferFunction> {
        self.linear.transfer_function(0, 0)
    }

    fn b_vec(&self) -> Vec<T> {
        (0..self.linear.order())
            .map(|i| self.linear.b[(i, 0)])
            .collect()
    }
}

/// The start of a nonlinearity's memory a simulation on a measured record took (the input's
/// direction of motion before the record, or one of
/// [`StaticNonlinearity::memory_histories`] by its index).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum MemoryStart {
    /// The input taken as rising before the record.
    Rising,
    /// The input taken as falling before the record.
    Falling,
    /// Behind the memory history of this index.
    History(usize),
}

/// A typed error unless the record has one input and one output.
pub(crate) fn check_siso<T: Real>(data: &IoData<T>) -> Result<()> {
    if data.n_inputs() != 1 || data.n_outputs() != 1 {
        return Err(Error::Dimension(format!(
            "a Hammerstein model is single-input single-output; the record has {} input(s) and {} output(s)",
            data.n_inputs(),
            data.n_outputs()
        )));
    }
    Ok(())
}

fn check_input<T: Real>(u: &[T]) -> Result<()> {
    if let Some(index) = u.iter().position(|x| !x.is_finite()) {
        return Err(Error::NonFinite {
            what: "input".into(),
            index,
        });
    }
    Ok(())
}
