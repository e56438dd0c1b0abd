//! The covariance of a fit's reported parameters, kept in the factored form the standard errors
//! are computed from (`uncertainty.rs`), so that the standard error of any linear combination
//! wᵀθ — e.g. a preload's jump e1 − e2, whose parts are strongly correlated — can be read
//! without refitting and without forming JᵀJ.
//!
//! Algorithm (the truncated-SVD covariance of `uncertainty.rs`; Golub & Van Loan, *Matrix
//! Computations*, 4th ed., §5.5; Hansen 1998, §3.2): with the Jacobian's R factor column-scaled,
//! R D⁻¹ = U Σ Vᵀ, the covariance of θ is σ̂² D⁻¹ V_k Σ_k⁻² V_kᵀ D⁻¹ over the kept (determined)
//! directions k. For a combination c = wᵀθ put u = D⁻¹w (its direction in the scaled
//! coordinates): Var c = σ̂² ‖Σ_k⁻¹ V_kᵀ u‖², and c is not determined by the record when u lies
//! more than [`NULL_SHARE`] in the discarded directions, ‖V_nᵀ u‖ > NULL_SHARE·‖u‖. For w = e_j
//! this is exactly parameter j's standard error.

/// Share of a combination's direction in the undetermined subspace above which its standard
/// error is reported as +∞ (not determined by the record).
pub const NULL_SHARE: f64 = 0.1;

/// The covariance of the reported parameters (the nonlinearity's θ, then the output map's), in
/// factored form.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ParameterCovariance {
    /// Rows of V_k Σ_k⁻¹ for the reported parameters (r × kept, row-major).
    kept: Vec<f64>,
    /// Rows of V_n (the discarded directions) for the reported parameters (r × discarded).
    null: Vec<f64>,
    /// 1/d_j: the reported parameters' inverse column scales.
    inv_scale: Vec<f64>,
    /// σ̂ times the long-record factor √(window/N).
    sigma: f64,
}

impl ParameterCovariance {
    /// The covariance from the SVD pieces: `v_rows[j]` is row j of V (all directions) for
    /// reported parameter j, `s` the singular values, `kept[k]` whether direction k is kept,
    /// `scale[j]` = d_j, `sigma` = σ̂ times the long-record factor.
    pub(crate) fn new(
        v_rows: &[Vec<f64>],
        s: &[f64],
        kept: &[bool],
        scale: &[f64],
        sigma: f64,
    ) -> Self {
        let mut out = Self {
            sigma,
            inv_scale: scale.iter().map(|d| 1.0 / d).collect(),
            ..Self::default()
        };
        for row in v_rows {
            for (k, &keep) in kept.iter().enumerate() {
                if keep {
                    out.kept.push(row[k] / s[k]);
                } else {
                    out.null.push(row[k]);
                }
            }
        }
        out
    }

    /// The number of reported parameters.
    pub fn len(&self) -> usize {
        self.inv_scale.len()
    }

    /// True when no parameter is reported.
    pub fn is_empty(&self) -> bool {
        self.inv_scale.is_empty()
    }

    /// The standard error of wᵀθ (`weights` in the order of the reported parameters, missing
    /// ones 0); `+∞` when the record does not determine the combination.
    pub fn standard_error(&self, weights: &[f64]) -> f64 {
        let r = self.len();
        if r == 0 {
            return f64::INFINITY;
        }
        let (nk, nn) = (self.kept.len() / r, self.null.len() / r);
        let u: Vec<f64> = (0..r)
            .map(|j| weights.get(j).copied().unwrap_or(0.0) * self.inv_scale[j])
            .collect();
        let norm = u.iter().map(|x| x * x).sum::<f64>().sqrt();
        if norm == 0.0 {
            return 0.0;
        }
        let proj = |m: &[f64], cols: usize, k: usize, div: f64| {
            (0..r).map(|j| m[j * cols + k] * u[j]).sum::<f64>() / div
        };
        let null = (0..nn)
            .map(|k| proj(&self.null, nn, k, norm).powi(2))
            .sum::<f64>()
            .sqrt();
        if null > NULL_SHARE {
            return f64::INFINITY;
        }
        let var: f64 = (0..nk).map(|k| proj(&self.kept, nk, k, 1.0).powi(2)).sum();
        let se = self.sigma * var.sqrt();
        if se.is_nan() { f64::INFINITY } else { se }
    }

    /// Every reported parameter's standard error (the combinations e_j).
    pub fn standard_errors(&self) -> Vec<f64> {
        (0..self.len())
            .map(|j| {
                let mut w = vec![0.0; self.len()];
                w[j] = 1.0;
                self.standard_error(&w)
            })
            .collect()
    }
}

#[cfg(test)]
mod unit {
    use super::*;

    /// Two parameters whose sum the data do not determine (V's second direction discarded): each
    /// alone is undetermined, their difference is, with the variance σ²·‖Σ⁻¹Vᵀu‖².
    #[test]
    fn a_difference_is_determined_when_the_sum_is_not() {
        let h = std::f64::consts::FRAC_1_SQRT_2;
        // V = [[h, h], [−h, h]]: direction 0 = (1, −1)/√2 kept (σ = 2), direction 1 = (1, 1)/√2
        let c = ParameterCovariance::new(
            &[vec![h, h], vec![-h, h]],
            &[2.0, 1e-12],
            &[true, false],
            &[1.0, 1.0],
            0.5,
        );
        let se = c.standard_errors();
        assert!(se.iter().all(|s| s.is_infinite()), "{se:?}");
        // u = (1, −1): Vₖᵀu = √2, / σ = √2/2, times 0.5
        let d = c.standard_error(&[1.0, -1.0]);
        assert!((d - 0.5 * 2f64.sqrt() / 2.0).abs() < 1e-12, "{d}");
        assert!(c.standard_error(&[1.0, 1.0]).is_infinite());
        assert_eq!(c.standard_error(&[0.0, 0.0]), 0.0);
    }
}
