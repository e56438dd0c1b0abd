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

use super::refine::{Point, column_scale, damped_step, jacobian, simulate};
use crate::data::IoData;
use crate::error::{Error, Result};
use crate::fit::fitted::model::HammersteinModel;
use crate::fit::iteration::problem::{Iterate, Problem, normalise_iterate, to_statespace};
use crate::fit::numerics::linear_ls::mse;
use crate::fit::settings::Hammerstein;
use crate::real::Real;
use crate::regressors::{OutputMap, StaticNonlinearity};
use faer::Mat;

/// LM iteration limit of the joint refinement.
const MAX_LM_ITER: usize = 150;
/// Relative MSE decrease below which LM stops.
const LM_TOL: f64 = 1e-10;

/// The refinement's Jacobian of ŷ = g(x) + c with an output map: the columns of
/// `refine::jacobian` (θ, a, the free b, q) times g'(x), then ∂g/∂w, then the offset column.
#[allow(clippy::too_many_arguments)]
pub(in crate::fit) fn mapped_jacobian<T: Real>(
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
pub(in crate::fit) fn free_response_numerator<T: Real>(a: &[T], f: &[T]) -> Vec<T> {
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
/// map `map`, from two starts refined jointly, the lower training MSE kept: the two-stage start
/// (initialised as the module says) and `model` itself with the map at the identity
/// ([`identity_start`]). The map family holds the identity (unit slope, zero value at 0: a
/// polynomial with its higher coefficients 0, a saturation with limits beyond the output's
/// range), so the second start is `model` and the refinement, which takes only steps that lower
/// the MSE, cannot end above it: on the cascaded tanks (saturation, order 2, cubic map) the
/// two-stage start alone can stay above the model it extends.
pub(crate) fn fit_output_map<T: Real>(
    settings: &Hammerstein<T>,
    data: &IoData<T>,
    model: HammersteinModel<T>,
    map: &dyn OutputMap<T>,
) -> Result<HammersteinModel<T>> {
    let identity = identity_start(data, &model, map);
    let two_stage = fit_joint(settings, data, model, map, MapStart::Initialised);
    let Some(start) = identity else {
        return two_stage;
    };
    let kept = refit_with_map(settings, data, start);
    match (two_stage, kept) {
        (Ok(a), Ok(b)) => Ok(if b.report.train_mse < a.report.train_mse {
            b
        } else {
            a
        }),
        (Ok(m), Err(_)) | (Err(_), Ok(m)) => Ok(m),
        (Err(e), Err(_)) => Err(e),
    }
}

/// `model` with a copy of `map` set to the identity on the model's linear output x (the map
/// initialised to reproduce x itself: `OutputMap::initialize(x, x)`), so that the model with
/// the map simulates as `model`; `None` when the family does not reproduce x within 1e-9 of its
/// largest magnitude (a map without the identity) or the model does not simulate.
fn identity_start<T: Real>(
    data: &IoData<T>,
    model: &HammersteinModel<T>,
    map: &dyn OutputMap<T>,
) -> Option<HammersteinModel<T>> {
    let sim = model.simulate_on(data).ok()?;
    let x = model.linear_output(&sim.v, &sim.x0);
    let mut g = map.clone_box();
    g.initialize(&x, &x).ok()?;
    let gx = g.eval(&x);
    let scale = x.iter().fold(0.0f64, |m, v| m.max(v.as_f64().abs()));
    let off = x
        .iter()
        .zip(&gx)
        .fold(0.0f64, |m, (a, b)| m.max((a.as_f64() - b.as_f64()).abs()));
    if off.is_nan() || off > 1e-9 * scale.max(f64::MIN_POSITIVE) {
        return None;
    }
    let mut start = model.clone().with_output_map(Some(g)).ok()?;
    start.x0 = sim.x0;
    Some(start)
}

/// The joint refinement of a Hammerstein–Wiener `model` from its own point: its map, block,
/// initial state and offset kept as the start (a nested refit: the model's nonlinearity may be
/// extended by an effect at its null value, so the start reproduces the model it extends and
/// the refit cannot end above it).
pub(crate) fn refit_with_map<T: Real>(
    settings: &Hammerstein<T>,
    data: &IoData<T>,
    model: HammersteinModel<T>,
) -> Result<HammersteinModel<T>> {
    let map = model
        .output_map
        .as_ref()
        .map(|g| g.clone_box())
        .ok_or_else(|| Error::Identification("the model has no output map to keep".into()))?;
    fit_joint(settings, data, model, map.as_ref(), MapStart::Kept)
}

/// Where the joint refinement starts.
#[derive(Clone, Copy, PartialEq, Eq)]
enum MapStart {
    /// The map initialised on the Hammerstein model's output (the two-stage start).
    Initialised,
    /// The model's own map, block, initial state and offset.
    Kept,
}

fn fit_joint<T: Real>(
    settings: &Hammerstein<T>,
    data: &IoData<T>,
    model: HammersteinModel<T>,
    map: &dyn OutputMap<T>,
    how: MapStart,
) -> Result<HammersteinModel<T>> {
    let la = settings.linalg_backend()?;
    let with_d = model.has_feedthrough();
    let n = model.linear.order();
    let fixed = settings
        .clone()
        .order(crate::subspace::Order::Fixed(n))
        .with_d(with_d);
    let method = fixed.subspace_at(fixed.options.horizon)?;
    let problem = Problem::new(la.as_ref(), method.as_ref(), &fixed, data);
    let mut lm = MapLm {
        problem: &problem,
        nl: model.nl.clone_box(),
        g: map.clone_box(),
        free_b: Vec::new(),
        offset: false,
        mu: T::lit(1e-3),
    };
    // a kept start carries the model's offset outside the map, where a preload spanning the
    // constant inside it does not replace it (the map is nonlinear)
    lm.offset = problem.fits_offset(lm.nl.as_ref())
        || (how == MapStart::Kept && settings.options.offset && model.offset != T::zero());
    let mut point = lm.start(&model, data, how)?;
    let Some(mut eval) = lm.cost(&point) else {
        return Err(Error::Identification(
            "the output map's start does not simulate".into(),
        ));
    };
    let p =
        point.block.theta.len() + n + lm.free_b.len() + n + point.w.len() + usize::from(lm.offset);
    let mut iters = 0;
    for _ in 0..MAX_LM_ITER {
        if problem.y.len() <= p {
            break;
        }
        iters += 1;
        if !lm.iteration(&mut point, &mut eval, p) || eval.mse <= problem.floor {
            break;
        }
    }
    let MapLm { mut nl, mut g, .. } = lm;
    nl.set_params(&point.block.theta)?;
    g.set_params(&point.w)?;
    let mut it = point.into_iterate(n, eval.mse);
    normalise_iterate(&problem, nl.as_mut(), &mut it);
    let mut linear = to_statespace(&it)?;
    linear.ts = data.sample_time();
    let mut report = model.report.clone();
    report.train_mse = eval.mse;
    if let Some(r) = report.refinement.as_mut() {
        r.iterations += iters;
    }
    let mut out = HammersteinModel::from_parts(nl, linear, it.offset, model.settings, report)?
        .with_output_map(Some(g))?;
    out.x0 = it.x0;
    Ok(out)
}

/// A point of the joint refinement: the refinement's point (θ, the block's denominator a,
/// numerator b and free-response numerator q, the offset c) and the map's parameters w.
#[derive(Clone)]
struct MapPoint<T: Real> {
    block: Point<T>,
    w: Vec<T>,
}

impl<T: Real> MapPoint<T> {
    /// The point moved by the LM step `step` (rows θ, a₁…aₙ, the free b, q, w, c).
    fn moved(&self, step: &Mat<T>, free_b: &[usize], offset: bool) -> Self {
        let mut p = self.clone();
        let mut col = p.block.move_block(step, free_b);
        for wi in p.w.iter_mut() {
            *wi += step[(col, 0)];
            col += 1;
        }
        if offset {
            p.block.c += step[(col, 0)];
        }
        p
    }

    /// The single-input iterate of order `n` in observer canonical form (A = [−a | I; 0],
    /// B_k = b_k − a_k b_0, C = e1ᵀ, D = b_0, x0 = q) with MSE `mse`.
    fn into_iterate(self, n: usize, mse: f64) -> Iterate<T> {
        let theta = self.block.theta.clone();
        self.block.into_iterate(n, theta, mse)
    }
}

/// A point's simulation: MSE, output ŷ, the block's output x and v = N(u; θ).
struct MapEval<T: Real> {
    mse: f64,
    yh: Vec<T>,
    x: Vec<T>,
    v: Vec<T>,
}

/// The joint Levenberg–Marquardt refinement: the problem, the input nonlinearity and the map
/// evaluated at the points tried, the parameter layout and the damping μ.
struct MapLm<'p, 'a, T: Real> {
    problem: &'p Problem<'a, T>,
    nl: Box<dyn StaticNonlinearity<T>>,
    g: Box<dyn OutputMap<T>>,
    /// Indices k of the free numerator coefficients b_k.
    free_b: Vec<usize>,
    offset: bool,
    mu: T,
}

impl<T: Real> MapLm<'_, '_, T> {
    /// The starting point (stage 1, see the module): the map initialised on the Hammerstein
    /// model's linear output x, its slope s moved into b, q so that the scaled block reproduces
    /// s·x; sets `g` to the initialised map and `free_b`. With [`MapStart::Kept`] the model's own
    /// map (already in `g`) and offset, and its linear output x before the map, at s = 1.
    fn start(
        &mut self,
        model: &HammersteinModel<T>,
        data: &IoData<T>,
        how: MapStart,
    ) -> Result<MapPoint<T>> {
        let (u, y) = (&self.problem.u, &self.problem.y);
        let (nn, n) = (y.len(), model.linear.order());
        let with_d = self.problem.settings.options.with_d;
        let sim = model.simulate_on(data)?;
        let (x_model, s, c0) = match how {
            MapStart::Initialised => {
                let x: Vec<T> = sim.y_hat.iter().map(|&v| v - model.offset).collect();
                let (s, c0) = self.g.initialize(&x, y)?;
                (x, s, c0)
            }
            // the linear output before the map, the map at unit scale
            MapStart::Kept => (model.linear_output(&sim.v, &sim.x0), T::one(), model.offset),
        };
        let c = if self.offset { c0 } else { T::zero() };
        // the linear block as a transfer function, scaled by s
        let tf = model.linear.transfer_function(0, 0)?;
        let a: Vec<T> = tf.denominator.iter().map(|&v| T::lit(v)).collect();
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
        self.free_b = (start..=n).filter(|&k| k != k0).collect();
        // q so that the scaled block reproduces s·x (its initial state included)
        let e = impulse_response(&a, nn);
        let v0 = self.nl.eval(u);
        let (_, forced) = simulate(&a, &b, &[], T::zero(), &v0);
        let f: Vec<T> = (0..nn).map(|k| x_model[k] * s - forced[k]).collect();
        let q = if n > 0 {
            let reg = Mat::from_fn(nn, n, |k, j| if k >= j { e[k - j] } else { T::zero() });
            let rhs = Mat::from_fn(nn, 1, |k, _| f[k]);
            let sol = self.problem.la.lstsq(reg.as_ref(), rhs.as_ref())?;
            (0..n).map(|j| sol[(j, 0)]).collect()
        } else {
            Vec::new()
        };
        Ok(MapPoint {
            block: Point {
                theta: self.nl.params(),
                a,
                b,
                q,
                c,
            },
            w: self.g.params(),
        })
    }

    /// The simulation of `point`; `None` when a parameter is refused or the MSE not finite.
    fn cost(&mut self, point: &MapPoint<T>) -> Option<MapEval<T>> {
        let block = &point.block;
        // the stability constraint, as in the Hammerstein refinement (`refine::Lm::cost`)
        if self.problem.refuses_block(&block.a) {
            return None;
        }
        self.nl.set_params(&block.theta).ok()?;
        self.g.set_params(&point.w).ok()?;
        let v = self.nl.eval(&self.problem.u);
        let (_, x) = simulate(&block.a, &block.b, &block.q, T::zero(), &v);
        let yh: Vec<T> = self.g.eval(&x).into_iter().map(|t| t + block.c).collect();
        let m = mse(&self.problem.y, &yh);
        m.is_finite().then_some(MapEval { mse: m, yh, x, v })
    }

    /// One LM iteration over the `p` parameters from `point` (simulated as `eval`): both updated
    /// when a step lowered the MSE; true when it lowered it by more than `LM_TOL` (relative).
    fn iteration(&mut self, point: &mut MapPoint<T>, eval: &mut MapEval<T>, p: usize) -> bool {
        let (u, y) = (&self.problem.u, &self.problem.y);
        let nn = y.len();
        let jac = mapped_jacobian(
            self.nl.as_ref(),
            self.g.as_ref(),
            u,
            &point.block.a,
            &point.block.b,
            &eval.v,
            &eval.x,
            &self.free_b,
            self.offset,
        );
        // one QR of [J | r] per iteration, the damped steps on the small triangle (Moré 1978)
        let mut jr = Mat::<T>::zeros(nn, p + 1);
        for j in 0..p {
            jr.col_mut(j).copy_from(jac.col(j));
        }
        for k in 0..nn {
            jr[(k, p)] = y[k] - eval.yh[k];
        }
        let Ok(rf) = self.problem.la.qr_r_in_place(jr.as_mut()) else {
            return false;
        };
        if rf.nrows() < p + 1 {
            return false;
        }
        let scale = column_scale(&rf, p, T::epsilon());
        for _ in 0..12 {
            let Some(step) = damped_step(self.problem.la, &rf, &scale, self.mu) else {
                return false;
            };
            let trial = point.moved(&step, &self.free_b, self.offset);
            match self.cost(&trial) {
                Some(e) if e.mse < eval.mse => {
                    let rel = (eval.mse - e.mse) / eval.mse.max(f64::MIN_POSITIVE);
                    (*point, *eval) = (trial, e);
                    self.mu = (self.mu / T::lit(3.0)).max(T::lit(1e-12));
                    return rel > LM_TOL;
                }
                _ => self.mu *= T::lit(4.0),
            }
        }
        false
    }
}
