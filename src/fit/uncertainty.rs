//! Standard errors of the nonlinearity's parameters (and of the output map's, when the model has
//! one: the Jacobian is then the chain rule through the map, `output_fit::mapped_jacobian`) at a
//! fitted model.
//!
//! Algorithm: the asymptotic covariance of an output-error (prediction-error) estimate,
//! Cov θ̂ ≈ σ̂²·(JᵀJ)⁻¹ with σ̂² = ‖r‖²/(N − p) (Ljung, *System Identification*, 2nd ed. 1999,
//! §9.3; Söderström & Stoica 1989, ch. 7), evaluated at the final model in the record's units
//! and computed by QR, never by forming JᵀJ: J = QR, Cov = σ̂²·R⁻¹R⁻ᵀ, so the standard error of
//! parameter j is σ̂·‖row j of R⁻¹‖ (computed through the SVD of the column-scaled R, so that
//! directions an over-sized linear block leaves undetermined do not spill into θ). J is the refinement's Jacobian (`refine.rs`: the same
//! parametrisation — θ, the denominator a, the numerator b less the coefficient that fixes the
//! scale, the free response q, the offset c), so the linear block's uncertainty is accounted
//! for, not held fixed. The columns of a discontinuity's position (the nonlinearity's
//! `jump_params`) are secant slopes over a few per cent of the input's spread, as in the
//! refinement: the derivative almost everywhere is blind to the samples a jump passes, the
//! secant measures how the fit degrades when it moves. For those parameters the standard error
//! is an approximation (the estimate of a jump position is not asymptotically normal), good
//! enough for the question it answers here: is the parameter distinguishable from its null value?
//!
//! Records longer than [`WINDOW`] samples: J is built on the first `WINDOW` samples and the
//! standard errors scaled by √(WINDOW/N) (the information of a stationary record grows linearly
//! with its length), so memory stays bounded on long records; a window longer than the
//! refinement's direct limit (65 536 samples) gives its R factor by chunked QR instead of J
//! (the same R up to round-off), so memory is O(p²) there too.

use super::fitted::covariance::ParameterCovariance;
use super::fitted::model::HammersteinModel;
use super::refinement::linear_output::LinearOutput;
use super::refinement::output_fit::{free_response_numerator, mapped_jacobian};
use super::refinement::refine::{free_response_fit, jacobian_or_r, simulate_linear};
use crate::data::IoData;
use crate::real::Real;
use crate::regressors::{OutputMap, StaticNonlinearity};
use crate::solvers::LinAlg;
use faer::{Mat, MatRef};

/// Longest stretch of the record the Jacobian is built on.
pub const WINDOW: usize = 1 << 18;

/// Standard errors of the nonlinearity's parameters θ (in the order of
/// [`HammersteinModel::parameters`]), followed by the output map's (when the model has one), on
/// the record `data`; `None` when they cannot be computed
/// (too few samples for the parameters, a non-finite Jacobian). An entry is `+∞` when its
/// parameter is not identifiable from the record (a zero pivot of R).
pub fn standard_errors<T: Real>(model: &HammersteinModel<T>, data: &IoData<T>) -> Option<Vec<f64>> {
    covariance(model, data).map(|c| c.standard_errors())
}

/// Sets `model`'s reported standard errors and parameter covariance on the record `data` (empty
/// and `None` when they cannot be computed): what every fit does last.
pub(crate) fn attach<T: Real>(model: &mut HammersteinModel<T>, data: &IoData<T>) {
    let cov = covariance(model, data);
    model.report.standard_errors = cov
        .as_ref()
        .map(ParameterCovariance::standard_errors)
        .unwrap_or_default();
    model.report.covariance = cov;
}

/// The covariance of the nonlinearity's parameters θ followed by the output map's (the
/// parameters of [`standard_errors`], same algorithm), in the factored form that gives the
/// standard error of any combination ([`ParameterCovariance::standard_error`]); `None` when it
/// cannot be computed.
pub fn covariance<T: Real>(
    model: &HammersteinModel<T>,
    data: &IoData<T>,
) -> Option<ParameterCovariance> {
    let la = model.settings.linalg_backend().ok()?;
    let full = data.len();
    let nn = full.min(WINDOW);
    // the window's samples only (the delayed input's first nn samples are the delay of the
    // input's first nn)
    let u_all = super::numerics::linear_ls::delayed(&data.input_slice(0)[..nn], model.delay());
    let u = &u_all[..nn];
    let y = &data.output_slice(0)[..nn];
    let nl = model.nl.as_ref();
    let tf = model.linear.transfer_function(0, 0).ok()?;
    let a: Vec<T> = tf.denominator.iter().map(|&x| T::lit(x)).collect();
    let mut b: Vec<T> = tf.numerator.iter().map(|&x| T::lit(x)).collect();
    let n = a.len() - 1;
    let with_d = model.has_feedthrough();
    if !with_d {
        b[0] = T::zero();
    }
    // the scale G·N = (G/s)·(s·N) is fixed by holding one numerator coefficient (the largest,
    // as the refinement does); the θ standard errors are those of the model's normalisation
    let start = usize::from(!with_d);
    let k0 = (start..=n).max_by(|&i, &j| {
        b[i].abs()
            .partial_cmp(&b[j].abs())
            .unwrap_or(std::cmp::Ordering::Equal)
    })?;
    let free_b: Vec<usize> = (start..=n).filter(|&k| k != k0).collect();
    let offset = model.offset_fitted();
    let n_theta = nl.params().len();
    let nw = model.output_map.as_ref().map_or(0, |g| g.params().len());
    let p = n_theta + n + free_b.len() + n + nw + usize::from(offset);
    if nn <= p + 1 {
        return None;
    }
    // through an output map, the initial state on the whole record first (its simulation, one
    // signal of the record, done before the window's signals exist)
    let map_x0 = match model.output_map {
        Some(_) => Some(model.initial_state_on(data).ok()?),
        None => None,
    };
    let v = nl.eval(u);
    // the parameters reported: θ, then the output map's w (after a, the free b and q)
    let lin_cols = n_theta + n + free_b.len() + n;
    let reported: Vec<usize> = (0..n_theta).chain(lin_cols..lin_cols + nw).collect();
    let lin = Linear {
        a: &a,
        b: &b,
        free_b: &free_b,
        offset,
    };
    let (jac, sse) = match model.output_map.as_deref() {
        None => residual_plain(la.as_ref(), nl, u, y, &v, &lin)?,
        Some(g) => residual_mapped(model, map_x0.as_deref()?, g, u, y, &v, &lin)?,
    };
    let sigma2 = sse / (nn - p) as f64;
    if !sigma2.is_finite() {
        return None;
    }
    let mut jm = jac;
    let r = la.qr_r_in_place(jm.as_mut()).ok()?;
    if r.nrows() < p {
        return None;
    }
    let window = (nn as f64 / full as f64).sqrt();
    covariance_from_r(la.as_ref(), r.as_ref(), p, sigma2, &reported, window)
}

/// The refinement's parametrisation of the linear block: denominator a, numerator b (the held
/// coefficient included), the free numerator indices, whether the offset is a parameter.
struct Linear<'a, T: Real> {
    a: &'a [T],
    b: &'a [T],
    free_b: &'a [usize],
    offset: bool,
}

/// The Jacobian and the residual sum of squares of a model without output map, its free
/// response q and offset c re-estimated by least squares (the model's own x0 belongs to its
/// state coordinates; q is the same thing in these), rows folded in by chunked QR.
fn residual_plain<T: Real>(
    la: &dyn LinAlg<T>,
    nl: &dyn StaticNonlinearity<T>,
    u: &[T],
    y: &[T],
    v: &[T],
    lin: &Linear<'_, T>,
) -> Option<(Mat<T>, f64)> {
    let (a, b, offset) = (lin.a, lin.b, lin.offset);
    let n = a.len() - 1;
    // y_lin alone, ŷ = y_lin + c formed where it is read, each signal dropped once read (a
    // window of 2^18 samples: 2.1 MB each)
    let yl0 = simulate_linear(a, b, &[], v);
    let sol = free_response_fit(la, a, y, LinearOutput::Given(&yl0), offset).ok()?;
    drop(yl0);
    let q: Vec<T> = sol[..n].to_vec();
    let c = if offset { sol[n] } else { T::zero() };
    let yl = simulate_linear(a, b, &q, v);
    let sse: f64 = y
        .iter()
        .zip(&yl)
        .map(|(&yk, &xk)| (yk - (xk + c)).as_f64().powi(2))
        .sum();
    // long windows: the Jacobian's R factor by chunked QR (O(p²) memory; its QR is itself up
    // to round-off)
    let jac = jacobian_or_r(la, nl, u, a, b, v, &yl, lin.free_b, offset).ok()?;
    Some((jac, sse))
}

/// The Jacobian (chain rule through the map `g`) and the residual sum of squares of a model with
/// an output map: through the map the initial state is not linear in y, so the model's own
/// estimate on the record (Gauss–Newton in `simulate_on`), `x0`, gives the free response's numerator q.
fn residual_mapped<T: Real>(
    model: &HammersteinModel<T>,
    x0: &[T],
    g: &dyn OutputMap<T>,
    u: &[T],
    y: &[T],
    v: &[T],
    lin: &Linear<'_, T>,
) -> Option<(Mat<T>, f64)> {
    let (a, b) = (lin.a, lin.b);
    let (nn, n) = (y.len(), a.len() - 1);
    let zeros = vec![T::zero(); nn];
    let bv: Vec<T> = (0..n).map(|i| model.linear.b[(i, 0)]).collect();
    let mut f = Vec::new();
    super::numerics::linear_ls::simulate_into(
        model.linear.a.as_ref(),
        &bv,
        model.linear.c.as_ref(),
        T::zero(),
        x0,
        T::zero(),
        &zeros,
        &mut f,
    );
    let q = free_response_numerator(a, &f);
    let x = simulate_linear(a, b, &q, v);
    let yh = g.eval(&x);
    let sse: f64 = (0..nn)
        .map(|k| (y[k] - yh[k] - model.offset).as_f64().powi(2))
        .sum();
    let nl = model.nl.as_ref();
    let jac = mapped_jacobian(nl, g, u, a, b, v, &x, lin.free_b, lin.offset);
    Some((jac, sse))
}

/// The covariance of the parameters `reported` from the R factor `r` (p columns) of the
/// Jacobian, the residual variance `sigma2` and the long-record factor `window`.
fn covariance_from_r<T: Real>(
    la: &dyn LinAlg<T>,
    r: MatRef<'_, T>,
    p: usize,
    sigma2: f64,
    reported: &[usize],
    window: f64,
) -> Option<ParameterCovariance> {
    // Cov = σ̂²(RᵀR)⁺ by the SVD of R with its columns scaled to unit norm (the parameters'
    // units differ by orders of magnitude): R D⁻¹ = U Σ Vᵀ, Cov = σ̂² D⁻¹ V Σ⁻² Vᵀ D⁻¹. Directions
    // with σ below √ε·σ_max are ones the record does not determine (e.g. a near pole–zero
    // cancellation of an over-sized block); a parameter (or combination, `covariance.rs`) whose
    // direction lies more than NULL_SHARE in them gets +∞, the others their error from the
    // determined directions — the truncated-SVD covariance (Golub & Van Loan, *Matrix
    // Computations*, 4th ed., §5.5: rank-deficient least squares; Hansen, *Rank-Deficient and
    // Discrete Ill-Posed Problems*, 1998, §3.2). A small share comes from the scale
    // normalisation coupling θ's gain to a cancelling pole–zero pair: within the block's
    // determined part θ is still determined.
    let d: Vec<T> = (0..p)
        .map(|j| {
            (0..=j)
                .fold(T::zero(), |s, i| s + r[(i, j)] * r[(i, j)])
                .sqrt()
                .max(T::min_positive_value())
        })
        .collect();
    let rs = Mat::from_fn(
        p,
        p,
        |i, j| if i <= j { r[(i, j)] / d[j] } else { T::zero() },
    );
    let svd = la.svd(rs.as_ref()).ok()?;
    let s: Vec<f64> = svd.s.iter().map(|x| x.as_f64()).collect();
    let smax = s.first().copied().unwrap_or(0.0);
    if !(smax.is_finite() && smax > 0.0) {
        return None;
    }
    let tol = smax * T::epsilon().as_f64().sqrt();
    let kept: Vec<bool> = s.iter().map(|&x| x > tol).collect();
    let v_rows: Vec<Vec<f64>> = reported
        .iter()
        .map(|&j| (0..s.len()).map(|k| svd.v[(j, k)].as_f64()).collect())
        .collect();
    let scale: Vec<f64> = reported.iter().map(|&j| d[j].as_f64()).collect();
    let sigma = sigma2.sqrt() * window;
    Some(ParameterCovariance::new(&v_rows, &s, &kept, &scale, sigma))
}
