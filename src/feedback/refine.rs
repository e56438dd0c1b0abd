//! Output-error Levenberg–Marquardt refinement of a feedback model: all parameters (A, B, C,
//! D, E, the nonlinearity's θ, the offsets and the initial state) at once, or the initial state
//! alone (a validation record's x0).
//!
//! Each iteration takes the exact Jacobian from the forward sensitivity recursion
//! ([`super::simulate`]), the QR factor R of [J r] (so Qᵀr comes with it), and solves the damped
//! problem min ‖J δ − r‖² + λ‖D δ‖² through the small stacked system [R; √λ D] (Moré, "The
//! Levenberg–Marquardt algorithm: implementation and theory", 1978: D the column norms of J).
//! The full parametrisation of (A, B, C, E) is redundant (any similarity transform, and E's
//! scale against f's) — the damping keeps the step in the redundant directions small, as in
//! the fully parametrised PNLSS fit (Paduart et al., Automatica 46, 2010). A step whose
//! simulation diverges is refused like one that increases the cost: λ grows and a shorter
//! step is tried.

use super::model::FeedbackModel;
use super::simulate::{Layout, run};
use crate::error::Result;
use crate::solvers::{Faer, LinAlg};
use faer::Mat;

/// What a refinement did.
#[derive(Debug, Clone, PartialEq)]
pub struct RefineReport {
    /// Accepted steps.
    pub iterations: usize,
    /// Steps refused because their simulation diverged.
    pub diverged_steps: usize,
    /// Mean squared error before (normalised units).
    pub mse_start: f64,
    /// Mean squared error after (normalised units).
    pub mse_end: f64,
}

fn mse(y: &[f64], yh: &[f64]) -> f64 {
    y.iter().zip(yh).map(|(a, b)| (a - b).powi(2)).sum::<f64>() / y.len().max(1) as f64
}

/// Refines `m` and the initial state `x0` on the normalised record (u, y); with
/// `model_free = false` only x0 moves. Stops when a step taken with the damping λ at or below
/// its starting value 1e-3 lowers the MSE by less than the fraction `tolerance` (a heavily
/// damped step's small gain does not end it), after `max_iterations`, or when no damping finds
/// a lower cost. Returns the new x0 and what happened.
pub(crate) fn refine(
    m: &mut FeedbackModel,
    x0: &[f64],
    u: &[f64],
    y: &[f64],
    model_free: bool,
    max_iterations: usize,
    tolerance: f64,
) -> Result<(Vec<f64>, RefineReport)> {
    let la = Faer::default();
    let lay = Layout::of(m, model_free);
    let np = lay.len();
    let nn = u.len();
    let mut p = lay.pack(m, x0);
    let yh0 = run(m, u, x0, None)?;
    let mut cost = mse(y, &yh0);
    let mut report = RefineReport {
        iterations: 0,
        diverged_steps: 0,
        mse_start: cost,
        mse_end: cost,
    };
    let mut lambda: f64 = 1e-3;
    let mut jr = Mat::<f64>::zeros(nn, np + 1);
    let mut x0_cur = x0.to_vec();
    for _ in 0..max_iterations {
        // the Jacobian fills columns 0..np, the residual the last one
        let yh = run(m, u, &x0_cur, Some((&lay, &mut jr)))?;
        for k in 0..nn {
            jr[(k, np)] = y[k] - yh[k];
        }
        let r = la.qr_r(jr.as_ref())?;
        let dscale: Vec<f64> = (0..np)
            .map(|j| {
                let s = (0..=j.min(r.nrows() - 1))
                    .map(|i| r[(i, j)].powi(2))
                    .sum::<f64>()
                    .sqrt();
                s.max(1e-12)
            })
            .collect();
        let rows = r.nrows().min(np);
        let mut accepted = false;
        for _ in 0..12 {
            let sl = lambda.sqrt();
            let a = Mat::from_fn(rows + np, np, |i, j| {
                if i < rows {
                    r[(i, j)]
                } else if i - rows == j {
                    sl * dscale[j]
                } else {
                    0.0
                }
            });
            let b = Mat::from_fn(rows + np, 1, |i, _| if i < rows { r[(i, np)] } else { 0.0 });
            let delta = la.lstsq(a.as_ref(), b.as_ref())?;
            let trial_p: Vec<f64> = (0..np).map(|j| p[j] + delta[(j, 0)]).collect();
            let mut trial = m.clone();
            let ok = lay.unpack(&trial_p, &mut trial).ok().and_then(|tx0| {
                match run(&trial, u, &tx0, None) {
                    Ok(yh) => Some((mse(y, &yh), tx0)),
                    Err(_) => {
                        report.diverged_steps += 1;
                        None
                    }
                }
            });
            match ok {
                Some((c, tx0)) if c.is_finite() && c < cost => {
                    let gain = (cost - c) / cost.max(1e-300);
                    // a small gain of a heavily damped step says the damping limits the step,
                    // not that the optimum is near: only a step taken with the damping at or
                    // below its starting value ends the refinement on a small gain
                    let damped = lambda > 1e-3;
                    *m = trial;
                    p = trial_p;
                    x0_cur = tx0;
                    cost = c;
                    lambda = (lambda / 3.0).max(1e-12);
                    report.iterations += 1;
                    accepted = true;
                    if gain < tolerance && !damped {
                        report.mse_end = cost;
                        return Ok((x0_cur, report));
                    }
                    break;
                }
                _ => lambda *= 8.0,
            }
            if lambda > 1e12 {
                break;
            }
        }
        if !accepted {
            break;
        }
    }
    report.mse_end = cost;
    Ok((x0_cur, report))
}

/// The initial state alone of a fixed model on the normalised record (u, y), from each of
/// `starts`: Levenberg–Marquardt on x0 over the whole record, and the same continued over
/// prefixes that grow fourfold from 50 samples to the whole record, each stage started from
/// the last one's x0. A friction that sticks keeps the memory of a wrong initial state (the
/// position where it stops), so the whole record's cost in x0 has local minima; over a short
/// prefix the transient dominates and the cost is nearly quadratic. The prefix continuation is
/// the shortened simulation horizon of Ribeiro, Tiels, Umenberger, Schön & Aguirre, "On the
/// smoothness of nonlinear system identification", Automatica 121, 2020. Returns the x0 with
/// the lowest MSE over the whole record and that MSE; `None` when every start diverges.
pub(crate) fn estimate_x0(
    m: &FeedbackModel,
    starts: &[Vec<f64>],
    u: &[f64],
    y: &[f64],
) -> Option<(f64, Vec<f64>)> {
    let nn = u.len();
    let mut best: Option<(f64, Vec<f64>)> = None;
    let mut keep = |mse: f64, x0: Vec<f64>| {
        if mse.is_finite() && best.as_ref().is_none_or(|b| mse < b.0) {
            best = Some((mse, x0));
        }
    };
    for start in starts {
        let mut mm = m.clone();
        if let Ok((x0, rep)) = refine(&mut mm, start, u, y, false, 20, 1e-6) {
            keep(rep.mse_end, x0);
        }
        let mut x0 = start.clone();
        let mut len = 50usize;
        while len < nn {
            let mut mm = m.clone();
            if let Ok((x, _)) = refine(&mut mm, &x0, &u[..len], &y[..len], false, 20, 1e-6) {
                x0 = x;
            }
            len *= 4;
        }
        let mut mm = m.clone();
        if let Ok((x0, rep)) = refine(&mut mm, &x0, u, y, false, 20, 1e-6) {
            keep(rep.mse_end, x0);
        }
    }
    best
}
