//! Whiteness of the residuals: sample autocorrelation, per-lag bounds ±z/√N and the Ljung–Box
//! portmanteau test (Ljung & Box, Biometrika 65, 1978).

use super::{TestFamily, TestResult};
use crate::diagnosis::stats::{chi2_sf, normal_quantile};

/// Sample autocorrelation r(1..=max_lag) of `e` (mean removed, biased normalisation by r(0)).
pub fn autocorrelation(e: &[f64], max_lag: usize) -> Vec<f64> {
    let n = e.len();
    let mean = e.iter().sum::<f64>() / n.max(1) as f64;
    let c: Vec<f64> = e.iter().map(|x| x - mean).collect();
    let r0: f64 = c.iter().map(|x| x * x).sum();
    (1..=max_lag.min(n.saturating_sub(1)))
        .map(|k| {
            if r0 > 0.0 {
                (k..n).map(|t| c[t] * c[t - k]).sum::<f64>() / r0
            } else {
                0.0
            }
        })
        .collect()
}

/// Half-width of the two-sided (1 − alpha) confidence band of one autocorrelation of white noise.
pub fn per_lag_bound(n: usize, alpha: f64) -> f64 {
    normal_quantile(1.0 - alpha / 2.0) / (n as f64).sqrt()
}

/// Ljung–Box test of whiteness over lags 1..=lags: Q = N(N+2) Σ r_k²/(N−k) ~ χ²(lags) under H0.
pub fn ljung_box(e: &[f64], lags: usize) -> TestResult {
    let n = e.len() as f64;
    let r = autocorrelation(e, lags);
    let q = n
        * (n + 2.0)
        * r.iter()
            .enumerate()
            .map(|(i, rk)| rk * rk / (n - (i + 1) as f64))
            .sum::<f64>();
    let m = r.len() as f64;
    let mut t = TestResult::new(
        "whiteness",
        "autocorrelation of the residuals (Ljung–Box)",
        TestFamily::Linear,
        "Q",
        q,
        vec![m],
        chi2_sf(q, m),
    );
    let bound = per_lag_bound(e.len(), 0.01);
    let outside = r.iter().filter(|x| x.abs() > bound).count();
    let (kmax, rmax) = r.iter().enumerate().fold((0, 0.0f64), |b, (i, &x)| {
        if x.abs() > b.1.abs() { (i + 1, x) } else { b }
    });
    t.detail = format!(
        "Q = {q:.1} over {m} lags; {outside} lag(s) outside ±{bound:.3} (99 %); largest r({kmax}) = {rmax:.3}"
    );
    t.coefficients = r;
    t
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{RngExt, SeedableRng, rngs::StdRng};

    #[test]
    fn ljung_box_keeps_its_size_on_white_noise_and_sees_colour() {
        let mut rng = StdRng::seed_from_u64(7);
        let mut rejections = 0;
        for _ in 0..200 {
            let e: Vec<f64> = (0..1000).map(|_| rng.random_range(-1.0..1.0)).collect();
            if ljung_box(&e, 20).p_value < 0.05 {
                rejections += 1;
            }
        }
        assert!(
            (3..=20).contains(&rejections),
            "{rejections}/200 false alarms"
        );
        let w: Vec<f64> = (0..1001).map(|_| rng.random_range(-1.0..1.0)).collect();
        let ma: Vec<f64> = (1..1001).map(|k| w[k] + 0.3 * w[k - 1]).collect();
        assert!(ljung_box(&ma, 20).p_value < 1e-6);
    }
}
