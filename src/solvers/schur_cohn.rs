//! Stability of a discrete-time denominator a(z) = 1 + a₁z⁻¹ + … + aₙz⁻ⁿ without its roots.
//!
//! Algorithm: the Schur–Cohn (step-down, Levinson–Durbin backwards) recursion — the reflection
//! coefficient kₘ = aₘ of the degree-m monic polynomial, then
//! a'ᵢ = (aᵢ − kₘ·aₘ₋ᵢ)/(1 − kₘ²), i = 1…m−1; every root lies strictly inside the unit circle
//! if and only if |kₘ| < 1 for m = n…1 (Jury 1964; Oppenheim & Schafer, *Discrete-Time Signal
//! Processing*, 3rd ed., §6.6.2 and problem 6.23; the same test as MATLAB's `isstable` for a
//! polynomial). Computed in f64: n ≤ a few tens here, and an eigenvalue solver is not needed to
//! decide one inequality per trial step of a refinement.

use crate::real::Real;

/// True when every root of the monic denominator `a` = [1, a₁, …, aₙ] (powers of z⁻¹) lies
/// strictly inside the circle of radius `radius`; false for a non-finite coefficient.
pub(crate) fn roots_inside<T: Real>(a: &[T], radius: f64) -> bool {
    // roots of a(z) inside radius r ⇔ roots of a(r·z) inside the unit circle: aₖ → aₖ/rᵏ
    let mut p: Vec<f64> = a
        .iter()
        .enumerate()
        .map(|(k, x)| x.as_f64() / radius.powi(k as i32))
        .collect();
    if p.iter().any(|x| !x.is_finite()) || p.is_empty() {
        return false;
    }
    let lead = p[0];
    if lead == 0.0 {
        return false;
    }
    p.iter_mut().for_each(|x| *x /= lead);
    let mut m = p.len() - 1;
    while m > 0 {
        let k = p[m];
        if k.is_nan() || k.abs() >= 1.0 {
            return false;
        }
        let den = 1.0 - k * k;
        let next: Vec<f64> = (0..m).map(|i| (p[i] - k * p[m - i]) / den).collect();
        p = next;
        m -= 1;
    }
    true
}

/// The denominator `a` with every root scaled by `s` (aₖ → aₖ·sᵏ): the uniform shrink of the
/// poles `problem::stabilised` applies to A, on the transfer function's coefficients.
pub(crate) fn roots_scaled<T: Real>(a: &[T], s: f64) -> Vec<T> {
    a.iter()
        .enumerate()
        .map(|(k, &x)| x * T::lit(s.powi(k as i32)))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The coefficients [1, a₁, …] of ∏(1 − pᵢz⁻¹) for real and complex-pair roots.
    fn poly(real: &[f64], pairs: &[(f64, f64)]) -> Vec<f64> {
        let mut p = vec![1.0];
        let mul = |p: &Vec<f64>, f: &[f64]| {
            let mut r = vec![0.0; p.len() + f.len() - 1];
            for (i, x) in p.iter().enumerate() {
                for (j, y) in f.iter().enumerate() {
                    r[i + j] += x * y;
                }
            }
            r
        };
        for &r in real {
            p = mul(&p, &[1.0, -r]);
        }
        for &(re, im) in pairs {
            p = mul(&p, &[1.0, -2.0 * re, re * re + im * im]);
        }
        p
    }

    /// The test agrees with the roots' moduli on both sides of the circle, for real roots, pairs,
    /// and a root just outside among stable ones (MR damper-like: 1.0037 beside 0.5 and 0.9).
    #[test]
    fn the_test_agrees_with_the_roots() {
        assert!(roots_inside(&poly(&[0.5, -0.9], &[(0.6, 0.7)]), 1.0));
        assert!(!roots_inside(&poly(&[0.5, 1.0037], &[(0.6, 0.7)]), 1.0));
        assert!(!roots_inside(&poly(&[0.5], &[(0.8, 0.61)]), 1.0)); // |p| = 1.006
        assert!(roots_inside(&poly(&[0.5], &[(0.8, 0.59)]), 1.0)); // |p| = 0.994
        assert!(!roots_inside(&poly(&[-1.0], &[]), 1.0)); // on the circle
        // the radius: 0.95 is inside 0.96, not inside 0.94
        let p = poly(&[0.95, 0.2], &[(0.1, 0.3)]);
        assert!(roots_inside(&p, 0.96) && !roots_inside(&p, 0.94));
        assert!(!roots_inside(&[1.0, f64::NAN], 1.0));
        assert!(roots_inside(&[1.0f64], 1.0));
    }

    /// Scaling the coefficients scales the roots: 1.0037 and a pair of modulus 1.006 by 0.99
    /// land inside.
    #[test]
    fn scaled_roots_land_inside() {
        let p = poly(&[1.0037, 0.3], &[(0.8, 0.61)]);
        assert!(!roots_inside(&p, 1.0));
        let s = roots_scaled(&p, 0.99);
        assert!(roots_inside(&s, 1.0) && !roots_inside(&s, 0.99));
        let q = poly(&[1.0037 * 0.99, 0.3 * 0.99], &[(0.8 * 0.99, 0.61 * 0.99)]);
        assert!(s.iter().zip(&q).all(|(a, b)| (a - b).abs() < 1e-12));
    }
}
