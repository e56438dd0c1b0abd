//! The dynamic-hysteresis candidate: a Prandtl–Ishlinskii sum of play operators missing from the
//! model (`regressors::PrandtlIshlinskii`; Kuhnen 2003, Brokate & Sprekels 1996).
//!
//! Signature: the residual is regressed (input-referred, through the model's linear block) on
//! the play operators F_{r_j}\[u\] of the input's own grid (`regressors::play_grid`) **beyond**
//! the input-level bins and their rising/falling split — the columns that a constant-width
//! (UDN) hysteresis already explains. What the plays add is a loop whose width depends on the
//! amplitude of the last reversal, which a split per level bin cannot express; the nested F test
//! of the K play columns is the evidence.
//!
//! Refit: the plays' weights constrained to the sign of the gain p (a classical PI operator's
//! non-negative density), by an outer active set on the grid (`pi_one_sign`).

use super::candidate::{Evidence, MissingEffect, Refit, RefitContext, readable};
use super::estimate::{Estimates, Quantity};
use super::pi_one_sign::{one_sign_refit, play_weights, required_sign};
use crate::data::IoData;
use crate::diagnosis::ids::{CandidateId, TestId};
use crate::diagnosis::residual_tests::analysis::ResidualAnalysis;
use crate::diagnosis::residual_tests::checks::signature::{Domain, direction_bins, level_bins};
use crate::error::Result;
use crate::fit::{Hammerstein, HammersteinModel};
use crate::real::Real;
use crate::regressors::{DEFAULT_PLAYS, Effect, play_checked, play_grid};

/// Name of the effect in the nonlinearity's effect list.
const NAME: &str = "prandtl-ishlinskii";

/// Dynamic (amplitude-dependent) hysteresis, added with `settings.with_effect(PrandtlIshlinskii)`.
#[derive(Debug, Clone, Copy, Default)]
pub struct PrandtlIshlinskiiCandidate;

/// Level of the joint F test of the play weights when none is significant alone.
pub(crate) const JOINT_LEVEL: f64 = 0.01;

/// p-value of the F test that the refit's `k` added parameters are 0 (nested least squares,
/// F = ((MSE₀ − MSE₁)/k) / (MSE₁/(N − k)); e.g. Söderström & Stoica 1989, *System
/// Identification*, §11.5); 1 when the refit is not better than its reference.
pub(crate) fn joint_p_value<T: Real>(refit: &Refit<T>, n: usize, k: usize) -> f64 {
    let (before, after) = (refit.reference_train_mse, refit.train_mse);
    let dof = n.saturating_sub(k) as f64;
    if !(after > 0.0 && before > after && dof > 0.0 && k > 0) {
        return 1.0;
    }
    let f = (before - after) / k as f64 / (after / dof);
    crate::diagnosis::stats::f_sf(f, k as f64, dof)
}

/// The weight names of the built-in basis (w1..wK).
fn weight_names() -> Vec<String> {
    (1..=DEFAULT_PLAYS).map(|j| format!("w{j}")).collect()
}

impl<T: Real> MissingEffect<T> for PrandtlIshlinskiiCandidate {
    fn id(&self) -> CandidateId {
        CandidateId::Effect(Effect::PrandtlIshlinskii)
    }
    fn applies_to(&self, model: &HammersteinModel<T>) -> bool {
        !model.nonlinearity().effects().iter().any(|e| e == NAME)
            && model
                .settings()
                .with_effect(Effect::PrandtlIshlinskii)
                .is_ok()
    }
    fn evidence(&self, a: &ResidualAnalysis) -> Option<Evidence> {
        let (r, c) = play_grid(&a.u, DEFAULT_PLAYS)?;
        let plays: Vec<Vec<f64>> = r.iter().map(|&r| play_checked(&a.u, r, c)).collect();
        let mut beyond = level_bins(&a.u, a.options.bins);
        beyond.extend(direction_bins(&a.u, &a.direction, a.options.direction_bins));
        let t = a.signature_test_beyond(
            TestId::PrandtlIshlinskii,
            "play operators of the input beyond level bins and their rising/falling split \
             (amplitude-dependent hysteresis signature)",
            &plays,
            Domain::Input,
            &beyond,
        );
        let sentence = format!(
            "{} play operators of u (thresholds {}…{}) explain part of the residual beyond a \
             constant-width rising/falling split ({}, p = {}): the loop width depends on the \
             amplitude of the input's reversals",
            r.len(),
            readable(r[0]),
            readable(r[r.len() - 1]),
            t.detail.split(';').next().unwrap_or_default(),
            readable(t.p_value)
        );
        let estimate = Estimates::residual([(Quantity::Plays, Some(r.len() as f64))]);
        Some(Evidence::from_test(&t, sentence, estimate))
    }
    /// The model's settings with the play operators added, order and feed-through kept (as for
    /// the UDN effects).
    fn apply(&self, model: &HammersteinModel<T>, _a: &ResidualAnalysis) -> Result<Hammerstein<T>> {
        Ok(Hammerstein::at_structure_of(
            model.settings().with_effect(Effect::PrandtlIshlinskii)?,
            model,
        ))
    }
    /// The refit with the whole grid, then with the plays whose weights are against the gain p
    /// removed until the kept ones agree (`pi_one_sign`): the weights of the refit have one sign.
    fn refit(&self, ctx: &RefitContext<'_, T>) -> Result<Refit<T>> {
        // an input of two levels identifies no hysteresis beyond an affine map
        super::identifiability::identifiable(ctx.train, Effect::PrandtlIshlinskii)?;
        let settings = self.apply(ctx.model, ctx.analysis)?;
        let full = ctx.fit(&settings)?;
        let names = weight_names();
        let refs: Vec<&str> = names.iter().map(String::as_str).collect();
        let one = one_sign_refit(ctx, full)?;
        let mut r = Refit::of_model(ctx, one.model, &refs)?;
        if !one.removed.is_empty() {
            let mut removed = one.removed;
            removed.sort_unstable();
            let removed: Vec<String> = removed.iter().map(|j| format!("w{j}")).collect();
            r.change = format!(
                "{}; plays {} removed (their weights were against the gain p)",
                r.change,
                removed.join(", ")
            );
        }
        if !one.one_sign {
            r.change
                .push_str("; the kept plays' weights are all against the gain p");
        }
        Ok(r)
    }
    fn refit_estimate(&self, model: &HammersteinModel<T>) -> Estimates {
        let names = weight_names();
        let refs: Vec<&str> = names.iter().map(String::as_str).collect();
        Estimates::of_parameters(model, &refs)
    }
    /// Null value: the play weights jointly not distinguishable from 0 (none within two standard
    /// errors of 0 alone and the F test of the kept plays not significant). Not credited either:
    /// every weight against the gain p (the one-sign refit keeps no play), or — for a refit not
    /// made by [`refit`](MissingEffect::refit) — weights clearly of both signs, which no physical
    /// hysteresis loop has (a Prandtl–Ishlinskii operator with non-negative weights is a
    /// clockwise, monotone loop); a fit with such weights uses the plays to cancel each other
    /// (seen on the EMPS drive: training fit 98.9 %, validation −26 %).
    fn null_parameters(&self, refit: &Refit<T>, train: &IoData<T>) -> Option<String> {
        let mut j = judge_weights(refit)?;
        if let Some(m) = &refit.model {
            let (sign, w) = (required_sign(m), play_weights(m));
            if !w.is_empty() && w.iter().all(|&(_, v)| sign * v < 0.0) {
                return Some(format!(
                    "every play weight is against the gain p ({}): a fit with the weights of \
                     p's sign keeps no play",
                    j.shown.join(", ")
                ));
            }
        }
        if j.signs.is_empty() {
            // neighbouring plays are nearly collinear: each weight alone may be undetermined
            // while the kept plays are clearly not 0 together, which the F test of the nested
            // models (the refit against the model without plays) measures
            let p = joint_p_value(refit, train.len(), j.count);
            if p.is_nan() || p >= JOINT_LEVEL {
                return Some(format!(
                    "every play weight is within two standard errors of 0 ({}) and together \
                     they are not distinguishable from 0 (F test p = {})",
                    j.shown.join(", "),
                    readable(p)
                ));
            }
            // the sign of the whole operator is its weights' sum
            j.signs.push(j.sum.signum());
        }
        let gain = refit.model.as_ref().and_then(|m| {
            m.parameters()
                .into_iter()
                .find(|(k, _)| k == "p")
                .map(|(_, v)| v.signum())
        });
        let mixed = j.signs.iter().any(|&s| s > 0.0) && j.signs.iter().any(|&s| s < 0.0);
        let against_gain = gain.is_some_and(|g| g != 0.0 && j.signs.iter().all(|&s| s != g));
        (mixed || against_gain).then(|| {
            format!(
                "play weights {} ({}): no physical hysteresis loop has them, the plays cancel each other",
                if mixed { "clearly of both signs" } else { "all against the gain p" },
                j.shown.join(", ")
            )
        })
    }
}

/// A refit's play weights as the null rule reads them.
struct JudgedWeights {
    /// "w1 = … ± …" of every weight (the removed plays' "w2 = 0 (removed)").
    shown: Vec<String>,
    /// Signs of the weights more than two standard errors from 0.
    signs: Vec<f64>,
    /// Sum of the weights.
    sum: f64,
    /// Number of weights the refit estimated (the kept plays).
    count: usize,
}

/// The weights w1..wK of `refit`'s estimates; `None` when it has none (not a PI refit). A play the
/// one-sign refit removed has no estimate: its weight is 0.
fn judge_weights<T: Real>(refit: &Refit<T>) -> Option<JudgedWeights> {
    let mut j = JudgedWeights {
        shown: Vec::new(),
        signs: Vec::new(),
        sum: 0.0,
        count: 0,
    };
    for n in &weight_names() {
        let Some(e) = refit.estimate.parameter(n) else {
            j.shown.push(format!("{n} = 0 (removed)"));
            continue;
        };
        // (as for the UDN effects: no standard error computed counts as 0, NaN as ∞)
        let (v, se) = (e.value, e.standard_error.unwrap_or(0.0));
        let se = if se.is_nan() { f64::INFINITY } else { se };
        if v.abs() > 2.0 * se {
            j.signs.push(v.signum());
        }
        j.sum += v;
        j.count += 1;
        j.shown.push(if se.is_finite() {
            format!("{n} = {} ± {}", readable(v), readable(se))
        } else {
            format!("{n} = {} (not determined by the record)", readable(v))
        });
    }
    (j.count > 0).then_some(j)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::diagnosis::estimate::Estimate;

    /// A refit with these play weights and standard errors (no model: no gain p to compare).
    fn refit(weights: &[(f64, f64)]) -> Refit<f64> {
        let names = weight_names();
        Refit {
            train_mse: 1.0,
            reference_train_mse: 2.0,
            added_parameters: names.len() as i64,
            added_states: 0,
            validation_mse: 1.0,
            reference_mse: 2.0,
            change: String::new(),
            estimate: names
                .iter()
                .zip(weights)
                .map(|(n, &(v, se))| Estimate::refit(Quantity::Parameter(n.clone()), v, Some(se)))
                .collect(),
            null_parameters: None,
            model: None,
        }
    }

    fn judged(weights: &[(f64, f64)]) -> Option<String> {
        let u = vec![0.0, 1.0, 0.0, -1.0];
        let data = IoData::siso(&u, &u).unwrap();
        MissingEffect::<f64>::null_parameters(&PrandtlIshlinskiiCandidate, &refit(weights), &data)
    }

    #[test]
    fn null_mixed_and_physical_weights() {
        assert_eq!(weight_names().len(), 6);
        // all within two standard errors of 0: null
        let null = judged(&[(0.1, 0.1); 6]).expect("null weights are not credited");
        assert!(null.contains("within two standard errors"), "{null}");
        // significant weights of both signs (the EMPS fit): not credited
        let mixed = [
            (4.8, 0.9),
            (-9.3, 1.7),
            (5.0, 0.9),
            (-1.2, 0.2),
            (0.1, 0.5),
            (0.0, 0.5),
        ];
        let why = judged(&mixed).expect("alternating weights are not credited");
        assert!(why.contains("both signs"), "{why}");
        // significant weights of one sign, the others at 0: credited
        let physical = [
            (0.5, 0.1),
            (0.3, 0.1),
            (0.2, 0.1),
            (-0.05, 0.1),
            (0.1, 0.02),
            (0.0, 0.1),
        ];
        assert_eq!(judged(&physical), None);
    }

    #[test]
    fn collinear_weights_are_judged_together() {
        // each weight within two standard errors, but the refit halves the training MSE on
        // 2000 samples: jointly not 0, credited with the sign of their sum
        let u: Vec<f64> = (0..2000).map(|k| (k as f64 * 0.1).sin()).collect();
        let data = IoData::siso(&u, &u).unwrap();
        let collinear = refit(&[(0.2, 0.11); 6]);
        assert_eq!(
            MissingEffect::<f64>::null_parameters(&PrandtlIshlinskiiCandidate, &collinear, &data),
            None
        );
        // the same weights without a better fit: null
        let mut flat = refit(&[(0.2, 0.11); 6]);
        flat.train_mse = flat.reference_train_mse;
        let why = MissingEffect::<f64>::null_parameters(&PrandtlIshlinskiiCandidate, &flat, &data)
            .expect("a refit that explains nothing is not credited");
        assert!(why.contains("not distinguishable"), "{why}");
    }
}
