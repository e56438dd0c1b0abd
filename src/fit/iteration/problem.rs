//! The bottom of the loop: the fixed data of one fit (`Problem`), one iterate (`Iterate`), the
//! workspace the least-squares steps reuse, and the single steps of one iteration that do not
//! search: (A, C) by the subspace method, the gains from the rank-one factor, the single-input
//! block given (A, C) (steps 2–6 of the loop, see `loop_state.rs`), the re-identification before
//! the refinement and the numeric helpers (variance, exact-fit floor, pole shrink).

use crate::data::{IoData, IoView, min_samples_for_horizon};
use crate::error::Result;
use crate::fit::fitted::model::HammersteinModel;
use crate::fit::numerics::linear_ls::{LsTerms, LsWork, delayed, fit_given_ac, mse, simulate_into};
use crate::fit::numerics::offset_fold::{OffsetMode, carried_offset, folded_gains, without_column};
use crate::fit::numerics::rank_one::{factor, markov_of, markov_rows, scale_for};
use crate::fit::observer::Observer;
use crate::fit::settings::Hammerstein;
use crate::real::Real;
use crate::regressors::StaticNonlinearity;
use crate::solvers::LinAlg;
use crate::solvers::schur_cohn::roots_inside;
use crate::statespace::StateSpace;
use crate::subspace::{SubspaceMethod, max_order, select_order};
use faer::{Mat, MatRef};
use std::borrow::Cow;

/// Horizon of the single-input re-identification of the linear block before the refinement.
pub(crate) const RESTART_HORIZON: usize = 20;
/// The real poles a nested start tries for the states it adds (`Problem::nested_start`).
pub(crate) const NESTED_POLES: [f64; 5] = [-0.5, 0.0, 0.5, 0.8, 0.95];

/// What the least-squares steps of a fit reuse from call to call (the regression matrix and
/// the free-response columns); passed as `&mut`, one per fit.
#[derive(Default)]
pub(crate) struct Workspace<T: Real> {
    /// Regression matrix and free-response cache of the B/D/x0 least squares.
    pub ls: LsWork<T>,
    /// The same for the second thread of the search's candidates evaluated two at a time
    /// (`search.rs`).
    pub side: LsWork<T>,
}

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

impl<T: Real> Iterate<T> {
    /// A fitted model's nonlinearity parameters, block, x0 and offset as an iterate of MSE `mse`.
    pub(crate) fn of_model(m: &HammersteinModel<T>, mse: f64) -> Self {
        let l = &m.linear;
        Iterate {
            theta: m.nl.params(),
            a: l.a.clone(),
            b: (0..l.a.nrows()).map(|i| l.b[(i, 0)]).collect(),
            c: l.c.clone(),
            d: l.d[(0, 0)],
            x0: m.x0.clone(),
            offset: m.offset,
            mse,
        }
    }
}

/// `model` with the iterate `it` in place of its nonlinearity parameters, block (normalised as
/// the problem's settings say, sample time `ts`), x0, offset and training MSE.
pub(crate) fn adopt_iterate<T: Real>(
    problem: &Problem<'_, T>,
    model: &mut HammersteinModel<T>,
    mut it: Iterate<T>,
    ts: f64,
) -> Result<()> {
    model.nl.set_params(&it.theta)?;
    normalise_iterate(problem, model.nl.as_mut(), &mut it);
    let mut linear = to_statespace(&it)?;
    linear.ts = ts;
    model.linear = linear;
    model.x0 = it.x0;
    model.offset = it.offset;
    model.report.train_mse = it.mse;
    Ok(())
}

/// The fixed data of one fit: the delayed input, the output, the solvers and the settings.
pub(crate) struct Problem<'a, T: Real> {
    pub la: &'a dyn LinAlg<T>,
    pub method: &'a dyn SubspaceMethod<T>,
    pub settings: &'a Hammerstein<T>,
    /// The delayed input (borrowed from the record without a delay: long records keep no copy).
    pub u: Cow<'a, [T]>,
    /// The output (borrowed from the record).
    pub y: Cow<'a, [T]>,
    pub k_rows: usize,
    /// MSE at or below which the fit counts as exact (round-off level of var(y)).
    pub floor: f64,
    /// Change of the offset below which it counts as settled (√ε·std(y)).
    pub offset_tol: f64,
    /// Notified after every iteration of the loop (attached at fit time; none by default).
    pub observer: Option<&'a dyn Observer>,
}

impl<'a, T: Real> Problem<'a, T> {
    /// The problem of fitting `data` with `settings` (the input delayed by the settings' delay).
    pub fn new(
        la: &'a dyn LinAlg<T>,
        method: &'a dyn SubspaceMethod<T>,
        settings: &'a Hammerstein<T>,
        data: &'a IoData<T>,
    ) -> Self {
        let y = Cow::Borrowed(data.output_slice(0));
        let var = variance(&y);
        Problem {
            la,
            method,
            settings,
            u: delayed(data.input_slice(0), settings.options.delay),
            y,
            k_rows: markov_rows(
                settings.options.horizon,
                max_order(settings.options.horizon, 1),
            ),
            floor: exact_floor::<T>(var),
            offset_tol: T::epsilon().as_f64().sqrt() * var.sqrt(),
            observer: None,
        }
    }

    /// The same problem with `observer` notified after every iteration.
    pub fn observed(mut self, observer: Option<&'a dyn Observer>) -> Self {
        self.observer = observer;
        self
    }

    /// Whether the stability constraint (`Hammerstein::stable`) refuses a block with denominator
    /// `a`: the constraint is on and a root lies outside `STABLE_RADIUS` (Schur–Cohn test).
    pub fn refuses_block(&self, a: &[T]) -> bool {
        self.settings.options.stable && !roots_inside(a, STABLE_RADIUS)
    }

    /// Whether the loop estimates its own output offset: not when the nonlinearity's regressors
    /// already span the constant (preload without dead-zone), where an offset column would make
    /// the linear step rank deficient and the preload steps absorb the offset.
    pub fn fits_offset(&self, nl: &dyn StaticNonlinearity<T>) -> bool {
        self.settings.options.offset && !nl.spans_constant()
    }

    /// How the linear steps treat the offset for `nl` (`offset_fold.rs`).
    pub fn offset_mode(&self, nl: &dyn StaticNonlinearity<T>) -> OffsetMode {
        if !self.settings.options.offset {
            OffsetMode::Absent
        } else if let Some(pair) = nl.constant_pair() {
            OffsetMode::Folded(pair.0, pair.1)
        } else if nl.spans_constant() {
            OffsetMode::Absent
        } else {
            OffsetMode::Fitted
        }
    }

    /// The offset hint of the next subspace step after iterate `it`: its fitted offset, or the
    /// offset a folded model carries in its gains (`offset_fold.rs`); `None` without an offset.
    pub fn next_offset_hint(&self, nl: &dyn StaticNonlinearity<T>, it: &Iterate<T>) -> Option<T> {
        match self.offset_mode(nl) {
            OffsetMode::Fitted => Some(it.offset),
            OffsetMode::Folded(_, j) => carried_offset(
                self.la,
                &nl.gains(),
                j,
                it.a.as_ref(),
                &it.b,
                it.c.as_ref(),
                it.d,
            ),
            OffsetMode::Absent => None,
        }
    }

    pub fn terms(&self, nl: &dyn StaticNonlinearity<T>) -> LsTerms {
        LsTerms {
            with_d: self.settings.options.with_d,
            x0: true,
            offset: self.fits_offset(nl),
        }
    }

    /// Step 2: (A, C) from (φ, y); the order by the rule when `order` is `None`.
    ///
    /// Offsets: with `offset_hint = Some(c)` (the previous iterate's offset) the subspace step sees
    /// the raw φ and y − c, which is exactly LTI (with an initial state) once c is right; without a
    /// hint (first iteration) it sees first differences of φ and y, exactly LTI whatever the
    /// offset (the differenced noise is coloured, so later iterations switch to the hint). A
    /// folded offset (`OffsetMode::Folded`) leaves the dropped column out; its hint is the offset
    /// the model carries in its gains (`next_offset_hint`).
    #[allow(clippy::type_complexity)]
    pub fn identify_ac(
        &self,
        phi: MatRef<'_, T>,
        order: Option<usize>,
        offset_hint: Option<T>,
        mode: OffsetMode,
    ) -> Result<(Mat<T>, Mat<T>, Vec<f64>, usize)> {
        let nn = self.y.len();
        let reduced = match mode {
            OffsetMode::Folded(_, j) => Some(without_column(phi, j)),
            _ => None,
        };
        let phi = reduced.as_ref().map_or(phi, |m| m.as_ref());
        let fit_offset = mode != OffsetMode::Absent;
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
                &self.settings.options.order,
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
        ws: &mut Workspace<T>,
        nl: &dyn StaticNonlinearity<T>,
        n: usize,
        offset: T,
    ) -> Option<Iterate<T>> {
        let nn = self.y.len();
        let mut h = RESTART_HORIZON
            .max(self.settings.options.horizon)
            .max(n + 1);
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
        let it = self.evaluate(ws, nl, a.as_ref(), c.as_ref()).ok()?;
        it.mse.is_finite().then_some(it)
    }

    /// The linear block of order `n` from a fitted higher-order block (`a`, `b`, `c`) by
    /// balanced truncation (`subspace::balanced_truncation`), then B, D, x0 and the offset by
    /// least squares for v = N(u; θ) held fixed (step 6). `None` when `n` is not below the
    /// block's order, the block is not stable, or the least squares fail.
    pub fn reduced_start(
        &self,
        ws: &mut Workspace<T>,
        nl: &dyn StaticNonlinearity<T>,
        (a, b, c): (MatRef<'_, T>, MatRef<'_, T>, MatRef<'_, T>),
        n: usize,
    ) -> Option<Iterate<T>> {
        let (ar, _, cr, _) = crate::subspace::balanced_truncation(self.la, a, b, c, n)?;
        let ar = stabilised(ar);
        let it = self.evaluate(ws, nl, ar.as_ref(), cr.as_ref()).ok()?;
        it.mse.is_finite().then_some(it)
    }

    /// The linear block of order `n` that extends a fitted lower-order block (`a`, `c`) by real
    /// poles (the nested start): A = diag(a, λ, …), C = [c, 1, …], then B, D, x0 and the offset by
    /// least squares for v = N(u; θ) held fixed (step 6). With the new states' B zero it is the
    /// lower-order fit, so its MSE is at most that one's: a higher-order candidate started here
    /// cannot end above the lower order. λ is the best of `NESTED_POLES`. `None` when `n` is not
    /// above the block's order or every least squares fails.
    pub fn nested_start(
        &self,
        ws: &mut Workspace<T>,
        nl: &dyn StaticNonlinearity<T>,
        (a, c): (MatRef<'_, T>, MatRef<'_, T>),
        n: usize,
    ) -> Option<Iterate<T>> {
        let m = a.nrows();
        if n <= m || c.ncols() != m {
            return None;
        }
        let mut best: Option<Iterate<T>> = None;
        for &lambda in &NESTED_POLES {
            let an = Mat::from_fn(n, n, |i, j| match (i < m, j < m) {
                (true, true) => a[(i, j)],
                (false, false) if i == j => T::lit(lambda),
                _ => T::zero(),
            });
            let cn = Mat::from_fn(1, n, |_, j| if j < m { c[(0, j)] } else { T::one() });
            let Ok(it) = self.evaluate(ws, nl, an.as_ref(), cn.as_ref()) else {
                continue;
            };
            if it.mse.is_finite() && best.as_ref().is_none_or(|b| it.mse < b.mse) {
                best = Some(it);
            }
        }
        best
    }

    /// Steps 3–5 without the search: g by least squares and rank-one factorisation given (A, C),
    /// then θ from g.
    pub fn update_gains(
        &self,
        ws: &mut Workspace<T>,
        nl: &mut dyn StaticNonlinearity<T>,
        phi: MatRef<'_, T>,
        a: MatRef<'_, T>,
        c: MatRef<'_, T>,
    ) -> Result<()> {
        let (ro_g, ro_markov) = if let OffsetMode::Folded(i, j) = self.offset_mode(nl) {
            let reduced = without_column(phi, j);
            let terms = LsTerms {
                offset: true,
                ..self.terms(nl)
            };
            let fit = fit_given_ac(self.la, a, c, reduced.as_ref(), &self.y, terms, &mut ws.ls)?;
            let ro = factor(self.la, a, fit.b.as_ref(), c, &fit.d, self.k_rows)?;
            let g = folded_gains(
                self.la,
                a,
                fit.b.as_ref(),
                c,
                &fit.d,
                &ro.g,
                fit.offset,
                (i, j),
            )?;
            (g, ro.markov)
        } else {
            let fit = fit_given_ac(self.la, a, c, phi, &self.y, self.terms(nl), &mut ws.ls)?;
            let ro = factor(self.la, a, fit.b.as_ref(), c, &fit.d, self.k_rows)?;
            (ro.g, ro.markov)
        };
        let s = scale_for(self.settings.options.normalization, &ro_g, &ro_markov)?;
        let g: Vec<T> = ro_g.iter().map(|&x| x * s).collect();
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
        ws: &mut Workspace<T>,
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
            &mut ws.ls,
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
}

/// Largest pole radius an intermediate linear block of the loop may have.
pub(crate) const MAX_POLE_RADIUS: f64 = 0.9995;

/// Largest pole radius a block may reach under the stability constraint (`Hammerstein::stable`):
/// a margin inside the unit circle (a time constant of 10 000 samples), so that an optimum
/// pressed against the boundary stays stable through the eigenvalues computed from the
/// transfer function's coefficients and the units carried back (ensaio04 ended at 1 + 9e-8 with
/// the bound at 1).
pub const STABLE_RADIUS: f64 = 0.9999;

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
    let Ok(s) = scale_for(problem.settings.options.normalization, &g, &markov) else {
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
