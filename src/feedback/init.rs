//! The start of a feedback fit: the linear model, then the feedback coefficients by one linear
//! least squares.
//!
//! With A and C of the linear subspace model fixed, and z taken from the measured output (its
//! first difference for `velocity`), the output
//!
//! y(k) = C Aᵏ x₀ + Σ_{t<k} C A^{k−1−t} (B u(t) + M φ(z(t))) + D u(k) + y₀
//!
//! is linear in B, M (n × r: the basis columns φ fed back through E gᵀ), x₀, D and y₀: the
//! B/D/x₀ step of subspace identification with the basis columns as extra inputs. This is the
//! input–output form of the linear-in-parameters initialisation of nonlinear feedback models
//! (Van Mulders, Schoukens & Vanbeylen, "Identification of systems with localised nonlinearity:
//! from state-space to block-structured models", Automatica 49, 2013; Vanbeylen, "Nonlinear LFR
//! block-oriented model: potential benefits and improved, user-friendly identification
//! method", IEEE TIM 62, 2013): the states are those of the linear model and the feedback
//! variable is the measured one, so the step needs no simulation of the nonlinear loop. The
//! measured z carries the noise (an errors-in-variables bias); the output-error refinement
//! that follows removes it. The best rank-one factor of M (its leading singular pair) gives
//! E and f's gains; a threshold (dead-zone b, saturation s) is chosen on a grid of quantiles
//! of |z|, a scale (the Coulomb width δ) on a geometric grid, by the same least squares.

use super::FeedbackOn;
use super::model::FeedbackModel;
use crate::error::{Error, Result};
use crate::regressors::StaticNonlinearity;
use crate::solvers::{Faer, LinAlg};
use crate::statespace::StateSpace;
use faer::Mat;

/// The feedback variable measured on a normalised record: y − D u (centred), or its first
/// difference.
pub(crate) fn measured_z(u: &[f64], y: &[f64], d: f64, on: FeedbackOn) -> Vec<f64> {
    let v: Vec<f64> = u.iter().zip(y).map(|(u, y)| y - d * u).collect();
    let mean = v.iter().sum::<f64>() / v.len().max(1) as f64;
    match on {
        // a state combination is not measured: the output stands in (its basis is made
        // for each candidate F's own z, `state.rs`)
        FeedbackOn::Output | FeedbackOn::State => v.iter().map(|x| x - mean).collect(),
        FeedbackOn::Velocity => (0..v.len())
            .map(|k| if k == 0 { 0.0 } else { v[k] - v[k - 1] })
            .collect(),
    }
}

/// Columns C (qI − A)⁻¹ e_i s, i = 1..n, of one signal s (zero initial state).
fn responses(a: &Mat<f64>, c: &[f64], s: &[f64], out: &mut Mat<f64>, col0: usize) {
    let n = c.len();
    // X(k) n × n: state of the n single-input systems (A, e_i); output row C X(k)
    let mut x = vec![0.0; n * n]; // x[i * n + r]: system i, state r
    let mut xn = vec![0.0; n * n];
    for (k, &sk) in s.iter().enumerate() {
        for i in 0..n {
            let xi = &x[i * n..(i + 1) * n];
            out[(k, col0 + i)] = (0..n).map(|r| c[r] * xi[r]).sum();
            for r in 0..n {
                let mut v = if r == i { sk } else { 0.0 };
                for l in 0..n {
                    v += a[(r, l)] * xi[l];
                }
                xn[i * n + r] = v;
            }
        }
        std::mem::swap(&mut x, &mut xn);
    }
}

/// The least squares of the start for a given basis: returns (B, M, x0, D, y0, residual SS).
fn lip(
    lin: &StateSpace<f64>,
    u: &[f64],
    y: &[f64],
    phi: &Mat<f64>,
    with_d: bool,
) -> Result<(Vec<f64>, Mat<f64>, Vec<f64>, f64, f64, f64)> {
    let n = lin.order();
    let r = phi.ncols();
    let nn = u.len();
    let a = lin.a.to_owned();
    let c: Vec<f64> = (0..n).map(|j| lin.c[(0, j)]).collect();
    let ncol = n * (1 + r) + n + usize::from(with_d) + 1;
    let mut x = Mat::<f64>::zeros(nn, ncol);
    responses(&a, &c, u, &mut x, 0);
    for j in 0..r {
        let s: Vec<f64> = (0..nn).map(|k| phi[(k, j)]).collect();
        responses(&a, &c, &s, &mut x, n * (1 + j));
    }
    // free response C Aᵏ e_i
    let x0c = n * (1 + r);
    let mut st = Mat::<f64>::identity(n, n);
    for k in 0..nn {
        for i in 0..n {
            x[(k, x0c + i)] = (0..n).map(|l| c[l] * st[(l, i)]).sum();
        }
        st = &a * &st;
    }
    let mut col = x0c + n;
    if with_d {
        for k in 0..nn {
            x[(k, col)] = u[k];
        }
        col += 1;
    }
    for k in 0..nn {
        x[(k, col)] = 1.0;
    }
    let yv = Mat::from_fn(nn, 1, |k, _| y[k]);
    let th = Faer::default().lstsq(x.as_ref(), yv.as_ref())?;
    let fitted = &x * &th;
    let ss = (0..nn)
        .map(|k| (y[k] - fitted[(k, 0)]).powi(2))
        .sum::<f64>();
    let b = (0..n).map(|i| th[(i, 0)]).collect();
    let m = Mat::from_fn(n, r, |i, j| th[(n * (1 + j) + i, 0)]);
    let x0 = (0..n).map(|i| th[(x0c + i, 0)]).collect();
    let d = if with_d { th[(x0c + n, 0)] } else { 0.0 };
    let y0 = th[(col, 0)];
    Ok((b, m, x0, d, y0, ss))
}

/// The start: the basis `f` fitted by the least squares above on the linear model `lin`
/// (normalised record u, y) with the feedback variable `z` (measured, or the linear model's
/// simulated one). Thresholds listed by `searched_params` are chosen on a grid of
/// quantiles of |z|; a scale (a searched parameter whose `search_range` starts above zero:
/// the Coulomb width) on a geometric grid of that range.
pub(crate) fn start(
    lin: &StateSpace<f64>,
    mut f: Box<dyn StaticNonlinearity<f64>>,
    on: FeedbackOn,
    with_d: bool,
    u: &[f64],
    y: &[f64],
    z: &[f64],
    scales: (f64, f64),
) -> Result<FeedbackModel> {
    let n = lin.order();
    let mut grid: Vec<Option<(usize, f64)>> = vec![None];
    let searched = f.searched_params();
    if let Some(&ix) = searched.first() {
        let (lo, hi) = f.search_range(ix, z);
        if lo > 0.0 && hi > lo {
            // a scale (the Coulomb width): nine values spaced geometrically over its range
            grid = (0..9)
                .map(|i| Some((ix, lo * (hi / lo).powf(i as f64 / 8.0))))
                .collect();
        } else {
            // a threshold (dead-zone, saturation): the deciles of |z|
            let mut abs: Vec<f64> = z.iter().map(|v| v.abs()).collect();
            abs.sort_by(f64::total_cmp);
            grid = (1..10)
                .map(|i| Some((ix, abs[(abs.len() - 1) * i / 10])))
                .collect();
        }
    }
    let mut best: Option<(f64, Box<dyn StaticNonlinearity<f64>>, _)> = None;
    for g in grid {
        let mut fb = f.clone_box();
        if let Some((ix, t)) = g {
            let mut th = fb.params();
            th[ix] = t;
            fb.set_params(&th)?;
        }
        let phi = fb.regressors(z);
        check_representable(&phi, fb.as_ref(), z)?;
        // velocity feedback: the viscous column z beside the basis (last)
        let phi = if on == FeedbackOn::Velocity {
            let r = phi.ncols();
            faer::Mat::from_fn(
                phi.nrows(),
                r + 1,
                |k, j| if j < r { phi[(k, j)] } else { z[k] },
            )
        } else {
            phi
        };
        let sol = lip(lin, u, y, &phi, with_d)?;
        if best.as_ref().is_none_or(|b| sol.5 < b.0) {
            best = Some((sol.5, fb, sol));
        }
    }
    let (_, fb, (b, mm, x0, d, y0, _)) = best.expect("grid is not empty");
    f = fb;
    // rank-one factor of M = E gᵀ
    let r = mm.ncols();
    let (e, g) = if r == 1 {
        ((0..n).map(|i| mm[(i, 0)]).collect::<Vec<_>>(), vec![1.0])
    } else {
        let svd = Faer::default().svd(mm.as_ref())?;
        let s0 = svd.s.first().copied().unwrap_or(0.0);
        (
            (0..n).map(|i| svd.u[(i, 0)] * s0).collect(),
            (0..r).map(|j| svd.v[(j, 0)]).collect(),
        )
    };
    let (g, viscous) = if on == FeedbackOn::Velocity {
        (g[..g.len() - 1].to_vec(), g[g.len() - 1])
    } else {
        (g, 0.0)
    };
    f.update_from_gains(&g, z)?;
    let mut x0f = x0;
    if on == FeedbackOn::Velocity {
        let cx: f64 = (0..n).map(|i| lin.c[(0, i)] * x0f[i]).sum();
        x0f.push(cx);
    }
    let zr = z
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
            (a.min(v), b.max(v))
        });
    Ok(FeedbackModel {
        a: lin.a.to_owned(),
        b,
        c: (0..n).map(|j| lin.c[(0, j)]).collect(),
        d,
        e,
        f,
        viscous,
        on,
        fz: Vec::new(),
        input: None,
        output: None,
        with_d,
        u_offset: 0.0,
        y_offset: y0,
        u_scale: scales.0,
        y_scale: scales.1,
        x0: x0f,
        z_range: zr,
    })
}

/// Errors when the basis has no column that varies over the visited z (it cannot represent a
/// nonlinearity there: a threshold beyond the range, a user basis that is zero), naming the
/// range.
fn check_representable(phi: &Mat<f64>, f: &dyn StaticNonlinearity<f64>, z: &[f64]) -> Result<()> {
    let (lo, hi) = z
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
            (a.min(v), b.max(v))
        });
    if phi.ncols() == 0 {
        return Err(Error::InvalidParameter(format!(
            "the feedback basis '{}' has no columns: it cannot represent a nonlinearity",
            f.name()
        )));
    }
    for j in 0..phi.ncols() {
        let col: Vec<f64> = (0..phi.nrows()).map(|k| phi[(k, j)]).collect();
        if col.iter().any(|v| !v.is_finite()) {
            return Err(Error::InvalidParameter(format!(
                "the feedback basis '{}' gives non-finite values over the visited z range [{lo:.4}, {hi:.4}]",
                f.name()
            )));
        }
    }
    let varies = (0..phi.ncols()).any(|j| {
        let first = phi[(0, j)];
        (0..phi.nrows()).any(|k| (phi[(k, j)] - first).abs() > 1e-12 * (1.0 + first.abs()))
    });
    if !varies {
        return Err(Error::InvalidParameter(format!(
            "the feedback basis '{}' is constant over the visited z range [{lo:.4}, {hi:.4}] (normalised units): \
             it cannot represent the requested nonlinearity there",
            f.name()
        )));
    }
    Ok(())
}
