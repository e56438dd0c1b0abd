//! Levenberg–Marquardt refinement of several Hammerstein branches at once on the joint output
//! error of their sum (the several-input fit's polish after backfitting, `miso::backfit`).
//!
//! Backfitting is block-coordinate descent on the joint output error: each branch is refitted
//! with the others held, which crawls when the branches' outputs are correlated. Following the
//! backfitting by a joint Gauss–Newton/Levenberg–Marquardt step over all parameters is the
//! standard polish of additive models (Hastie & Tibshirani, *Generalized Additive Models*, 1990,
//! §4; for block-oriented systems Bai 2010). The model is
//!
//!   y(k) = Σᵢ [bᵢ(z) vᵢ(k) + qᵢ(z) δ(k)] / aᵢ(z) + c,   vᵢ = Nᵢ(uᵢ(k − nkᵢ); θᵢ),
//!
//! each branch parametrised exactly as the single-input refinement (`refine.rs`: θᵢ, aᵢ, the
//! free bᵢ with its own held numerator coefficient, qᵢ) and one shared offset c. Branch i's
//! output depends on its own parameters only, so the Jacobian is the branches' single-input
//! Jacobians side by side (`JacobianStream` each, without its offset column) and one column of
//! ones; its rows are folded into the R factor of [J | r] block by block (`residual_factor_up_to`)
//! and each LM step is Moré's (1978) damped solve with Marquardt's scaling. A step is taken only
//! when the total MSE falls.

use super::linear_output::LinearOutput;
use super::refine::{
    Branch, DIRECT_ROWS, JacobianStream, LM_TOL, MAX_LM_ITER, Point, column_scale, damped_step,
    mse_with_offset, residual_factor_up_to, simulate_linear, start_point,
};
use crate::data::IoData;
use crate::error::Result;
use crate::fit::fitted::model::HammersteinModel;
use crate::fit::iteration::problem::{Iterate, Problem, normalise_iterate, to_statespace};
use crate::real::Real;
use crate::solvers::LinAlg;
use crate::subspace::SubspaceMethod;
use faer::Mat;
use std::sync::Arc;

/// The joint refinement's result: the branches refined (each in its model's normalisation),
/// their training outputs (the first with the offset) and the total training MSE.
pub(crate) struct JointFit<T: Real> {
    /// The refined branches, in input order.
    pub branches: Vec<HammersteinModel<T>>,
    /// Each branch's training output (the first includes the offset).
    pub contributions: Vec<Vec<T>>,
    /// Total training MSE of the refined branches' sum.
    pub mse: f64,
}

/// The result of [`refine_jointly`]: the refined branches when their total training MSE is below
/// the start's, and the LM iterations run either way.
pub(crate) type JointOutcome<T> = (Option<JointFit<T>>, usize);

/// A joint point's simulation: the total MSE, each branch's linear output and v, and their sum.
struct Eval<T: Real> {
    mse: f64,
    yl: Vec<Vec<T>>,
    v: Vec<Vec<T>>,
    sum: Vec<T>,
}

/// Refines the fitted `branches` jointly on the output `y` (their sum's record): `recs[i]` is
/// branch i's record (its input, the output less the other branches' contributions: the
/// starting free response and offset are fitted there). The LM stops when an iteration lowers
/// the total MSE by less than `tolerance` (relative; the sweeps' own stop) or finds no step.
/// `None` in the result when the total MSE did not fall below `mse_before` or a branch has no
/// transfer-function form.
pub(crate) fn refine_jointly<T: Real>(
    branches: &[HammersteinModel<T>],
    recs: &[IoData<T>],
    y: &[T],
    mse_before: f64,
    tolerance: f64,
) -> Result<JointOutcome<T>> {
    refine_jointly_folding(branches, recs, y, mse_before, tolerance, DIRECT_ROWS)
}

/// [`refine_jointly`] with every iteration's rows folded in one block and one QR, whatever the
/// record's length (a test's reference for the streamed fold of records over `DIRECT_ROWS`).
#[cfg(test)]
pub(crate) fn refine_jointly_whole<T: Real>(
    branches: &[HammersteinModel<T>],
    recs: &[IoData<T>],
    y: &[T],
    mse_before: f64,
    tolerance: f64,
) -> Result<JointOutcome<T>> {
    refine_jointly_folding(branches, recs, y, mse_before, tolerance, usize::MAX)
}

/// [`refine_jointly`] with records up to `direct_rows` folded in one QR per iteration, longer
/// ones streamed (`refine::residual_factor_up_to`).
fn refine_jointly_folding<T: Real>(
    branches: &[HammersteinModel<T>],
    recs: &[IoData<T>],
    y: &[T],
    mse_before: f64,
    tolerance: f64,
    direct_rows: usize,
) -> Result<JointOutcome<T>> {
    let las = branches
        .iter()
        .map(|b| b.settings.linalg_backend())
        .collect::<Result<Vec<Arc<dyn LinAlg<T>>>>>()?;
    let methods = branches
        .iter()
        .map(|b| b.settings.subspace_at(b.settings.options.horizon))
        .collect::<Result<Vec<Arc<dyn SubspaceMethod<T>>>>>()?;
    let problems: Vec<Problem<'_, T>> = (0..branches.len().min(recs.len()))
        .map(|i| {
            Problem::new(
                las[i].as_ref(),
                methods[i].as_ref(),
                &branches[i].settings,
                &recs[i],
            )
        })
        .collect();
    if problems.len() != branches.len() || problems.iter().any(|p| p.y.len() != y.len()) {
        return Ok((None, 0));
    }
    let nn = y.len();
    let mut parts = Vec::with_capacity(branches.len());
    let mut points = Vec::with_capacity(branches.len());
    let mut offset = false;
    let mut c = T::zero();
    for (i, (b, problem)) in branches.iter().zip(&problems).enumerate() {
        let Ok(Some((mut point, mut layout))) =
            start_point(problem, b.nl.as_ref(), &Iterate::of_model(b, f64::INFINITY))
        else {
            return Ok((None, 0));
        };
        // one offset for the sum: the first branch's (as the backfitting fits it)
        if i == 0 {
            offset = layout.offset;
            c = point.c;
        }
        layout.offset = false;
        point.c = T::zero();
        parts.push(Branch::new(problem, layout, b.nl.clone_box(), &point, true));
        points.push(point);
    }
    let mut lm = JointLm {
        parts,
        y,
        offset,
        mu: T::lit(1e-3),
        tolerance: tolerance.max(LM_TOL),
        direct_rows,
    };
    let Some(mut eval) = lm.cost(&points, c) else {
        return Ok((None, 0));
    };
    let p = lm.len();
    let mut iterations = 0;
    for _ in 0..MAX_LM_ITER {
        iterations += 1;
        if nn < p + 1 || !lm.iteration(&mut points, &mut c, &mut eval) {
            break;
        }
    }
    if eval.mse.partial_cmp(&mse_before) != Some(std::cmp::Ordering::Less) {
        return Ok((None, iterations));
    }
    let mut refined = Vec::with_capacity(branches.len());
    let mut contributions = Vec::with_capacity(branches.len());
    let parts = lm.parts;
    for (i, ((part, mut point), yl)) in parts.into_iter().zip(points).zip(eval.yl).enumerate() {
        let mut nl = part.work;
        nl.set_params(&point.theta)?;
        let shift = if i == 0 { c } else { T::zero() };
        point.c = shift;
        let mut it = point.into_iterate(part.layout.n, nl.params(), eval.mse);
        normalise_iterate(part.problem, nl.as_mut(), &mut it);
        let mut linear = to_statespace(&it)?;
        linear.ts = branches[i].linear.ts;
        let mut model = branches[i].clone();
        model.nl = nl;
        model.linear = linear;
        model.offset = it.offset;
        model.x0 = it.x0;
        model.report.train_mse = eval.mse;
        refined.push(model);
        contributions.push(yl.into_iter().map(|x| x + shift).collect());
    }
    Ok((
        Some(JointFit {
            branches: refined,
            contributions,
            mse: eval.mse,
        }),
        iterations,
    ))
}

/// The joint LM iteration's fixed parts (the branches, the output, whether the offset is
/// fitted) and its damping μ.
struct JointLm<'p, 'a, 'y, T: Real> {
    parts: Vec<Branch<'p, 'a, T>>,
    y: &'y [T],
    offset: bool,
    mu: T,
    /// Relative MSE fall of an iteration below which the LM stops.
    tolerance: f64,
    /// Records up to this length fold their rows into R in one QR, longer ones stream.
    direct_rows: usize,
}

impl<T: Real> JointLm<'_, '_, '_, T> {
    /// Number of parameters: every branch's and the offset.
    fn len(&self) -> usize {
        self.parts.iter().map(|p| p.layout.len()).sum::<usize>() + usize::from(self.offset)
    }

    /// The simulation of the branches at `points` with the offset `c`; `None` when a θ is
    /// inadmissible or the MSE not finite.
    fn cost(&mut self, points: &[Point<T>], c: T) -> Option<Eval<T>> {
        let mut sum = vec![T::zero(); self.y.len()];
        let (mut yls, mut vs) = (Vec::new(), Vec::new());
        for (part, point) in self.parts.iter_mut().zip(points) {
            // the stability constraint, as in one branch's refinement (`refine::Lm::cost`)
            if part.problem.refuses_block(&point.a) {
                return None;
            }
            part.work.set_params(&point.theta).ok()?;
            let v = part.work.eval(&part.problem.u);
            let yl = simulate_linear(&point.a, &point.b, &point.q, &v);
            for (s, x) in sum.iter_mut().zip(&yl) {
                *s += *x;
            }
            yls.push(yl);
            vs.push(v);
        }
        let mse = mse_with_offset(self.y, &sum, c);
        mse.is_finite().then_some(Eval {
            mse,
            yl: yls,
            v: vs,
            sum,
        })
    }

    /// One LM iteration from `points` and `c` (simulated as `eval`): all updated when a step
    /// lowered the total MSE; true when it lowered it by more than the tolerance (relative).
    fn iteration(&mut self, points: &mut Vec<Point<T>>, c: &mut T, eval: &mut Eval<T>) -> bool {
        let p = self.len();
        let la = self.parts[0].problem.la;
        let nn = self.y.len();
        let offset = self.offset;
        let rf = {
            let mut streams: Vec<JacobianStream<'_, T>> = self
                .parts
                .iter()
                .zip(points.iter())
                .zip(eval.v.iter().zip(&eval.yl))
                .map(|((part, point), (v, yl))| {
                    part.stream(point, v, LinearOutput::Given(yl), false)
                })
                .collect();
            let (y, sum, c0) = (self.y, &eval.sum, *c);
            // each row block: the branches' blocks side by side, then the offset's ones, then
            // the residual y − (Σ branches + c)
            let next = |rows: usize| {
                let mut out: Option<(usize, Mat<T>)> = None;
                let mut col = 0;
                for s in streams.iter_mut() {
                    let (k0, blk) = s.next_block(rows)?;
                    let (_, o) = out.get_or_insert_with(|| (k0, Mat::zeros(blk.nrows(), p + 1)));
                    let w = blk.ncols() - 1;
                    for j in 0..w {
                        for t in 0..blk.nrows() {
                            o[(t, col + j)] = blk[(t, j)];
                        }
                    }
                    col += w;
                }
                if let Some((_, o)) = out.as_mut().filter(|_| offset) {
                    for t in 0..o.nrows() {
                        o[(t, col)] = T::one();
                    }
                }
                if let Some((k0, o)) = out.as_mut() {
                    for t in 0..o.nrows() {
                        o[(t, p)] = y[*k0 + t] - (sum[*k0 + t] + c0);
                    }
                }
                out
            };
            residual_factor_up_to(la, p, nn, self.direct_rows, next)
        };
        let Ok(rf) = rf else {
            return false;
        };
        let scale = column_scale(&rf, p, T::min_positive_value());
        for _ in 0..12 {
            let Some(step) = damped_step(la, &rf, &scale, self.mu) else {
                return false;
            };
            let mut at = 0;
            let trial: Vec<Point<T>> = self
                .parts
                .iter()
                .zip(points.iter())
                .map(|(part, point)| {
                    let w = part.layout.len();
                    let own = Mat::from_fn(w, 1, |r, _| step[(at + r, 0)]);
                    at += w;
                    point.moved(&own, &part.layout)
                })
                .collect();
            let tc = if offset { *c + step[(at, 0)] } else { *c };
            match self.cost(&trial, tc) {
                Some(e) if e.mse < eval.mse => {
                    let rel = (eval.mse - e.mse) / eval.mse.max(f64::MIN_POSITIVE);
                    (*points, *c, *eval) = (trial, tc, e);
                    self.mu = (self.mu / T::lit(3.0)).max(T::lit(1e-12));
                    // a decrease the sweeps would stop at counts as converged
                    return rel > self.tolerance;
                }
                _ => {
                    self.mu *= T::lit(4.0);
                }
            }
        }
        false
    }
}
