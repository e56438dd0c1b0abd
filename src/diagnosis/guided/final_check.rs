//! The guided loop's checks on what it extends and on the model it ends with.
//!
//! - **A step is never worse on training than the model it extends** ([`no_worse_on_training`]):
//!   every refit the loop takes nests the model it came from (an effect at its null value, an
//!   output map at the identity, states with zero input weight), so its training MSE — the
//!   criterion every fit minimises — cannot exceed that model's when the fit found its optimum.
//!   A refit that ends above it ended in a worse local optimum, and the loop does not take it.
//! - **An input that cannot identify an effect** (`identifiability.rs`): the candidates that
//!   add one are not refitted, and the final model keeps none.
//! - **No credit for nothing on the final model** ([`Diagnoser::check_final`]): the null-value
//!   rules the candidates apply when an effect is added ([`MissingEffect::null_parameters`]) are
//!   applied again to the model the loop ends with — a later step (an order raised) can move a
//!   parameter to its null value or, for play weights, against the gain. An effect found null is
//!   dropped and the model refitted without it (from the final model and from the default
//!   start, the lower training MSE kept), and the check repeats. Play weights against the gain
//!   are removed first by the one-sign refit of the Prandtl–Ishlinskii candidate.
//! - **A saturation limit the record does not measure** ([`unmeasured_limits`]): the UDN's
//!   saturation has two finite limits; when fewer than [`UNMEASURED_SHARE`] of the training
//!   samples reach one of them, that limit sits at the input's extreme (the fit moves it there
//!   when the system saturates on one side only) and is said, with how many samples reach it.
//! - **An order the record does not support** ([`unsupported_order`]): an order raise whose
//!   refit's block is unstable is not taken, and said (states that leave the unit circle fit
//!   the training record, not a system that settles); the model keeps the order it had. A
//!   final block that is still unstable at an order the loop raised is said as well.

use crate::data::IoData;
use crate::diagnosis::candidates::candidate::{MissingEffect, Refit, readable};
use crate::diagnosis::candidates::estimate::{Estimate, Estimates, Quantity};
use crate::diagnosis::candidates::identifiability::{identifiable, input_levels};
use crate::diagnosis::diagnoser::diagnose::Diagnoser;
use crate::diagnosis::diagnoser::outcome::Diagnosis;
use crate::diagnosis::ids::CandidateId;
use crate::error::{Error, Result};
use crate::fit::order_selection::{free_parameters, training_mse};
use crate::fit::{Hammerstein, HammersteinModel, Observer};
use crate::real::Real;
use crate::regressors::{Effect, EffectSet};

/// Relative slack of [`no_worse_on_training`]: the training MSEs of two fits of the same record
/// are sums of N squares formed in different orders; 1e-9 is far above their round-off (N·ε ≈
/// 2e-13 for N = 1e3 in f64) and far below any difference a fit means.
pub const TRAINING_SLACK: f64 = 1e-9;

/// `Ok(next)` when `next` (a refit the guided loop would take from `current`) fits the
/// training record no worse than `current` ([`training_mse`], with [`TRAINING_SLACK`]); an
/// error saying both MSEs otherwise.
pub(crate) fn no_worse_on_training<T: Real>(
    current: &HammersteinModel<T>,
    next: HammersteinModel<T>,
    train: &IoData<T>,
) -> Result<HammersteinModel<T>> {
    let (before, after) = (training_mse(current, train), training_mse(&next, train));
    if after > before * (1.0 + TRAINING_SLACK) {
        return Err(Error::Identification(format!(
            "its refit trains at MSE {} above the {} of the model it extends (a worse local \
             optimum): not taken",
            readable(after),
            readable(before)
        )));
    }
    Ok(next)
}

/// Why `next`, a refit the guided loop would take from `current` at a higher order, is not
/// supported by the record: its block is unstable (spectral radius above 1), so the added
/// states fit the training record rather than a system that settles, and the loop keeps
/// `current`'s order. `None` when `next` keeps the order or its block is stable.
pub(crate) fn unsupported_order<T: Real>(
    current: &HammersteinModel<T>,
    next: &HammersteinModel<T>,
    train: &IoData<T>,
) -> Option<String> {
    let (n0, n) = (current.linear().order(), next.linear().order());
    let rho = next.linear().spectral_radius().unwrap_or(f64::NAN);
    (n > n0 && (rho.is_nan() || rho > 1.0)).then(|| {
        format!(
            "order {n} is not supported by the record ({} training samples): its refit's block \
             is unstable (spectral radius {}); the model keeps order {n0}",
            train.len(),
            format_args!("{rho:.6}")
        )
    })
}

/// Share of the training samples below which a saturation limit counts as not measured by the
/// record ([`unmeasured_limits`]): 1 %, the tail the zone guard leaves outside the limits' range.
pub const UNMEASURED_SHARE: f64 = 0.01;

/// The saturation limits of `model` that fewer than [`UNMEASURED_SHARE`] of the training
/// samples reach, one sentence each (empty without a saturation, or with a hysteresis, whose
/// branch variable is not the input). A sample reaches the upper limit z1 when its dead-zone
/// output w = sign(u)·max(|u| − b, 0) exceeds it, the lower limit z2 when w is below it.
pub(crate) fn unmeasured_limits<T: Real>(
    model: &HammersteinModel<T>,
    train: &IoData<T>,
) -> Vec<String> {
    let Some(set) = effects_of(model) else {
        return Vec::new();
    };
    if !set.contains(Effect::Saturation) || set.contains(Effect::Hysteresis) {
        return Vec::new();
    }
    let p: std::collections::HashMap<String, f64> = model.parameters().into_iter().collect();
    let (Some(&z1), Some(&z2)) = (p.get("z1"), p.get("z2")) else {
        return Vec::new();
    };
    let b = p.get("b").copied().unwrap_or(0.0);
    let u: Vec<f64> = train.input(0).iter().map(|u| u.as_f64()).collect();
    let w: Vec<f64> = u
        .iter()
        .map(|u| u.signum() * (u.abs() - b).max(0.0))
        .collect();
    let n = w.len();
    let (lo, hi) = u
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), &x| {
            (l.min(x), h.max(x))
        });
    let limits = [
        (
            "upper",
            "z1",
            z1,
            w.iter().filter(|&&x| x > z1).count(),
            "maximum",
            hi,
        ),
        (
            "lower",
            "z2",
            z2,
            w.iter().filter(|&&x| x < z2).count(),
            "minimum",
            lo,
        ),
    ];
    limits
        .iter()
        .filter(|(.., k, _, _)| (*k as f64) < UNMEASURED_SHARE * n as f64)
        .map(|(side, name, z, k, extreme, at)| {
            format!(
                "the saturation's {side} limit {name} = {} is reached by {k} of {n} training \
                 samples (the input's {extreme} {}): the record does not measure it, the \
                 saturation acts on one side only",
                readable(*z),
                readable(*at)
            )
        })
        .collect()
}

/// What the final check removes from a model.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Part {
    /// One effect of the input nonlinearity.
    Effect(Effect),
    /// Every effect of the input nonlinearity (an input that identifies none).
    AllEffects,
    /// The output map.
    OutputMap,
}

impl Part {
    fn label(self) -> String {
        match self {
            Part::Effect(e) => format!("- {e}"),
            Part::AllEffects => "- input effects".into(),
            Part::OutputMap => "- output map".into(),
        }
    }
}

/// The effects of `model`'s nonlinearity as a set (`None` when one is not a UDN effect).
fn effects_of<T: Real>(model: &HammersteinModel<T>) -> Option<EffectSet> {
    EffectSet::parse(&model.nonlinearity().effects().join(",")).ok()
}

/// `model`'s settings without `part`, at its order and feed-through (its options, subspace
/// method, backend and, unless dropped, output map kept).
fn settings_without<T: Real>(model: &HammersteinModel<T>, part: Part) -> Result<Hammerstein<T>> {
    let s = model.settings();
    let map = s.output_map().map(|m| m.clone_box());
    let set = effects_of(model)
        .ok_or_else(|| Error::Identification("the nonlinearity is not a UDN".into()))?;
    let (set, map) = match part {
        Part::Effect(e) => (set.without(e), map),
        Part::AllEffects => (EffectSet::empty(), map),
        Part::OutputMap => (set, None),
    };
    let mut h = Hammerstein::udn(set);
    if let Some(m) = s.user_method() {
        h = h.subspace_method(m.clone());
    }
    if let Some(la) = s.user_linalg() {
        h = h.linalg(la.clone());
    }
    Ok(h.output_nonlinearity(map)
        .with_options(s.options().clone())
        .at_structure_of(model))
}

/// `model` refitted without `part` on `train`: from `model` itself (its block and the
/// parameters the reduced nonlinearity shares with it, then the refinement) and from the
/// default start, the lower training MSE kept.
fn refit_without<T: Real>(
    model: &HammersteinModel<T>,
    part: Part,
    train: &IoData<T>,
    observer: Option<&dyn Observer>,
) -> Result<HammersteinModel<T>> {
    refit_as(&settings_without(model, part)?, model, train, observer)
}

/// `settings` (a part of `model` removed) fitted on `train` from `model` itself (its block and
/// the parameters the nonlinearity shares with it by name, the others 0, then the refinement)
/// and from the default start, the lower training MSE kept.
fn refit_as<T: Real>(
    settings: &Hammerstein<T>,
    model: &HammersteinModel<T>,
    train: &IoData<T>,
    observer: Option<&dyn Observer>,
) -> Result<HammersteinModel<T>> {
    let current: Vec<(String, f64)> = model.parameters();
    let theta: Vec<f64> = settings
        .build_nonlinearity()?
        .param_names()
        .iter()
        .map(|n| {
            current
                .iter()
                .find(|(k, _)| k == n)
                .map_or(0.0, |(_, v)| *v)
        })
        .collect();
    let nested = settings.fit_from(train, model, &theta);
    let scratch = match observer {
        Some(o) => settings.fit_observed(train, o),
        None => settings.fit(train),
    };
    match (nested, scratch) {
        (Ok(a), Ok(b)) => Ok(if training_mse(&b, train) < training_mse(&a, train) {
            b
        } else {
            a
        }),
        (Ok(m), Err(_)) | (Err(_), Ok(m)) => Ok(m),
        (Err(e), Err(_)) => Err(e),
    }
}

/// A [`Refit`] view of `model` as if `part` had just been added to `reduced`: what the
/// candidates' null-value rules read.
fn view_of<T: Real>(
    model: &HammersteinModel<T>,
    reduced_mse: f64,
    reduced_k: usize,
    estimate: Estimates,
    train: &IoData<T>,
) -> Refit<T> {
    Refit {
        train_mse: training_mse(model, train),
        reference_train_mse: reduced_mse,
        added_parameters: free_parameters(model) as i64 - reduced_k as i64,
        added_states: 0,
        validation_mse: f64::NAN,
        reference_mse: f64::NAN,
        change: String::new(),
        estimate,
        null_parameters: None,
        model: Some(model.clone()),
    }
}

impl<T: Real> Diagnoser<T> {
    /// Why `part` of `model` is at its null value on `train` (the candidate's own rule), with
    /// the model refitted without it when that was needed to judge (`reduced`); `None` when
    /// `part` is credited.
    fn null_part(
        &self,
        model: &HammersteinModel<T>,
        part: Part,
        train: &IoData<T>,
        observer: Option<&dyn Observer>,
        reduced: &mut Option<HammersteinModel<T>>,
    ) -> Option<String> {
        let (id, estimate) = match part {
            Part::Effect(e) => {
                let c = self.candidates().get(&CandidateId::Effect(e))?;
                (CandidateId::Effect(e), c.refit_estimate(model))
            }
            Part::OutputMap => {
                let mut est = Estimates::new();
                for (k, v, se) in model.output_map_parameters_with_errors() {
                    est.insert(Estimate::refit(Quantity::OutputMap(k), v, se));
                }
                (CandidateId::OutputNonlinearity, est)
            }
            Part::AllEffects => return None,
        };
        let candidate: &dyn MissingEffect<T> = self.candidates().get(&id)?;
        // the play weights and the output map are judged against the model without them
        // (their joint F test)
        let joint = matches!(
            part,
            Part::Effect(Effect::PrandtlIshlinskii) | Part::OutputMap
        );
        let (reduced_mse, reduced_k) = if joint {
            if reduced.is_none() {
                *reduced = refit_without(model, part, train, observer).ok();
            }
            let r = reduced.as_ref()?;
            (training_mse(r, train), free_parameters(r))
        } else {
            (f64::NAN, free_parameters(model))
        };
        let view = view_of(model, reduced_mse, reduced_k, estimate, train);
        candidate.null_parameters(&view, train)
    }

    /// The parts of `model` to check, in order: the output map, then the input effects (the
    /// dynamic hysteresis first, then the UDN's in their canonical order).
    fn parts_of(model: &HammersteinModel<T>) -> Vec<Part> {
        let mut parts = Vec::new();
        if model.output_map().is_some() {
            parts.push(Part::OutputMap);
        }
        if let Some(set) = effects_of(model) {
            if set.contains(Effect::PrandtlIshlinskii) {
                parts.push(Part::Effect(Effect::PrandtlIshlinskii));
            }
            parts.extend(
                Effect::ALL
                    .iter()
                    .filter(|e| set.contains(**e))
                    .map(|&e| Part::Effect(e)),
            );
        }
        parts
    }

    /// `model` refitted without the play weights against its gain (the plays of the sign of p
    /// kept, on the same grid: `PrandtlIshlinskii::on_subset` of the model's UDN), with the
    /// sentence that says so; `None` when it has no plays, none is against the gain, every one
    /// is (then the null-value rule drops the operator) or the refit fails.
    fn one_sign_of(
        model: &HammersteinModel<T>,
        train: &IoData<T>,
        observer: Option<&dyn Observer>,
    ) -> Option<(HammersteinModel<T>, String)> {
        use crate::diagnosis::candidates::pi_one_sign::{play_weights, required_sign};
        let sign = required_sign(model);
        let weights = play_weights(model);
        let (kept, wrong): (Vec<_>, Vec<_>) = weights.iter().partition(|&&(_, w)| sign * w >= 0.0);
        if wrong.is_empty() || kept.is_empty() {
            return None;
        }
        let kept: Vec<usize> = kept.iter().map(|&&(j, _)| j).collect();
        let udn = settings_without(model, Part::Effect(Effect::PrandtlIshlinskii)).ok()?;
        let nl = crate::regressors::PrandtlIshlinskii::on_subset(
            udn.build_nonlinearity().ok()?,
            crate::regressors::DEFAULT_PLAYS,
            &kept,
        )
        .ok()?;
        let s = model.settings();
        let mut h = Hammerstein::new(Box::new(nl));
        if let Some(m) = s.user_method() {
            h = h.subspace_method(m.clone());
        }
        if let Some(la) = s.user_linalg() {
            h = h.linalg(la.clone());
        }
        let settings = h
            .output_nonlinearity(s.output_map().map(|m| m.clone_box()))
            .with_options(s.options().clone())
            .at_structure_of(model);
        let refit = refit_as(&settings, model, train, observer).ok()?;
        let shown: Vec<String> = wrong
            .iter()
            .map(|&&(j, w)| format!("w{j} = {}", readable(w)))
            .collect();
        Some((
            refit,
            format!(
                "- plays against the gain: play weights of the sign opposite to p ({}) removed: \
                 no physical hysteresis loop has them",
                shown.join(", ")
            ),
        ))
    }

    /// The final check of the guided loop on the model it ends with, `end` (see the module):
    /// effects the input cannot identify dropped, play weights against the gain removed, null
    /// effects and a null output map dropped — each change refitted and diagnosed, returned as
    /// the steps to append (change, model, diagnosis) — and an unstable block at an order the
    /// loop raised above `start`'s said. Returns those steps and what it found, one sentence
    /// each.
    #[allow(clippy::type_complexity)]
    pub(crate) fn check_final(
        &self,
        start: &HammersteinModel<T>,
        end: &HammersteinModel<T>,
        train: &IoData<T>,
        validation: &IoData<T>,
        observer: Option<&dyn Observer>,
    ) -> Result<(
        Vec<(String, HammersteinModel<T>, Diagnosis<T>)>,
        Vec<String>,
    )> {
        let mut notes = Vec::new();
        let mut added: Vec<(String, HammersteinModel<T>, Diagnosis<T>)> = Vec::new();
        // each round removes one part at least: the rounds are bounded by the parts
        for _ in 0..8 {
            let model = added.last().map_or(end, |(_, m, _)| m);
            let parts = Self::parts_of(model);
            let has_effects = parts.iter().any(|p| matches!(p, Part::Effect(_)));
            let mut found: Option<(HammersteinModel<T>, String, String)> = None;
            if has_effects && identifiable(train, Effect::Hysteresis).is_err() {
                let reason = format!(
                    "the input takes {} levels: no static map beyond an affine one is \
                     identifiable; the input effects ({}) are dropped",
                    input_levels(train, 3),
                    model.nonlinearity().effects().join(", ")
                );
                if let Ok(m) = refit_without(model, Part::AllEffects, train, observer) {
                    found = Some((m, Part::AllEffects.label(), reason));
                }
            }
            if found.is_none()
                && let Some((m, reason)) = Self::one_sign_of(model, train, observer)
            {
                found = Some((m, "- plays against the gain".into(), reason));
            }
            if found.is_none() {
                for part in parts {
                    let mut reduced = None;
                    let Some(reason) = self.null_part(model, part, train, observer, &mut reduced)
                    else {
                        continue;
                    };
                    let refit = match reduced {
                        Some(r) => Ok(r),
                        None => refit_without(model, part, train, observer),
                    };
                    if let Ok(m) = refit {
                        found = Some((m, part.label(), format!("{}: {reason}", part.label())));
                        break;
                    }
                }
            }
            let Some((m, label, reason)) = found else {
                break;
            };
            let diagnosis = self.run(&m, train, validation, observer)?;
            notes.push(reason);
            added.push((label, m, diagnosis));
        }
        let last = added.last().map_or(end, |(_, m, _)| m);
        notes.extend(unmeasured_limits(last, train));
        let (n0, n) = (start.linear().order(), last.linear().order());
        let rho = last.linear().spectral_radius().unwrap_or(f64::NAN);
        if n > n0 && rho > 1.0 {
            notes.push(format!(
                "order {n} is not supported by the record ({} training samples): the block the \
                 loop raised from order {n0} is unstable (spectral radius {}), its added states \
                 fit the training record, not a system that settles",
                train.len(),
                format_args!("{rho:.6}")
            ));
        }
        Ok((added, notes))
    }
}
