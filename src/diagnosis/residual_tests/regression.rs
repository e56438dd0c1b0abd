//! Least squares for the residual tests: nested-model F tests and autoregressive prewhitening.
//!
//! Algorithm: the columns are orthonormalised in order by classical Gram–Schmidt with
//! re-orthogonalisation ("CGS2", Giraud et al., Numer. Math. 101, 2005), which is as accurate as
//! Householder QR for the tall, well-scaled designs used here; a column whose norm falls below
//! 1e-9 of its original norm after projection is treated as linearly dependent and dropped (its
//! coefficient is 0 and it costs no degree of freedom). The F test of a nested model is the
//! classical one (Seber & Lee, *Linear Regression Analysis*, §4.3). Residual colour is handled by
//! prewhitening with an AR(p) model of the restricted model's residuals, p chosen by BIC
//! (Cochrane–Orcutt-type feasible GLS), so the F test keeps its size when the residuals of a
//! simulation are coloured.

use super::stats::f_sf;

/// An orthonormal basis Q of the kept columns and the triangular factor R (kept × kept).
#[derive(Debug, Clone)]
struct Orth {
    q: Vec<Vec<f64>>,
    /// R in column order of the kept columns (R[i][j], i ≤ j).
    r: Vec<Vec<f64>>,
    /// Indices of the kept input columns.
    kept: Vec<usize>,
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

fn orthonormalise(cols: &[&[f64]]) -> Orth {
    let mut q: Vec<Vec<f64>> = Vec::new();
    let mut r: Vec<Vec<f64>> = Vec::new();
    let mut kept = Vec::new();
    for (j, c) in cols.iter().enumerate() {
        let norm0 = dot(c, c).sqrt();
        if !(norm0 > 0.0 && norm0.is_finite()) {
            continue;
        }
        let mut v = c.to_vec();
        let mut coef = vec![0.0; q.len()];
        for _pass in 0..2 {
            for (i, qi) in q.iter().enumerate() {
                let h = dot(qi, &v);
                coef[i] += h;
                for (vk, qk) in v.iter_mut().zip(qi) {
                    *vk -= h * qk;
                }
            }
        }
        let nv = dot(&v, &v).sqrt();
        if nv <= 1e-9 * norm0 {
            continue;
        }
        for vk in v.iter_mut() {
            *vk /= nv;
        }
        coef.push(nv);
        // store column j of R
        for (i, row) in r.iter_mut().enumerate() {
            row.push(coef[i]);
        }
        let mut new_row = vec![0.0; coef.len() - 1];
        new_row.push(nv);
        r.push(new_row);
        q.push(v);
        kept.push(j);
    }
    Orth { q, r, kept }
}

/// Ordinary least squares of `y` on `cols`: coefficients (0 for dropped columns), residuals, rank.
#[derive(Debug, Clone)]
pub struct LeastSquares {
    /// Coefficient of every column (0 for a column dropped as linearly dependent).
    pub coefficients: Vec<f64>,
    /// Residuals y − Xβ.
    pub residuals: Vec<f64>,
    /// Residual sum of squares.
    pub rss: f64,
    /// Number of linearly independent columns used.
    pub rank: usize,
    /// Standard errors of the coefficients under white residuals (0 for dropped columns).
    pub std_errors: Vec<f64>,
}

/// Least squares fit of `y` on the columns `cols` (all of length y.len()).
pub fn least_squares(y: &[f64], cols: &[&[f64]]) -> LeastSquares {
    let o = orthonormalise(cols);
    let k = o.q.len();
    let qty: Vec<f64> = o.q.iter().map(|qi| dot(qi, y)).collect();
    let mut residuals = y.to_vec();
    for (qi, &h) in o.q.iter().zip(&qty) {
        for (rk, qk) in residuals.iter_mut().zip(qi) {
            *rk -= h * qk;
        }
    }
    let rss = dot(&residuals, &residuals);
    // back substitution R β = Qᵀy
    let mut beta = vec![0.0; k];
    for i in (0..k).rev() {
        let mut s = qty[i];
        for j in i + 1..k {
            s -= o.r[i][j] * beta[j];
        }
        beta[i] = s / o.r[i][i];
    }
    // diag((RᵀR)⁻¹) = row norms² of R⁻¹
    let dof = (y.len() as f64 - k as f64).max(1.0);
    let sigma2 = rss / dof;
    let mut rinv = vec![vec![0.0; k]; k];
    for j in 0..k {
        rinv[j][j] = 1.0 / o.r[j][j];
        for i in (0..j).rev() {
            let mut s = 0.0;
            for l in i + 1..=j {
                s += o.r[i][l] * rinv[l][j];
            }
            rinv[i][j] = -s / o.r[i][i];
        }
    }
    let mut coefficients = vec![0.0; cols.len()];
    let mut std_errors = vec![0.0; cols.len()];
    for (i, &c) in o.kept.iter().enumerate() {
        coefficients[c] = beta[i];
        std_errors[c] = (sigma2 * rinv[i].iter().map(|x| x * x).sum::<f64>()).sqrt();
    }
    LeastSquares {
        coefficients,
        residuals,
        rss,
        rank: k,
        std_errors,
    }
}

/// Result of an F test of `extra` columns added to a `base` design.
#[derive(Debug, Clone)]
pub struct NestedTest {
    /// F statistic.
    pub f: f64,
    /// Numerator degrees of freedom (independent extra columns).
    pub df1: f64,
    /// Denominator degrees of freedom.
    pub df2: f64,
    /// Upper-tail p-value.
    pub p_value: f64,
    /// Coefficients of the extra columns in the full model.
    pub coefficients: Vec<f64>,
    /// Their standard errors.
    pub std_errors: Vec<f64>,
    /// Residual sum of squares of the restricted (base) model.
    pub rss_base: f64,
    /// Residual sum of squares of the full model.
    pub rss_full: f64,
}

/// Classical F test of H0: the `extra` columns add nothing to `base` for explaining `y`.
///
/// Returns `None` when no extra column is linearly independent of the base or no degree of
/// freedom is left.
pub fn nested_f_test(y: &[f64], base: &[&[f64]], extra: &[&[f64]]) -> Option<NestedTest> {
    let restricted = least_squares(y, base);
    let mut all: Vec<&[f64]> = base.to_vec();
    all.extend_from_slice(extra);
    let full = least_squares(y, &all);
    let df1 = full.rank as f64 - restricted.rank as f64;
    let df2 = y.len() as f64 - full.rank as f64;
    if df1 < 1.0 || df2 < 1.0 {
        return None;
    }
    let num = ((restricted.rss - full.rss).max(0.0)) / df1;
    let den = full.rss / df2;
    let f = if den > 0.0 { num / den } else { f64::INFINITY };
    Some(NestedTest {
        f,
        df1,
        df2,
        p_value: f_sf(f, df1, df2),
        coefficients: full.coefficients[base.len()..].to_vec(),
        std_errors: full.std_errors[base.len()..].to_vec(),
        rss_base: restricted.rss,
        rss_full: full.rss,
    })
}

/// Autoregressive model e(k) = Σ a_i e(k−i) + w(k) of a residual series, fitted by least squares.
#[derive(Debug, Clone, PartialEq)]
pub struct ArFilter {
    /// Coefficients a_1..a_p (empty: no prewhitening).
    pub coefficients: Vec<f64>,
}

impl ArFilter {
    /// Fits AR(p) for p = 0..=max_order by least squares and keeps the order with the smallest BIC.
    pub fn fit_bic(e: &[f64], max_order: usize) -> Self {
        let n = e.len();
        if n < 4 * (max_order + 1) {
            return Self {
                coefficients: Vec::new(),
            };
        }
        let start = max_order;
        let target = &e[start..];
        let m = target.len() as f64;
        let lags: Vec<Vec<f64>> = (1..=max_order)
            .map(|i| e[start - i..n - i].to_vec())
            .collect();
        let mut best = (m * (dot(target, target) / m).max(1e-300).ln(), Vec::new());
        for p in 1..=max_order {
            let cols: Vec<&[f64]> = lags[..p].iter().map(|c| c.as_slice()).collect();
            let ls = least_squares(target, &cols);
            let bic = m * (ls.rss / m).max(1e-300).ln() + (p as f64) * m.ln();
            if bic < best.0 {
                best = (bic, ls.coefficients);
            }
        }
        Self {
            coefficients: best.1,
        }
    }

    /// Order p.
    pub fn order(&self) -> usize {
        self.coefficients.len()
    }

    /// Applies A(q) = 1 − Σ a_i q^{−i} to `x`, dropping the first p samples.
    pub fn apply(&self, x: &[f64]) -> Vec<f64> {
        let p = self.order();
        (p..x.len())
            .map(|k| {
                x[k] - self
                    .coefficients
                    .iter()
                    .enumerate()
                    .map(|(i, a)| a * x[k - 1 - i])
                    .sum::<f64>()
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{RngExt, SeedableRng, rngs::StdRng};

    #[test]
    fn least_squares_recovers_coefficients_and_drops_dependent_columns() {
        let mut rng = StdRng::seed_from_u64(3);
        let n = 500;
        let x1: Vec<f64> = (0..n).map(|_| rng.random_range(-1.0..1.0)).collect();
        let x2: Vec<f64> = (0..n).map(|_| rng.random_range(-1.0..1.0)).collect();
        let x3: Vec<f64> = x1.iter().zip(&x2).map(|(a, b)| a - 2.0 * b).collect();
        let one = vec![1.0; n];
        let y: Vec<f64> = (0..n).map(|k| 0.5 + 2.0 * x1[k] - 3.0 * x2[k]).collect();
        let ls = least_squares(&y, &[&one, &x1, &x2, &x3]);
        assert_eq!(ls.rank, 3);
        assert!((ls.coefficients[0] - 0.5).abs() < 1e-10);
        assert!((ls.coefficients[1] - 2.0).abs() < 1e-10);
        assert!((ls.coefficients[2] + 3.0).abs() < 1e-10);
        assert_eq!(ls.coefficients[3], 0.0);
        assert!(ls.rss < 1e-18);
    }

    #[test]
    fn f_test_size_and_power() {
        // under H0 the p-values are uniform: about 5 % below 0.05 over many replications
        let mut rng = StdRng::seed_from_u64(11);
        let n = 200;
        let reps = 400;
        let mut rejections = 0;
        let mut detected = 0;
        for _ in 0..reps {
            let x: Vec<f64> = (0..n).map(|_| rng.random_range(-1.0..1.0)).collect();
            let z: Vec<f64> = (0..n).map(|_| rng.random_range(-1.0..1.0)).collect();
            let w: Vec<f64> = (0..n).map(|_| rng.random_range(-1.0..1.0)).collect();
            let one = vec![1.0; n];
            let y: Vec<f64> = (0..n).map(|k| x[k] + w[k]).collect();
            let t = nested_f_test(&y, &[&one, &x], &[&z]).unwrap();
            if t.p_value < 0.05 {
                rejections += 1;
            }
            let y1: Vec<f64> = (0..n).map(|k| x[k] + 0.3 * z[k] + w[k]).collect();
            if nested_f_test(&y1, &[&one, &x], &[&z]).unwrap().p_value < 0.05 {
                detected += 1;
            }
        }
        let rate = rejections as f64 / reps as f64;
        assert!((0.025..=0.08).contains(&rate), "false-alarm rate {rate}");
        assert!(
            detected as f64 / reps as f64 > 0.8,
            "power {detected}/{reps}"
        );
    }

    #[test]
    fn ar_prewhitening_recovers_an_ar2() {
        let mut rng = StdRng::seed_from_u64(5);
        let n = 4000;
        let mut e = vec![0.0; n];
        for k in 2..n {
            e[k] = 1.2 * e[k - 1] - 0.5 * e[k - 2] + rng.random_range(-1.0..1.0);
        }
        let ar = ArFilter::fit_bic(&e, 10);
        assert!(ar.order() >= 2, "{ar:?}");
        assert!((ar.coefficients[0] - 1.2).abs() < 0.06, "{ar:?}");
        assert!((ar.coefficients[1] + 0.5).abs() < 0.06, "{ar:?}");
        assert_eq!(ar.apply(&e).len(), n - ar.order());
    }
}
