//! The Diebold–Mariano test of equal predictive accuracy: two models' errors on the same samples
//! compared through the mean of their squared-loss differential, its variance estimated by
//! Newey–West (Bartlett kernel) so that serially correlated errors are allowed (Diebold &
//! Mariano, J. Business & Economic Statistics 13(3), 1995; Newey & West, Econometrica 55(3),
//! 1987). The guided loop confirms its steps with it and `structure` ranks single-branch models
//! with it.

/// The loss differential's mean and its Diebold–Mariano statistic (Newey–West variance, Bartlett
/// kernel, ⌊4 (n/100)^{2/9}⌋ lags).
pub fn diebold_mariano(before: &[f64], after: &[f64]) -> (f64, f64) {
    let n = before.len().min(after.len());
    if n < 2 {
        return (f64::NAN, f64::NAN);
    }
    let d: Vec<f64> = (0..n)
        .map(|k| after[k].powi(2) - before[k].powi(2))
        .collect();
    let mean = d.iter().sum::<f64>() / n as f64;
    let lags = ((4.0 * (n as f64 / 100.0).powf(2.0 / 9.0)).floor() as usize).min(n - 1);
    let gamma = |j: usize| -> f64 {
        (j..n)
            .map(|k| (d[k] - mean) * (d[k - j] - mean))
            .sum::<f64>()
            / n as f64
    };
    let mut v = gamma(0);
    for j in 1..=lags {
        v += 2.0 * (1.0 - j as f64 / (lags as f64 + 1.0)) * gamma(j);
    }
    let se = (v.max(0.0) / n as f64).sqrt();
    let stat = if se > 0.0 {
        mean / se
    } else if mean < 0.0 {
        f64::NEG_INFINITY
    } else if mean > 0.0 {
        f64::INFINITY
    } else {
        0.0
    };
    (mean, stat)
}
