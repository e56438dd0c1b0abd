//! Probability distributions for the residual tests: normal, chi-square, F and Student t tail
//! probabilities, through the regularised incomplete gamma and beta functions of `statrs`
//! (`statrs::function`: Lanczos ln Γ; the incomplete gamma by series / continued fraction and the
//! incomplete beta by its continued fraction, as in Press et al., *Numerical Recipes*, 3rd ed.,
//! §6.1–6.4; erfc and its inverse for the normal). statrs replaced 400 lines of hand-written
//! special functions here; the tests below pin the wrappers to closed forms and tables.
//! Everything is in f64: p-values do not depend on the model's scalar type. Invalid arguments
//! (NaN, negative shapes) give NaN, never a panic.

use statrs::function::{beta, erf, gamma};
#[cfg(test)]
use std::f64::consts::PI;

/// ln Γ(x) for x > 0.
pub fn ln_gamma(x: f64) -> f64 {
    if x.is_nan() || x <= 0.0 {
        return f64::NAN;
    }
    gamma::ln_gamma(x)
}

/// Regularised lower incomplete gamma P(a, x).
pub fn gamma_p(a: f64, x: f64) -> f64 {
    if x.is_infinite() && x > 0.0 && a > 0.0 {
        return 1.0;
    }
    if x == 0.0 && a > 0.0 {
        return 0.0;
    }
    gamma::checked_gamma_lr(a, x).unwrap_or(f64::NAN)
}

/// Regularised upper incomplete gamma Q(a, x) = 1 − P(a, x), accurate when small.
pub fn gamma_q(a: f64, x: f64) -> f64 {
    if x.is_infinite() && x > 0.0 && a > 0.0 {
        return 0.0;
    }
    if x == 0.0 && a > 0.0 {
        return 1.0;
    }
    gamma::checked_gamma_ur(a, x).unwrap_or(f64::NAN)
}

/// Regularised incomplete beta I_x(a, b).
pub fn beta_inc(a: f64, b: f64, x: f64) -> f64 {
    beta::checked_beta_reg(a, b, x).unwrap_or(f64::NAN)
}

/// Standard normal cumulative distribution function Φ(z).
pub fn normal_cdf(z: f64) -> f64 {
    if z.is_nan() {
        return f64::NAN;
    }
    if z < 0.0 {
        normal_sf(-z)
    } else {
        1.0 - normal_sf(z)
    }
}

/// Standard normal upper tail 1 − Φ(z), accurate far into the tail (Φ̄(z) = Q(½, z²/2)/2 for
/// z ≥ 0; statrs' erfc is accurate to ≈1e-12 relative, the incomplete gamma to ≈1e-15).
pub fn normal_sf(z: f64) -> f64 {
    if z.is_nan() {
        return f64::NAN;
    }
    if z < 0.0 {
        return 1.0 - normal_sf(-z);
    }
    0.5 * gamma_q(0.5, 0.5 * z * z)
}

/// Two-sided normal p-value P(|Z| ≥ |z|).
pub fn normal_two_sided(z: f64) -> f64 {
    (2.0 * normal_sf(z.abs())).min(1.0)
}

/// Standard normal quantile Φ⁻¹(p), 0 < p < 1 (−√2·erfc⁻¹(2p)).
pub fn normal_quantile(p: f64) -> f64 {
    if p.is_nan() || !(0.0..=1.0).contains(&p) {
        return f64::NAN;
    }
    if p == 0.0 {
        return f64::NEG_INFINITY;
    }
    if p == 1.0 {
        return f64::INFINITY;
    }
    -std::f64::consts::SQRT_2 * erf::erfc_inv(2.0 * p)
}

/// Chi-square upper tail P(χ²_k ≥ x).
pub fn chi2_sf(x: f64, k: f64) -> f64 {
    if x.is_nan() {
        return f64::NAN;
    }
    if x <= 0.0 {
        return 1.0;
    }
    gamma_q(0.5 * k, 0.5 * x)
}

/// F-distribution upper tail P(F_{d1,d2} ≥ f).
pub fn f_sf(f: f64, d1: f64, d2: f64) -> f64 {
    if f.is_nan() {
        return f64::NAN;
    }
    if f <= 0.0 {
        return 1.0;
    }
    if f.is_infinite() {
        return 0.0;
    }
    beta_inc(0.5 * d2, 0.5 * d1, d2 / (d2 + d1 * f))
}

/// Two-sided Student t p-value P(|T_ν| ≥ |t|).
pub fn t_two_sided(t: f64, nu: f64) -> f64 {
    if t.is_nan() {
        return f64::NAN;
    }
    if t.is_infinite() {
        return 0.0;
    }
    beta_inc(0.5 * nu, 0.5, nu / (nu + t * t))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: f64, b: f64, rel: f64) {
        assert!(
            (a - b).abs() <= rel * b.abs().max(1e-300),
            "{a} vs {b} (rel {})",
            ((a - b) / b).abs()
        );
    }

    #[test]
    fn ln_gamma_known_values() {
        close(ln_gamma(1.0).exp(), 1.0, 1e-13);
        close(ln_gamma(5.0).exp(), 24.0, 1e-13);
        close(ln_gamma(0.5).exp(), PI.sqrt(), 1e-13);
        close(ln_gamma(0.1).exp(), 9.513_507_698_668_732, 1e-12);
        // Γ(10.5) = 20! / (4^10 10!) √π
        let g105 = 2_432_902_008_176_640_000.0 / (1_048_576.0 * 3_628_800.0) * PI.sqrt();
        close(ln_gamma(10.5), g105.ln(), 1e-13);
        close(
            ln_gamma(200.0),
            (1..200).map(|k| (k as f64).ln()).sum::<f64>(),
            1e-13,
        );
    }

    #[test]
    fn incomplete_gamma_against_closed_forms() {
        for &x in &[0.01, 0.5, 1.0, 3.0, 10.0, 40.0] {
            close(gamma_p(1.0, x), 1.0 - (-x).exp(), 1e-12);
            close(gamma_q(1.0, x), (-x).exp(), 1e-12);
            // Q(2, x) = e^{-x}(1 + x)
            close(gamma_q(2.0, x), (-x).exp() * (1.0 + x), 1e-12);
        }
        // P(a, x) + Q(a, x) = 1 on both branches
        for &(a, x) in &[
            (0.5, 0.2),
            (3.5, 2.0),
            (3.5, 7.0),
            (50.0, 49.0),
            (50.0, 80.0),
        ] {
            close(gamma_p(a, x) + gamma_q(a, x), 1.0, 1e-13);
        }
    }

    #[test]
    fn incomplete_beta_against_closed_forms() {
        close(beta_inc(1.0, 1.0, 0.3), 0.3, 1e-13);
        // I_x(2,3) = 1 - [(1-x)^4 + 4x(1-x)^3]
        close(beta_inc(2.0, 3.0, 0.4), 0.5248, 1e-12);
        close(beta_inc(3.0, 2.0, 0.6), 1.0 - 0.5248, 1e-12);
        // I_x(a, 1) = x^a
        close(beta_inc(2.5, 1.0, 0.7), 0.7f64.powf(2.5), 1e-12);
        close(beta_inc(0.5, 0.5, 0.5), 0.5, 1e-12);
    }

    #[test]
    fn invalid_arguments_give_nan_not_a_panic() {
        assert!(gamma_q(-1.0, 2.0).is_nan());
        assert!(gamma_p(2.0, -1.0).is_nan());
        assert!(beta_inc(1.0, 1.0, 2.0).is_nan());
        assert!(ln_gamma(-3.0).is_nan());
        assert!(normal_quantile(1.5).is_nan());
        assert!(f_sf(2.0, -1.0, 3.0).is_nan());
        assert_eq!(chi2_sf(0.0, 3.0), 1.0);
    }

    #[test]
    fn normal_known_values() {
        close(normal_cdf(1.959_963_984_540_054), 0.975, 1e-14);
        close(normal_cdf(0.0), 0.5, 1e-15);
        close(normal_sf(3.0), 1.349_898_031_630_094_6e-3, 1e-12);
        close(normal_sf(8.0), 6.220_960_574_271_785e-16, 1e-10);
        close(normal_quantile(0.975), 1.959_963_984_540_054, 1e-12);
        close(normal_quantile(0.001), -3.090_232_306_167_813_5, 1e-12);
        close(normal_quantile(1e-10), -6.361_340_902_404_056, 1e-10);
        for &p in &[1e-6, 0.01, 0.2, 0.5, 0.77, 0.999] {
            close(normal_cdf(normal_quantile(p)), p, 1e-12);
        }
    }

    #[test]
    fn chi_square_f_and_t_tails() {
        // tables: χ²_{0.95}(1) = 3.841459, χ²_{0.95}(10) = 18.307038, χ²_{0.99}(26) = 45.641683
        close(chi2_sf(3.841_458_820_694_124, 1.0), 0.05, 1e-10);
        close(chi2_sf(18.307_038_053_275_146, 10.0), 0.05, 1e-10);
        close(chi2_sf(45.6417, 26.0), 0.01, 1e-4);
        // χ²_2 tail is exp(-x/2)
        close(chi2_sf(7.3, 2.0), (-3.65f64).exp(), 1e-12);
        // F table: F_{0.95}(5, 10) = 3.3258; closed form P(F_{2,ν} ≥ f) = (1 + 2f/ν)^(−ν/2)
        close(f_sf(3.3258, 5.0, 10.0), 0.05, 1e-4);
        for &(f, nu) in &[(0.3, 7.0), (2.5, 40.0), (9.0, 300.0)] {
            close(
                f_sf(f, 2.0, nu),
                (1.0 + 2.0 * f / nu).powf(-nu / 2.0),
                1e-11,
            );
        }
        // t: t_{0.975}(10) = 2.228139; Cauchy (ν = 1) closed form; F(1, ν) = t²
        close(t_two_sided(2.228_138_851_986_274, 10.0), 0.05, 1e-9);
        close(t_two_sided(1.7, 1.0), 1.0 - 2.0 / PI * 1.7f64.atan(), 1e-12);
        close(
            f_sf(2.1f64.powi(2), 1.0, 37.0),
            t_two_sided(2.1, 37.0),
            1e-12,
        );
        // large ν tends to the normal
        close(t_two_sided(1.96, 1e7), normal_two_sided(1.96), 1e-5);
    }
}
