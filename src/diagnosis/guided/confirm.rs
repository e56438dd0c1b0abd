//! Confirmation of a guided step on data the choice did not see: the training record's last
//! part is held back, the step is replayed on the rest and judged on the held-back part.
//!
//! Why: the guided loop ([`super::follow`]) chooses each change on the training record (ΔBIC of
//! the training simulation error). A change that lowers the training criterion can still make
//! the model worse on data it has not seen (a record unlike the rest, an effect that fits the
//! noise of one part). The user's validation part must stay untouched by the choice, so the
//! check uses the training record alone: the hold-out ("validation set") approach of Hastie,
//! Tibshirani & Friedman, *The Elements of Statistical Learning*, 2nd ed., 2009, §7.2 and §7.10.
//!
//! Algorithm ([`Confirmer`]):
//! 1. Two folds of the training record: its last quarter held back (the models fitted on the
//!    leading three quarters) and its first quarter held back (fitted on the trailing three
//!    quarters) — contiguous parts, as a dynamic model needs ([`ConfirmRule::hold_back`],
//!    [`ConfirmRule::folds`]); each part at least [`ConfirmRule::min_held_back`] samples,
//!    otherwise no step is checked and each says so.
//! 2. Fit the starting model's structure (its order fixed) on each fitting part.
//! 3. For each step the loop proposes: refit the same candidate on each fitting part from that
//!    part's current model (the candidate's own refit, as the diagnosis does it), and simulate
//!    both models on the held-back part (initial state estimated there by least squares, as
//!    every comparison does).
//! 4. The loss differential d_k = e_after(k)² − e_before(k)² on the held-back samples of both
//!    folds; its mean d̄ (the change of the held-back MSE) and the Diebold–Mariano statistic
//!    DM = d̄ / √(V̂/n), V̂ the Newey–West (Bartlett-kernel) long-run variance of d with
//!    ⌊4 (n/100)^{2/9}⌋ lags (Diebold & Mariano, "Comparing predictive accuracy", J. Business &
//!    Economic Statistics 13(3), 1995; Newey & West, Econometrica 55(3), 1987), since simulation
//!    errors are autocorrelated.
//! 5. The step is **confirmed** when DM < z, z = [`ConfirmRule::z`] (default −1): the held-back
//!    MSE falls by more than one standard error of its change — the one-standard-error rule of
//!    cross-validation (Breiman, Friedman, Olshen & Stone, *Classification and Regression
//!    Trees*, 1984, §3.4.3; Hastie, Tibshirani & Friedman §7.10): the larger model is taken
//!    only when unseen data prefer it by more than their own noise. The one-sided p-value Φ(DM)
//!    is reported.
//!
//! An unconfirmed step is not taken: the loop stops there ([`crate::diagnosis::FollowStop::NotConfirmed`])
//! — the candidates after the first are ranked lower on the same training criterion the held-back
//! data just contradicted.

use crate::data::IoData;
use crate::diagnosis::compare::compare;
use crate::diagnosis::diagnoser::diagnose::Diagnoser;
use crate::diagnosis::ids::CandidateId;
use crate::diagnosis::residual_tests::stats::normal_cdf;
pub use crate::diebold_mariano::diebold_mariano;
use crate::error::{Error, Result};
use crate::fit::HammersteinModel;
use crate::fit::order_selection::training_mse;
use crate::real::Real;
use serde::Serialize;

/// The rule a guided step is confirmed by (see the module's text).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct ConfirmRule {
    /// Fraction of the training record held back at its end (default 0.25).
    pub hold_back: f64,
    /// Fewest held-back samples a check needs (default 50; fewer: steps are not checked).
    pub min_held_back: usize,
    /// Threshold on the Diebold–Mariano statistic: confirmed when DM < z (default −1: the
    /// held-back MSE falls by more than one standard error of its change).
    pub z: f64,
    /// Held-back parts: 1 (the last part) or 2 (the last and the first part, each model
    /// refitted on the rest; default).
    pub folds: usize,
}

impl Default for ConfirmRule {
    fn default() -> Self {
        Self {
            hold_back: 0.25,
            min_held_back: 50,
            z: -1.0,
            folds: 2,
        }
    }
}

/// The check of one guided step on the held-back part of the training record.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Confirmation {
    /// The step was checked and the held-back data agree (or it could not be checked: see
    /// `note`).
    pub confirmed: bool,
    /// Held-back samples (0 when not checked).
    pub held_back: usize,
    /// Held-back MSE of the model before the step (both refitted on the fitting part).
    pub mse_before: f64,
    /// Held-back MSE of the model after the step.
    pub mse_after: f64,
    /// Diebold–Mariano statistic of the loss differential (negative: the step helps).
    pub statistic: f64,
    /// One-sided p-value of "the step does not lower the held-back MSE" (Φ(DM)).
    pub p_value: f64,
    /// Why the step was not checked, when it was not.
    pub note: Option<String>,
}

impl Confirmation {
    pub(crate) fn unchecked(note: String) -> Self {
        Self {
            confirmed: true,
            held_back: 0,
            mse_before: f64::NAN,
            mse_after: f64::NAN,
            statistic: f64::NAN,
            p_value: f64::NAN,
            note: Some(note),
        }
    }

    /// One line: "held-back MSE a → b (DM −2.1, p = 0.02): confirmed".
    pub fn text(&self) -> String {
        if let Some(n) = &self.note {
            return format!("not checked: {n}");
        }
        format!(
            "held-back MSE {} → {} ({:+.2} %, DM {:.2}, p = {:.3}, {} samples): {}",
            crate::diagnosis::candidates::candidate::readable(self.mse_before),
            crate::diagnosis::candidates::candidate::readable(self.mse_after),
            100.0 * (self.mse_after / self.mse_before - 1.0),
            self.statistic,
            self.p_value,
            self.held_back,
            if self.confirmed {
                "confirmed"
            } else {
                "not confirmed"
            }
        )
    }
}

/// One fold: the part the models are fitted on, the part held back, and the fitting part's
/// current model.
struct Fold<T: Real> {
    fit_part: IoData<T>,
    held: IoData<T>,
    current: HammersteinModel<T>,
}

/// Replays the guided loop's steps on the fitting parts of the training record and confirms each
/// on the held-back parts (the module's algorithm).
pub(crate) struct Confirmer<T: Real> {
    rule: ConfirmRule,
    folds: Vec<Fold<T>>,
    why_not: Option<String>,
}

impl<T: Real> Confirmer<T> {
    /// Splits `train` into the folds and fits `start`'s structure on each fitting part (step 2).
    pub(crate) fn new(rule: ConfirmRule, start: &HammersteinModel<T>, train: &IoData<T>) -> Self {
        let n = train.len();
        let held = ((n as f64) * rule.hold_back.clamp(0.0, 0.5)).round() as usize;
        let not_checked = |why: String| Self {
            rule,
            folds: Vec::new(),
            why_not: Some(why),
        };
        if held < rule.min_held_back || n - held < rule.min_held_back {
            return not_checked(format!(
                "the training record ({n} samples) is too short to hold back {} of them",
                rule.min_held_back.max(held)
            ));
        }
        // the last part held back (fitted on the leading rest), then the first part (fitted
        // on the trailing rest): contiguous parts, as a dynamic model needs
        let bounds = [(0, n - held, n - held, n), (held, n, 0, held)];
        let settings = start.settings().clone().at_structure_of(start);
        let mut folds = Vec::new();
        let mut failed = Vec::new();
        for &(a, b, c, d) in bounds.iter().take(rule.folds.clamp(1, 2)) {
            let parts = train.slice(a, b).and_then(|f| Ok((f, train.slice(c, d)?)));
            let fold = parts.and_then(|(fit_part, held)| {
                let current = settings.fit(&fit_part)?;
                Ok(Fold {
                    fit_part,
                    held,
                    current,
                })
            });
            // a part the record cannot give (e.g. a held-back quarter at rest, a constant
            // input) leaves that fold out; the steps are checked on the other
            match fold {
                Ok(f) => folds.push(f),
                Err(e) => failed.push(format!("samples {c}..{d} held back: {e}")),
            }
        }
        if folds.is_empty() {
            return not_checked(format!(
                "no part of the training record can be held back: {}",
                failed.join("; ")
            ));
        }
        Self {
            rule,
            folds,
            why_not: None,
        }
    }

    /// Steps 3–5 for the step that adds candidate `effect` (its model on the whole training
    /// record: `next_full`); a confirmed step becomes each fitting part's current model.
    pub(crate) fn check(
        &mut self,
        diagnoser: &Diagnoser<T>,
        effect: &CandidateId,
        next_full: &HammersteinModel<T>,
    ) -> Confirmation {
        if self.folds.is_empty() {
            return Confirmation::unchecked(
                self.why_not
                    .clone()
                    .unwrap_or_else(|| "no fitting part".into()),
            );
        }
        let mut nexts = Vec::new();
        let (mut before, mut after) = (Vec::new(), Vec::new());
        for f in &self.folds {
            match replay(
                diagnoser,
                effect,
                &f.current,
                next_full,
                &f.fit_part,
                &f.held,
            ) {
                Ok((m, b, a)) => {
                    nexts.push(m);
                    before.extend(b);
                    after.extend(a);
                }
                Err(e) => {
                    // the step cannot be replayed on a fitting part: not checked, said (and
                    // the later steps neither)
                    let c =
                        Confirmation::unchecked(format!("its refit on a fitting part failed: {e}"));
                    self.folds.clear();
                    self.why_not = c.note.clone();
                    return c;
                }
            }
        }
        let mse = |e: &[f64]| e.iter().map(|x| x * x).sum::<f64>() / e.len().max(1) as f64;
        let (_, statistic) = diebold_mariano(&before, &after);
        let (mse_before, mse_after) = (mse(&before), mse(&after));
        let confirmed = statistic < self.rule.z && mse_after.is_finite();
        if confirmed {
            for (f, m) in self.folds.iter_mut().zip(nexts) {
                f.current = m;
            }
        }
        Confirmation {
            confirmed,
            held_back: before.len(),
            mse_before,
            mse_after,
            statistic,
            p_value: normal_cdf(statistic),
            note: None,
        }
    }
}

/// The candidate's refit of `current` on `fit_part` (a refit without a model of its own, as the
/// output map: `next_full`'s structure refitted there) and both models' held-back residuals.
fn replay<T: Real>(
    diagnoser: &Diagnoser<T>,
    effect: &CandidateId,
    current: &HammersteinModel<T>,
    next_full: &HammersteinModel<T>,
    fit_part: &IoData<T>,
    held: &IoData<T>,
) -> Result<(HammersteinModel<T>, Vec<f64>, Vec<f64>)> {
    use crate::diagnosis::candidates::candidate::RefitContext;
    let candidate = diagnoser
        .candidates()
        .get(effect)
        .ok_or_else(|| Error::UnknownCandidate {
            name: effect.to_string(),
        })?;
    let analysis = diagnoser.analysis(current, fit_part)?;
    let held_c = compare(current, held)?;
    let ctx = RefitContext {
        model: current,
        train: fit_part,
        validation: held,
        validation_comparison: &held_c,
        analysis: &analysis,
        train_mse: training_mse(current, fit_part),
        observer: None,
    };
    let refit = candidate.refit(&ctx)?;
    let next = match refit.model {
        Some(m) => m,
        None => next_full
            .settings()
            .clone()
            .at_structure_of(next_full)
            .fit(fit_part)?,
    };
    let after = compare(&next, held)?.residual;
    Ok((next, held_c.residual, after))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn diebold_mariano_signs_follow_the_loss_differential() {
        let mut s = 7u64;
        let mut noise = || {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((s >> 11) as f64 / (1u64 << 53) as f64) - 0.5
        };
        let before: Vec<f64> = (0..400).map(|_| noise()).collect();
        let worse: Vec<f64> = before.iter().map(|e| 1.5 * e).collect();
        let better: Vec<f64> = before.iter().map(|e| 0.5 * e).collect();
        let (d, z) = diebold_mariano(&before, &worse);
        assert!(d > 0.0 && z > 3.0, "worse: d̄ {d}, DM {z}");
        let (d, z) = diebold_mariano(&before, &better);
        assert!(d < 0.0 && z < -3.0, "better: d̄ {d}, DM {z}");
        let (d, z) = diebold_mariano(&before, &before);
        assert!(d == 0.0 && z == 0.0);
    }
}
