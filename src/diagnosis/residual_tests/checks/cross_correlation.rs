//! Cross-correlation of the residuals with the input at lags 0..=max_lag, with the variance of
//! each correlation corrected for the colour of both series (Bartlett's formula,
//! Var r_eu(k) ≈ (1/N) Σ_j ρ_ee(j) ρ_uu(j); Box, Jenkins & Reinsel, *Time Series Analysis*, §11.1),
//! combined over lags by a Bonferroni correction.

use super::whiteness::autocorrelation;
use super::{TestFamily, TestResult};
use crate::diagnosis::stats::normal_two_sided;

/// Sample cross-correlation r(k) = Σ_t e(t) u(t−k) / (N σ_e σ_u) for k = 0..=max_lag.
pub fn cross_correlation(e: &[f64], u: &[f64], max_lag: usize) -> Vec<f64> {
    let n = e.len().min(u.len());
    let me = e[..n].iter().sum::<f64>() / n as f64;
    let mu = u[..n].iter().sum::<f64>() / n as f64;
    let se = e[..n].iter().map(|x| (x - me).powi(2)).sum::<f64>().sqrt();
    let su = u[..n].iter().map(|x| (x - mu).powi(2)).sum::<f64>().sqrt();
    (0..=max_lag.min(n.saturating_sub(1)))
        .map(|k| {
            if se > 0.0 && su > 0.0 {
                (k..n).map(|t| (e[t] - me) * (u[t - k] - mu)).sum::<f64>() / (se * su)
            } else {
                0.0
            }
        })
        .collect()
}

/// Test of H0 "residual uncorrelated with the input at lags 0..=max_lag" (Bonferroni over lags).
pub fn cross_correlation_test(e: &[f64], u: &[f64], max_lag: usize) -> TestResult {
    let n = e.len().min(u.len());
    let r = cross_correlation(e, u, max_lag);
    // Bartlett variance with both autocorrelations truncated at 25 lags (or N/4)
    let m = 25.min(n / 4);
    let re = autocorrelation(&e[..n], m);
    let ru = autocorrelation(&u[..n], m);
    let s = 1.0 + 2.0 * re.iter().zip(&ru).map(|(a, b)| a * b).sum::<f64>();
    let var = s.max(0.1) / n as f64;
    let z: Vec<f64> = r.iter().map(|x| x / var.sqrt()).collect();
    let (kmax, zmax) =
        z.iter().enumerate().fold(
            (0, 0.0f64),
            |b, (i, &x)| if x.abs() > b.1.abs() { (i, x) } else { b },
        );
    let lags = r.len() as f64;
    let p = (normal_two_sided(zmax) * lags).min(1.0);
    let mut t = TestResult::new(
        "input-cross-correlation",
        "cross-correlation of the residuals with the input at lags 0..25 (Bonferroni)",
        TestFamily::Linear,
        "max|z|",
        zmax.abs(),
        Vec::new(),
        p,
    );
    t.detail = format!(
        "largest correlation r({kmax}) = {:.3} (z = {zmax:.2}, colour-corrected bound ±{:.3} at 99 %)",
        r[kmax],
        2.576 * var.sqrt()
    );
    t.coefficients = r;
    t
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{RngExt, SeedableRng, rngs::StdRng};

    #[test]
    fn size_with_coloured_series_and_power() {
        let mut rng = StdRng::seed_from_u64(9);
        let n = 1000;
        let mut alarms = 0;
        for _ in 0..200 {
            // both series low-passed: the uncorrected ±2.58/√N bound would over-reject
            let mut a = 0.0;
            let mut b = 0.0;
            let mut u = Vec::with_capacity(n);
            let mut e = Vec::with_capacity(n);
            for _ in 0..n {
                a = 0.8 * a + rng.random_range(-1.0..1.0);
                b = 0.8 * b + rng.random_range(-1.0..1.0);
                u.push(a);
                e.push(b);
            }
            if cross_correlation_test(&e, &u, 25).p_value < 0.05 {
                alarms += 1;
            }
        }
        assert!(alarms <= 20, "{alarms}/200 false alarms at 5 %");
        let u: Vec<f64> = (0..n).map(|_| rng.random_range(-1.0..1.0)).collect();
        let e: Vec<f64> = (0..n)
            .map(|k| if k >= 3 { 0.2 * u[k - 3] } else { 0.0 } + rng.random_range(-1.0..1.0))
            .collect();
        let t = cross_correlation_test(&e, &u, 25);
        assert!(t.p_value < 1e-3, "{t:?}");
        assert!(t.detail.contains("r(3)"), "{}", t.detail);
    }
}
