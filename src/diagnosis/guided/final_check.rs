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
//! - **A saturation limit the record does not measure** ([`unmeasured`]): when fewer
//!   than [`UNMEASURED_SHARE`] of the training samples reach one of the UDN saturation's two
//!   limits, or it lies within two standard errors of the extreme of the signal it clips (the
//!   saturation's null rule, one side at a time), that limit sits at the input's extreme (the
//!   fit moves it there when the system saturates on one side only) and the model credits a
//!   parameter the record does not determine. The model is refitted with that limit dropped (a one-sided saturation,
//!   [`SaturationSides`]: from the model with the limit removed and from the default start, the
//!   lower training MSE kept), and the one-sided model is kept unless the limit lowers the
//!   training error distinguishably: the F test of the one dropped parameter (the two-sided
//!   model against the one-sided it nests, the limit at ±∞), at the level [`JOINT_LEVEL`] the
//!   play weights' joint test uses. Kept or not, the note says the limit, how many samples reach
//!   it, both training MSEs and the test.
//! - **An order the record does not support** ([`unsupported_order`]): an order raise whose
//!   refit's block is unstable is not taken, and said (states that leave the unit circle fit
//!   the training record, not a system that settles); the model keeps the order it had. A
//!   final block that is still unstable at an order the loop raised is said as well.

use crate::data::IoData;
use crate::diagnosis::candidates::candidate::{MissingEffect, Refit, readable};
use crate::diagnosis::candidates::estimate::{Estimate, Estimates, Quantity};
use crate::diagnosis::candidates::identifiability::{identifiable, input_levels};
use crate::diagnosis::candidates::pi_candidate::{JOINT_LEVEL, joint_p_value};
use crate::diagnosis::diagnoser::diagnose::Diagnoser;
use crate::diagnosis::diagnoser::outcome::Diagnosis;
use crate::diagnosis::ids::CandidateId;
use crate::error::{Error, Result};
use crate::fit::order_selection::{free_parameters, training_mse};
use crate::fit::{Hammerstein, HammersteinModel, Observer};
use crate::real::Real;
use crate::regressors::{
    DEFAULT_PLAYS, Effect, EffectSet, NonlinearitySpec, PrandtlIshlinskii, SaturationSides,
    StaticNonlinearity, Udn, from_spec,
};

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
/// record ([`unmeasured`]): 1 %, the tail the zone guard leaves outside the limits' range.
pub const UNMEASURED_SHARE: f64 = 0.01;

/// A saturation limit the training record does not measure: fewer than [`UNMEASURED_SHARE`] of
/// its samples reach it, or it is not clearly inside their range (within two standard errors of
/// the extreme of the signal it clips: the saturation's null rule, one side at a time).
#[derive(Debug, Clone)]
struct Unmeasured {
    /// "upper" or "lower".
    side: &'static str,
    /// Its parameter, "z1" or "z2".
    name: &'static str,
    /// Its value and standard error (`None`: not estimated).
    value: f64,
    se: Option<f64>,
    /// How many training samples reach it, of `n`.
    reached: usize,
    n: usize,
    /// The input's extreme on its side ("maximum" or "minimum") and its value.
    extreme: &'static str,
    at: f64,
    /// The limits the saturation keeps without it.
    keep: SaturationSides,
}

impl Unmeasured {
    /// "the saturation's lower limit z2 = … is reached by k of N training samples (the input's
    /// minimum …): the record does not measure it".
    fn text(&self) -> String {
        format!("the saturation's {} limit {}", self.side, self.reach())
    }

    /// "z2 = … ± … is reached by k of N training samples (the input's minimum …): the record
    /// does not measure it".
    fn reach(&self) -> String {
        let se = match self.se {
            Some(se) if se.is_finite() => format!(" ± {}", readable(se)),
            Some(_) => " (not determined by the record)".into(),
            None => String::new(),
        };
        let why = if (self.reached as f64) < UNMEASURED_SHARE * self.n as f64 {
            ""
        } else {
            ", within two standard errors of the extreme of the signal it clips"
        };
        format!(
            "{} = {}{se} is reached by {} of {} training samples (the input's {} {}){why}: \
             the record does not measure it",
            self.name,
            readable(self.value),
            self.reached,
            self.n,
            self.extreme,
            readable(self.at)
        )
    }
}

/// The saturation limits of `model` the training record does not measure ([`Unmeasured`]),
/// fewest samples reaching them first (none without a saturation, or with a hysteresis, whose
/// branch variable is not the input; a one-sided saturation's absent limit is no parameter and
/// never listed). A sample reaches the upper limit z1 when its dead-zone output
/// w = sign(u)·max(|u| − b, 0) exceeds it, the lower limit z2 when w is below it: one pass over
/// the record per limit; a limit within two standard errors of w's extreme on its side (or
/// with an undetermined error) is not clearly inside the range either. A one-sided saturation
/// has nothing listed: its null rule judges it whole.
fn unmeasured<T: Real>(model: &HammersteinModel<T>, train: &IoData<T>) -> Vec<Unmeasured> {
    let Some(set) = effects_of(model) else {
        return Vec::new();
    };
    if !set.contains(Effect::Saturation) || set.contains(Effect::Hysteresis) {
        return Vec::new();
    }
    let p: std::collections::HashMap<String, (f64, Option<f64>)> = model
        .parameters_with_errors()
        .into_iter()
        .map(|(k, v, se)| (k, (v, se)))
        .collect();
    let b = p.get("b").map_or(0.0, |x| x.0);
    let u: Vec<f64> = train.input(0).iter().map(|u| u.as_f64()).collect();
    let w: Vec<f64> = u
        .iter()
        .map(|u| u.signum() * (u.abs() - b).max(0.0))
        .collect();
    let n = w.len();
    let extremes = |x: &[f64]| {
        x.iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), &x| {
                (l.min(x), h.max(x))
            })
    };
    let ((lo, hi), (w_lo, w_hi)) = (extremes(&u), extremes(&w));
    // a one-sided saturation is judged whole by the saturation's null rule
    if !(p.contains_key("z1") && p.contains_key("z2")) {
        return Vec::new();
    }
    let mut out: Vec<Unmeasured> = Vec::new();
    if let Some(&(z1, se)) = p.get("z1") {
        out.push(Unmeasured {
            side: "upper",
            name: "z1",
            value: z1,
            se,
            reached: w.iter().filter(|&&x| x > z1).count(),
            n,
            extreme: "maximum",
            at: hi,
            keep: SaturationSides::Lower,
        });
    }
    if let Some(&(z2, se)) = p.get("z2") {
        out.push(Unmeasured {
            side: "lower",
            name: "z2",
            value: z2,
            se,
            reached: w.iter().filter(|&&x| x < z2).count(),
            n,
            extreme: "minimum",
            at: lo,
            keep: SaturationSides::Upper,
        });
    }
    out.retain(|l| {
        let inside = match l.se {
            Some(se) if !se.is_finite() => false,
            Some(se) if l.name == "z1" => l.value + 2.0 * se < w_hi,
            Some(se) => l.value - 2.0 * se > w_lo,
            None => true,
        };
        (l.reached as f64) < UNMEASURED_SHARE * n as f64 || !inside
    });
    out.sort_by_key(|l| l.reached);
    out
}

/// `spec` (a UDN's, or a Prandtl–Ishlinskii operator's around one) with the saturation's
/// limits `keep` only: the UDN's `saturation_sides` set and the parameter `dropped` removed
/// from the UDN's and the wrapper's lists. `None` for any other kind or without that parameter.
fn one_sided_spec(
    spec: &NonlinearitySpec,
    keep: SaturationSides,
    dropped: &str,
) -> Option<NonlinearitySpec> {
    let mut out = spec.clone();
    match spec.kind.as_str() {
        "udn" => out.config["saturation_sides"] = keep.name().into(),
        "prandtl-ishlinskii" => {
            let base: NonlinearitySpec =
                serde_json::from_value(spec.config.get("base")?.clone()).ok()?;
            out.config["base"] =
                serde_json::to_value(one_sided_spec(&base, keep, dropped)?).ok()?;
        }
        _ => return None,
    }
    let i = out.param_names.iter().position(|n| n == dropped)?;
    out.param_names.remove(i);
    out.params.remove(i);
    Some(out)
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
    // a one-sided saturation stays one-sided
    let sides = SaturationSides::of_spec(&model.nonlinearity().spec());
    let mut h = if set.contains(Effect::Saturation) && sides != SaturationSides::Both {
        let udn = Udn::<T>::new(set.udn_part()).with_saturation_sides(sides)?;
        if set.contains(Effect::PrandtlIshlinskii) {
            Hammerstein::new(Box::new(PrandtlIshlinskii::new(
                Box::new(udn),
                DEFAULT_PLAYS,
            )?))
        } else {
            Hammerstein::new(Box::new(udn))
        }
    } else {
        Hammerstein::udn(set)
    };
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

/// `model`'s settings with the nonlinearity `nl` instead of its own, at its order and
/// feed-through (its options, subspace method, backend and output map kept).
fn settings_with<T: Real>(
    model: &HammersteinModel<T>,
    nl: Box<dyn StaticNonlinearity<T>>,
) -> Hammerstein<T> {
    let s = model.settings();
    let mut h = Hammerstein::new(nl);
    if let Some(m) = s.user_method() {
        h = h.subspace_method(m.clone());
    }
    if let Some(la) = s.user_linalg() {
        h = h.linalg(la.clone());
    }
    h.output_nonlinearity(s.output_map().map(|m| m.clone_box()))
        .with_options(s.options().clone())
        .at_structure_of(model)
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
        let refit = refit_as(&settings_with(model, Box::new(nl)), model, train, observer).ok()?;
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

    /// `model` with the least reached saturation limit the record does not measure dropped
    /// ([`unmeasured`]; the others are said and kept): refitted with the other
    /// limit only ([`one_sided_spec`]; [`refit_as`]: from `model` with the limit removed and from
    /// the default start, the lower training MSE kept) and kept unless the two-sided model is
    /// better on training by the F test of the one dropped parameter (p < [`JOINT_LEVEL`]:
    /// F = (MSE₁ − MSE₂) / (MSE₂ / (N − 1)), MSE₁ the one-sided, MSE₂ the two-sided training
    /// MSE; [`joint_p_value`]). Returns the one-sided model with its step's label when kept, and
    /// the sentences to add (the limit, the training MSEs before and after, the test); nothing
    /// without such a limit.
    fn drop_unmeasured_limit(
        model: &HammersteinModel<T>,
        train: &IoData<T>,
        observer: Option<&dyn Observer>,
    ) -> (Option<(String, HammersteinModel<T>)>, Vec<String>) {
        let limits = unmeasured(model, train);
        let Some(l) = limits.first() else {
            return (None, Vec::new());
        };
        let others: Vec<String> = limits[1..]
            .iter()
            .map(|o| format!("{}, kept", o.text()))
            .collect();
        let keep = l.keep.name();
        let refit = one_sided_spec(&model.nonlinearity().spec(), l.keep, l.name)
            .ok_or_else(|| Error::Identification("not a UDN saturation".into()))
            .and_then(|spec| from_spec::<T>(&spec))
            .and_then(|nl| refit_as(&settings_with(model, nl), model, train, observer));
        let one = match refit {
            Ok(m) => m,
            Err(e) => {
                let mut notes = vec![format!(
                    "{}; its refit with the {keep} limit only failed ({e}): the limit is kept",
                    l.text()
                )];
                notes.extend(others);
                return (None, notes);
            }
        };
        let (two_mse, one_mse) = (training_mse(model, train), training_mse(&one, train));
        let view = view_of(
            model,
            one_mse,
            free_parameters(&one),
            Estimates::new(),
            train,
        );
        let p = joint_p_value(&view, train.len(), 1);
        let mses = format!(
            "training MSE {two_mse:.6e} with both limits, {one_mse:.6e} with the {keep} limit \
             only, F test of {} p = {}",
            l.name,
            readable(p)
        );
        let mut notes = if p.is_nan() || p >= JOINT_LEVEL {
            vec![format!(
                "- saturation's {} limit: {}; dropped, the saturation acts on the {keep} side \
                 only ({mses})",
                l.side,
                l.reach()
            )]
        } else {
            vec![format!(
                "{}, but the samples that reach it lower the training error distinguishably \
                 ({mses}): both limits are kept",
                l.text()
            )]
        };
        notes.extend(others);
        let label = format!("- saturation's {} limit", l.side);
        (
            (p.is_nan() || p >= JOINT_LEVEL).then_some((label, one)),
            notes,
        )
    }

    /// The final check of the guided loop on the model it ends with, `end` (see the module):
    /// effects the input cannot identify dropped, play weights against the gain removed, null
    /// effects and a null output map dropped, a saturation limit the record does not measure
    /// dropped when the F test does not keep it — each change refitted and diagnosed, returned
    /// as the steps to append (change, model, diagnosis) — and an unstable block at an order the
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
        let mut limits_done = false;
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
            // a saturation limit the record does not measure, once no other part is null (the
            // one-sided model is checked again in the next round)
            if found.is_none() && !limits_done {
                let (one, said) = Self::drop_unmeasured_limit(model, train, observer);
                let mut said = said.into_iter();
                match one {
                    Some((label, m)) => {
                        let reason = said.next().unwrap_or_default();
                        notes.extend(said);
                        found = Some((m, label, reason));
                    }
                    None => {
                        notes.extend(said);
                        limits_done = true;
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
