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

use super::driver::{Iterate, Problem};
use super::fit_report::RefineReport;
use crate::error::Result;
use crate::real::Real;
use crate::regressors::zone::spread;
use crate::regressors::{JUMP_SECANT_FRACTION, StaticNonlinearity};
use crate::statespace::StateSpace;
use faer::Mat;

/// LM iteration limit.
const MAX_LM_ITER: usize = 100;
/// Relative MSE decrease below which LM stops.
const LM_TOL: f64 = 1e-10;

/// Parameter layout of the refinement.
struct Layout {
    n_theta: usize,
    n: usize,
    /// Indices k of the free numerator coefficients b_k.
    free_b: Vec<usize>,
    offset: bool,
}

impl Layout {
    fn len(&self) -> usize {
        self.n_theta + self.n + self.free_b.len() + self.n + usize::from(self.offset)
    }
}

/// Output of [b(z) v + q(z) δ]/a(z) + c; also returns y_lin (without c).
pub(super) fn simulate<T: Real>(a: &[T], b: &[T], q: &[T], c: T, v: &[T]) -> (Vec<T>, Vec<T>) {
    let n = a.len() - 1;
    let nn = v.len();
    let mut yl = vec![T::zero(); nn];
    for k in 0..nn {
        let mut s = T::zero();
        for i in 0..=n.min(k) {
            s += b[i] * v[k - i];
        }
        if k < q.len() {
            s += q[k];
        }
        for i in 1..=n.min(k) {
            s -= a[i] * yl[k - i];
        }
        yl[k] = s;
    }
    let y = yl.iter().map(|&x| x + c).collect();
    (y, yl)
}

/// x/a(z) from zero initial conditions.
pub(super) fn filter_ar<T: Real>(a: &[T], x: &[T]) -> Vec<T> {
    let n = a.len() - 1;
    let mut out = vec![T::zero(); x.len()];
    for k in 0..x.len() {
        let mut s = x[k];
        for i in 1..=n.min(k) {
            s -= a[i] * out[k - i];
        }
        out[k] = s;
    }
    out
}

/// Refines θ, the linear block, x0 and the offset from the loop's iterate; `None` when the MSE did
/// not fall.
pub(crate) fn refine<T: Real>(
    problem: &Problem<'_, T>,
    nl: &dyn StaticNonlinearity<T>,
    it: &Iterate<T>,
) -> Result<(Option<Iterate<T>>, RefineReport)> {
    let not_accepted = |iters| RefineReport {
        mse_before: it.mse,
        mse_after: it.mse,
        iterations: iters,
        accepted: false,
    };
    let n = it.a.nrows();
    let ss = StateSpace::new(
        it.a.clone(),
        Mat::from_fn(n, 1, |i, _| it.b[i]),
        it.c.clone(),
        Mat::from_fn(1, 1, |_, _| it.d),
    )?;
    let Ok(tf) = ss.transfer_function(0, 0) else {
        return Ok((None, not_accepted(0)));
    };
    let mut a: Vec<T> = tf.denominator.iter().map(|&x| T::lit(x)).collect();
    let mut b: Vec<T> = tf.numerator.iter().map(|&x| T::lit(x)).collect();
    if !problem.settings.with_d {
        b[0] = T::zero();
    }
    // the scale G·N = (G/s)·(s·N) is fixed by holding the largest numerator coefficient: holding
    // the first one (the Markov normalisation) makes the path to the optimum a long curved valley
    // when that coefficient is small (slow or high-order blocks; LM then crawls). The model's own
    // normalisation is re-applied afterwards.
    let bmax = b.iter().fold(T::zero(), |m, x| m.max(x.abs()));
    if bmax.partial_cmp(&T::zero()) != Some(std::cmp::Ordering::Greater) {
        return Ok((None, not_accepted(0)));
    }
    let Some(k0) = b.iter().position(|x| x.abs() == bmax) else {
        return Ok((None, not_accepted(0)));
    };
    let start = if problem.settings.with_d { 0 } else { 1 };
    let layout = Layout {
        n_theta: nl.params().len(),
        n,
        free_b: (start..=n).filter(|&k| k != k0).collect(),
        offset: problem.fits_offset(nl),
    };
    let u = &problem.u;
    let y = &problem.y;
    let nn = y.len();
    let mut work = nl.clone_box();
    // initial q, c: least squares on the free-response basis given θ, a, b
    let v0 = work.eval(u);
    let (_, yl0) = simulate(&a, &b, &[], T::zero(), &v0);
    let e = filter_ar(&a, &impulse::<T>(nn));
    let np0 = n + usize::from(layout.offset);
    let reg = Mat::from_fn(nn, np0, |k, j| {
        if j < n {
            if k >= j { e[k - j] } else { T::zero() }
        } else {
            T::one()
        }
    });
    let rhs = Mat::from_fn(nn, 1, |k, _| y[k] - yl0[k]);
    let sol = problem.la.lstsq(reg.as_ref(), rhs.as_ref())?;
    let mut q: Vec<T> = (0..n).map(|j| sol[(j, 0)]).collect();
    let mut c = if layout.offset {
        sol[(n, 0)]
    } else {
        T::zero()
    };
    let mut theta = work.params();

    #[allow(clippy::type_complexity)]
    let cost = |work: &mut Box<dyn StaticNonlinearity<T>>,
                theta: &[T],
                a: &[T],
                b: &[T],
                q: &[T],
                c: T|
     -> Option<(f64, Vec<T>, Vec<T>, Vec<T>)> {
        work.set_params(theta).ok()?;
        let v = work.eval(u);
        let (yh, yl) = simulate(a, b, q, c, &v);
        let m = super::linear_ls::mse(y, &yh);
        if m.is_finite() {
            Some((m, yh, yl, v))
        } else {
            None
        }
    };
    let Some((mut cur, mut yh, mut yl, mut v)) = cost(&mut work, &theta, &a, &b, &q, c) else {
        return Ok((None, not_accepted(0)));
    };
    let start_mse = cur;
    let mut mu = T::lit(1e-3);
    let mut iters = 0;
    let p = layout.len();
    for _ in 0..MAX_LM_ITER {
        iters += 1;
        // Jacobian of ŷ
        let jac = jacobian(
            work.as_ref(),
            u,
            &a,
            &b,
            &v,
            &yl,
            &e,
            &layout.free_b,
            layout.offset,
        );
        // one QR of [J | r] per iteration (Moré 1978): R and Qᵀr serve every μ below, each trial
        // then solves the small (2p × p) problem [R; √μ·D] δ = [Qᵀr; 0]
        let mut jr = Mat::<T>::zeros(nn, p + 1);
        for j in 0..p {
            jr.col_mut(j).copy_from(jac.col(j));
        }
        for k in 0..nn {
            jr[(k, p)] = y[k] - yh[k];
        }
        let Ok(rf) = problem.la.qr_r_in_place(jr.as_mut()) else {
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
                    .max(T::min_positive_value())
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
            let Ok(step) = problem.la.lstsq(aug.as_ref(), rhs.as_ref()) else {
                break;
            };
            let mut t2 = theta.clone();
            let (mut a2, mut b2, mut q2, mut c2) = (a.clone(), b.clone(), q.clone(), c);
            let mut col = 0;
            for tj in t2.iter_mut() {
                *tj += step[(col, 0)];
                col += 1;
            }
            for ai in a2.iter_mut().skip(1) {
                *ai += step[(col, 0)];
                col += 1;
            }
            for &bk in &layout.free_b {
                b2[bk] += step[(col, 0)];
                col += 1;
            }
            for qi in q2.iter_mut() {
                *qi += step[(col, 0)];
                col += 1;
            }
            if layout.offset {
                c2 += step[(col, 0)];
            }
            match cost(&mut work, &t2, &a2, &b2, &q2, c2) {
                Some((m, yh2, yl2, v2)) if m < cur => {
                    let rel = (cur - m) / cur.max(f64::MIN_POSITIVE);
                    (theta, a, b, q, c) = (t2, a2, b2, q2, c2);
                    (cur, yh, yl, v) = (m, yh2, yl2, v2);
                    mu = (mu / T::lit(3.0)).max(T::lit(1e-12));
                    // a tiny decrease counts as converged
                    improved = rel > LM_TOL;
                    break;
                }
                _ => {
                    mu *= T::lit(4.0);
                }
            }
        }
        if !improved {
            break;
        }
    }
    // restore the accepted θ in `work`
    let _ = work.set_params(&theta);
    if !(cur < it.mse && cur < start_mse * (1.0 + 1e-15)) {
        return Ok((None, not_accepted(iters)));
    }
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
    let bo: Vec<T> = (0..n).map(|i| b[i + 1] - a[i + 1] * b[0]).collect();
    let cm = Mat::from_fn(1, n, |_, j| if j == 0 { T::one() } else { T::zero() });
    let refined = Iterate {
        theta: work.params(),
        a: am,
        b: bo,
        c: cm,
        d: b[0],
        x0: q,
        offset: c,
        mse: cur,
    };
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

/// ∂v/∂θ with the columns of the nonlinearity's jump parameters replaced by secant slopes over
/// ±`JUMP_SECANT_FRACTION` of the input spread (one-sided at the admissible range's edge): at a
/// moving jump the derivative almost everywhere is blind to the samples the jump passes, and LM
/// steps built on it fail until μ has shrunk them to nothing.
fn jacobian_with_secants<T: Real>(nl: &dyn StaticNonlinearity<T>, u: &[T]) -> Mat<T> {
    let mut jv = nl.param_jacobian(u);
    let jumps = nl.jump_params();
    if jumps.is_empty() {
        return jv;
    }
    let h = T::lit(JUMP_SECANT_FRACTION) * spread(u);
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

pub(super) fn impulse<T: Real>(n: usize) -> Vec<T> {
    let mut d = vec![T::zero(); n];
    if n > 0 {
        d[0] = T::one();
    }
    d
}

/// The refinement's Jacobian of ŷ at (θ, a, b): columns θ, a₁…aₙ, the free b_k, q₀…q_{n−1}, c.
#[allow(clippy::too_many_arguments)]
pub(super) fn jacobian<T: Real>(
    nl: &dyn StaticNonlinearity<T>,
    u: &[T],
    a: &[T],
    b: &[T],
    v: &[T],
    yl: &[T],
    e: &[T],
    free_b: &[usize],
    offset: bool,
) -> Mat<T> {
    let nn = u.len();
    let n = a.len() - 1;
    let n_theta = nl.params().len();
    let p = n_theta + n + free_b.len() + n + usize::from(offset);
    let jv = jacobian_with_secants(nl, u);
    let mut jac = Mat::<T>::zeros(nn, p);
    let mut col = 0;
    for j in 0..n_theta {
        let x: Vec<T> = (0..nn).map(|k| jv[(k, j)]).collect();
        let (_, f) = simulate(a, b, &[], T::zero(), &x);
        for k in 0..nn {
            jac[(k, col)] = f[k];
        }
        col += 1;
    }
    let d = filter_ar(a, yl);
    for i in 1..=n {
        for k in i..nn {
            jac[(k, col)] = -d[k - i];
        }
        col += 1;
    }
    let w = filter_ar(a, v);
    for &bk in free_b {
        for k in bk..nn {
            jac[(k, col)] = w[k - bk];
        }
        col += 1;
    }
    for i in 0..n {
        for k in i..nn {
            jac[(k, col)] = e[k - i];
        }
        col += 1;
    }
    if offset {
        for k in 0..nn {
            jac[(k, col)] = T::one();
        }
    }
    jac
}
