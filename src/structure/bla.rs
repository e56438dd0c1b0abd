//! The best linear approximation (BLA) of a multisine record, per level, with its noise and
//! nonlinear-distortion variances per excited line.
//!
//! Robust method (Pintelon & Schoukens 2012, §4.3.1), M ≥ 2 realizations and P ≥ 2 steady
//! periods: per realization m the FRF averaged over the periods G^[m](k) = mean_p Y/U and the noise
//! variance of that mean from the period-to-period scatter; the BLA is mean_m G^[m], its total
//! variance Σ_m |G^[m] − G|² / (M(M−1)), its noise variance Σ_m σ²_n^[m] / M², and the stochastic
//! nonlinear distortion's share is their difference. Fast method (§4.3.2), one realization of a
//! random-odd multisine: the FRF and its noise variance as above; the distortion read at the
//! detection lines (non-excited odd lines: odd distortion; even lines: even distortion) above the
//! noise there, and carried to the excited lines by the nearest detection lines. One realization
//! of a full-grid multisine gives the FRF and its noise variance only.
//!
//! Nonlinearity verdict: under a linear system each line's ratio of total to noise variance (robust)
//! or detection-line power to its noise variance (fast) is F-distributed; the verdict counts the
//! lines significant at 1 % and tests that count against the binomial(K, 1 %) tail (p < 0.001).

use super::record::Record;
use crate::error::{Error, Result};
use realfft::RealFftPlanner;
use realfft::num_complex::Complex;

/// Complex numbers of the BLA (re-exported from `realfft`).
pub type C64 = Complex<f64>;

/// The BLA on one excited line.
#[derive(Debug, Clone, serde::Serialize)]
pub struct LineBla {
    /// Line index k (frequency k/N of the sampling frequency).
    pub k: usize,
    /// Frequency as a fraction of the sampling frequency.
    pub freq: f64,
    /// BLA real and imaginary part.
    pub g: (f64, f64),
    /// Variance of the BLA estimate: noise and stochastic distortion.
    pub var_total: f64,
    /// Noise variance of the BLA estimate (none with one period).
    pub var_noise: Option<f64>,
    /// Stochastic nonlinear distortion's variance of the BLA estimate, total − noise, ≥ 0
    /// (none when it cannot be separated).
    pub var_distortion: Option<f64>,
}

impl LineBla {
    /// The BLA as a complex number.
    pub fn value(&self) -> C64 {
        C64::new(self.g.0, self.g.1)
    }
}

/// How the variances were obtained.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum BlaMethod {
    /// Several realizations and periods: noise and distortion separated on the excited lines.
    Robust,
    /// One realization with detection lines: the distortion from the detection lines.
    Fast,
    /// One realization of a full grid: the noise variance only.
    NoiseOnly,
    /// One period: the total variance over realizations only, noise not separable.
    TotalOnly,
}

/// Whether a level's record shows nonlinear distortion above the noise, and the evidence.
#[derive(Debug, Clone, serde::Serialize)]
pub struct Nonlinearity {
    /// Distortion significantly above the noise.
    pub detected: bool,
    /// Mean distortion over mean noise, dB.
    pub db_above_noise: f64,
    /// Lines with distortion significant at 1 %.
    pub lines: usize,
    /// Lines tested.
    pub of: usize,
    /// Binomial tail probability of that many significant lines under linearity.
    pub p_value: f64,
    /// Which lines were tested.
    pub basis: String,
}

/// The BLA of one level.
#[derive(Debug, Clone, serde::Serialize)]
pub struct LevelBla {
    /// Level index.
    pub level: usize,
    /// RMS of the steady input.
    pub rms: f64,
    /// Realizations M.
    pub realizations: usize,
    /// Steady periods P (the smallest over the realizations).
    pub periods: usize,
    /// How the variances were obtained.
    pub method: BlaMethod,
    /// The BLA on the excited lines.
    pub lines: Vec<LineBla>,
    /// Output power at the even detection lines above the noise there, dB (none without them).
    pub even_db: Option<f64>,
    /// Output power at the odd detection lines above the noise there, dB.
    pub odd_db: Option<f64>,
    /// The nonlinearity verdict (none when the record cannot tell: one realization of a full
    /// grid, or one period).
    pub nonlinearity: Option<Nonlinearity>,
}

/// The BLAs of all levels of a record.
#[derive(Debug, Clone, serde::Serialize)]
pub struct Bla {
    /// Samples per period.
    pub period: usize,
    /// The excited lines (shared by all levels).
    pub excited: Vec<usize>,
    /// Per level, lowest RMS first.
    pub levels: Vec<LevelBla>,
}

/// Survival function of the F(d1, d2) distribution.
pub(crate) fn f_sf(f: f64, d1: f64, d2: f64) -> f64 {
    if f <= 0.0 {
        return 1.0;
    }
    statrs::function::beta::beta_reg(d2 / 2.0, d1 / 2.0, d2 / (d2 + d1 * f))
}

/// P(X ≥ c) for X ~ binomial(n, p).
fn binomial_tail(c: usize, n: usize, p: f64) -> f64 {
    if c == 0 {
        return 1.0;
    }
    if c > n {
        return 0.0;
    }
    statrs::function::beta::beta_reg(c as f64, (n - c + 1) as f64, p)
}

/// Spectra (lines 0..=N/2, scaled by 1/N) of each steady period of a signal.
fn period_spectra(
    x: &[f64],
    n: usize,
    fft: &std::sync::Arc<dyn realfft::RealToComplex<f64>>,
) -> Vec<Vec<C64>> {
    let mut buf = vec![0.0; n];
    (1..x.len() / n)
        .map(|p| {
            buf.copy_from_slice(&x[p * n..(p + 1) * n]);
            let mut out = fft.make_output_vec();
            fft.process(&mut buf, &mut out)
                .expect("buffer lengths come from the plan");
            out.iter_mut().for_each(|c| *c /= n as f64);
            out
        })
        .collect()
}

/// The excited lines of a record: lines 1..N/2 whose input power, averaged over all steady
/// periods (each level normalised by its power), lies within 30 dB of the strongest lines'.
pub fn excited_lines(record: &Record) -> Result<Vec<usize>> {
    let n = record.period();
    let mut planner = RealFftPlanner::<f64>::new();
    let fft = planner.plan_fft_forward(n);
    let mut power = vec![0.0; n / 2 + 1];
    for b in record.blocks() {
        let spectra = period_spectra(&b.u, n, &fft);
        let mut p = vec![0.0; n / 2 + 1];
        for s in &spectra {
            for (pk, c) in p.iter_mut().zip(s) {
                *pk += c.norm_sqr();
            }
        }
        let total: f64 = p[1..].iter().sum();
        if total > 0.0 {
            for (a, v) in power.iter_mut().zip(&p) {
                *a += v / total;
            }
        }
    }
    let top = (n - 1) / 2;
    let mut sorted: Vec<f64> = power[1..=top].to_vec();
    sorted.sort_by(|a, b| b.total_cmp(a));
    let strongest = sorted.iter().take(10).sum::<f64>() / sorted.len().clamp(1, 10) as f64;
    if strongest <= 0.0 {
        return Err(Error::ConstantInput { name: "u".into() });
    }
    let lines: Vec<usize> = (1..=top)
        .filter(|&k| power[k] >= 1e-3 * strongest)
        .collect();
    Ok(lines)
}

/// The BLA of every level of a measured record (see the module text for the method).
pub fn bla(record: &Record) -> Result<Bla> {
    if !record.has_output() {
        return Err(Error::InvalidParameter(
            "the record has no output column y: replay its input u on the plant and add the measured y".into(),
        ));
    }
    let n = record.period();
    let excited = excited_lines(record)?;
    let (kmin, kmax) = (excited[0], *excited.last().expect("non-empty"));
    let detection: Vec<usize> = (kmin..=kmax)
        .filter(|k| excited.binary_search(k).is_err())
        .collect();
    let mut planner = RealFftPlanner::<f64>::new();
    let fft = planner.plan_fft_forward(n);
    let mut levels = Vec::with_capacity(record.levels());
    for level in 0..record.levels() {
        let blocks: Vec<_> = record
            .blocks()
            .iter()
            .filter(|b| b.level == level)
            .collect();
        let m = blocks.len();
        // per realization: mean FRF over periods, its noise variance; output at detection lines
        let mut g_m: Vec<Vec<C64>> = Vec::with_capacity(m);
        let mut vn_m: Vec<Vec<f64>> = Vec::with_capacity(m);
        let mut u_pow = vec![0.0; excited.len()];
        let mut det_pow = vec![0.0; detection.len()];
        let mut det_noise = vec![0.0; detection.len()];
        let mut periods = usize::MAX;
        for b in &blocks {
            let us = period_spectra(&b.u, n, &fft);
            let ys = period_spectra(b.y.as_ref().expect("has_output"), n, &fft);
            let p = us.len();
            periods = periods.min(p);
            let block_power: f64 = excited
                .iter()
                .map(|&k| us.iter().map(|s| s[k].norm_sqr()).sum::<f64>())
                .sum::<f64>()
                / (p * excited.len()) as f64;
            let mut g = Vec::with_capacity(excited.len());
            let mut vn = Vec::with_capacity(excited.len());
            for (i, &k) in excited.iter().enumerate() {
                let up: f64 = us.iter().map(|s| s[k].norm_sqr()).sum::<f64>() / p as f64;
                if up < 1e-3 * block_power {
                    return Err(Error::InvalidParameter(format!(
                        "unexcited line: line {k} (frequency {:.5} of the sampling frequency) is excited \
                         in the record but {:.1} dB below the other lines in level {level} realization {}; \
                         every realization must excite the same lines",
                        k as f64 / n as f64,
                        10.0 * (up / block_power).log10(),
                        b.realization
                    )));
                }
                u_pow[i] += up / m as f64;
                let gp: Vec<C64> = us.iter().zip(&ys).map(|(u, y)| y[k] / u[k]).collect();
                let mean = gp.iter().sum::<C64>() / p as f64;
                g.push(mean);
                vn.push(if p > 1 {
                    gp.iter().map(|x| (x - mean).norm_sqr()).sum::<f64>() / (p * (p - 1)) as f64
                } else {
                    f64::NAN
                });
            }
            for (i, &k) in detection.iter().enumerate() {
                let mean = ys.iter().map(|s| s[k]).sum::<C64>() / p as f64;
                det_pow[i] += mean.norm_sqr() / m as f64;
                if p > 1 {
                    det_noise[i] += ys.iter().map(|s| (s[k] - mean).norm_sqr()).sum::<f64>()
                        / (p * (p - 1)) as f64
                        / m as f64;
                }
            }
            g_m.push(g);
            vn_m.push(vn);
        }
        let has_noise = periods > 1;
        let method = match (m > 1, has_noise) {
            (true, true) => BlaMethod::Robust,
            (true, false) => BlaMethod::TotalOnly,
            (false, true) if !detection.is_empty() => BlaMethod::Fast,
            (false, true) => BlaMethod::NoiseOnly,
            (false, false) => {
                return Err(Error::TooFewSamples {
                    needed: 3 * n,
                    got: 2 * n,
                    reason: format!(
                        "level {level}: one realization of one steady period gives no variance; \
                         measure two steady periods or two realizations"
                    ),
                });
            }
        };
        // detection-line distortion power above the noise (fast method and even/odd levels)
        let det_excess: Vec<f64> = det_pow
            .iter()
            .zip(&det_noise)
            .map(|(p, v)| (p - v).max(0.0))
            .collect();
        let mut lines = Vec::with_capacity(excited.len());
        for (i, &k) in excited.iter().enumerate() {
            let g = g_m.iter().map(|g| g[i]).sum::<C64>() / m as f64;
            let vnoise = has_noise.then(|| vn_m.iter().map(|v| v[i]).sum::<f64>() / (m * m) as f64);
            let (var_total, var_distortion) = match method {
                BlaMethod::Robust | BlaMethod::TotalOnly => {
                    let vt = g_m.iter().map(|gm| (gm[i] - g).norm_sqr()).sum::<f64>()
                        / (m * (m - 1)) as f64;
                    (vt, vnoise.map(|vn| (vt - vn).max(0.0)))
                }
                BlaMethod::Fast => {
                    let d = nearest_mean(&detection, &det_excess, k, 4) / u_pow[i];
                    (vnoise.unwrap_or(0.0) + d, Some(d))
                }
                BlaMethod::NoiseOnly => (vnoise.unwrap_or(f64::NAN), None),
            };
            lines.push(LineBla {
                k,
                freq: k as f64 / n as f64,
                g: (g.re, g.im),
                var_total,
                var_noise: vnoise,
                var_distortion,
            });
        }
        let db_of = |sel: &dyn Fn(usize) -> bool| -> Option<f64> {
            let idx: Vec<usize> = (0..detection.len())
                .filter(|&i| sel(detection[i]))
                .collect();
            if idx.is_empty() || !has_noise {
                return None;
            }
            let e: f64 = idx.iter().map(|&i| det_excess[i]).sum();
            let v: f64 = idx.iter().map(|&i| det_noise[i]).sum();
            Some(db(e, v))
        };
        let even_db = db_of(&|k| k % 2 == 0);
        let odd_db = db_of(&|k| k % 2 == 1);
        let nonlinearity = match method {
            BlaMethod::Robust => {
                let (d1, d2) = (2.0 * (m - 1) as f64, 2.0 * (m * (periods - 1)) as f64);
                let sig = lines
                    .iter()
                    .filter(|l| f_sf(l.var_total / l.var_noise.unwrap_or(f64::NAN), d1, d2) < 0.01)
                    .count();
                let e: f64 = lines.iter().filter_map(|l| l.var_distortion).sum();
                let v: f64 = lines.iter().filter_map(|l| l.var_noise).sum();
                Some(verdict(
                    sig,
                    lines.len(),
                    db(e, v),
                    "excited lines, robust method",
                ))
            }
            BlaMethod::Fast => {
                let d2 = 2.0 * (periods - 1) as f64;
                let sig = det_pow
                    .iter()
                    .zip(&det_noise)
                    .filter(|(p, v)| f_sf(*p / *v, 2.0, d2) < 0.01)
                    .count();
                let e: f64 = det_excess.iter().sum();
                let v: f64 = det_noise.iter().sum();
                Some(verdict(
                    sig,
                    detection.len(),
                    db(e, v),
                    "detection lines, fast method",
                ))
            }
            _ => None,
        };
        levels.push(LevelBla {
            level,
            rms: record.rms(level),
            realizations: m,
            periods,
            method,
            lines,
            even_db,
            odd_db,
            nonlinearity,
        });
    }
    Ok(Bla {
        period: n,
        excited,
        levels,
    })
}

fn db(excess: f64, noise: f64) -> f64 {
    if noise > 0.0 {
        (10.0 * (excess.max(1e-300) / noise).log10()).max(-99.0)
    } else {
        f64::INFINITY
    }
}

fn verdict(sig: usize, of: usize, db_above_noise: f64, basis: &str) -> Nonlinearity {
    let p_value = binomial_tail(sig, of, 0.01);
    Nonlinearity {
        detected: p_value < 1e-3,
        db_above_noise,
        lines: sig,
        of,
        p_value,
        basis: basis.to_string(),
    }
}

/// Mean of `values` at the `count` entries of `lines` nearest to `k`.
fn nearest_mean(lines: &[usize], values: &[f64], k: usize, count: usize) -> f64 {
    let mut idx: Vec<usize> = (0..lines.len()).collect();
    idx.sort_by_key(|&i| lines[i].abs_diff(k));
    let take = idx.len().min(count);
    if take == 0 {
        return 0.0;
    }
    idx[..take].iter().map(|&i| values[i]).sum::<f64>() / take as f64
}
