//! The signature of a nonlinearity in feedback: is the residual explained by an odd function of
//! the simulated output ŷ, or of its first difference Δŷ, beyond what functions of the input
//! explain?
//!
//! A Lur'e system x(k+1) = A x + B u + E f(z), z = C x or its difference, seen through a linear
//! model leaves the residual e ≈ G·(f(z) − k z) + noise: the part of f the linear loop gain k
//! does not carry, filtered by the closed loop (which the model's linear block approximates).
//! Each shape — z³ (stiffness, `poly3`), tanh(z/δ) (Coulomb friction, `coulomb`, δ at 2, 5 and
//! 15 % of z's RMS), clip(z, ±d) (a clearance, `dead-zone`, whose force beyond the gap d is
//! z − clip(z); d at the 20, 40 and 60 % quantiles of |z|) — is built on z = ŷ − ȳ (`output`)
//! and on z = Δŷ (`velocity`), filtered through the model's linear block, and tested with z
//! itself (filtered) in the null model, so that a linear loop gain does not count.
//!
//! An input nonlinearity can explain the same residual (a static map of u through G looks like
//! one of ŷ where G is smooth): [`held_out`] compares, on the last third of the record (the
//! regressions fitted on the first two thirds), the residual variance the feedback shape explains
//! with the variance the input-side shapes explain together — level bins, their rising/falling
//! split, hinges at the extremes, a clip at small |u|, u² and u³, the columns of the input-side
//! candidates' own tests.

use super::signature::{
    Domain, centred_power, clip, direction, direction_bins, hinges, level_bins, quantile_sorted,
    sorted,
};
use crate::diagnosis::regression::least_squares;
use crate::diagnosis::residual_tests::analysis::ResidualAnalysis;
use crate::feedback::{FeedbackKind, FeedbackOn};

/// The feedback shapes the signature tries: (basis, what z is).
pub const VARIANTS: [(FeedbackKind, FeedbackOn); 6] = [
    (FeedbackKind::Poly3, FeedbackOn::Output),
    (FeedbackKind::Coulomb, FeedbackOn::Output),
    (FeedbackKind::DeadZone, FeedbackOn::Output),
    (FeedbackKind::Poly3, FeedbackOn::Velocity),
    (FeedbackKind::Coulomb, FeedbackOn::Velocity),
    (FeedbackKind::DeadZone, FeedbackOn::Velocity),
];

/// Widths of the Coulomb column's transition tried, as fractions of z's RMS.
const COULOMB_WIDTHS: [f64; 3] = [0.02, 0.05, 0.15];

/// Quantiles of |z| at which the clearance column's gap is tried.
const GAPS: [f64; 3] = [0.2, 0.4, 0.6];

/// The command line's name of a feedback basis.
pub fn kind_name(kind: FeedbackKind) -> String {
    match kind {
        FeedbackKind::Poly3 => "poly3".into(),
        FeedbackKind::Poly5 => "poly5".into(),
        FeedbackKind::Coulomb => "coulomb".into(),
        FeedbackKind::DeadZone => "dead-zone".into(),
        FeedbackKind::Saturation => "saturation".into(),
        FeedbackKind::Pwl(k) => format!("pwl:{k}"),
    }
}

/// The feedback variable of the simulated output: ŷ − mean(ŷ), or its first difference (0 at
/// the first sample). A state combination (`State`) is not a function of ŷ alone: the output
/// stands in for it (the signature's variants are the output and the velocity).
pub fn feedback_variable(y_hat: &[f64], on: FeedbackOn) -> Vec<f64> {
    match on {
        FeedbackOn::Output | FeedbackOn::State => {
            let m = y_hat.iter().sum::<f64>() / y_hat.len().max(1) as f64;
            y_hat.iter().map(|v| v - m).collect()
        }
        FeedbackOn::Velocity => std::iter::once(0.0)
            .chain(y_hat.windows(2).map(|w| w[1] - w[0]))
            .collect(),
    }
}

fn rms(v: &[f64]) -> f64 {
    let s = (v.iter().map(|x| x * x).sum::<f64>() / v.len().max(1) as f64).sqrt();
    if s > 0.0 && s.is_finite() { s } else { 1.0 }
}

/// The candidate columns of one shape on z (several for the Coulomb friction and the clearance:
/// one per transition width or gap tried; the test keeps the best).
pub fn shape_columns(z: &[f64], kind: FeedbackKind) -> Vec<Vec<f64>> {
    let s = rms(z);
    match kind {
        FeedbackKind::Coulomb => COULOMB_WIDTHS
            .iter()
            .map(|w| z.iter().map(|v| (v / (w * s)).tanh()).collect())
            .collect(),
        FeedbackKind::DeadZone => {
            let a = sorted(&z.iter().map(|v| v.abs()).collect::<Vec<_>>());
            GAPS.iter()
                .map(|&q| clip(z, quantile_sorted(&a, q).max(1e-12 * s)))
                .collect()
        }
        // poly3 (and any other odd basis): the cube
        _ => vec![z.iter().map(|v| (v / s).powi(3)).collect()],
    }
}

/// The outcome of the signature on one analysis: the best shape, its test and the held-out
/// comparison with the input side.
#[derive(Debug, Clone)]
pub struct FeedbackSignature {
    /// The basis whose column explains the residual best.
    pub kind: FeedbackKind,
    /// What z is for it.
    pub on: FeedbackOn,
    /// Its nested F test (one column beyond the level and direction bins of u and z itself),
    /// the p-value Bonferroni-corrected over the shapes tried.
    pub f: f64,
    /// That p-value.
    pub p_value: f64,
    /// Share of the held-out residual variance (beyond z and a constant) the feedback shape
    /// explains.
    pub held_out_feedback: f64,
    /// Share the input-side shapes explain together, on the same held-out part.
    pub held_out_input: f64,
}

impl FeedbackSignature {
    /// The rule: a feedback nonlinearity is offered only when its shape explains more of the
    /// held-out residual than the input-side shapes do together.
    pub fn offered(&self) -> bool {
        self.held_out_feedback > self.held_out_input && self.held_out_feedback > 0.0
    }
}

/// The feedback signature of `a`'s residual; `None` when no shape could be tested.
pub fn feedback_signature(a: &ResidualAnalysis) -> Option<FeedbackSignature> {
    let mut beyond = level_bins(&a.u, a.options.bins);
    beyond.extend(direction_bins(&a.u, &a.direction, a.options.direction_bins));
    let mut best: Option<(f64, f64, FeedbackKind, FeedbackOn, Vec<f64>)> = None;
    let mut tried = 0usize;
    for (kind, on) in VARIANTS {
        let z = feedback_variable(&a.y_hat, on);
        let mut base = beyond.clone();
        base.push(z.clone());
        base.extend(a.lag_base().iter().cloned());
        for col in shape_columns(&z, kind) {
            tried += 1;
            let Some(t) = a
                .engine()
                .test(std::slice::from_ref(&col), &base, Domain::Input)
            else {
                continue;
            };
            if best.as_ref().is_none_or(|b| t.f > b.0) {
                best = Some((t.f, t.p_value, kind, on, col));
            }
        }
    }
    let (f, p, kind, on, col) = best?;
    let z = feedback_variable(&a.y_hat, on);
    let (fb, inp) = held_out(a, &z, &col);
    Some(FeedbackSignature {
        kind,
        on,
        f,
        p_value: (p * tried as f64).min(1.0),
        held_out_feedback: fb,
        held_out_input: inp,
    })
}

/// The input-side shapes of the built-in signature tests (before filtering).
fn input_shapes(a: &ResidualAnalysis) -> Vec<Vec<f64>> {
    let u = &a.u;
    let s = sorted(u);
    let abs = sorted(&u.iter().map(|v| v.abs()).collect::<Vec<_>>());
    let mut cols = level_bins(u, a.options.bins);
    cols.extend(direction_bins(u, &direction(u), a.options.direction_bins));
    cols.extend(hinges(
        u,
        quantile_sorted(&s, 0.1),
        quantile_sorted(&s, 0.9),
    ));
    cols.push(clip(u, quantile_sorted(&abs, 0.2)));
    cols.push(centred_power(u, 2));
    cols.push(centred_power(u, 3));
    cols
}

/// Held-out explained variance (Hastie, Tibshirani & Friedman 2009, *The Elements of Statistical
/// Learning*, §7.2: the error on data the fit did not see): the residual e (after the analysis'
/// burn-in) is regressed by least squares on the first two thirds, with a constant and G·z in
/// every design, and each design predicts the last third; returned for the feedback column
/// `col` and for the input-side shapes together, each as 1 − SSE/SSE₀, SSE₀ the base design's
/// (constant and G·z alone). Negative: the shapes predict worse than the base.
pub fn held_out(a: &ResidualAnalysis, z: &[f64], col: &[f64]) -> (f64, f64) {
    let n = a.residual.len();
    let burn = (n / 20).clamp(10, 100).min(n / 4);
    let split = burn + 2 * (n - burn) / 3;
    let g = |c: &[f64]| a.engine().filter(c);
    let one = vec![1.0; n];
    let base = [one, g(z)];
    let sse = |extra: &[Vec<f64>]| -> f64 {
        let cols: Vec<Vec<f64>> = base.iter().cloned().chain(extra.iter().cloned()).collect();
        let fit_cols: Vec<&[f64]> = cols.iter().map(|c| &c[burn..split]).collect();
        let ls = least_squares(&a.residual[burn..split], &fit_cols);
        (split..n)
            .map(|k| {
                let p: f64 = cols
                    .iter()
                    .zip(&ls.coefficients)
                    .map(|(c, b)| c[k] * b)
                    .sum();
                (a.residual[k] - p).powi(2)
            })
            .sum()
    };
    let s0 = sse(&[]);
    if s0.is_nan() || s0 <= 0.0 {
        return (0.0, 0.0);
    }
    let fb = sse(&[g(col)]);
    let inputs: Vec<Vec<f64>> = input_shapes(a).iter().map(|c| g(c)).collect();
    let inp = sse(&inputs);
    (1.0 - fb / s0, 1.0 - inp / s0)
}
