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
        match self.kept_factor(weights) {
            Some(f) => finite_or_inf(self.sigma * dot(&f, &f).sqrt()),
            None => f64::INFINITY,
        }
    }

    /// The standard error of wᵀθ with hᵀθ held at its estimate: the conditional variance
    /// Var(wᵀθ) − Cov(wᵀθ, hᵀθ)² / Var(hᵀθ) (the Gaussian conditional; Anderson, *An
    /// Introduction to Multivariate Statistical Analysis*, 3rd ed. 2003, §2.5). With h the
    /// direction of a rescaling (the gains of a Hammerstein nonlinearity, which the linear block
    /// can compensate: G·N = (G/s)·(s·N)) this is the error of wᵀθ in a normalisation that fixes
    /// the scale: a Wald test is not invariant to the normalisation (Gregory & Veall,
    /// *Econometrica* 53, 1985), and the question "is wᵀθ = 0?" does not depend on the scale.
    /// `+∞` when the record does not determine wᵀθ; the plain standard error when it does not
    /// determine hᵀθ.
    pub fn standard_error_given(&self, weights: &[f64], held: &[f64]) -> f64 {
        let Some(fw) = self.kept_factor(weights) else {
            return f64::INFINITY;
        };
        let var_w = dot(&fw, &fw);
        let var = match self.kept_factor(held) {
            Some(fh) if dot(&fh, &fh) > 0.0 => {
                let c = dot(&fw, &fh);
                (var_w - c * c / dot(&fh, &fh)).max(0.0)
            }
            _ => var_w,
        };
        finite_or_inf(self.sigma * var.sqrt())
    }

    /// Σ_k⁻¹V_kᵀu (u = D⁻¹w) over the kept directions, so that Var(wᵀθ) = σ̂²‖·‖²; `None` when
    /// u lies more than [`NULL_SHARE`] in the discarded directions (the zero combination: the
    /// empty vector).
    fn kept_factor(&self, weights: &[f64]) -> Option<Vec<f64>> {
        let r = self.len();
        if r == 0 {
            return None;
        }
        let (nk, nn) = (self.kept.len() / r, self.null.len() / r);
        let u: Vec<f64> = (0..r)
            .map(|j| weights.get(j).copied().unwrap_or(0.0) * self.inv_scale[j])
            .collect();
        let norm = dot(&u, &u).sqrt();
        if norm == 0.0 {
            return Some(Vec::new());
        }
        let proj =
            |m: &[f64], cols: usize, k: usize| (0..r).map(|j| m[j * cols + k] * u[j]).sum::<f64>();
        let null: Vec<f64> = (0..nn).map(|k| proj(&self.null, nn, k) / norm).collect();
        if dot(&null, &null).sqrt() > NULL_SHARE {
            return None;
        }
        Some((0..nk).map(|k| proj(&self.kept, nk, k)).collect())
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

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

fn finite_or_inf(se: f64) -> f64 {
    if se.is_nan() { f64::INFINITY } else { se }
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

    /// Holding a combination removes its share of the variance: for two determined parameters
    /// with Cov = σ²·diag(1/s₀², 1/s₁²) rotated by V, the conditional variance of θ₀ given θ₁
    /// is 1/(Cov⁻¹)₀₀ (the Gaussian conditional).
    #[test]
    fn holding_a_combination_gives_the_conditional_variance() {
        let h = std::f64::consts::FRAC_1_SQRT_2;
        let (s0, s1) = (2.0, 0.5);
        let c = ParameterCovariance::new(
            &[vec![h, h], vec![-h, h]],
            &[s0, s1],
            &[true, true],
            &[1.0, 1.0],
            1.0,
        );
        // Cov⁻¹ = V diag(s²) Vᵀ: (Cov⁻¹)₀₀ = (s0² + s1²)/2
        let want = (2.0 / (s0 * s0 + s1 * s1)).sqrt();
        let got = c.standard_error_given(&[1.0, 0.0], &[0.0, 1.0]);
        assert!((got - want).abs() < 1e-12, "{got} vs {want}");
        // holding nothing (an undetermined or zero direction): the plain standard error
        let plain = c.standard_error(&[1.0, 0.0]);
        assert_eq!(c.standard_error_given(&[1.0, 0.0], &[0.0, 0.0]), plain);
    }
}
