//! Feedback on a state combination, `--feedback-on state`: z(k) = F x(k), F (n values)
//! estimated by the fit.
//!
//! **Identifiability.** F is free up to two things the loop cannot tell apart: the state
//! coordinates (a similarity transform x → T x moves F to F T⁻¹ with A, B, C and E, as it
//! moves C), and z's scale, which f absorbs (F → αF with f(·) → f(·/α) is the same loop).
//! The first is left to the refinement's damping, as for the fully parametrised (A, B, C, E)
//! ([`super::refine`]). The second is fixed after the refinement: **F is scaled so that z = F x
//! has, along the model's simulation of the training record, the RMS of C x** (the noise-free
//! output without its feed-through and offset), and f is rescaled to match
//! ([`StaticNonlinearity::rescaled`]: the built-in bases all say how). z is then in the output's
//! units, like the z of `--feedback-on output`. A user's basis that cannot rescale keeps the
//! scale of its start (the same normalisation on the linear model's states).
//!
//! **The start** (Van Mulders, Schoukens & Vanbeylen, "Identification of systems with
//! localised nonlinearity: from state-space to block-structured models", Automatica 49, 2013:
//! the nonlinear feedback estimated linearly on the states of the linear model). The states
//! x̂ of the linear subspace model are simulated on the training input. Their directions are
//! made comparable by whitening: the SVD of the (centred) state matrix through its QR factor,
//! X = Q R, R = U S Vᵀ, gives ξ = S⁻¹ Vᵀ x with uncorrelated unit-variance components. The
//! candidate directions d (in ξ) are C's own direction (F = C: the `output` start, so that
//! the state fit starts where the output fit does), the leading principal directions (the
//! axes of ξ), and each pair of these rotated by ±45°. For each, z = F_d x̂ with
//! F_d = dᵀ S⁻¹ Vᵀ scaled to the RMS of C x̂, and the linear-in-parameters step of
//! [`super::init`] fits B, E, f's gains, x₀, D and y₀ with that z. The direction whose start
//! simulates with the lowest training error is the one that best explains the output through
//! a nonlinearity of one state combination — a projection-pursuit search (Friedman & Stuetzle,
//! "Projection pursuit regression", JASA 76, 1981) scored by the linear-in-parameters fit.
//! The best starts (and the F = C start) go to the output-error refinement of all parameters
//! with F among them ([`super::simulate`]: ∂z/∂p = F ∂x/∂p + ∂F/∂p x).

use super::model::FeedbackModel;
use super::simulate;
use crate::error::Result;
use crate::regressors::StaticNonlinearity;
use crate::solvers::{Faer, LinAlg};
use crate::statespace::StateSpace;
use faer::Mat;

/// The number of starts (besides F = C) the refinement takes from the direction search.
pub(crate) const STATE_STARTS: usize = 2;

/// The states x̂(k) of the linear model (A, B) on the input `u` from `x0`, row k of an N × n
/// matrix.
fn linear_states(lin: &StateSpace<f64>, u: &[f64], x0: &[f64]) -> Mat<f64> {
    let n = lin.order();
    let mut x: Vec<f64> = (0..n).map(|i| x0.get(i).copied().unwrap_or(0.0)).collect();
    let mut out = Mat::<f64>::zeros(u.len(), n);
    for (k, &uk) in u.iter().enumerate() {
        for i in 0..n {
            out[(k, i)] = x[i];
        }
        let xn: Vec<f64> = (0..n)
            .map(|i| lin.b[(i, 0)] * uk + (0..n).map(|l| lin.a[(i, l)] * x[l]).sum::<f64>())
            .collect();
        x = xn;
    }
    out
}

fn rms(v: &[f64]) -> f64 {
    (v.iter().map(|x| x * x).sum::<f64>() / v.len().max(1) as f64).sqrt()
}

/// The candidate state combinations of the start (the module's text): each F with its z along
/// the linear model's states, scaled to the RMS of C x̂; the first is F = C.
pub(crate) fn candidates(
    lin: &StateSpace<f64>,
    u: &[f64],
    x0: &[f64],
) -> Result<Vec<(Vec<f64>, Vec<f64>)>> {
    let n = lin.order();
    let nn = u.len();
    let xs = linear_states(lin, u, x0);
    let c: Vec<f64> = (0..n).map(|j| lin.c[(0, j)]).collect();
    let z_of = |f: &[f64]| -> Vec<f64> {
        (0..nn)
            .map(|k| (0..n).map(|i| f[i] * xs[(k, i)]).sum())
            .collect()
    };
    let target = rms(&z_of(&c));
    let mut out: Vec<(Vec<f64>, Vec<f64>)> = Vec::new();
    let push = |f: Vec<f64>, out: &mut Vec<(Vec<f64>, Vec<f64>)>| {
        let z = z_of(&f);
        let r = rms(&z);
        if !(r > 0.0 && r.is_finite() && target > 0.0) {
            return;
        }
        let s = target / r;
        out.push((
            f.iter().map(|v| v * s).collect(),
            z.iter().map(|v| v * s).collect(),
        ));
    };
    push(c.clone(), &mut out);
    // whitening of the centred states: X = Q R, R = U S Vᵀ
    let mean: Vec<f64> = (0..n)
        .map(|i| (0..nn).map(|k| xs[(k, i)]).sum::<f64>() / nn.max(1) as f64)
        .collect();
    let xc = Mat::from_fn(nn, n, |k, i| xs[(k, i)] - mean[i]);
    let la = Faer::default();
    let r = la.qr_r(xc.as_ref())?;
    let rr = Mat::from_fn(r.nrows().min(n), n, |i, j| r[(i, j)]);
    let svd = la.svd(rr.as_ref())?;
    let smax = svd.s.first().copied().unwrap_or(0.0);
    let rank = svd
        .s
        .iter()
        .filter(|&&s| s > 1e-8 * smax && s > 0.0)
        .count();
    if rank == 0 {
        return Ok(out);
    }
    // F_d = dᵀ S⁻¹ Vᵀ for a direction d over the first `rank` whitened components
    let f_of = |d: &[f64]| -> Vec<f64> {
        (0..n)
            .map(|j| (0..rank).map(|i| d[i] / svd.s[i] * svd.v[(j, i)]).sum())
            .collect()
    };
    // C's whitened direction S Vᵀ Cᵀ, and the leading axes
    let dc: Vec<f64> = (0..rank)
        .map(|i| svd.s[i] * (0..n).map(|j| svd.v[(j, i)] * c[j]).sum::<f64>())
        .collect();
    let unit = |d: Vec<f64>| -> Option<Vec<f64>> {
        let norm = d.iter().map(|v| v * v).sum::<f64>().sqrt();
        (norm > 0.0 && norm.is_finite()).then(|| d.iter().map(|v| v / norm).collect())
    };
    let mut base: Vec<Vec<f64>> = unit(dc).into_iter().collect();
    for i in 0..rank.min(4) {
        base.push((0..rank).map(|j| f64::from(i == j)).collect());
    }
    let mut dirs: Vec<Vec<f64>> = Vec::new();
    let add = |d: Vec<f64>, dirs: &mut Vec<Vec<f64>>| {
        let Some(d) = unit(d) else { return };
        // a direction and its opposite are the same candidate (f's gains take the sign)
        if dirs
            .iter()
            .any(|e| e.iter().zip(&d).map(|(a, b)| a * b).sum::<f64>().abs() > 0.99)
        {
            return;
        }
        dirs.push(d);
    };
    // C's direction first: it is already among the candidates as F = C
    for d in &base {
        add(d.clone(), &mut dirs);
    }
    for a in 0..base.len() {
        for b in a + 1..base.len() {
            for sign in [1.0, -1.0] {
                let d: Vec<f64> = base[a]
                    .iter()
                    .zip(&base[b])
                    .map(|(x, y)| x + sign * y)
                    .collect();
                add(d, &mut dirs);
            }
        }
    }
    for d in dirs.iter().skip(1) {
        push(f_of(d), &mut out);
    }
    Ok(out)
}

/// Keeps the F = C start (the first) and the `STATE_STARTS` others with the lowest start
/// error (`None`: the start diverged, last).
pub(crate) fn keep_best<T>(starts: &mut Vec<(FeedbackModel, Option<f64>, T)>) {
    if starts.len() <= 1 + STATE_STARTS {
        return;
    }
    let mut rest = starts.split_off(1);
    rest.sort_by(|a, b| {
        a.1.unwrap_or(f64::INFINITY)
            .total_cmp(&b.1.unwrap_or(f64::INFINITY))
    });
    rest.truncate(STATE_STARTS);
    starts.extend(rest);
}

/// Fixes z's scale (the module's normalisation): F scaled so that z = F x has the RMS of C x
/// along the model's simulation of the normalised input `us` from its x₀, f rescaled to keep
/// the loop. A basis that cannot rescale leaves the model as it is.
pub(crate) fn normalise_scale(m: &mut FeedbackModel, us: &[f64]) -> Result<()> {
    let mut z = Vec::new();
    let y = simulate::run_z(m, us, &m.x0, None, Some(&mut z))?;
    let cx: Vec<f64> = y
        .iter()
        .zip(us)
        .map(|(y, u)| y - m.d * u - m.y_offset)
        .collect();
    let (rz, rc) = (rms(&z), rms(&cx));
    if !(rz > 0.0 && rc > 0.0 && rz.is_finite() && rc.is_finite()) {
        return Ok(());
    }
    let alpha = rc / rz;
    let Some(f) = m.f.rescaled(alpha, 1.0) else {
        return Ok(());
    };
    m.f = f;
    m.fz.iter_mut().for_each(|v| *v *= alpha);
    Ok(())
}

/// The basis for a state start: the user's (cloned) or the built-in kind made for this z.
pub(crate) fn basis_for(
    user: Option<&dyn StaticNonlinearity<f64>>,
    kind: super::FeedbackKind,
    z: &[f64],
) -> Result<Box<dyn StaticNonlinearity<f64>>> {
    match user {
        Some(b) => Ok(b.clone_box()),
        None => super::feedback_basis(kind, z),
    }
}

#[cfg(test)]
mod tests {
    use super::super::simulate::{Layout, run, worst_sensitivity_error};
    use super::super::{FeedbackKind, FeedbackOn, feedback_basis};
    use super::*;

    /// A second-order state-feedback model with a cubic f, all parameters non-zero.
    fn model() -> FeedbackModel {
        let mut f = feedback_basis(FeedbackKind::Poly3, &[-1.0, 1.0]).unwrap();
        f.set_params(&[-0.3]).unwrap();
        FeedbackModel {
            a: Mat::from_fn(2, 2, |i, j| [[1.2, 1.0], [-0.5, 0.1]][i][j]),
            b: vec![1.0, 0.4],
            c: vec![1.0, 0.2],
            d: 0.1,
            e: vec![0.7, 0.3],
            f,
            viscous: 0.0,
            on: FeedbackOn::State,
            fz: vec![0.5, -0.8],
            input: None,
            output: None,
            with_d: true,
            u_offset: 0.05,
            y_offset: -0.1,
            u_scale: 1.0,
            y_scale: 1.0,
            x0: vec![0.2, -0.1],
            z_range: (-1.0, 1.0),
        }
    }

    #[test]
    fn the_sensitivities_with_f_are_the_finite_differences() {
        let m = model();
        let u: Vec<f64> = (0..60).map(|k| 0.3 * (0.37 * k as f64).sin()).collect();
        let lay = Layout::of(&m, true);
        let worst = worst_sensitivity_error(&m, &u);
        // F's columns are the last model group before x₀
        let o = lay.offsets();
        assert_eq!(o[8] - o[9], 2);
        assert!(worst < 1e-5, "largest relative Jacobian error {worst}");
    }

    #[test]
    fn rescaling_z_keeps_the_loop() {
        let mut m = model();
        let u: Vec<f64> = (0..80).map(|k| 0.4 * (0.21 * k as f64).cos()).collect();
        let before = run(&m, &u, &m.x0, None).unwrap();
        let f0 = m.fz.clone();
        normalise_scale(&mut m, &u).unwrap();
        let after = run(&m, &u, &m.x0, None).unwrap();
        assert!(f0.iter().zip(&m.fz).any(|(a, b)| (a - b).abs() > 1e-6));
        for (a, b) in before.iter().zip(&after) {
            assert!((a - b).abs() < 1e-9, "{a} vs {b}");
        }
    }
}
