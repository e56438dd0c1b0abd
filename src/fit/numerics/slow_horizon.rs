//! The subspace horizon a fitted block's time constant asks for (issue 10, "local minima at the
//! true order"; `docs/battery.md`).
//!
//! The loop's r-input subspace steps use the settings' horizon (8 block rows by default). When the
//! block's slowest mode decays by less than 1/e over that many samples, the block-Hankel
//! matrices' past and future windows see only the start of the slow modes: clustered slow poles
//! (0.84–0.94 on development record 591) give singular values that the noise swamps, the first
//! iterate's (A, C) is wrong (877× the noise when started at the true θ) and the loop and the
//! refinement end in a local minimum (3.5× the noise at the true order; the true model 0.98×).
//! The window length of subspace identification should cover the dominant time constant, not
//! just exceed the order (Verhaegen & Verdult 2007, *Filtering and System Identification*,
//! § 9.6: the number of block rows s ≫ n; Ljung 1999, § 10.6): the fit is redone at a horizon
//! of at least the slowest time constant τ = −1/ln ρ (ρ the largest pole modulus of the fitted
//! block) and kept when its training error is lower by more than the noise explains.

use super::jump_centre::LR_BOUND;
use crate::data::min_samples_for_horizon;

/// Longest horizon the rule asks for (block rows): 40 samples cover τ = 40 (ρ = 0.975); the
/// subspace step's cost grows with the horizon's square.
pub const MAX_SLOW_HORIZON: usize = 40;

/// The horizon a refit should use when the fitted block's slowest pole (modulus `rho`) has a time
/// constant longer than the current `horizon`: ⌈τ⌉ (τ = −1/ln ρ; an unstable or integrating
/// block gets `MAX_SLOW_HORIZON`), at most `MAX_SLOW_HORIZON` and at most what `n_samples` allow
/// with `regressors` inputs. `None` when the current horizon already spans τ, or when the longer
/// horizon would not be longer.
pub fn slow_horizon(
    rho: f64,
    horizon: usize,
    n_samples: usize,
    regressors: usize,
) -> Option<usize> {
    if !rho.is_finite() || rho <= 0.0 {
        return None;
    }
    let tau = if rho >= 1.0 {
        f64::INFINITY
    } else {
        -1.0 / rho.ln()
    };
    if tau <= horizon as f64 {
        return None;
    }
    let mut h = if tau.is_finite() {
        (tau.ceil() as usize).min(MAX_SLOW_HORIZON)
    } else {
        MAX_SLOW_HORIZON
    };
    while h > horizon && min_samples_for_horizon(h, regressors.max(1), 1) > n_samples {
        h -= 1;
    }
    (h > horizon).then_some(h)
}

/// Whether a refit's training MSE `refit` is lower than the first fit's `first` by more than the
/// noise decides on `n_samples` samples (N·ln(first/refit) beyond the likelihood-ratio bound
/// `jump_centre::LR_BOUND`, 3.84: χ²₁ at 95 %) (two fits of the same structure at MSEs within the bound
/// differ by chance: a jump moved to a neighbouring interval, say); false when not finite.
pub fn clearly_lower(refit: f64, first: f64, n_samples: usize) -> bool {
    if !refit.is_finite() || refit <= 0.0 {
        return false;
    }
    !first.is_finite() || n_samples as f64 * (first / refit).ln() > LR_BOUND
}

/// The largest modulus of `poles` (re, im); 0 for none.
pub fn spectral_radius(poles: &[(f64, f64)]) -> f64 {
    poles
        .iter()
        .map(|&(re, im)| re.hypot(im))
        .fold(0.0, f64::max)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fast_blocks_keep_the_horizon() {
        // the paper's Example 1: poles of modulus 0.59, τ = 1.9
        assert_eq!(slow_horizon(0.59, 8, 2000, 4), None);
        // τ = 7.5 < 8
        assert_eq!(slow_horizon(0.875, 8, 2000, 4), None);
    }

    #[test]
    fn slow_blocks_get_their_time_constant() {
        // ρ = 0.96: τ = 24.5
        assert_eq!(slow_horizon(0.96, 8, 2000, 3), Some(25));
        assert_eq!(slow_horizon(0.999, 8, 2000, 3), Some(MAX_SLOW_HORIZON));
        assert_eq!(slow_horizon(1.2, 8, 2000, 3), Some(MAX_SLOW_HORIZON));
    }

    #[test]
    fn refits_within_the_noise_are_not_taken() {
        assert!(clearly_lower(0.9, 1.0, 1000));
        assert!(!clearly_lower(0.999, 1.0, 1000));
        assert!(!clearly_lower(f64::NAN, 1.0, 1000));
        assert!(clearly_lower(1.0, f64::INFINITY, 1000));
    }

    #[test]
    fn short_records_bound_the_horizon() {
        let h = slow_horizon(0.999, 8, 200, 3).unwrap();
        assert!(h > 8 && min_samples_for_horizon(h, 3, 1) <= 200, "{h}");
        assert_eq!(slow_horizon(0.999, 8, 10, 3), None);
    }
}
