//! Levenberg–Marquardt refinement of the loop's result on the simulation error (beyond the paper).
//!
//! Parametrisation: the nonlinearity's θ, the linear block as a SISO transfer function
//! G(z) = (b0 + b1 z⁻¹ + … + bn z⁻ⁿ)/(1 + a1 z⁻¹ + … + an z⁻ⁿ) with the first non-negligible
//! numerator coefficient held at its value (the scale, fixed by the normalisation; b0 held at 0
//! without D), the initial condition as the numerator q(z) of the free response q(z)/a(z)
//! (= the initial state of the observer canonical form), and the offset c:
//!
//!   y(k) = [b(z) v(k) + q(z) δ(k)] / a(z) + c,   v = N(u; θ).
//!
//! The Jacobian is exact: ∂y/∂θ = (b/a)·∂v/∂θ (the nonlinearity's `param_jacobian`),
//! ∂y/∂b_i = z⁻ⁱ v/a, ∂y/∂q_i = z⁻ⁱ δ/a, ∂y/∂a_i = −z⁻ⁱ y_lin/a, ∂y/∂c = 1. Each LM step solves
//! the damped least-squares problem [J; √μ·diag(‖J_j‖)] δ = [r; 0] by QR (Marquardt's scaling).
//! A step is taken only when the MSE falls; the refined model replaces the loop's only when its
//! MSE is lower.
//!
//! Memory: the Jacobian is never formed whole. Its rows are produced in blocks of
//! `tsqr::BLOCK_ROWS` by [`JacobianStream`] (every column is a linear filter of a signal; the
//! filters carry their past from block to block) and folded into the R factor of [J | r] by the
//! sequential TSQR of `solvers/tsqr.rs` (Demmel et al. 2012), so an LM iteration needs O(p²)
//! memory besides the signals, whatever the record's length.

use crate::error::{Error, Result};
use crate::fit::fit_report::RefineReport;
use crate::fit::iteration::problem::{Iterate, MAX_POLE_RADIUS, Problem, to_statespace};
use crate::fit::numerics::jump_centre::centred_theta;
use crate::fit::numerics::jump_scan::{
    SCAN_ITERATIONS, SCAN_POINTS, block_gain, fit_is_exact, jump_matters, local_values, scan_values,
};
use crate::fit::numerics::kink_scan::{MIN_NEAR_KINK_RATIO, kink_values, near_kink_ratio};
use crate::fit::refinement::linear_output::{LinearOutput, add_squares, mse_filtered};
use crate::real::Real;
use crate::regressors::zone::spread;
use crate::regressors::{JUMP_SECANT_FRACTION, StaticNonlinearity};
use crate::solvers::LinAlg;
use crate::solvers::channel_filter::ChannelFilter;
use crate::solvers::recursion::TfFilter;
use crate::solvers::schur_cohn::roots_scaled;
use crate::solvers::tsqr::{BLOCK_ROWS, Tsqr, solve_from_r};
use crate::statespace::StateSpace;
use faer::Mat;
use std::borrow::Cow;

/// LM iteration limit.
pub(in crate::fit) const MAX_LM_ITER: usize = 100;
/// Relative MSE decrease below which LM stops (an accepted step's, or a trial step's predicted
/// one). 1e-8 would save 14 % of a default fit's instructions and leaves the fit batteries'
/// records as they are, but the diagnosis battery's nested comparisons lose with it (after
/// `follow` 141 → 139 of 144 at the floor, complete models adequate 55 → 53 of 56;
/// `docs/performance.md`): the models compared must be converged well inside the
/// tests' thresholds.
pub(in crate::fit) const LM_TOL: f64 = 1e-10;
/// Marquardt scale of a held parameter relative to the largest free one (`pin_held`).
const PIN_SCALE: f64 = 1e10;
/// LM iterations of one profile evaluation in the centring (the others re-adapted to a moved
/// jump parameter: inside an interval the model is smooth in them and starts near their optimum).
const PROFILE_ITERATIONS: usize = 3;

/// Parameter layout of the refinement.
pub(in crate::fit) struct Layout {
    pub n_theta: usize,
    pub n: usize,
    /// Indices k of the free numerator coefficients b_k.
    pub free_b: Vec<usize>,
    pub offset: bool,
}

impl Layout {
    /// Number of parameters.
    pub(in crate::fit) fn len(&self) -> usize {
        self.n_theta + self.n + self.free_b.len() + self.n + usize::from(self.offset)
    }
}

/// Output of [b(z) v + q(z) δ]/a(z) + c; also returns y_lin (without c).
pub(in crate::fit) fn simulate<T: Real>(
    a: &[T],
    b: &[T],
    q: &[T],
    c: T,
    v: &[T],
) -> (Vec<T>, Vec<T>) {
    let yl = simulate_linear(a, b, q, v);
    let y = yl.iter().map(|&x| x + c).collect();
    (y, yl)
}

/// The y_lin of [`simulate`] alone (its output is y_lin + c, formed where it is read: long
/// records keep one signal less).
pub(in crate::fit) fn simulate_linear<T: Real>(a: &[T], b: &[T], q: &[T], v: &[T]) -> Vec<T> {
    // the difference equation, q(k) entering after the numerator's sum (`TfFilter`)
    let mut yl = TfFilter::new(a.len() - 1).run_with(a, b, q, v);
    yl.drain(..a.len() - 1);
    yl
}

/// `linear_ls::mse` of y against y_lin + c, the sum formed in the same order.
pub(in crate::fit) fn mse_with_offset<T: Real>(y: &[T], yl: &[T], c: T) -> f64 {
    add_squares(0.0, y, yl, c) / y.len().max(1) as f64
}

/// Refines θ, the linear block, x0 and the offset from the loop's iterate; `None` when the MSE did
/// not fall.
pub(crate) fn refine<T: Real>(
    problem: &Problem<'_, T>,
    nl: &dyn StaticNonlinearity<T>,
    it: &Iterate<T>,
) -> Result<(Option<Iterate<T>>, RefineReport)> {
    refine_with(problem, nl, it, MAX_LM_ITER)
}

/// [`refine`] with at most `max_iter` LM iterations (the polish of a screened fit on the whole
/// record takes a few).
pub(crate) fn refine_with<T: Real>(
    problem: &Problem<'_, T>,
    nl: &dyn StaticNonlinearity<T>,
    it: &Iterate<T>,
    max_iter: usize,
) -> Result<(Option<Iterate<T>>, RefineReport)> {
    let not_accepted = |iters| RefineReport {
        mse_before: it.mse,
        mse_after: it.mse,
        iterations: iters,
        accepted: false,
    };
    // a start whose numerics fail (the free response of an unstable loop block overflowing its
    // least squares) is no start: the loop's iterate is kept, as for a refinement that finds
    // nothing better
    let start = match start_point(problem, nl, it) {
        Err(Error::LinAlg(_) | Error::NonFinite { .. }) => None,
        other => other?,
    };
    let Some((mut point, layout)) = start else {
        return Ok((None, not_accepted(0)));
    };
    let mut lm = Lm {
        fit: Branch::new(problem, layout, nl.clone_box(), &point, true),
        mu: T::lit(1e-3),
        tol: problem.settings.lm_tol.unwrap_or(LM_TOL),
        held: Vec::new(),
    };
    let Some(mut eval) = lm.cost(&point) else {
        return Ok((None, not_accepted(0)));
    };
    let start_mse = eval.mse;
    let mut iters = 0;
    for _ in 0..max_iter {
        iters += 1;
        if problem.y.len() < lm.fit.layout.len() + 1 || !lm.iteration(&mut point, &mut eval) {
            break;
        }
    }
    let cur = eval.mse;
    // restore the accepted θ in `work`
    let _ = lm.fit.work.set_params(&point.theta);
    if !(cur < it.mse && cur < start_mse * (1.0 + 1e-15)) {
        return Ok((None, not_accepted(iters)));
    }
    let refined = point.into_iterate(lm.fit.layout.n, lm.fit.work.params(), cur);
    Ok((
        Some(refined),
        RefineReport {
            mse_before: it.mse,
            mse_after: cur,
            iterations: iters,
            accepted: true,
        },
    ))
}

/// `it` with the jump parameters of `nl` (set to `it`'s θ here) moved to the posterior medians
/// over the intervals the training record resolves them to (`jump_centre`); `it` itself when none
/// moved. The likelihood is the **profile** over the other parameters: each evaluation holds the
/// jump parameters and gives the rest (θ, block, free response, offset) `PROFILE_ITERATIONS` LM
/// iterations. The section (the rest held) is far narrower than what the record resolves when
/// the others can compensate a moved jump — a UDN's dead-zone b beside a preload is exactly flat
/// inside its interval once e1, e2 (and z1, z2) follow, while its section peaks at the fitted b.
pub(crate) fn centre_jumps<T: Real>(
    problem: &Problem<'_, T>,
    nl: &dyn StaticNonlinearity<T>,
    it: Iterate<T>,
) -> Iterate<T> {
    let held = nl.jump_params();
    if held.is_empty() {
        return it;
    }
    let mut work = nl.clone_box();
    if work.set_params(&it.theta).is_err() {
        return it;
    }
    // the profile only where a crossing sample shows above the noise (`jump_matters`, the scan's
    // gate): elsewhere it would cost ≈ 30 LM iterations for positions the noise hides, and the
    // section (no iteration) is kept
    let iterations = match jumps_that_matter(problem, work.as_ref(), &it) {
        Some(j) if !j.is_empty() => PROFILE_ITERATIONS,
        _ => 0,
    };
    let Ok(Some((point, layout))) = start_point(problem, work.as_ref(), &it) else {
        return it;
    };
    let mut lm = Lm {
        fit: Branch::new(problem, layout, work, &point, iterations > 0),
        mu: T::lit(1e-3),
        tol: problem.settings.lm_tol.unwrap_or(LM_TOL),
        held,
    };
    let Some(start) = lm.cost(&point) else {
        return it;
    };
    // `centred_theta` sets θ on its own copy of `nl` before reading the jump positions
    let moved = centred_theta(nl, &problem.u, &point.theta, start.mse, |t| {
        profiled(&mut lm, &point, t, iterations).map(|(_, m)| m)
    });
    let Some((theta, _)) = moved else {
        return it;
    };
    let Some((p, mse)) = profiled(&mut lm, &point, &theta, iterations) else {
        return it;
    };
    if lm.fit.work.set_params(&p.theta).is_err() {
        return it;
    }
    let theta = lm.fit.work.params();
    p.into_iterate(lm.fit.layout.n, theta, mse)
}

/// `point` with θ set to `theta` and the parameters `lm` does not hold re-adapted by
/// `iterations` LM iterations (0: the section), and its training MSE; `None` when θ is
/// inadmissible.
fn profiled<T: Real>(
    lm: &mut Lm<'_, '_, T>,
    point: &Point<T>,
    theta: &[T],
    iterations: usize,
) -> Option<(Point<T>, f64)> {
    let mut p = point.clone();
    p.theta = theta.to_vec();
    let mut e = lm.cost(&p)?;
    lm.mu = T::lit(1e-3);
    for _ in 0..iterations {
        if !lm.iteration(&mut p, &mut e) {
            break;
        }
    }
    Some((p, e.mse))
}

/// `it` restarted from other values of its threshold parameters: for each jump parameter of
/// `nl` whose jumps matter to the record (`jump_matters`: never on an exact fit), `SCAN_POINTS`
/// starts with it at an order statistic of its positions (`jump_scan.rs`); for each kink
/// parameter (a saturation limit) whose neighbourhood the residual says is misplaced
/// (`kink_scan.rs`), starts at other clipped shares. Each start gets `SCAN_ITERATIONS` LM
/// iterations with every parameter free; the best start is refined to its end and returned when
/// its training MSE is below `it`'s. `None` otherwise.
pub(crate) fn scan_restarts<T: Real>(
    problem: &Problem<'_, T>,
    nl: &dyn StaticNonlinearity<T>,
    it: &Iterate<T>,
) -> Option<Iterate<T>> {
    let mut work = nl.clone_box();
    work.set_params(&it.theta).ok()?;
    // the jumps' gate first: it reads θ and the block's transfer function only
    let jumps = jumps_that_matter(problem, work.as_ref(), it)?;
    let kinks = if fit_is_exact(it.mse, problem.floor) {
        Vec::new()
    } else {
        work.kink_params()
    };
    if jumps.is_empty() && kinks.is_empty() {
        return None;
    }
    let (point, layout) = start_point(problem, work.as_ref(), it).ok()??;
    // the kinks' gate reads the start's residual, simulated without the refinement's set-up
    // (which the benchmark record, whose gates both say no, would pay for nothing)
    let kink_starts = if kinks.is_empty() {
        Vec::new()
    } else {
        work.set_params(&point.theta).ok()?;
        let v = work.eval(&problem.u);
        let yl = simulate_linear(&point.a, &point.b, &point.q, &v);
        let residual: Vec<T> = problem
            .y
            .iter()
            .zip(&yl)
            .map(|(&y, &yl)| y - yl - point.c)
            .collect();
        kink_starts(work.as_mut(), &problem.u, &point, &kinks, &residual)?
    };
    if jumps.is_empty() && kink_starts.is_empty() {
        return None;
    }
    let mut lm = Lm {
        fit: Branch::new(problem, layout, work, &point, true),
        mu: T::lit(1e-3),
        tol: problem.settings.lm_tol.unwrap_or(LM_TOL),
        held: Vec::new(),
    };
    let start = lm.cost(&point)?.mse;
    let mut starts = jump_starts(&mut lm, &point, &jumps)?;
    starts.extend(kink_starts);
    if starts.is_empty() {
        return None;
    }
    let (mut p, _) = best_start(&mut lm, &point, &starts)?;
    // an iteration that found no step leaves its signals emptied: simulate the best start anew
    let mut e = lm.cost(&p)?;
    if e.mse >= start {
        return None;
    }
    lm.mu = T::lit(1e-3);
    for _ in 0..MAX_LM_ITER {
        if !lm.iteration(&mut p, &mut e) {
            break;
        }
    }
    if !(e.mse < start && e.mse < it.mse) {
        return None;
    }
    lm.fit.work.set_params(&p.theta).ok()?;
    let theta = lm.fit.work.params();
    Some(p.into_iterate(lm.fit.layout.n, theta, e.mse))
}

/// The jump parameters of `nl` (its θ set to `it`'s) whose jumps matter to the record fitted by
/// `it` (`jump_matters`: the output step above the residual's RMS, the fit not exact); `None`
/// when the block has no transfer function.
fn jumps_that_matter<T: Real>(
    problem: &Problem<'_, T>,
    nl: &dyn StaticNonlinearity<T>,
    it: &Iterate<T>,
) -> Option<Vec<usize>> {
    let tf = to_statespace(it).ok()?.transfer_function(0, 0).ok()?;
    let to_t = |v: &[f64]| v.iter().map(|&x| T::lit(x)).collect::<Vec<T>>();
    let gain = block_gain(
        &to_t(&tf.denominator),
        &to_t(&tf.numerator),
        problem.y.len(),
    );
    Some(
        nl.jump_params()
            .into_iter()
            .filter(|&j| jump_matters(nl.jump_step(j), gain, it.mse, problem.floor))
            .collect(),
    )
}

/// The starts of the jump parameters `jumps` from `point`: each at `SCAN_POINTS` order
/// statistics of its positions and in the intervals near its value (`local_values`), as
/// (parameter, value) pairs.
fn jump_starts<T: Real>(
    lm: &mut Lm<'_, '_, T>,
    point: &Point<T>,
    jumps: &[usize],
) -> Option<Vec<(usize, T)>> {
    let mut out = Vec::new();
    for &j in jumps {
        lm.fit.work.set_params(&point.theta).ok()?;
        let positions = lm.fit.work.jump_positions(j, &lm.fit.problem.u);
        let mut probe = lm.fit.work.clone_box();
        let mut admissible = |x| {
            let mut th = point.theta.clone();
            th[j] = x;
            probe.set_params(&th).is_ok()
        };
        let spread = scan_values(&positions, SCAN_POINTS, &mut admissible);
        let local = local_values(&positions, point.theta[j], &mut admissible);
        out.extend(spread.into_iter().chain(local).map(|x| (j, x)));
    }
    Some(out)
}

/// The starts of the kink parameters `kinks` of `work` (over the input `u`) from `point` whose
/// neighbourhood holds a larger residual than the record (`near_kink_ratio` above
/// `MIN_NEAR_KINK_RATIO`), at the clipped shares of `kink_values`, as (parameter, value) pairs.
fn kink_starts<T: Real>(
    work: &mut dyn StaticNonlinearity<T>,
    u: &[T],
    point: &Point<T>,
    kinks: &[usize],
    residual: &[T],
) -> Option<Vec<(usize, T)>> {
    let mut out = Vec::new();
    for &j in kinks {
        work.set_params(&point.theta).ok()?;
        let positions = work.kink_positions(j, u);
        if near_kink_ratio(&positions, point.theta[j], residual) <= MIN_NEAR_KINK_RATIO {
            continue;
        }
        let mut probe = work.clone_box();
        let values = kink_values(&positions, point.theta[j], |x| {
            let mut th = point.theta.clone();
            th[j] = x;
            probe.set_params(&th).is_ok()
        });
        out.extend(values.into_iter().map(|x| (j, x)));
    }
    Some(out)
}

/// The best of the `starts` (parameter, value) from `point` after `SCAN_ITERATIONS` LM
/// iterations each, with its MSE; `None` when none could be evaluated.
fn best_start<T: Real>(
    lm: &mut Lm<'_, '_, T>,
    point: &Point<T>,
    starts: &[(usize, T)],
) -> Option<(Point<T>, f64)> {
    let mut best: Option<(Point<T>, f64)> = None;
    for &(j, x) in starts {
        let mut p = point.clone();
        p.theta[j] = x;
        let Some(mut e) = lm.cost(&p) else {
            continue;
        };
        lm.mu = T::lit(1e-3);
        for _ in 0..SCAN_ITERATIONS {
            if !lm.iteration(&mut p, &mut e) {
                break;
            }
        }
        if best.as_ref().is_none_or(|(_, b)| e.mse < *b) {
            best = Some((p, e.mse));
        }
    }
    best
}

/// A point of the refinement: θ, the transfer function's denominator a and numerator b, the
/// free response's numerator q and the offset c (also the block part of the output map's joint
/// refinement, `output_fit::MapPoint`).
#[derive(Clone)]
pub(in crate::fit) struct Point<T: Real> {
    pub theta: Vec<T>,
    pub a: Vec<T>,
    pub b: Vec<T>,
    pub q: Vec<T>,
    pub c: T,
}

impl<T: Real> Point<T> {
    /// The point moved by the LM step `step` (its rows in the order of `layout`).
    pub(in crate::fit) fn moved(&self, step: &Mat<T>, layout: &Layout) -> Self {
        let mut p = self.clone();
        let col = p.move_block(step, &layout.free_b);
        if layout.offset {
            p.c += step[(col, 0)];
        }
        p
    }

    /// Adds the leading rows of the LM step `step` to θ, a₁…aₙ, the free b (indices `free_b`)
    /// and q, in that order; returns the next row (the caller's further parameters: the map's
    /// w, the offset c).
    pub(in crate::fit) fn move_block(&mut self, step: &Mat<T>, free_b: &[usize]) -> usize {
        let mut col = 0;
        let mut take = |x: &mut T| {
            *x += step[(col, 0)];
            col += 1;
        };
        self.theta.iter_mut().for_each(&mut take);
        self.a.iter_mut().skip(1).for_each(&mut take);
        for &bk in free_b {
            take(&mut self.b[bk]);
        }
        self.q.iter_mut().for_each(&mut take);
        col
    }

    /// The iterate of order `n` in observer canonical form: A = [−a | I; 0], B_k = b_k − a_k b_0,
    /// C = e1ᵀ, D = b_0, x0 = q, with the nonlinearity parameters `theta` and MSE `mse`.
    pub(in crate::fit) fn into_iterate(self, n: usize, theta: Vec<T>, mse: f64) -> Iterate<T> {
        let (a, b) = (&self.a, &self.b);
        let am = Mat::from_fn(n, n, |i, j| {
            if j == 0 {
                -a[i + 1]
            } else if j == i + 1 {
                T::one()
            } else {
                T::zero()
            }
        });
        let bo: Vec<T> = (0..n).map(|i| b[i + 1] - a[i + 1] * b[0]).collect();
        let cm = Mat::from_fn(1, n, |_, j| if j == 0 { T::one() } else { T::zero() });
        Iterate {
            theta,
            a: am,
            b: bo,
            c: cm,
            d: b[0],
            x0: self.q,
            offset: self.c,
            mse,
        }
    }
}

/// The refinement's starting point from the iterate `it` (its block as a transfer function, the
/// free response and offset by least squares given θ, a, b) and the parameter layout; `None`
/// when the block has no transfer function or a zero numerator.
pub(in crate::fit) fn start_point<T: Real>(
    problem: &Problem<'_, T>,
    nl: &dyn StaticNonlinearity<T>,
    it: &Iterate<T>,
) -> Result<Option<(Point<T>, Layout)>> {
    let n = it.a.nrows();
    let ss = StateSpace::new(
        it.a.clone(),
        Mat::from_fn(n, 1, |i, _| it.b[i]),
        it.c.clone(),
        Mat::from_fn(1, 1, |_, _| it.d),
    )?;
    let Ok(tf) = ss.transfer_function(0, 0) else {
        return Ok(None);
    };
    let mut a: Vec<T> = tf.denominator.iter().map(|&x| T::lit(x)).collect();
    // a stability-constrained refinement starts inside the circle: an unstable block's poles
    // shrunk uniformly to `MAX_POLE_RADIUS` (the loop's own rule for its intermediate blocks)
    if problem.refuses_block(&a) {
        let rho = ss.spectral_radius()?;
        a = roots_scaled(&a, MAX_POLE_RADIUS / rho);
    }
    let mut b: Vec<T> = tf.numerator.iter().map(|&x| T::lit(x)).collect();
    if !problem.settings.options.with_d {
        b[0] = T::zero();
    }
    // the scale G·N = (G/s)·(s·N) is fixed by holding the largest numerator coefficient: holding
    // the first one (the Markov normalisation) makes the path to the optimum a long curved valley
    // when that coefficient is small (slow or high-order blocks; LM then crawls). The model's own
    // normalisation is re-applied afterwards.
    let bmax = b.iter().fold(T::zero(), |m, x| m.max(x.abs()));
    if bmax.partial_cmp(&T::zero()) != Some(std::cmp::Ordering::Greater) {
        return Ok(None);
    }
    let Some(k0) = b.iter().position(|x| x.abs() == bmax) else {
        return Ok(None);
    };
    let start = if problem.settings.options.with_d {
        0
    } else {
        1
    };
    let layout = Layout {
        n_theta: nl.params().len(),
        n,
        free_b: (start..=n).filter(|&k| k != k0).collect(),
        offset: problem.fits_offset(nl),
    };
    let work = nl.clone_box();
    // initial q, c: least squares on the free-response basis given θ, a, b (chunked QR)
    let v0 = work.eval(&problem.u);
    let yl0 = LinearOutput::filtered(&a, &b, &[], &v0);
    let sol = free_response_fit(problem.la, &a, &problem.y, yl0, layout.offset)?;
    drop(v0);
    let q: Vec<T> = sol[..n].to_vec();
    let c = if layout.offset { sol[n] } else { T::zero() };
    let theta = work.params();
    Ok(Some((Point { theta, a, b, q, c }, layout)))
}

/// A point's simulation: its MSE and v = N(u; θ). The linear output y_lin and ŷ = y_lin + c
/// are not kept: the MSE and the Jacobian's rows filter them from v block by block
/// (`linear_output.rs`; a long record holds one signal, not three).
struct Eval<T: Real> {
    mse: f64,
    v: Vec<T>,
}

/// One block's fixed parts of a refinement: the record, the parameter layout, the nonlinearity
/// evaluated at the points tried, the jumps' secant width and the free-response columns'
/// filter. The single-input LM (`Lm`) holds one; the several-input joint refinement
/// (`joint_refine.rs`) one per branch.
pub(in crate::fit) struct Branch<'p, 'a, T: Real> {
    pub problem: &'p Problem<'a, T>,
    pub layout: Layout,
    /// The nonlinearity evaluated at the points tried.
    pub work: Box<dyn StaticNonlinearity<T>>,
    /// Secant half-width of the jump parameters.
    pub h: T,
    /// The starting denominator (the free-response columns' filter).
    pub a_free: Vec<T>,
    /// The free-response columns' signal for `a_free` on the whole record (empty for records
    /// the Jacobian streams in blocks, or when not kept): the same in every iteration.
    pub free_cols: Vec<T>,
}

impl<'p, 'a, T: Real> Branch<'p, 'a, T> {
    /// The parts for a refinement starting at `start` (its denominator filters the free-response
    /// columns; their signal kept across iterations when `keep_free_cols`).
    pub(in crate::fit) fn new(
        problem: &'p Problem<'a, T>,
        layout: Layout,
        work: Box<dyn StaticNonlinearity<T>>,
        start: &Point<T>,
        keep_free_cols: bool,
    ) -> Self {
        Branch {
            problem,
            layout,
            work,
            h: secant_width(&problem.u),
            a_free: start.a.clone(),
            free_cols: if keep_free_cols {
                free_response_signal(&start.a, problem.y.len())
            } else {
                Vec::new()
            },
        }
    }

    /// The Jacobian's row stream at `point` (simulated as `v`, its linear output `yl`), with an
    /// offset column when `offset`.
    pub(in crate::fit) fn stream<'s>(
        &'s self,
        point: &'s Point<T>,
        v: &'s [T],
        yl: LinearOutput<'s, T>,
        offset: bool,
    ) -> JacobianStream<'s, T> {
        let stream = JacobianStream::new(
            self.work.as_ref(),
            &self.problem.u,
            &point.a,
            &point.b,
            v,
            yl,
            &self.layout.free_b,
            offset,
            self.h,
            &self.a_free,
        );
        if self.free_cols.is_empty() {
            stream
        } else {
            stream.with_free_cols(&self.free_cols)
        }
    }
}

/// The Levenberg–Marquardt iteration's fixed parts and its damping μ.
struct Lm<'p, 'a, T: Real> {
    fit: Branch<'p, 'a, T>,
    mu: T,
    /// Relative stopping tolerance (`LM_TOL` unless the settings loosen it).
    tol: f64,
    /// θ indices held at their value (a profile over them: `centre_jumps`); empty elsewhere.
    held: Vec<usize>,
}

impl<T: Real> Lm<'_, '_, T> {
    /// The simulation of `point`; `None` when θ is inadmissible or the MSE not finite.
    fn cost(&mut self, point: &Point<T>) -> Option<Eval<T>> {
        // a stability-constrained refinement refuses a step out of the circle as it refuses
        // an inadmissible θ (the damping then grows and the step shrinks towards the boundary)
        if self.fit.problem.refuses_block(&point.a) {
            return None;
        }
        self.fit.work.set_params(&point.theta).ok()?;
        let v = self.fit.work.eval(&self.fit.problem.u);
        let m = mse_filtered(
            &point.a,
            &point.b,
            &point.q,
            point.c,
            &v,
            &self.fit.problem.y,
        );
        if m.is_finite() {
            Some(Eval { mse: m, v })
        } else {
            None
        }
    }

    /// One LM iteration from `point` (simulated as `eval`): both updated when a step lowered the
    /// MSE; true when it lowered it by more than `LM_TOL` (relative).
    fn iteration(&mut self, point: &mut Point<T>, eval: &mut Eval<T>) -> bool {
        let p = self.fit.layout.len();
        // one QR of [J | r] per iteration (Moré 1978), accumulated block by block: R and Qᵀr
        // serve every μ below, each trial then solves the small (2p × p) problem
        // [R; √μ·D] δ = [Qᵀr; 0]
        let yl = LinearOutput::filtered(&point.a, &point.b, &point.q, &eval.v);
        let stream = self.fit.stream(point, &eval.v, yl, self.fit.layout.offset);
        let Ok(rf) = residual_factor(self.fit.problem.la, stream, &self.fit.problem.y, point.c)
        else {
            return false;
        };
        // the iterate's v is not read again (an accepted trial brings its own, and only the MSE
        // is read after the last iteration): on long records a trial then holds one signal,
        // not two
        eval.v = Vec::new();
        let mut scale = column_scale(&rf, p, T::min_positive_value());
        pin_held(&mut scale, &self.held);
        for _ in 0..12 {
            let Some(mut step) = damped_step(self.fit.problem.la, &rf, &scale, self.mu) else {
                return false;
            };
            for &j in &self.held {
                step[(j, 0)] = T::zero();
            }
            // a step the linearised model promises less than the tolerance counts as converged
            // (Moré 1978's prered test): at a kink of the cost the damped steps that follow only
            // shrink, and each costs a simulation
            if predicted_reduction(&rf, &step) < self.tol {
                return false;
            }
            let trial = point.moved(&step, &self.fit.layout);
            match self.cost(&trial) {
                Some(e) if e.mse < eval.mse => {
                    let rel = (eval.mse - e.mse) / eval.mse.max(f64::MIN_POSITIVE);
                    (*point, *eval) = (trial, e);
                    self.mu = (self.mu / T::lit(3.0)).max(T::lit(1e-12));
                    // a tiny decrease counts as converged
                    return rel > self.tol;
                }
                _ => {
                    self.mu *= T::lit(4.0);
                }
            }
        }
        false
    }
}

/// Marquardt's scaling of the `held` columns raised far above every other column's: the damped
/// step then leaves those parameters still (a penalty on their move, Moré 1978's D) and gives the
/// others the step of the problem without them — the profile over the held parameters.
fn pin_held<T: Real>(scale: &mut [T], held: &[usize]) {
    let top = scale.iter().fold(T::one(), |m, &x| m.max(x));
    for &j in held {
        if let Some(s) = scale.get_mut(j) {
            *s = top * T::lit(PIN_SCALE);
        }
    }
}

/// Half-width of the secant of a jump parameter: `JUMP_SECANT_FRACTION` of the input's spread.
pub(in crate::fit) fn secant_width<T: Real>(u: &[T]) -> T {
    T::lit(JUMP_SECANT_FRACTION) * spread(u)
}

/// ∂v/∂θ with the columns of the nonlinearity's jump parameters replaced by secant slopes over
/// ±`h` (one-sided at the admissible range's edge): at a moving jump the derivative almost
/// everywhere is blind to the samples the jump passes, and LM steps built on it fail until μ has
/// shrunk them to nothing.
fn jacobian_with_secants<T: Real>(nl: &dyn StaticNonlinearity<T>, u: &[T], h: T) -> Mat<T> {
    let mut jv = nl.param_jacobian(u);
    let jumps = nl.jump_params();
    if jumps.is_empty() {
        return jv;
    }
    if h.partial_cmp(&T::zero()) != Some(std::cmp::Ordering::Greater) {
        return jv;
    }
    let theta = nl.params();
    let mut probe = nl.clone_box();
    let mut at = |t: T, j: usize| -> Option<Vec<T>> {
        let mut th = theta.clone();
        th[j] = t;
        probe.set_params(&th).ok()?;
        Some(probe.eval(u))
    };
    for j in jumps {
        let t = theta[j];
        let (hi, lo) = (at(t + h, j), at(t - h, j));
        let (vp, vm, width) = match (hi, lo) {
            (Some(p), Some(m)) => (p, m, h + h),
            (Some(p), None) => (p, nl.eval(u), h),
            (None, Some(m)) => (nl.eval(u), m, h),
            (None, None) => continue,
        };
        for k in 0..u.len() {
            jv[(k, j)] = (vp[k] - vm[k]) / width;
        }
    }
    jv
}

/// The free-response columns' signal z⁻ⁱδ/a of a record of `nn` samples, with the filter's n
/// leading zeros (what `JacobianStream` filters in its one block); empty when the record is
/// longer than `DIRECT_ROWS` (the Jacobian then streams in blocks and filters as it goes).
fn free_response_signal<T: Real>(a: &[T], nn: usize) -> Vec<T> {
    if nn > DIRECT_ROWS {
        return Vec::new();
    }
    let imp: Vec<T> = (0..nn)
        .map(|k| if k == 0 { T::one() } else { T::zero() })
        .collect();
    TfFilter::new(a.len() - 1).run(a, &[T::one()], &imp)
}

/// Samples before a block on which the nonlinearity is evaluated to recover its memory (the
/// hysteresis direction) at the block's start; the cost function itself is always evaluated on
/// the whole record, so this only affects the search direction of a step (and not at all a
/// record shorter than one block).
const NL_OVERLAP: usize = 1024;

/// The relative decrease of the sum of squares the linearised model predicts for `step` from the
/// R factor `rf` of [J | r]: (‖c‖² − ‖c − Rδ‖²) / (‖c‖² + ρ²), c = Qᵀr (Moré 1978's prered).
pub(in crate::fit) fn predicted_reduction<T: Real>(rf: &Mat<T>, step: &Mat<T>) -> f64 {
    let p = rf.ncols() - 1;
    let mut before = 0.0;
    let mut after = 0.0;
    for i in 0..p {
        let c = rf[(i, p)].as_f64();
        let rd: f64 = (i..p)
            .map(|j| rf[(i, j)].as_f64() * step[(j, 0)].as_f64())
            .sum();
        before += c * c;
        after += (c - rd) * (c - rd);
    }
    let rho = rf[(p, p)].as_f64();
    (before - after) / (before + rho * rho).max(f64::MIN_POSITIVE)
}

/// Marquardt's scaling D of the first `p` columns of the R factor `rf`: the column norms of R
/// (those of J), at least `floor`.
pub(in crate::fit) fn column_scale<T: Real>(rf: &Mat<T>, p: usize, floor: T) -> Vec<T> {
    (0..p)
        .map(|j| {
            (0..=j)
                .fold(T::zero(), |s, i| s + rf[(i, j)] * rf[(i, j)])
                .sqrt()
                .max(floor)
        })
        .collect()
}

/// The Levenberg–Marquardt step for damping `mu` from the R factor `rf` ((p + 1)², of [J | r])
/// with Marquardt's scaling `scale`: the least-squares solution of [R; √μ·D] δ = [Qᵀr; 0]
/// (Moré 1978: one QR per iteration, each μ a small 2p × p problem).
pub(in crate::fit) fn damped_step<T: Real>(
    la: &dyn LinAlg<T>,
    rf: &Mat<T>,
    scale: &[T],
    mu: T,
) -> Option<Mat<T>> {
    let p = scale.len();
    let aug = Mat::<T>::from_fn(2 * p, p, |i, j| {
        if i < p {
            if i <= j { rf[(i, j)] } else { T::zero() }
        } else if i - p == j {
            mu.sqrt() * scale[j]
        } else {
            T::zero()
        }
    });
    let rhs = Mat::<T>::from_fn(2 * p, 1, |i, _| if i < p { rf[(i, p)] } else { T::zero() });
    la.lstsq(aug.as_ref(), rhs.as_ref()).ok()
}

/// The refinement's Jacobian of ŷ at (θ, a, b), row block by row block: columns θ, a₁…aₙ, the
/// free b_k, q₀…q_{n−1}, c.
pub(in crate::fit) struct JacobianStream<'a, T: Real> {
    nl: &'a dyn StaticNonlinearity<T>,
    u: &'a [T],
    a: &'a [T],
    b: &'a [T],
    v: &'a [T],
    /// The linear output y_lin (without c) at (a, b) and the free response.
    yl: LinearOutput<'a, T>,
    free_b: &'a [usize],
    offset: bool,
    h: T,
    a_free: &'a [T],
    /// The free-response columns' signal z⁻ⁱδ/a_free on the whole record (n leading zeros),
    /// when the caller keeps it across iterations (it depends on a_free alone).
    free_cols: Option<&'a [T]>,
    theta_f: ChannelFilter<T>,
    /// y_lin/a and v/a (the a and b columns), together.
    dw_f: ChannelFilter<T>,
    e_f: TfFilter<T>,
    next: usize,
}

impl<'a, T: Real> JacobianStream<'a, T> {
    /// A stream over the record `u` with the model's v = N(u; θ) and linear output `yl` (read
    /// block by block, in order); `h` is
    /// the jump parameters' secant half-width ([`secant_width`] of the whole record); the
    /// free-response columns are z⁻ⁱδ/a_free (the refinement keeps its starting denominator
    /// there, as it always has: with the current a the LM runs markedly more iterations on
    /// over-parametrised blocks for a tiny gain).
    #[allow(clippy::too_many_arguments)]
    pub(in crate::fit) fn new(
        nl: &'a dyn StaticNonlinearity<T>,
        u: &'a [T],
        a: &'a [T],
        b: &'a [T],
        v: &'a [T],
        yl: LinearOutput<'a, T>,
        free_b: &'a [usize],
        offset: bool,
        h: T,
        a_free: &'a [T],
    ) -> Self {
        let n = a.len() - 1;
        Self {
            nl,
            u,
            a,
            b,
            v,
            yl,
            free_b,
            offset,
            h,
            a_free,
            free_cols: None,
            theta_f: ChannelFilter::new(n, nl.params().len()),
            dw_f: ChannelFilter::new(n, 2),
            e_f: TfFilter::new(n),
            next: 0,
        }
    }

    /// The stream with the free-response columns' signal `e` of the whole record given
    /// ([`free_response_signal`] of its a_free and record length).
    pub(in crate::fit) fn with_free_cols(mut self, e: &'a [T]) -> Self {
        self.free_cols = Some(e);
        self
    }

    /// Number of columns.
    pub(in crate::fit) fn cols(&self) -> usize {
        let n = self.a.len() - 1;
        self.n_theta() + n + self.free_b.len() + n + usize::from(self.offset)
    }

    /// Number of nonlinearity parameters.
    fn n_theta(&self) -> usize {
        self.nl.params().len()
    }

    /// The next block of at most `rows` rows (`None` at the end of the record), and its first
    /// sample's index; the block has one more column than the Jacobian, left zero.
    pub(in crate::fit) fn next_block(&mut self, rows: usize) -> Option<(usize, Mat<T>)> {
        self.next_rows(rows).map(|(k0, jac, _)| (k0, jac))
    }

    /// [`next_block`](Self::next_block) with its last column the residual y − (y_lin + c) of
    /// the record's output `y`: a block of [J | r].
    pub(in crate::fit) fn next_block_with_residual(
        &mut self,
        rows: usize,
        y: &[T],
        c: T,
    ) -> Option<(usize, Mat<T>)> {
        let (k0, mut jac, yl) = self.next_rows(rows)?;
        let p = jac.ncols() - 1;
        for (t, &ylt) in yl.iter().enumerate() {
            jac[(t, p)] = y[k0 + t] - (ylt + c);
        }
        Some((k0, jac))
    }

    /// [`next_block`](Self::next_block) with the block's linear output y_lin.
    fn next_rows(&mut self, rows: usize) -> Option<(usize, Mat<T>, Cow<'a, [T]>)> {
        let nn = self.u.len();
        let k0 = self.next;
        if k0 >= nn || rows == 0 {
            return None;
        }
        let k1 = (k0 + rows).min(nn);
        self.next = k1;
        let m = k1 - k0;
        let n = self.a.len() - 1;
        let one = [T::one()];
        // one spare column at the end, for the residual of [J | r]
        let mut jac = Mat::<T>::zeros(m, self.cols() + 1);
        let mut col = 0;
        let ov = k0.min(NL_OVERLAP);
        let jv = jacobian_with_secants(self.nl, &self.u[k0 - ov..k1], self.h);
        // the θ columns through b/a together (the same bits as one filter per column)
        self.theta_f.run(
            self.a,
            self.b,
            |j| &jv.col_as_slice(j)[ov..ov + m],
            |j, t, y| jac[(t, j)] = y,
        );
        col += self.n_theta();
        let (yl, v) = (self.yl.block(k0, k1), &self.v[k0..k1]);
        let dw = self
            .dw_f
            .run_extended(self.a, &one, |c| if c == 0 { &yl } else { v });
        let (d, w) = (&dw[0], &dw[1]);
        for i in 1..=n {
            for t in 0..m {
                jac[(t, col)] = -d[n + t - i];
            }
            col += 1;
        }
        for &bk in self.free_b {
            for t in 0..m {
                jac[(t, col)] = w[n + t - bk];
            }
            col += 1;
        }
        let e: Cow<'_, [T]> = match self.free_cols {
            Some(e) if k0 == 0 && k1 == nn && e.len() == n + nn => Cow::Borrowed(e),
            _ => {
                let imp: Vec<T> = (k0..k1)
                    .map(|k| if k == 0 { T::one() } else { T::zero() })
                    .collect();
                Cow::Owned(self.e_f.run(self.a_free, &one, &imp))
            }
        };
        for i in 0..n {
            for t in 0..m {
                jac[(t, col)] = e[n + t - i];
            }
            col += 1;
        }
        if self.offset {
            for t in 0..m {
                jac[(t, col)] = T::one();
            }
        }
        Some((k0, jac, yl))
    }
}

/// The refinement's Jacobian of ŷ at (θ, a, b) on the whole record (one block): columns θ,
/// a₁…aₙ, the free b_k, q₀…q_{n−1}, c.
#[allow(clippy::too_many_arguments)]
pub(in crate::fit) fn jacobian<T: Real>(
    nl: &dyn StaticNonlinearity<T>,
    u: &[T],
    a: &[T],
    b: &[T],
    v: &[T],
    yl: &[T],
    free_b: &[usize],
    offset: bool,
) -> Mat<T> {
    let yl = LinearOutput::Given(yl);
    let mut s = JacobianStream::new(nl, u, a, b, v, yl, free_b, offset, secant_width(u), a);
    let p = s.cols();
    // the spare last column is dropped in place (no copy of the block)
    s.next_block(u.len()).map_or_else(
        || Mat::zeros(0, p),
        |(_, mut m)| {
            m.truncate(m.nrows(), p);
            m
        },
    )
}

/// [`jacobian`] for records up to `DIRECT_ROWS` samples; for longer ones its R factor (p × p,
/// the same R up to round-off and row signs: what a QR of the Jacobian gives) folded in row
/// blocks by chunked QR, so that memory stays O(p²) (the standard errors' use).
#[allow(clippy::too_many_arguments)]
pub(in crate::fit) fn jacobian_or_r<T: Real>(
    la: &dyn LinAlg<T>,
    nl: &dyn StaticNonlinearity<T>,
    u: &[T],
    a: &[T],
    b: &[T],
    v: &[T],
    yl: &[T],
    free_b: &[usize],
    offset: bool,
) -> Result<Mat<T>> {
    if u.len() <= DIRECT_ROWS {
        return Ok(jacobian(nl, u, a, b, v, yl, free_b, offset));
    }
    let yl = LinearOutput::Given(yl);
    let mut s = JacobianStream::new(nl, u, a, b, v, yl, free_b, offset, secant_width(u), a);
    let p = s.cols();
    // the blocks' spare last column stays zero: R's leading p × p block is J's R
    let mut ts = Tsqr::new(la, p + 1);
    while let Some((_, blk)) = s.next_block(STREAM_ROWS) {
        ts.push_block(blk.as_ref())?;
    }
    let mut r = ts.finish()?;
    r.truncate(p, p);
    Ok(r)
}

/// Records up to this length get [J | r] whole and one QR (no chunking overhead).
pub(in crate::fit) const DIRECT_ROWS: usize = 1 << 16;
/// Rows of the Jacobian blocks of longer records (each folded into R in `BLOCK_ROWS` pieces).
const STREAM_ROWS: usize = 1 << 14;

/// The R factor ((p + 1)², upper triangular) of [J | y − ŷ], ŷ = y_lin + c, accumulated block
/// by block.
fn residual_factor<T: Real>(
    la: &dyn LinAlg<T>,
    mut stream: JacobianStream<'_, T>,
    y: &[T],
    c: T,
) -> Result<Mat<T>> {
    let p = stream.cols();
    residual_factor_of(la, p, y.len(), |rows| {
        stream.next_block_with_residual(rows, y, c)
    })
}

/// The R factor ((p + 1)², upper triangular) of [J | r] for a Jacobian of `p` columns on `nn`
/// rows produced by `next_block` (a block of [J | r] of at most the given rows, p + 1 columns,
/// with its first row's index; `None` at the end): one QR for records up to `DIRECT_ROWS`, a
/// TSQR of `STREAM_ROWS` blocks beyond (the single-input refinement's stream, or the joint
/// refinement's side-by-side branch streams).
pub(in crate::fit) fn residual_factor_of<T: Real>(
    la: &dyn LinAlg<T>,
    p: usize,
    nn: usize,
    next_block: impl FnMut(usize) -> Option<(usize, Mat<T>)>,
) -> Result<Mat<T>> {
    residual_factor_up_to(la, p, nn, DIRECT_ROWS, next_block)
}

/// [`residual_factor_of`] with records up to `direct_rows` (not `DIRECT_ROWS`) in one QR
/// (`usize::MAX`: every record, the reference the streamed fold is tested against).
pub(in crate::fit) fn residual_factor_up_to<T: Real>(
    la: &dyn LinAlg<T>,
    p: usize,
    nn: usize,
    direct_rows: usize,
    mut next_block: impl FnMut(usize) -> Option<(usize, Mat<T>)>,
) -> Result<Mat<T>> {
    let direct = nn <= direct_rows;
    let rows = if direct { nn } else { STREAM_ROWS };
    let mut ts = Tsqr::new(la, p + 1);
    while let Some((_, mut blk)) = next_block(rows) {
        if direct {
            let r = la.qr_r_in_place(blk.as_mut())?;
            return Ok(Mat::from_fn(p + 1, p + 1, |i, j| {
                if i < r.nrows() { r[(i, j)] } else { T::zero() }
            }));
        }
        ts.push_block(blk.as_ref())?;
    }
    ts.finish()
}

/// Least squares for the free response q (n values) and, with `offset`, the output offset c, on
/// y − y_lin: regressors the impulse response of 1/a(z) delayed by 0…n−1 and a constant, rows
/// folded in by chunked QR (y_lin read block by block).
pub(in crate::fit) fn free_response_fit<T: Real>(
    la: &dyn LinAlg<T>,
    a: &[T],
    y: &[T],
    mut yl0: LinearOutput<'_, T>,
    offset: bool,
) -> Result<Vec<T>> {
    let n = a.len() - 1;
    let np = n + usize::from(offset);
    let mut ts = Tsqr::new(la, np + 1);
    let mut f = TfFilter::new(n);
    let one = [T::one()];
    let mut row = vec![T::zero(); np + 1];
    let nn = y.len();
    let mut k0 = 0;
    while k0 < nn {
        let k1 = (k0 + BLOCK_ROWS).min(nn);
        let imp: Vec<T> = (k0..k1)
            .map(|k| if k == 0 { T::one() } else { T::zero() })
            .collect();
        let e = f.run(a, &one, &imp);
        let yl = yl0.block(k0, k1);
        for t in 0..k1 - k0 {
            for (j, r) in row.iter_mut().take(n).enumerate() {
                *r = e[n + t - j];
            }
            if offset {
                row[n] = T::one();
            }
            row[np] = y[k0 + t] - yl[t];
            ts.push_row(&row)?;
        }
        k0 = k1;
    }
    let r = ts.finish()?;
    Ok(solve_from_r(la, &r, nn)?.0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::solvers::Faer;

    /// A pinned column's parameter does not move, and the free ones take the step of the least
    /// squares without it (the profile's step): J = [j1 j2], the step with j2 held solves J·δ ≈ r
    /// over δ1 alone.
    #[test]
    fn a_held_parameter_stays_and_the_others_solve_without_it() {
        let j1 = [1.0, 2.0, 0.5, -1.0, 0.3];
        let j2 = [0.4, -0.7, 1.5, 0.2, 0.9];
        let r = [1.0, 0.5, -0.2, 0.8, 0.1];
        let m = Mat::<f64>::from_fn(5, 3, |i, k| [j1[i], j2[i], r[i]][k]);
        // the R factor of [J | r] (upper triangle of a QR)
        let rf = m.qr().R().to_owned();
        let rf = Mat::<f64>::from_fn(3, 3, |i, k| rf[(i, k)]);
        let mut scale = column_scale(&rf, 2, f64::MIN_POSITIVE);
        pin_held(&mut scale, &[1]);
        let step = damped_step(&Faer::default(), &rf, &scale, 1e-12).unwrap();
        let alone = j1.iter().zip(&r).map(|(a, b)| a * b).sum::<f64>()
            / j1.iter().map(|a| a * a).sum::<f64>();
        assert!(step[(1, 0)].abs() < 1e-8, "{:?}", step[(1, 0)]);
        assert!(
            (step[(0, 0)] - alone).abs() < 1e-8,
            "{} vs {alone}",
            step[(0, 0)]
        );
    }
}
