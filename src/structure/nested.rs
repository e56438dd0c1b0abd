//! Joint rational fits of the BLAs of several levels under nested hypotheses, and the F tests
//! between them (Schoukens, Marconato, Pintelon, Vandersteen, Rolain, "Structure discrimination in
//! block-oriented models using linear approximations: a theoretic framework", Automatica 53, 2015:
//! single-branch structures keep poles and zeros across levels, parallel branches move zeros, a
//! nonlinearity in feedback moves poles).
//!
//! Hypotheses, from the most to the least restricted, all of order n:
//! - `Linear`: one B/A for every level;
//! - `SharedAll`: one B/A and a gain per level (single branch);
//! - `SharedPoles`: one A, a B per level (parallel branches);
//! - `Free`: an A and a B per level (feedback).
//!
//! Each fit minimises the weighted error Σ_l Σ_k |G_l(k) − Ĝ_l(w_k)|² / σ²_l(k): Sanathanan–Koerner
//! iterations (the linearised error A·G − B weighted by 1/|A_prev|) for a start, then
//! Levenberg–Marquardt on the real and imaginary parts (column-scaled, each step a QR least-squares
//! solve). Nested hypotheses are compared by the F test on their costs,
//! F = ((V_r − V_f)/(p_f − p_r)) / (V_f/(N − p_f)), N the number of real residuals, which does not
//! depend on the scale of the weights.

use super::bla::C64;
use super::parametric::monic;
use crate::error::{Error, Result};
use faer::Mat;
use faer::linalg::solvers::SolveLstsq;

/// The BLA of one level on its lines: axis values w, values G and weights 1/σ.
#[derive(Debug, Clone)]
pub struct LevelData {
    /// w on each line.
    pub w: Vec<C64>,
    /// The BLA on each line.
    pub g: Vec<C64>,
    /// 1/σ on each line (σ² the BLA's variance there).
    pub weight: Vec<f64>,
}

/// A hypothesis on how the levels' linear models relate.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Hypothesis {
    /// One model for every level.
    Linear,
    /// Shared poles and zeros, a gain per level.
    SharedAll,
    /// Shared poles, zeros per level.
    SharedPoles,
    /// Each level its own poles and zeros.
    Free,
}

/// Where each level's coefficients sit in the parameter vector.
#[derive(Debug, Clone)]
struct Layout {
    a: Vec<Vec<usize>>,
    b: Vec<Vec<usize>>,
    gain: Vec<Option<usize>>,
    params: usize,
}

impl Layout {
    fn new(h: Hypothesis, n: usize, levels: usize) -> Self {
        let nb = n + 1;
        let mut a = Vec::new();
        let mut b = Vec::new();
        let mut gain = Vec::new();
        let params = match h {
            Hypothesis::Free => {
                for l in 0..levels {
                    let o = l * (n + nb);
                    a.push((o..o + n).collect());
                    b.push((o + n..o + n + nb).collect());
                    gain.push(None);
                }
                levels * (n + nb)
            }
            Hypothesis::SharedPoles => {
                for l in 0..levels {
                    a.push((0..n).collect());
                    let o = n + l * nb;
                    b.push((o..o + nb).collect());
                    gain.push(None);
                }
                n + levels * nb
            }
            Hypothesis::SharedAll | Hypothesis::Linear => {
                for l in 0..levels {
                    a.push((0..n).collect());
                    b.push((n..n + nb).collect());
                    gain.push((h == Hypothesis::SharedAll && l > 0).then(|| n + nb + l - 1));
                }
                n + nb
                    + if h == Hypothesis::SharedAll {
                        levels - 1
                    } else {
                        0
                    }
            }
        };
        Self { a, b, gain, params }
    }
}

/// A joint fit of all levels under one hypothesis.
#[derive(Debug, Clone)]
pub struct JointFit {
    /// The hypothesis.
    pub hypothesis: Hypothesis,
    /// Order n.
    pub order: usize,
    /// Weighted cost V.
    pub cost: f64,
    /// Number of free parameters.
    pub params: usize,
    /// Number of real residuals (twice the lines over all levels).
    pub residuals: usize,
    theta: Vec<f64>,
    layout: Layout,
    cov: Mat<f64>,
}

impl JointFit {
    /// Level l's denominator coefficients a_0..a_{n−1} (monic), numerator b_0..b_n (gain
    /// included) and their covariance (a then b).
    pub fn level_model(&self, l: usize) -> (Vec<f64>, Vec<f64>, Mat<f64>) {
        let ly = &self.layout;
        let c = ly.gain[l].map_or(1.0, |i| self.theta[i]);
        let a: Vec<f64> = ly.a[l].iter().map(|&i| self.theta[i]).collect();
        let b: Vec<f64> = ly.b[l].iter().map(|&i| c * self.theta[i]).collect();
        let idx: Vec<usize> = ly.a[l].iter().chain(&ly.b[l]).copied().collect();
        let cov = Mat::from_fn(idx.len(), idx.len(), |i, j| self.cov[(idx[i], idx[j])]);
        (a, b, cov)
    }

    /// The model's value at level l and axis value w.
    pub fn eval(&self, l: usize, w: C64) -> C64 {
        let (a, b, _) = self.level_model(l);
        super::parametric::polyval(&b, w) / monic(&a, w)
    }
}

/// Weighted residuals (re, im interleaved) and, when asked, the Jacobian of the model's
/// parameters.
fn residuals(
    data: &[LevelData],
    ly: &Layout,
    theta: &[f64],
    jac: Option<&mut Mat<f64>>,
) -> Vec<f64> {
    let rows: usize = data.iter().map(|d| 2 * d.w.len()).sum();
    let mut r = Vec::with_capacity(rows);
    let mut jm = jac;
    let mut row = 0;
    for (l, d) in data.iter().enumerate() {
        let c = ly.gain[l].map_or(1.0, |i| theta[i]);
        let a: Vec<f64> = ly.a[l].iter().map(|&i| theta[i]).collect();
        let b: Vec<f64> = ly.b[l].iter().map(|&i| theta[i]).collect();
        for k in 0..d.w.len() {
            let w = d.w[k];
            let av = monic(&a, w);
            let bv = super::parametric::polyval(&b, w);
            let h = bv / av;
            let e = (d.g[k] - h * c) * d.weight[k];
            r.push(e.re);
            r.push(e.im);
            if let Some(j) = jm.as_deref_mut() {
                // derivative of the residual: −weight · ∂(c·B/A)
                let s = -d.weight[k];
                let mut wp = C64::new(1.0, 0.0);
                for i in 0..a.len().max(b.len()) {
                    if i < a.len() {
                        let dv = -h * c * wp / av * s;
                        j[(row, ly.a[l][i])] += dv.re;
                        j[(row + 1, ly.a[l][i])] += dv.im;
                    }
                    if i < b.len() {
                        let dv = wp * c / av * s;
                        j[(row, ly.b[l][i])] += dv.re;
                        j[(row + 1, ly.b[l][i])] += dv.im;
                    }
                    wp *= w;
                }
                if let Some(gi) = ly.gain[l] {
                    let dv = h * s;
                    j[(row, gi)] += dv.re;
                    j[(row + 1, gi)] += dv.im;
                }
            }
            row += 2;
        }
    }
    r
}

fn cost(r: &[f64]) -> f64 {
    r.iter().map(|v| v * v).sum()
}

/// Sanathanan–Koerner start for a layout without gains: iterated linear least squares of
/// (A·G − B)·weight/|A_prev|.
fn sk_start(data: &[LevelData], ly: &Layout, n: usize, iterations: usize) -> Result<Vec<f64>> {
    let rows: usize = data.iter().map(|d| 2 * d.w.len()).sum();
    let p = ly.params;
    let mut theta = vec![0.0; p];
    let mut prev: Vec<Vec<f64>> = data.iter().map(|d| vec![1.0; d.w.len()]).collect();
    for _ in 0..iterations {
        let mut m = Mat::<f64>::zeros(rows, p);
        let mut rhs = Mat::<f64>::zeros(rows, 1);
        let mut row = 0;
        for (l, d) in data.iter().enumerate() {
            for k in 0..d.w.len() {
                let s = d.weight[k] / prev[l][k];
                let w = d.w[k];
                let mut wp = C64::new(1.0, 0.0);
                for i in 0..=n {
                    if i < n {
                        let v = wp * d.g[k] * s;
                        m[(row, ly.a[l][i])] += v.re;
                        m[(row + 1, ly.a[l][i])] += v.im;
                    }
                    let v = -wp * s;
                    m[(row, ly.b[l][i])] += v.re;
                    m[(row + 1, ly.b[l][i])] += v.im;
                    wp *= w;
                }
                let v = -w.powu(n as u32) * d.g[k] * s;
                rhs[(row, 0)] = v.re;
                rhs[(row + 1, 0)] = v.im;
                row += 2;
            }
        }
        theta = lstsq_scaled(&m, &rhs, 0.0)?;
        for (l, d) in data.iter().enumerate() {
            let a: Vec<f64> = ly.a[l].iter().map(|&i| theta[i]).collect();
            for k in 0..d.w.len() {
                prev[l][k] = monic(&a, d.w[k]).norm().max(1e-12);
            }
        }
    }
    Ok(theta)
}

/// Column-scaled least squares min |M x − rhs|² + lambda·|D x|² (D the column norms), by QR.
fn lstsq_scaled(m: &Mat<f64>, rhs: &Mat<f64>, lambda: f64) -> Result<Vec<f64>> {
    let (rows, p) = (m.nrows(), m.ncols());
    let norms: Vec<f64> = (0..p)
        .map(|j| {
            let s: f64 = (0..rows).map(|i| m[(i, j)] * m[(i, j)]).sum();
            if s > 0.0 { s.sqrt() } else { 1.0 }
        })
        .collect();
    let extra = if lambda > 0.0 { p } else { 0 };
    let a = Mat::from_fn(rows + extra, p, |i, j| {
        if i < rows {
            m[(i, j)] / norms[j]
        } else if i - rows == j {
            lambda.sqrt()
        } else {
            0.0
        }
    });
    let b = Mat::from_fn(
        rows + extra,
        1,
        |i, _| if i < rows { rhs[(i, 0)] } else { 0.0 },
    );
    let x = a.qr().solve_lstsq(&b);
    let out: Vec<f64> = (0..p).map(|j| x[(j, 0)] / norms[j]).collect();
    if out.iter().any(|v| !v.is_finite()) {
        return Err(Error::LinAlg("rational fit: singular least squares".into()));
    }
    Ok(out)
}

/// Levenberg–Marquardt from `theta`; returns the parameters, the cost and the Jacobian there.
fn levenberg_marquardt(
    data: &[LevelData],
    ly: &Layout,
    mut theta: Vec<f64>,
    iterations: usize,
) -> Result<(Vec<f64>, f64, Mat<f64>)> {
    let rows: usize = data.iter().map(|d| 2 * d.w.len()).sum();
    let p = ly.params;
    let mut jac = Mat::<f64>::zeros(rows, p);
    let mut r = residuals(data, ly, &theta, Some(&mut jac));
    let mut v = cost(&r);
    let mut lambda = 1e-4;
    for _ in 0..iterations {
        let rhs = Mat::from_fn(rows, 1, |i, _| -r[i]);
        let mut improved = false;
        for _ in 0..12 {
            let step = lstsq_scaled(&jac, &rhs, lambda)?;
            let trial: Vec<f64> = theta.iter().zip(&step).map(|(t, s)| t + s).collect();
            let rt = residuals(data, ly, &trial, None);
            let vt = cost(&rt);
            if vt.is_finite() && vt < v {
                let rel = (v - vt) / v.max(1e-300);
                theta = trial;
                v = vt;
                lambda = (lambda / 10.0).max(1e-12);
                improved = rel > 1e-7;
                break;
            }
            lambda *= 10.0;
        }
        jac = Mat::<f64>::zeros(rows, p);
        r = residuals(data, ly, &theta, Some(&mut jac));
        if !improved {
            break;
        }
    }
    Ok((theta, v, jac))
}

/// s²·(JᵀJ)⁻¹ from the QR of the column-scaled Jacobian, s² = V/(N − p).
fn covariance(jac: &Mat<f64>, v: f64) -> Mat<f64> {
    let (rows, p) = (jac.nrows(), jac.ncols());
    let norms: Vec<f64> = (0..p)
        .map(|j| {
            let s: f64 = (0..rows).map(|i| jac[(i, j)] * jac[(i, j)]).sum();
            if s > 0.0 { s.sqrt() } else { 1.0 }
        })
        .collect();
    let a = Mat::from_fn(rows, p, |i, j| jac[(i, j)] / norms[j]);
    let r = a.qr().thin_R().to_owned();
    // R⁻¹ by back substitution
    let mut ri = Mat::<f64>::zeros(p, p);
    for c in 0..p {
        for i in (0..=c).rev() {
            let mut s = if i == c { 1.0 } else { 0.0 };
            for k in i + 1..=c {
                s -= r[(i, k)] * ri[(k, c)];
            }
            let d = r[(i, i)];
            ri[(i, c)] = if d.abs() > 1e-300 {
                s / d
            } else {
                f64::INFINITY
            };
        }
    }
    let s2 = v / (rows.saturating_sub(p).max(1)) as f64;
    let cs = &ri * ri.transpose();
    Mat::from_fn(p, p, |i, j| s2 * cs[(i, j)] / (norms[i] * norms[j]))
}

/// Fits hypothesis `h` of order `n` to the levels' BLAs; `start` (optional) is a fit whose
/// level models start this one.
pub fn fit(
    data: &[LevelData],
    h: Hypothesis,
    n: usize,
    start: Option<&JointFit>,
) -> Result<JointFit> {
    fit_from(data, h, n, start, None)
}

/// As [`fit`]; with `pick = Some(l)` a shared denominator starts from level l's denominator of
/// `start` (instead of the mean over the levels).
pub fn fit_from(
    data: &[LevelData],
    h: Hypothesis,
    n: usize,
    start: Option<&JointFit>,
    pick: Option<usize>,
) -> Result<JointFit> {
    let levels = data.len();
    if levels == 0 {
        return Err(Error::NoExperiment);
    }
    if h == Hypothesis::Free && levels > 1 {
        return free_by_level(data, n, start);
    }
    let ly = Layout::new(h, n, levels);
    let residual_count: usize = data.iter().map(|d| 2 * d.w.len()).sum();
    if residual_count <= ly.params {
        return Err(Error::TooFewSamples {
            needed: ly.params / 2 + 1,
            got: residual_count / 2,
            reason: format!(
                "excited lines for a rational model of order {n} over {levels} level(s)"
            ),
        });
    }
    let theta0 = match (h, start) {
        (_, Some(s)) => from_models(s, &ly, data, pick)?,
        (Hypothesis::SharedAll, None) => {
            let lin = Layout::new(Hypothesis::Linear, n, levels);
            let t = sk_start(data, &lin, n, 5)?;
            let mut t = t;
            t.extend(std::iter::repeat_n(1.0, levels - 1));
            t
        }
        _ => sk_start(data, &ly, n, 5)?,
    };
    let (theta, cost, jac) = levenberg_marquardt(data, &ly, theta0, 40)?;
    let cov = covariance(&jac, cost);
    Ok(JointFit {
        hypothesis: h,
        order: n,
        cost,
        params: ly.params,
        residuals: residual_count,
        theta,
        layout: ly,
        cov,
    })
}

/// The free hypothesis as one fit per level (its Jacobian is block diagonal), assembled.
fn free_by_level(data: &[LevelData], n: usize, start: Option<&JointFit>) -> Result<JointFit> {
    let levels = data.len();
    let one = Layout::new(Hypothesis::Free, n, 1);
    let mut fits = Vec::with_capacity(levels);
    for (l, d) in data.iter().enumerate() {
        let sub = start.map(|s| {
            let (a, b, _) = s.level_model(l);
            JointFit {
                hypothesis: Hypothesis::Free,
                order: n,
                cost: 0.0,
                params: one.params,
                residuals: 2 * d.w.len(),
                theta: a.into_iter().chain(b).collect(),
                layout: one.clone(),
                cov: Mat::zeros(one.params, one.params),
            }
        });
        fits.push(fit_from(
            std::slice::from_ref(d),
            Hypothesis::Free,
            n,
            sub.as_ref(),
            None,
        )?);
    }
    let ly = Layout::new(Hypothesis::Free, n, levels);
    let p = ly.params;
    let per = one.params;
    let mut cov = Mat::<f64>::zeros(p, p);
    for (l, f) in fits.iter().enumerate() {
        for i in 0..per {
            for j in 0..per {
                cov[(l * per + i, l * per + j)] = f.cov[(i, j)];
            }
        }
    }
    Ok(JointFit {
        hypothesis: Hypothesis::Free,
        order: n,
        cost: fits.iter().map(|f| f.cost).sum(),
        params: p,
        residuals: fits.iter().map(|f| f.residuals).sum(),
        theta: fits.iter().flat_map(|f| f.theta.iter().copied()).collect(),
        layout: ly,
        cov,
    })
}

/// Start values for layout `ly` from another fit's level models: a shared A from the models'
/// mean denominator, shared B and gains by least squares with that A.
fn from_models(
    s: &JointFit,
    ly: &Layout,
    data: &[LevelData],
    pick: Option<usize>,
) -> Result<Vec<f64>> {
    let levels = data.len();
    let models: Vec<(Vec<f64>, Vec<f64>)> = (0..levels)
        .map(|l| {
            let (a, b, _) = s.level_model(l);
            (a, b)
        })
        .collect();
    let mut theta = vec![0.0; ly.params];
    let mut count = vec![0usize; ly.params];
    for l in 0..levels {
        let src = pick.filter(|&p| p < levels).unwrap_or(l);
        for (i, &ix) in ly.a[l].iter().enumerate() {
            theta[ix] += models[src].0[i];
            count[ix] += 1;
        }
    }
    // numerators: with the (possibly averaged) denominator, a linear least squares per b block
    let a_of = |l: usize, th: &[f64]| -> Vec<f64> {
        ly.a[l]
            .iter()
            .map(|&ix| th[ix] / count[ix].max(1) as f64)
            .collect()
    };
    let mut th = theta.clone();
    for l in 0..levels {
        let a = a_of(l, &theta);
        for (i, &ix) in ly.a[l].iter().enumerate() {
            th[ix] = a[i];
        }
    }
    let n = ly.a[0].len();
    let nb = n + 1;
    // the b block(s): gather equations of the levels sharing each block
    let shared_b = levels > 1 && ly.b[0] == ly.b[1];
    let groups: Vec<Vec<usize>> = if shared_b {
        vec![(0..levels).collect()]
    } else {
        (0..levels).map(|l| vec![l]).collect()
    };
    for g in groups {
        let rows: usize = g.iter().map(|&l| 2 * data[l].w.len()).sum();
        let mut m = Mat::<f64>::zeros(rows, nb);
        let mut rhs = Mat::<f64>::zeros(rows, 1);
        let mut row = 0;
        for &l in &g {
            let a: Vec<f64> = ly.a[l].iter().map(|&ix| th[ix]).collect();
            let d = &data[l];
            for k in 0..d.w.len() {
                let av = monic(&a, d.w[k]);
                let mut wp = C64::new(1.0, 0.0);
                for i in 0..nb {
                    let v = wp / av * d.weight[k];
                    m[(row, i)] = v.re;
                    m[(row + 1, i)] = v.im;
                    wp *= d.w[k];
                }
                let v = d.g[k] * d.weight[k];
                rhs[(row, 0)] = v.re;
                rhs[(row + 1, 0)] = v.im;
                row += 2;
            }
        }
        let b = lstsq_scaled(&m, &rhs, 0.0)?;
        for (i, &ix) in ly.b[g[0]].iter().enumerate() {
            th[ix] = b[i];
        }
    }
    for l in 0..levels {
        if let Some(gi) = ly.gain[l] {
            // gain of level l relative to the shared B/A
            let a: Vec<f64> = ly.a[l].iter().map(|&ix| th[ix]).collect();
            let b: Vec<f64> = ly.b[l].iter().map(|&ix| th[ix]).collect();
            let d = &data[l];
            let (mut num, mut den) = (0.0, 0.0);
            for k in 0..d.w.len() {
                let h = super::parametric::polyval(&b, d.w[k]) / monic(&a, d.w[k]);
                let w2 = d.weight[k] * d.weight[k];
                num += (h.conj() * d.g[k]).re * w2;
                den += h.norm_sqr() * w2;
            }
            th[gi] = if den > 0.0 { num / den } else { 1.0 };
        }
    }
    Ok(th)
}

/// The F test of a restricted fit against a fuller one: (F, p-value).
pub fn f_test(restricted: &JointFit, full: &JointFit) -> (f64, f64) {
    let d1 = full.params.saturating_sub(restricted.params).max(1) as f64;
    let d2 = full.residuals.saturating_sub(full.params).max(1) as f64;
    let f = ((restricted.cost - full.cost).max(0.0) / d1) / (full.cost / d2).max(1e-300);
    (f, super::bla::f_sf(f, d1, d2))
}
