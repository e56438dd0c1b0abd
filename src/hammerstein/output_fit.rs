//! Fitting a static output map after the linear block (Hammerstein–Wiener: y = g(G·N(u)) + c).
//!
//! Initialisation: the Hammerstein model (no map) is fitted first, as the settings ask; its
//! linear output x (offset removed, initial state estimated) is then the regressor of the map:
//! the map's own `initialize` fits y ≈ g(s·x) + c — linear least squares for the polynomial and
//! the piecewise-linear maps, a grid over the limits with least squares of the slope for the
//! saturation — and the slope s moves into the linear block (b ← s·b). This is the classical
//! two-stage start of Hammerstein–Wiener identification (Bai, *An optimal two-stage
//! identification algorithm for Hammerstein–Wiener nonlinear systems*, Automatica 34(3), 1998):
//! when g is close to its unit-slope form the first stage sees a nearly linear output path.
//!
//! Refinement: Levenberg–Marquardt on the simulation error over every parameter at once — the
//! input nonlinearity's θ, the linear block's a, b (less the held coefficient that fixes the
//! N·G scale) and free response q as in `refine.rs`, the map's w and the offset c. The Jacobian
//! is the chain rule through the map: ∂ŷ/∂p = g'(x)·∂x/∂p for θ, a, b, q (the columns of
//! `refine::jacobian`), ∂ŷ/∂w = ∂g/∂w, ∂ŷ/∂c = 1. The map's normalisation (unit slope and zero
//! value at x = 0) fixes the G·g scale, so the problem has no flat direction.

use super::linear_ls::{delayed, mse};
use super::model::HammersteinModel;
use super::problem::{Iterate, Problem, normalise_iterate, to_statespace};
use super::rank_one::markov_rows;
use super::refine::{jacobian, simulate};
use super::settings::Hammerstein;
use crate::data::IoData;
use crate::error::{Error, Result};
use crate::real::Real;
use crate::regressors::{OutputMap, StaticNonlinearity};
use crate::subspace::max_order;
use faer::Mat;

/// LM iteration limit of the joint refinement.
const MAX_LM_ITER: usize = 150;
/// Relative MSE decrease below which LM stops.
const LM_TOL: f64 = 1e-10;

/// The refinement's Jacobian of ŷ = g(x) + c with an output map: the columns of
/// `refine::jacobian` (θ, a, the free b, q) times g'(x), then ∂g/∂w, then the offset column.
#[allow(clippy::too_many_arguments)]
pub(super) fn mapped_jacobian<T: Real>(
    nl: &dyn StaticNonlinearity<T>,
    map: &dyn OutputMap<T>,
    u: &[T],
    a: &[T],
    b: &[T],
    v: &[T],
    x: &[T],
    free_b: &[usize],
    offset: bool,
) -> Mat<T> {
    let lin = jacobian(nl, u, a, b, v, x, free_b, false);
    let slope = map.derivative(x);
    let jw = map.param_jacobian(x);
    let (pl, nw) = (lin.ncols(), jw.ncols());
    Mat::from_fn(x.len(), pl + nw + usize::from(offset), |k, j| {
        if j < pl {
            slope[k] * lin[(k, j)]
        } else if j < pl + nw {
            jw[(k, j - pl)]
        } else {
            T::one()
        }
    })
}

/// The first `nn` samples of the impulse response of 1/a(z) (the free response's basis).
fn impulse_response<T: Real>(a: &[T], nn: usize) -> Vec<T> {
    let n = a.len() - 1;
    let mut out = vec![T::zero(); nn];
    for k in 0..nn {
        let mut s = if k == 0 { T::one() } else { T::zero() };
        for i in 1..=n.min(k) {
            s -= a[i] * out[k - i];
        }
        out[k] = s;
    }
    out
}

/// The numerator q(z) of a free response f (q/a = f): q_k = Σ_{i≤k} a_i f_{k−i}, k < n.
pub(super) fn free_response_numerator<T: Real>(a: &[T], f: &[T]) -> Vec<T> {
    let n = a.len() - 1;
    (0..n)
        .map(|k| {
            (0..=k).fold(T::zero(), |s, i| {
                s + a[i] * f.get(k - i).copied().unwrap_or(T::zero())
            })
        })
        .collect()
}

/// The fitted Hammerstein model `model` (on `data`, in the fit's units) extended by the output
/// map `map`: initialised as the module says, then refined jointly.
pub(crate) fn fit_output_map<T: Real>(
    settings: &Hammerstein<T>,
    data: &IoData<T>,
    model: HammersteinModel<T>,
    map: &dyn OutputMap<T>,
) -> Result<HammersteinModel<T>> {
    let la = settings.linalg_backend()?;
    let with_d = model.has_feedthrough();
    let n = model.linear.order();
    let fixed = settings
        .clone()
        .order(crate::subspace::Order::Fixed(n))
        .with_d(with_d);
    let method = fixed.subspace_at(fixed.horizon)?;
    let var = super::problem::variance(&data.output(0));
    let problem = Problem {
        la: la.as_ref(),
        method: method.as_ref(),
        settings: &fixed,
        u: delayed(&data.input(0), fixed.delay),
        y: data.output(0),
        k_rows: markov_rows(fixed.horizon, max_order(fixed.horizon, 1)),
        floor: super::problem::exact_floor::<T>(var),
        offset_tol: T::epsilon().as_f64().sqrt() * var.sqrt(),
    };
    let u = &problem.u;
    let y = &problem.y;
    let nn = y.len();
    let mut nl = model.nl.clone_box();
    let offset = problem.fits_offset(nl.as_ref());

    // stage 1: the Hammerstein model's linear output x
    let sim = model.simulate_on(data)?;
    let x_model: Vec<T> = sim.y_hat.iter().map(|&v| v - model.offset).collect();
    let mut g = map.clone_box();
    let (s, c0) = g.initialize(&x_model, y)?;
    let c0 = if offset { c0 } else { T::zero() };

    // the linear block as a transfer function, scaled by s
    let tf = model.linear.transfer_function(0, 0)?;
    let mut a: Vec<T> = tf.denominator.iter().map(|&v| T::lit(v)).collect();
    let mut b: Vec<T> = tf.numerator.iter().map(|&v| T::lit(v) * s).collect();
    if !with_d {
        b[0] = T::zero();
    }
    let start = usize::from(!with_d);
    let k0 = (start..=n)
        .max_by(|&i, &j| {
            b[i].abs()
                .partial_cmp(&b[j].abs())
                .unwrap_or(std::cmp::Ordering::Equal)
        })
        .ok_or_else(|| Error::Identification("the linear block has no numerator".into()))?;
    let free_b: Vec<usize> = (start..=n).filter(|&k| k != k0).collect();
    // q so that the scaled block reproduces s·x (its initial state included)
    let e = impulse_response(&a, nn);
    let v0 = nl.eval(u);
    let (_, forced) = simulate(&a, &b, &[], T::zero(), &v0);
    let f: Vec<T> = (0..nn).map(|k| x_model[k] * s - forced[k]).collect();
    let mut q = if n > 0 {
        let reg = Mat::from_fn(nn, n, |k, j| if k >= j { e[k - j] } else { T::zero() });
        let rhs = Mat::from_fn(nn, 1, |k, _| f[k]);
        let sol = la.lstsq(reg.as_ref(), rhs.as_ref())?;
        (0..n).map(|j| sol[(j, 0)]).collect()
    } else {
        Vec::new()
    };
    let mut theta = nl.params();
    let mut w = g.params();
    let mut c = c0;

    let cost = |nl: &mut Box<dyn StaticNonlinearity<T>>,
                g: &mut Box<dyn OutputMap<T>>,
                theta: &[T],
                a: &[T],
                b: &[T],
                q: &[T],
                w: &[T],
                c: T|
     -> Option<(f64, Vec<T>, Vec<T>, Vec<T>)> {
        nl.set_params(theta).ok()?;
        g.set_params(w).ok()?;
        let v = nl.eval(u);
        let (_, x) = simulate(a, b, q, T::zero(), &v);
        let yh: Vec<T> = g.eval(&x).into_iter().map(|t| t + c).collect();
        let m = mse(y, &yh);
        m.is_finite().then_some((m, yh, x, v))
    };
    let Some((mut cur, mut yh, mut x, mut v)) = cost(&mut nl, &mut g, &theta, &a, &b, &q, &w, c)
    else {
        return Err(Error::Identification(
            "the output map's start does not simulate".into(),
        ));
    };
    let n_theta = theta.len();
    let nw = w.len();
    let p = n_theta + n + free_b.len() + n + nw + usize::from(offset);
    let mut mu = T::lit(1e-3);
    let mut iters = 0;
    for _ in 0..MAX_LM_ITER {
        if nn <= p {
            break;
        }
        iters += 1;
        let jac = mapped_jacobian(nl.as_ref(), g.as_ref(), u, &a, &b, &v, &x, &free_b, offset);
        // one QR of [J | r] per iteration, the damped steps on the small triangle (Moré 1978)
        let mut jr = Mat::<T>::zeros(nn, p + 1);
        for j in 0..p {
            jr.col_mut(j).copy_from(jac.col(j));
        }
        for k in 0..nn {
            jr[(k, p)] = y[k] - yh[k];
        }
        let Ok(rf) = la.qr_r_in_place(jr.as_mut()) else {
            break;
        };
        if rf.nrows() < p + 1 {
            break;
        }
        let scale: Vec<T> = (0..p)
            .map(|j| {
                (0..=j)
                    .fold(T::zero(), |s, i| s + rf[(i, j)] * rf[(i, j)])
                    .sqrt()
                    .max(T::epsilon())
            })
            .collect();
        let mut improved = false;
        for _ in 0..12 {
            let aug = Mat::<T>::from_fn(2 * p, p, |i, j| {
                if i < p {
                    if i <= j { rf[(i, j)] } else { T::zero() }
                } else if i - p == j {
                    mu.sqrt() * scale[j]
                } else {
                    T::zero()
                }
            });
            let rhs =
                Mat::<T>::from_fn(2 * p, 1, |i, _| if i < p { rf[(i, p)] } else { T::zero() });
            let Ok(step) = la.lstsq(aug.as_ref(), rhs.as_ref()) else {
                break;
            };
            let mut col = 0;
            let mut take = |x: &mut T| {
                *x += step[(col, 0)];
                col += 1;
            };
            let mut t2 = theta.clone();
            let (mut a2, mut b2, mut q2, mut w2, mut c2) =
                (a.clone(), b.clone(), q.clone(), w.clone(), c);
            t2.iter_mut().for_each(&mut take);
            a2.iter_mut().skip(1).for_each(&mut take);
            for &bk in &free_b {
                take(&mut b2[bk]);
            }
            q2.iter_mut().for_each(&mut take);
            w2.iter_mut().for_each(&mut take);
            if offset {
                take(&mut c2);
            }
            match cost(&mut nl, &mut g, &t2, &a2, &b2, &q2, &w2, c2) {
                Some((m, yh2, x2, v2)) if m < cur => {
                    let rel = (cur - m) / cur.max(f64::MIN_POSITIVE);
                    (theta, a, b, q, w, c) = (t2, a2, b2, q2, w2, c2);
                    (cur, yh, x, v) = (m, yh2, x2, v2);
                    mu = (mu / T::lit(3.0)).max(T::lit(1e-12));
                    improved = rel > LM_TOL;
                    break;
                }
                _ => mu *= T::lit(4.0),
            }
        }
        if !improved || cur <= problem.floor {
            break;
        }
    }
    nl.set_params(&theta)?;
    g.set_params(&w)?;
    // observer canonical form: A = [−a | I; 0], B_k = b_k − a_k b_0, C = e1ᵀ, D = b_0, x0 = q
    let am = Mat::from_fn(n, n, |i, j| {
        if j == 0 {
            -a[i + 1]
        } else if j == i + 1 {
            T::one()
        } else {
            T::zero()
        }
    });
    let cm = Mat::from_fn(1, n, |_, j| if j == 0 { T::one() } else { T::zero() });
    let mut it = Iterate {
        theta: theta.clone(),
        a: am,
        b: (0..n).map(|i| b[i + 1] - a[i + 1] * b[0]).collect(),
        c: cm,
        d: b[0],
        x0: q,
        offset: c,
        mse: cur,
    };
    normalise_iterate(&problem, nl.as_mut(), &mut it);
    let mut linear = to_statespace(&it)?;
    linear.ts = data.sample_time();
    let mut report = model.report.clone();
    report.train_mse = cur;
    if let Some(r) = report.refinement.as_mut() {
        r.iterations += iters;
    }
    let mut out = HammersteinModel::from_parts(nl, linear, it.offset, model.settings, report)?
        .with_output_map(Some(g))?;
    out.x0 = it.x0;
    Ok(out)
}
