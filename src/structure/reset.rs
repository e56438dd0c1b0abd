//! Is a non-periodic record of one amplitude level nonlinear? Ramsey's RESET test on an ARX
//! model of the whole record (J. B. Ramsey, "Tests for specification errors in classical linear
//! least-squares regression analysis", J. R. Stat. Soc. B 31, 1969): the ARX model
//! y(t) + a_1 y(t−1) + … + a_n y(t−n) = b_0 u(t) + … + b_n u(t−n) + c + e(t), n chosen by BIC
//! (QR least squares), then its prediction ŷ(t) squared and cubed added as regressors, with the
//! squares and cubes of the past outputs y(t−1) … y(t−n) it is built from (standardised), and the
//! F test on their 2(n + 1) coefficients. The lagged powers extend Ramsey's ŷ², ŷ³ so that a
//! nonlinearity followed by a filter (Wiener–Hammerstein) is seen too.
//!
//! What it can and cannot show: a significant F says that the output depends on the input
//! beyond any linear model of that order (a static nonlinearity, wherever it sits, adds powers
//! of the signals); the F test assumes the equation error white (a high ARX order whitens most
//! of it: the unit test holds ten linear records with output noise through 1/(1 − 0.9 z⁻¹) to
//! at most one called nonlinear). Where the nonlinearity sits needs several levels.

use crate::error::{Error, Result};
use faer::Mat;
use faer::linalg::solvers::SolveLstsq;

/// The RESET test's outcome.
#[derive(Debug, Clone, serde::Serialize)]
pub struct Reset {
    /// ARX order (chosen by BIC).
    pub order: usize,
    /// The F statistic of the added powers.
    pub f: f64,
    /// Its p-value (F(added, N − p − added)).
    pub p_value: f64,
    /// Number of regressors added: ŷ(t)², ŷ(t)³ and y(t−k)², y(t−k)³ for k = 1..n.
    pub added: usize,
    /// Rows of the regression.
    pub rows: usize,
}

/// Least squares of `y` on the columns `cols` (all of length `y.len()`); returns the fitted
/// values and the residual sum of squares.
fn lstsq(cols: &[Vec<f64>], y: &[f64]) -> Result<(Vec<f64>, f64)> {
    let (rows, p) = (y.len(), cols.len());
    // columns scaled to unit norm for the QR's conditioning
    let norms: Vec<f64> = cols
        .iter()
        .map(|c| c.iter().map(|v| v * v).sum::<f64>().sqrt().max(1e-300))
        .collect();
    let m = Mat::from_fn(rows, p, |i, j| cols[j][i] / norms[j]);
    let rhs = Mat::from_fn(rows, 1, |i, _| y[i]);
    let x = m.qr().solve_lstsq(&rhs);
    let fit: Vec<f64> = (0..rows)
        .map(|i| (0..p).map(|j| m[(i, j)] * x[(j, 0)]).sum())
        .collect();
    if fit.iter().any(|v| !v.is_finite()) {
        return Err(Error::LinAlg("RESET: singular least squares".into()));
    }
    let v = fit.iter().zip(y).map(|(f, y)| (y - f) * (y - f)).sum();
    Ok((fit, v))
}

fn arx_columns(u: &[f64], y: &[f64], n: usize, start: usize) -> Vec<Vec<f64>> {
    let mut cols = Vec::with_capacity(2 * n + 2);
    for i in 1..=n {
        cols.push((start..y.len()).map(|t| -y[t - i]).collect());
    }
    for i in 0..=n {
        cols.push((start..y.len()).map(|t| u[t - i]).collect());
    }
    cols.push(vec![1.0; y.len() - start]);
    cols
}

/// The RESET test of a one-level record, ARX orders 1..=`max_order` (all fitted on the same
/// rows, from sample `max_order` on).
pub fn reset_test(u: &[f64], y: &[f64], max_order: usize) -> Result<Reset> {
    let max_order = max_order.max(1);
    let start = max_order;
    let rows = y.len().saturating_sub(start);
    if u.len() != y.len() || rows < 10 * (2 * max_order + 4) {
        return Err(Error::TooFewSamples {
            needed: start + 10 * (2 * max_order + 4),
            got: y.len().min(u.len()),
            reason: "the RESET test of an ARX model".into(),
        });
    }
    let target = &y[start..];
    let mut best: Option<(f64, usize, Vec<Vec<f64>>, Vec<f64>, f64)> = None;
    for n in 1..=max_order {
        let cols = arx_columns(u, y, n, start);
        let Ok((fit, v)) = lstsq(&cols, target) else {
            continue;
        };
        let bic = rows as f64 * (v / rows as f64).max(1e-300).ln()
            + cols.len() as f64 * (rows as f64).ln();
        if best.as_ref().is_none_or(|b| bic < b.0) {
            best = Some((bic, n, cols, fit, v));
        }
    }
    let (_, order, mut cols, fit, v0) =
        best.ok_or_else(|| Error::Identification("no ARX model could be fitted".into()))?;
    let mean = fit.iter().sum::<f64>() / rows as f64;
    let sd = (fit.iter().map(|f| (f - mean) * (f - mean)).sum::<f64>() / rows as f64)
        .sqrt()
        .max(1e-300);
    // the prediction's powers, and those of the past outputs it is built from (the lags let
    // the test see a nonlinearity that sits before a filter)
    cols.push(fit.iter().map(|f| ((f - mean) / sd).powi(2)).collect());
    cols.push(fit.iter().map(|f| ((f - mean) / sd).powi(3)).collect());
    for k in 1..=order {
        let z = |t: usize| (y[t - k] - mean) / sd;
        cols.push((start..y.len()).map(|t| z(t).powi(2)).collect());
        cols.push((start..y.len()).map(|t| z(t).powi(3)).collect());
    }
    let added = 2 * (order + 1);
    let (_, v1) = lstsq(&cols, target)?;
    let d2 = (rows - cols.len()) as f64;
    let f = ((v0 - v1).max(0.0) / added as f64) / (v1.max(1e-300) / d2);
    Ok(Reset {
        order,
        f,
        p_value: super::bla::f_sf(f, added as f64, d2),
        added,
        rows,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{RngExt, SeedableRng, rngs::StdRng};

    fn record(cubic: f64, seed: u64) -> (Vec<f64>, Vec<f64>) {
        record_noise(cubic, seed, 0.0)
    }

    /// `pole`: the output noise filtered by 1/(1 − pole·z⁻¹) (0: white).
    fn record_noise(cubic: f64, seed: u64, pole: f64) -> (Vec<f64>, Vec<f64>) {
        let mut rng = StdRng::seed_from_u64(seed);
        let u: Vec<f64> = (0..4000).map(|_| rng.random_range(-1.0..1.0)).collect();
        let mut x = vec![0.0f64; u.len()];
        for t in 2..u.len() {
            x[t] = 1.2 * x[t - 1] - 0.5 * x[t - 2] + 0.3 * u[t - 1];
        }
        let mut e = 0.0;
        let y = x
            .iter()
            .map(|v| {
                e = pole * e + 0.01 * rng.random_range(-1.0..1.0);
                v + cubic * v.powi(3) + e
            })
            .collect();
        (u, y)
    }

    #[test]
    fn reset_sees_a_cubic_and_not_a_linear_block() {
        let mut false_alarms = 0;
        for seed in 0..10 {
            let (u, y) = record(0.0, seed);
            if reset_test(&u, &y, 4).unwrap().p_value < 1e-3 {
                false_alarms += 1;
            }
            let (u, y) = record(0.3, seed);
            let r = reset_test(&u, &y, 4).unwrap();
            assert!(r.p_value < 1e-3, "{r:?}");
        }
        assert!(
            false_alarms <= 1,
            "{false_alarms} of 10 linear records called nonlinear"
        );
    }

    /// The Wiener–Hammerstein benchmark's excerpt (8000 samples of one level): nonlinear.
    #[cfg(feature = "csv")]
    #[test]
    fn reset_sees_the_wiener_hammerstein_benchmark() {
        let path = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/tests/data/wiener_hammerstein_2009/excerpt.csv"
        );
        let t = crate::data::CsvTable::read(path).unwrap();
        let r = reset_test(t.column("u").unwrap(), t.column("y").unwrap(), 8).unwrap();
        assert!(r.p_value < 1e-3, "{r:?}");
    }
}
