//! The Prandtl–Ishlinskii refit with its play weights constrained to one sign: an outer active
//! set at the model level.
//!
//! A classical PI operator has a non-negative weight density on its thresholds beside a
//! positive identity gain (Brokate & Sprekels 1996, *Hysteresis and Phase Transitions*, §2.3;
//! Kuhnen 2003, Eur. J. Control 9(4), the "classical" operator before its modification), so a
//! physical fit has every play weight of the sign of the gain p. The unconstrained refit may use
//! plays of both signs to cancel each other. As in Lawson & Hanson's NNLS (1974, *Solving Least
//! Squares Problems*, ch. 23), the plays whose weights are on the wrong side are removed and the
//! model is refitted on the rest of the grid, until every kept weight has the sign; the removed
//! plays' weights are 0. Unlike NNLS the set only shrinks (no removed play is tried again: each
//! step is a whole refit of the model, not a least-squares solve).

use super::candidate::RefitContext;
use crate::error::Result;
use crate::fit::{Hammerstein, HammersteinModel};
use crate::real::Real;
use crate::regressors::{DEFAULT_PLAYS, PrandtlIshlinskii};

/// The last refit of the active set.
pub(crate) struct OneSign<T: Real> {
    /// The refitted model (the unconstrained one when it already had one sign).
    pub model: HammersteinModel<T>,
    /// Positions (1-based) of the plays removed from the grid, in the order they were removed.
    pub removed: Vec<usize>,
    /// True when every kept weight has the sign of the model's gain p; false when the last
    /// refit's weights are all against it (removing them would leave no play).
    pub one_sign: bool,
}

/// The weights (w_j, position j on the grid) of a model's play operators.
pub(crate) fn play_weights<T: Real>(model: &HammersteinModel<T>) -> Vec<(usize, f64)> {
    model
        .parameters()
        .into_iter()
        .filter_map(|(name, v)| Some((name.strip_prefix('w')?.parse().ok()?, v)))
        .collect()
}

/// The sign the weights must have: that of the gain p (the identity play of the classical
/// operator), else that of the weights' sum; +1 when both are 0.
pub(crate) fn required_sign<T: Real>(model: &HammersteinModel<T>) -> f64 {
    let p = model
        .parameters()
        .into_iter()
        .find(|(k, _)| k == "p")
        .map(|(_, v)| v);
    let sum: f64 = play_weights(model).iter().map(|&(_, w)| w).sum();
    match p {
        Some(p) if p != 0.0 && p.is_finite() => p.signum(),
        _ if sum != 0.0 && sum.is_finite() => sum.signum(),
        _ => 1.0,
    }
}

/// The settings of `model` with the UDN plus the plays `kept` of the default grid (the model's
/// options, subspace method, backend and output map; its order and feed-through).
fn subset_settings<T: Real>(model: &HammersteinModel<T>, kept: &[usize]) -> Result<Hammerstein<T>> {
    let s = model.settings();
    let nl = PrandtlIshlinskii::on_subset(s.build_nonlinearity()?, DEFAULT_PLAYS, kept)?;
    let mut h = Hammerstein::new(Box::new(nl));
    if let Some(m) = s.user_method() {
        h = h.subspace_method(m.clone());
    }
    if let Some(la) = s.user_linalg() {
        h = h.linalg(la.clone());
    }
    let h = h
        .output_nonlinearity(s.output_map().map(|m| m.clone_box()))
        .with_options(s.options().clone());
    Ok(h.at_structure_of(model))
}

/// From `full` (the refit of `ctx.model` with the whole grid), removes the plays whose weights
/// are against the gain p and refits on the rest until every kept weight has p's sign. The sign
/// is each refit's own: (p, w, block) and (−p, −w, −block) are the same model, so only w·p is
/// physical. Stops with `one_sign` false when every kept weight is against p.
pub(crate) fn one_sign_refit<T: Real>(
    ctx: &RefitContext<'_, T>,
    full: HammersteinModel<T>,
) -> Result<OneSign<T>> {
    let mut model = full;
    let mut removed = Vec::new();
    loop {
        let sign = required_sign(&model);
        let weights = play_weights(&model);
        let (kept, wrong): (Vec<_>, Vec<_>) = weights.iter().partition(|&&(_, w)| sign * w >= 0.0);
        if wrong.is_empty() || kept.is_empty() {
            return Ok(OneSign {
                model,
                removed,
                one_sign: wrong.is_empty(),
            });
        }
        removed.extend(wrong.iter().map(|&&(j, _)| j));
        let kept: Vec<usize> = kept.iter().map(|&&(j, _)| j).collect();
        model = ctx.fit(&subset_settings(ctx.model, &kept)?)?;
    }
}
