//! Non-periodic records at several amplitudes: the record split by the input's local RMS (or
//! several records), an ARX model per amplitude class by linear least squares, and the same
//! movement test on the poles.
//!
//! Windows of `window` samples are ranked by the input's RMS and cut into `classes` groups of
//! equal count (the Silverbox "arrow", whose amplitude grows along the record, gives its low- and
//! high-amplitude parts). Per class the ARX model
//! y(t) + a_1 y(t−1) + … + a_n y(t−n) = b_0 u(t) + … + b_n u(t−n) + c + e(t)
//! is fitted on the rows whose lags stay inside one window (QR least squares; covariance
//! s²(ΦᵀΦ)⁻¹, Ljung, *System Identification*, 2nd ed. 1999, §9.2). Nested least squares over the
//! classes: a and b per class, against a shared a (poles move: F test), against shared a and b
//! with an offset per class (numerator moves).
//!
//! What this weaker evidence can and cannot show: without periodicity, noise and nonlinear
//! distortion are not separated, the ARX equation error is biased by coloured noise and
//! distortion (a bias that may differ between classes), and a gain change cannot be told from a
//! zero movement. Poles that move by many standard errors point to a nonlinearity in feedback;
//! poles that stay with a numerator that moves leave single-branch and parallel apart.

use super::nested::Hypothesis;
use super::parametric::{Axis, roots_with_errors};
use super::verdict::{LevelStructure, Movement, NestedTest, Structure, Verdict};
use crate::error::{Error, Result};
use faer::Mat;
use faer::linalg::solvers::SolveLstsq;

/// Options of the amplitude split.
#[derive(Debug, Clone)]
pub struct AmplitudeOptions {
    /// Window length in samples for the local RMS.
    pub window: usize,
    /// Number of amplitude classes.
    pub classes: usize,
    /// ARX order n (none: chosen by BIC up to `max_order`).
    pub order: Option<usize>,
    /// Highest order tried.
    pub max_order: usize,
    /// Sampling time (Hz in the evidence), if known.
    pub ts: Option<f64>,
    /// Level of the F tests.
    pub alpha: f64,
}

impl Default for AmplitudeOptions {
    fn default() -> Self {
        Self {
            window: 1000,
            classes: 2,
            order: None,
            max_order: 6,
            ts: None,
            alpha: 1e-3,
        }
    }
}

/// A class: the windows (start, end) it holds and its input RMS.
#[derive(Debug, Clone)]
pub struct AmplitudeClass {
    /// Sample ranges of the class.
    pub windows: Vec<(usize, usize)>,
    /// Input RMS over them.
    pub rms: f64,
}

/// Splits a record into `classes` classes by the input's RMS over windows of `window` samples.
pub fn split_by_rms(u: &[f64], window: usize, classes: usize) -> Result<Vec<AmplitudeClass>> {
    if classes < 2 {
        return Err(Error::InvalidParameter(
            "at least two amplitude classes are needed to see movement".into(),
        ));
    }
    let count = u.len() / window.max(1);
    if window < 20 || count < 2 * classes {
        return Err(Error::TooFewSamples {
            needed: 2 * classes * window.max(20),
            got: u.len(),
            reason: format!(
                "{classes} amplitude classes of at least two windows of {window} samples"
            ),
        });
    }
    let mean = u.iter().sum::<f64>() / u.len() as f64;
    let mut w: Vec<(f64, usize)> = (0..count)
        .map(|i| {
            let s = &u[i * window..(i + 1) * window];
            (
                (s.iter().map(|v| (v - mean) * (v - mean)).sum::<f64>() / window as f64).sqrt(),
                i,
            )
        })
        .collect();
    w.sort_by(|a, b| a.0.total_cmp(&b.0));
    let per = count / classes;
    Ok((0..classes)
        .map(|c| {
            let part = &w[c * per..if c + 1 == classes {
                count
            } else {
                (c + 1) * per
            }];
            let rms = (part.iter().map(|p| p.0 * p.0).sum::<f64>() / part.len() as f64).sqrt();
            let mut windows: Vec<(usize, usize)> = part
                .iter()
                .map(|p| (p.1 * window, (p.1 + 1) * window))
                .collect();
            windows.sort();
            AmplitudeClass { windows, rms }
        })
        .collect())
}

struct Rows {
    phi: Vec<Vec<f64>>, // per class: row-major regressors [−y lags (n), u lags (n+1)]
    y: Vec<Vec<f64>>,
    rows: Vec<usize>,
}

fn regressors(u: &[f64], y: &[f64], classes: &[AmplitudeClass], n: usize) -> Rows {
    let width = 2 * n + 1;
    let mut out = Rows {
        phi: Vec::new(),
        y: Vec::new(),
        rows: Vec::new(),
    };
    for c in classes {
        let mut phi = Vec::new();
        let mut ys = Vec::new();
        for &(s, e) in &c.windows {
            for t in s + n..e {
                for i in 1..=n {
                    phi.push(-y[t - i]);
                }
                for i in 0..=n {
                    phi.push(u[t - i]);
                }
                ys.push(y[t]);
            }
        }
        out.rows.push(ys.len());
        debug_assert_eq!(phi.len(), ys.len() * width);
        out.phi.push(phi);
        out.y.push(ys);
    }
    out
}

/// One nested least squares: `shared_a`, `shared_b` say which coefficients the classes share (an
/// offset per class always). Returns (cost, params, theta, covariance).
fn nested_ls(
    r: &Rows,
    n: usize,
    shared_a: bool,
    shared_b: bool,
) -> Result<(f64, usize, Vec<f64>, Mat<f64>)> {
    let k = r.rows.len();
    let (pa, pb) = (n, n + 1);
    let na_total = if shared_a { pa } else { k * pa };
    let nb_total = if shared_b { pb } else { k * pb };
    let p = na_total + nb_total + k;
    let total: usize = r.rows.iter().sum();
    if total <= p {
        return Err(Error::TooFewSamples {
            needed: p + 1,
            got: total,
            reason: "rows for the ARX models of the amplitude classes".into(),
        });
    }
    let mut m = Mat::<f64>::zeros(total, p);
    let mut rhs = Mat::<f64>::zeros(total, 1);
    let mut row = 0;
    for c in 0..k {
        let ao = if shared_a { 0 } else { c * pa };
        let bo = na_total + if shared_b { 0 } else { c * pb };
        for i in 0..r.rows[c] {
            let reg = &r.phi[c][i * (2 * n + 1)..(i + 1) * (2 * n + 1)];
            for j in 0..pa {
                m[(row, ao + j)] = reg[j];
            }
            for j in 0..pb {
                m[(row, bo + j)] = reg[pa + j];
            }
            m[(row, na_total + nb_total + c)] = 1.0;
            rhs[(row, 0)] = r.y[c][i];
            row += 1;
        }
    }
    let qr = m.qr();
    let x = qr.solve_lstsq(&rhs);
    let theta: Vec<f64> = (0..p).map(|i| x[(i, 0)]).collect();
    let mut cost = 0.0;
    for i in 0..total {
        let mut v = rhs[(i, 0)];
        for j in 0..p {
            v -= m[(i, j)] * theta[j];
        }
        cost += v * v;
    }
    let rr = qr.thin_R().to_owned();
    let mut ri = Mat::<f64>::zeros(p, p);
    for c in 0..p {
        for i in (0..=c).rev() {
            let mut s = if i == c { 1.0 } else { 0.0 };
            for l in i + 1..=c {
                s -= rr[(i, l)] * ri[(l, c)];
            }
            ri[(i, c)] = s / rr[(i, i)];
        }
    }
    let s2 = cost / (total - p) as f64;
    let cov = Mat::from_fn(p, p, |i, j| {
        s2 * (0..p).map(|l| ri[(i, l)] * ri[(j, l)]).sum::<f64>()
    });
    Ok((cost, p, theta, cov))
}

/// The structure analysis of a non-periodic record split into amplitude classes.
pub fn analyze_by_amplitude(u: &[f64], y: &[f64], options: &AmplitudeOptions) -> Result<Structure> {
    if u.len() != y.len() {
        return Err(Error::LengthMismatch {
            what: format!("u has {} samples, y {}", u.len(), y.len()),
        });
    }
    let classes = split_by_rms(u, options.window, options.classes)?;
    let (lo, hi) = (classes[0].rms, classes[classes.len() - 1].rms);
    if hi < 1.2 * lo {
        // what one level still tells: whether the record is nonlinear at all
        let what = match super::reset::reset_test(u, y, options.max_order) {
            Ok(r) if r.p_value < options.alpha => format!(
                "the record is nonlinear (RESET test on an ARX({}) model of the whole record: the \
                 squares and cubes of its prediction and past outputs explain the output further, \
                 F({}, {}) = {:.1}, {})",
                r.order,
                r.added,
                r.rows - 2 * r.order - 2 - r.added,
                r.f,
                if r.p_value < 1e-300 {
                    "p < 1e-300".to_string()
                } else {
                    format!("p = {:.1e}", r.p_value)
                }
            ),
            Ok(r) => format!(
                "no nonlinearity detected (RESET test on an ARX({}) model: F = {:.2}, p = {:.2})",
                r.order, r.f, r.p_value
            ),
            Err(e) => format!("the RESET test could not run: {e}"),
        };
        return Err(Error::InvalidParameter(format!(
            "the input's local RMS varies from {lo:.4} to {hi:.4} only (less than 20 %): the record \
             holds one amplitude level, so whether poles or zeros move with the level is not \
             testable. What one level tells: {what}. Measure at two or more amplitudes."
        )));
    }
    let order_of = |n: usize| -> Result<f64> {
        let r = regressors(u, y, &classes, n);
        let (v, p, _, _) = nested_ls(&r, n, false, false)?;
        let nr: f64 = r.rows.iter().sum::<usize>() as f64;
        Ok(nr * (v / nr).ln() + p as f64 * nr.ln())
    };
    let order = match options.order {
        Some(n) => n,
        None => (1..=options.max_order.max(1))
            .filter_map(|n| order_of(n).ok().map(|b| (b, n)))
            .min_by(|a, b| a.0.total_cmp(&b.0))
            .map(|x| x.1)
            .ok_or_else(|| Error::Identification("no ARX model could be fitted".into()))?,
    };
    let n = order;
    let r = regressors(u, y, &classes, n);
    let total: usize = r.rows.iter().sum();
    let free = nested_ls(&r, n, false, false)?;
    let poles_shared = nested_ls(&r, n, true, false)?;
    let all_shared = nested_ls(&r, n, true, true)?;
    let test = |q: &str,
                rs: &(f64, usize, Vec<f64>, Mat<f64>),
                fl: &(f64, usize, Vec<f64>, Mat<f64>),
                h: (Hypothesis, Hypothesis)| {
        let d1 = (fl.1 - rs.1).max(1) as f64;
        let d2 = (total - fl.1).max(1) as f64;
        let f = ((rs.0 - fl.0).max(0.0) / d1) / (fl.0 / d2);
        let p = super::bla::f_sf(f, d1, d2);
        NestedTest {
            question: q.into(),
            restricted: h.0,
            full: h.1,
            costs: (rs.0, fl.0),
            params: (rs.1, fl.1),
            f,
            p_value: p,
            rejected: p < options.alpha,
        }
    };
    let tests = vec![
        test(
            "poles move",
            &poles_shared,
            &free,
            (Hypothesis::SharedPoles, Hypothesis::Free),
        ),
        test(
            "numerator moves",
            &all_shared,
            &poles_shared,
            (Hypothesis::Linear, Hypothesis::SharedPoles),
        ),
    ];
    let verdict = if tests[0].rejected {
        Verdict::Feedback
    } else if tests[1].rejected {
        Verdict::SingleBranch
    } else {
        Verdict::Linear
    };
    let ts = options.ts.unwrap_or(1.0);
    let axis = Axis::z_domain(ts);
    let k = classes.len();
    let mut levels = Vec::with_capacity(k);
    let (_, _, theta, cov) = &free;
    for c in 0..k {
        // z^n + a_1 z^{n−1} + … + a_n: ascending coefficients a_n … a_1, monic top
        let idx_a: Vec<usize> = (0..n).rev().map(|j| c * n + j).collect();
        let coef: Vec<f64> = idx_a.iter().map(|&i| theta[i]).collect();
        let ca = Mat::from_fn(n, n, |i, j| cov[(idx_a[i], idx_a[j])]);
        let bo = k * n + c * (n + 1);
        let idx_b: Vec<usize> = (0..=n).rev().map(|j| bo + j).collect();
        let bcoef: Vec<f64> = idx_b.iter().map(|&i| theta[i]).collect();
        let cb = Mat::from_fn(n + 1, n + 1, |i, j| cov[(idx_b[i], idx_b[j])]);
        levels.push(LevelStructure {
            rms: classes[c].rms,
            poles: roots_with_errors(&coef, true, &ca, &axis)?,
            zeros: roots_with_errors(&bcoef, false, &cb, &axis)?,
            distortion_db: None,
        });
    }
    let mut moved = Vec::new();
    for (x, yv) in super::verdict::match_roots(&levels[0].poles, &levels[k - 1].poles) {
        if x.real || yv.real {
            continue;
        }
        moved.push(Movement {
            kind: "pole".into(),
            from_level: 0,
            to_level: k - 1,
            from: x.clone(),
            to: yv.clone(),
            freq_shift_se: (yv.freq - x.freq) / (x.freq_se.powi(2) + yv.freq_se.powi(2)).sqrt(),
            damping_shift_se: (yv.damping - x.damping)
                / (x.damping_se.powi(2) + yv.damping_se.powi(2)).sqrt(),
        });
    }
    moved.sort_by(|a, b| b.freq_shift_se.abs().total_cmp(&a.freq_shift_se.abs()));
    let mut notes = vec![
        "non-periodic record: ARX models per amplitude class; noise and nonlinear distortion are \
         not separated and the equation error's bias may differ between classes, so this \
         evidence is weaker than multisine BLAs"
            .to_string(),
    ];
    if verdict == Verdict::SingleBranch {
        notes.push(
            "poles stay, the numerator moves: single-branch or parallel branches (a gain change \
             and a zero movement are not separated here)"
                .into(),
        );
    }
    Ok(Structure {
        verdict,
        order,
        freq_unit: if options.ts.is_some() {
            "Hz".into()
        } else {
            "cycles/sample".into()
        },
        levels,
        tests,
        moved,
        ranking: None,
        candidates: match verdict {
            Verdict::Feedback => {
                vec!["static nonlinearity in feedback (lur'e / nonlinear lfr)".into()]
            }
            Verdict::SingleBranch => vec!["single-branch or parallel".into()],
            _ => vec!["linear (at these amplitudes)".into()],
        },
        notes,
    })
}
