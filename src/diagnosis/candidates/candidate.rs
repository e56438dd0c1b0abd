//! Missing-effect candidates: the [`MissingEffect`] trait a user can implement, the evidence a
//! candidate reads from the residual analysis, and the built-in candidates (hysteresis, dead-zone,
//! saturation, preload, dynamics, delay, output-nonlinearity).

use super::estimate::{Estimate, Estimates, Quantity};
use crate::data::IoData;
use crate::diagnosis::compare::{Comparison, compare_metrics};
use crate::diagnosis::ids::{CandidateId, TestId};
use crate::diagnosis::residual_tests::analysis::ResidualAnalysis;
use crate::diagnosis::residual_tests::checks::TestResult;
use crate::error::{Error, Result};
use crate::fit::{Hammerstein, HammersteinModel, Observer};
use crate::real::Real;
use crate::regressors::Effect;
use crate::subspace::Order;
use std::collections::BTreeMap;

/// What the residual analysis says about one candidate.
#[derive(Debug, Clone, serde::Serialize)]
pub struct Evidence {
    /// The test the evidence comes from.
    pub test: TestId,
    /// p-value of that test alone.
    pub p_value: f64,
    /// p-value after the multiple-testing correction.
    pub p_adjusted: f64,
    /// True when significant after the correction.
    pub significant: bool,
    /// One sentence with the numbers.
    pub sentence: String,
    /// Size estimates read from the residual (input units unless named otherwise; their
    /// source is [`Source::Residual`](super::estimate::Source::Residual)).
    pub estimate: Estimates,
}

impl Evidence {
    /// Evidence from a test result, with a sentence and size estimates (marked as read from the
    /// residual, whatever their source said).
    pub fn from_test(t: &TestResult, sentence: String, estimate: Estimates) -> Self {
        Self {
            test: t.name.clone(),
            p_value: t.p_value,
            p_adjusted: t.p_adjusted,
            significant: t.significant,
            sentence,
            estimate: estimate
                .into_iter()
                .map(|e| Estimate::residual(e.quantity, e.value))
                .collect(),
        }
    }
}

/// Everything a candidate's refit may use.
pub struct RefitContext<'a, T: Real> {
    /// The fitted model under diagnosis (its settings are `model.settings()`).
    pub model: &'a HammersteinModel<T>,
    /// Estimation data.
    pub train: &'a IoData<T>,
    /// Validation data.
    pub validation: &'a IoData<T>,
    /// The model's comparison on the validation data.
    pub validation_comparison: &'a Comparison,
    /// The residual analysis (training data).
    pub analysis: &'a ResidualAnalysis,
    /// The current model's training MSE as the selection criterion sees it (initial conditions
    /// estimated, [`crate::fit::order_selection::training_mse`]).
    pub train_mse: f64,
    /// The observer the diagnosis was run with ([`Diagnoser::diagnose_observed`]), which the
    /// refits notify; `None`: nobody watches.
    ///
    /// [`Diagnoser::diagnose_observed`]: crate::diagnosis::Diagnoser::diagnose_observed
    pub observer: Option<&'a dyn Observer>,
}

impl<T: Real> RefitContext<'_, T> {
    /// Fits `settings` on the training record, the diagnosis' observer (if any) notified: the
    /// refit of a candidate.
    pub fn fit(&self, settings: &Hammerstein<T>) -> Result<HammersteinModel<T>> {
        match self.observer {
            Some(o) => settings.fit_observed(self.train, o),
            None => settings.fit(self.train),
        }
    }
}

/// The outcome of refitting with a candidate added.
#[derive(Debug, Clone, serde::Serialize)]
#[serde(bound = "")]
pub struct Refit<T: Real = f64> {
    /// Training MSE of the refitted model (the selection criterion's view: initial conditions
    /// estimated).
    pub train_mse: f64,
    /// Training MSE the improvement is measured against (the current model's, unless a candidate
    /// needs a fairer reference, e.g. an affine output map for the output nonlinearity).
    pub reference_train_mse: f64,
    /// Free parameters the candidate adds to the reference (the k of the criterion).
    pub added_parameters: i64,
    /// Initial states among them (the criterion charges them less: [`crate::fit::order_selection::penalty`]).
    pub added_states: i64,
    /// Validation MSE of the refitted model (reported, not used to select).
    pub validation_mse: f64,
    /// Validation MSE of the reference (reported).
    pub reference_mse: f64,
    /// What changed ("order 2 → 3", "effects linear → hysteresis").
    pub change: String,
    /// Size estimates from the refitted model's parameters, with their standard errors when
    /// the fit computed them (serialised as the maps `estimate` and `standard_errors`).
    #[serde(flatten, serialize_with = "super::estimate::values_and_errors")]
    pub estimate: Estimates,
    /// Why the candidate's own parameters do not credit the effect (`None`: they do) — at their
    /// null value, or physically implausible: such a candidate is not suggested, whatever its MSE.
    pub null_parameters: Option<String>,
    /// The refitted model (kept, so that following the suggestion does not fit it again);
    /// `None` for candidates that change something outside the model (an output map).
    #[serde(skip)]
    pub model: Option<HammersteinModel<T>>,
}

impl<T: Real> Refit<T> {
    /// The refit of `ctx.model` into `refit`: its training and validation MSEs, the parameters it
    /// adds, the estimates `names` with their standard errors.
    pub fn of_model(
        ctx: &RefitContext<'_, T>,
        refit: HammersteinModel<T>,
        names: &[&str],
    ) -> Result<Self> {
        use crate::fit::order_selection::{free_parameters, training_mse};
        // the metrics alone: no copies of the record's series
        let validation_mse = compare_metrics(&refit, ctx.validation)?.mse;
        let k = |m: &HammersteinModel<T>| (free_parameters(m) + m.delay()) as i64;
        let estimate = Estimates::of_parameters(&refit, names);
        Ok(Self {
            train_mse: training_mse(&refit, ctx.train),
            reference_train_mse: ctx.train_mse,
            added_parameters: k(&refit) - k(ctx.model),
            added_states: refit.linear().order() as i64 - ctx.model.linear().order() as i64,
            validation_mse,
            reference_mse: ctx.validation_comparison.metrics.mse,
            change: change_text(ctx.model, &refit),
            estimate,
            null_parameters: None,
            model: Some(refit),
        })
    }
}

/// A physical effect (or linear deficit) a model may be missing: reads its evidence from the
/// residual analysis and refits the model with the effect added.
///
/// Register your own with [`crate::diagnosis::Registry::register`]; it is then tried and ranked
/// like the built-ins.
pub trait MissingEffect<T: Real>: Send + Sync {
    /// Which effect (a user's: [`CandidateId::user`]`(name)`); the registry's key and the name
    /// shown to the user.
    fn id(&self) -> CandidateId;
    /// False when the model already has the effect (no refit is tried).
    fn applies_to(&self, _model: &HammersteinModel<T>) -> bool {
        true
    }
    /// The evidence for this effect in the residuals (`None`: the candidate has no test of its own).
    fn evidence(&self, analysis: &ResidualAnalysis) -> Option<Evidence>;
    /// Settings with the effect added.
    fn apply(
        &self,
        model: &HammersteinModel<T>,
        analysis: &ResidualAnalysis,
    ) -> Result<Hammerstein<T>>;
    /// Refits with the effect added and measures the training and validation MSEs (default:
    /// [`apply`](Self::apply), fit on the training data, the estimates of
    /// [`refit_estimate`](Self::refit_estimate)).
    fn refit(&self, ctx: &RefitContext<'_, T>) -> Result<Refit<T>> {
        let settings = self.apply(ctx.model, ctx.analysis)?;
        let refit = ctx.fit(&settings)?;
        let estimate = self.refit_estimate(&refit);
        let mut r = Refit::of_model(ctx, refit, &[])?;
        r.estimate = estimate;
        Ok(r)
    }
    /// The size estimates to quote from a refitted model (default: none; usually
    /// [`Estimates::of_parameters`] of the effect's parameters).
    fn refit_estimate(&self, _model: &HammersteinModel<T>) -> Estimates {
        Estimates::new()
    }
    /// Why the refitted model's parameters for this effect are at their null value (the effect
    /// then explains nothing and is not suggested); `None` when they are not, or when the
    /// candidate has no such parameters (default).
    fn null_parameters(&self, _refit: &Refit<T>, _train: &IoData<T>) -> Option<String> {
        None
    }
}

fn change_text<T: Real>(before: &HammersteinModel<T>, after: &HammersteinModel<T>) -> String {
    let eb = before.nonlinearity().effects().join(",");
    let ea = after.nonlinearity().effects().join(",");
    let (nb, na) = (before.linear().order(), after.linear().order());
    let mut parts = Vec::new();
    if eb != ea {
        let f = |s: String| {
            if s.is_empty() {
                "linear".to_string()
            } else {
                s
            }
        };
        parts.push(format!("effects {} → {}", f(eb), f(ea)));
    }
    if nb != na {
        parts.push(format!("order {nb} → {na}"));
    }
    if parts.is_empty() {
        "same structure".into()
    } else {
        parts.join("; ")
    }
}

fn p_text(p: f64) -> String {
    if p < 1e-4 {
        format!("p = {p:.1e}")
    } else {
        format!("p = {p:.4}")
    }
}

fn stat_text(t: &TestResult) -> String {
    if t.df.len() == 2 {
        format!(
            "F({}, {}) = {:.1}, {}",
            t.df[0],
            t.df[1],
            t.statistic,
            p_text(t.p_value)
        )
    } else {
        format!(
            "{} = {:.2}, {}",
            t.statistic_name,
            t.statistic,
            p_text(t.p_value)
        )
    }
}

/// True when the model's nonlinearity already has this effect.
fn has_effect<T: Real>(model: &HammersteinModel<T>, e: Effect) -> bool {
    model.nonlinearity().effects().iter().any(|s| s == e.name())
}

/// One of the four UDN effects, added with `settings.with_effect(e)`.
#[derive(Debug, Clone, Copy)]
pub struct UdnEffect(pub Effect);

impl<T: Real> MissingEffect<T> for UdnEffect {
    fn id(&self) -> CandidateId {
        CandidateId::Effect(self.0)
    }
    fn applies_to(&self, model: &HammersteinModel<T>) -> bool {
        !has_effect(model, self.0) && model.settings().with_effect(self.0).is_ok()
    }
    fn evidence(&self, a: &ResidualAnalysis) -> Option<Evidence> {
        match self.0 {
            Effect::Hysteresis => {
                let t = a.test(TestId::InputDirection)?;
                let w = a.hysteresis_half_width();
                Some(Evidence::from_test(
                    t,
                    format!(
                        "at equal input level, rising and falling samples leave different residuals \
                         (input-referred falling − rising gap {}; {}): hysteresis half-width ≈ {}",
                        readable(-2.0 * mean(&t.coefficients)),
                        stat_text(t),
                        width(w)
                    ),
                    Estimates::residual([(Quantity::HalfWidth, w)]),
                ))
            }
            Effect::Saturation => {
                let t = a.test(TestId::InputExtremes)?;
                let (hi, lo) = a.saturation_levels();
                Some(Evidence::from_test(
                    t,
                    format!(
                        "beyond the input's extreme deciles the response flattens (extra slope {} above, \
                         {} below, model gain {}; {}): saturation from u ≈ {} and u ≈ {}",
                        readable(t.coefficients.first().copied().unwrap_or(f64::NAN)),
                        readable(-t.coefficients.get(1).copied().unwrap_or(f64::NAN)),
                        readable(a.gain),
                        stat_text(t),
                        readable(hi.unwrap_or(f64::NAN)),
                        readable(lo.unwrap_or(f64::NAN))
                    ),
                    Estimates::residual([(Quantity::UpperInput, hi), (Quantity::LowerInput, lo)]),
                ))
            }
            Effect::DeadZone => {
                let t = a.test(TestId::InputNearZero)?;
                let w = a.dead_zone_width();
                Some(Evidence::from_test(
                    t,
                    format!(
                        "for small |u| the response is weaker than the model's (extra slope {} against \
                         gain {}; {}): dead-zone half-width ≈ {}",
                        readable(t.coefficients.first().copied().unwrap_or(f64::NAN)),
                        readable(a.gain),
                        stat_text(t),
                        width(w)
                    ),
                    Estimates::residual([(Quantity::HalfWidth, w)]),
                ))
            }
            Effect::Preload => {
                let t = a.test(TestId::InputZeroStep)?;
                let e = a.preload_step();
                Some(Evidence::from_test(
                    t,
                    format!(
                        "the residual steps across u = 0 (input-referred step ±{}; {}): preload ≈ {}",
                        readable(e.unwrap_or(f64::NAN).abs()),
                        stat_text(t),
                        readable(e.unwrap_or(f64::NAN))
                    ),
                    Estimates::residual([(Quantity::Step, e)]),
                ))
            }
            // its own candidate (`PrandtlIshlinskiiCandidate`) reads its own signature
            Effect::PrandtlIshlinskii => None,
        }
    }
    /// The model's settings with the effect added and the model's order and feed-through kept (adding a static
    /// effect does not change the dynamics; re-selecting the order after adding one collapsed
    /// real fits, e.g. an MR-damper sine test from 74.9 % to −67 % validation fit).
    fn apply(&self, model: &HammersteinModel<T>, _a: &ResidualAnalysis) -> Result<Hammerstein<T>> {
        Ok(Hammerstein::at_structure_of(
            model.settings().with_effect(self.0)?,
            model,
        ))
    }
    /// Refits with the effect added at the model's order, from two starts: the default one
    /// (quantiles) and the current model with the new effect at its null value
    /// ([`Hammerstein::fit_from`]: its poles and parameters, then the refinement — so that the
    /// refit is not worse than the model it extends merely because the default start led
    /// elsewhere); the lower training MSE is kept.
    fn refit(&self, ctx: &RefitContext<'_, T>) -> Result<Refit<T>> {
        // an input of two levels identifies no static map beyond an affine one
        super::identifiability::identifiable(ctx.train, self.0)?;
        let settings = self.apply(ctx.model, ctx.analysis)?;
        let scratch = ctx
            .fit(&settings)
            .and_then(|m| Refit::of_model(ctx, m, udn_names(self.0)));
        // the nested start at the null value, and at the size the residuals suggest (a start
        // at a = 0 or b = 0 sits on the boundary where the refinement's step may not leave it)
        let a = ctx.analysis;
        let guess = match self.0 {
            Effect::Hysteresis => a.hysteresis_half_width().map(|w| vec![("a", w)]),
            Effect::DeadZone => a.dead_zone_width().map(|w| vec![("b", w)]),
            Effect::Preload => a
                .preload_step()
                .map(|e| vec![("e1", e.abs()), ("e2", -e.abs())]),
            Effect::Saturation => match a.saturation_levels() {
                (Some(hi), Some(lo)) => Some(vec![("z1", hi), ("z2", lo)]),
                _ => None,
            },
            Effect::PrandtlIshlinskii => None,
        };
        // a saturation's limits at the input's extremes clip no sample: that start is the
        // model itself, so the refit cannot end above it (the percentiles' start clips 2 %)
        let extremes = (self.0 == Effect::Saturation)
            .then(|| super::identifiability::input_extremes(ctx.train))
            .flatten()
            .map(|(lo, hi)| vec![("z1", hi), ("z2", lo)]);
        let starts = [Some(Vec::new()), guess, extremes];
        let nested = starts
            .iter()
            .flatten()
            .filter_map(|at| nested_start(ctx.model, ctx.train, self.0, at))
            .filter_map(|theta| {
                let m = settings.fit_from(ctx.train, ctx.model, &theta).ok()?;
                Refit::of_model(ctx, m, udn_names(self.0)).ok()
            })
            .min_by(|x, y| x.train_mse.total_cmp(&y.train_mse));
        better(
            scratch,
            nested.ok_or_else(|| Error::Identification("no nested start".into())),
        )
    }
    fn refit_estimate(&self, model: &HammersteinModel<T>) -> Estimates {
        Estimates::of_parameters(model, udn_names(self.0))
    }
    /// Null values: a hysteresis or dead-zone half-width, or the preload's jump at u = 0
    /// (e1 − e2, its standard error with the nonlinearity's scale held), within two standard
    /// errors of 0; both saturation limits not clearly inside the training input's range
    /// (z1 + 2σ ≥ max u and z2 − 2σ ≤ min u: the saturation never acts).
    fn null_parameters(&self, refit: &Refit<T>, train: &IoData<T>) -> Option<String> {
        let at = |name: &str| -> Option<(f64, f64)> {
            let e = refit.estimate.parameter(name)?;
            let (v, se) = (e.value, e.standard_error.unwrap_or(0.0));
            Some((v, if se.is_nan() { f64::INFINITY } else { se }))
        };
        let near_zero = |name: &str| at(name).is_some_and(|(v, se)| v.abs() <= 2.0 * se);
        let show = |name: &str| {
            at(name).map_or(String::new(), |(v, se)| {
                format!("{name} = {}", estimate_text(v, se))
            })
        };
        match self.0 {
            Effect::Hysteresis | Effect::DeadZone => {
                let name = udn_names(self.0)[0];
                near_zero(name).then(|| format!("{} is not distinguishable from 0", show(name)))
            }
            Effect::Preload => match preload_jump(refit) {
                Some((jump, se)) => (jump.abs() <= 2.0 * se).then(|| {
                    format!(
                        "the jump at u = 0, e1 − e2 = {} ({} and {}), is not distinguishable \
                         from 0",
                        estimate_text(jump, se),
                        show("e1"),
                        show("e2")
                    )
                }),
                // no covariance (a model assembled by hand): each step against 0
                None => (near_zero("e1") && near_zero("e2")).then(|| {
                    format!(
                        "{} and {} are not distinguishable from 0",
                        show("e1"),
                        show("e2")
                    )
                }),
            },
            Effect::Saturation => {
                let u = train.input(0);
                let hi = u
                    .iter()
                    .map(|x| x.as_f64())
                    .fold(f64::NEG_INFINITY, f64::max);
                let lo = u.iter().map(|x| x.as_f64()).fold(f64::INFINITY, f64::min);
                // a one-sided saturation's absent limit is at ±∞, beyond the input
                let (z1, s1) = at("z1").unwrap_or((f64::INFINITY, 0.0));
                let (z2, s2) = at("z2").unwrap_or((f64::NEG_INFINITY, 0.0));
                if z1.is_infinite() && z2.is_infinite() {
                    return None;
                }
                (z1 + 2.0 * s1 >= hi && z2 - 2.0 * s2 <= lo).then(|| {
                    let shown: Vec<String> = ["z1", "z2"]
                        .iter()
                        .filter(|n| at(n).is_some())
                        .map(|n| show(n))
                        .collect();
                    format!(
                        "the {} {} not clearly inside the input's range [{}, {}]: the \
                         saturation never acts",
                        if shown.len() == 1 { "limit" } else { "limits" },
                        if shown.len() == 1 {
                            format!("{} is", shown[0])
                        } else {
                            format!("{} are", shown.join(" and "))
                        },
                        readable(lo),
                        readable(hi)
                    )
                })
            }
            Effect::PrandtlIshlinskii => None,
        }
    }
}

/// "v ± se", or "v (not determined by the record)" when the standard error is infinite.
fn estimate_text(v: f64, se: f64) -> String {
    if se.is_finite() {
        format!("{} ± {}", readable(v), readable(se))
    } else {
        format!("{} (not determined by the record)", readable(v))
    }
}

/// A preload refit's jump at u = 0, e1 − e2, with its standard error from the refitted model's
/// parameter covariance (`None` without one). The jump, not each step, is the preload: the
/// steps' common part is a constant added to v, which a slow branch's free response or the
/// output offset nearly reproduces, so e1 and e2 can each be undetermined (strongly correlated)
/// while their difference is well determined — testing each against 0 rejected real preloads.
/// The error is taken with the nonlinearity's scale held (its gains p, e1, e2 along their
/// estimate, which the linear block can compensate): the question "is there a jump?" does not
/// depend on the scale, and when the block's gain is poorly determined the scale's uncertainty
/// (p, e1 and e2 then each ≈ 2 standard errors from 0) swamped a jump that lowered the
/// training MSE by 21 % (several-input battery, seed 73).
fn preload_jump<T: Real>(refit: &Refit<T>) -> Option<(f64, f64)> {
    let e = |name: &str| refit.estimate.parameter(name).map(|x| x.value);
    let (e1, e2) = (e("e1")?, e("e2")?);
    let m = refit.model.as_ref()?;
    let p = m
        .parameters()
        .into_iter()
        .find(|(n, _)| n == "p")
        .map(|x| x.1)?;
    let se = m.standard_error_given(
        &[("e1", 1.0), ("e2", -1.0)],
        &[("p", p), ("e1", e1), ("e2", e2)],
    )?;
    Some((e1 - e2, if se.is_nan() { f64::INFINITY } else { se }))
}

/// The refit with the lower training MSE of two (the default start and the nested one); the
/// first one's error when both failed.
fn better<T: Real>(a: Result<Refit<T>>, b: Result<Refit<T>>) -> Result<Refit<T>> {
    match (a, b) {
        (Ok(a), Ok(b)) => Ok(if b.train_mse < a.train_mse { b } else { a }),
        (Ok(r), Err(_)) | (Err(_), Ok(r)) => Ok(r),
        (Err(e), Err(_)) => Err(e),
    }
}

/// `settings` refitted on the training part from its default start and from the current model
/// ([`Hammerstein::fit_from`] at the model's θ: its poles and parameters, then the refinement —
/// so that the refit is not worse than the model it extends merely because the default start
/// led elsewhere), the lower training MSE kept ([`better`]).
fn from_scratch_or_nested<T: Real>(
    ctx: &RefitContext<'_, T>,
    settings: &Hammerstein<T>,
) -> Result<Refit<T>> {
    let theta: Vec<f64> = ctx.model.parameters().into_iter().map(|(_, v)| v).collect();
    let scratch = ctx.fit(settings).and_then(|m| Refit::of_model(ctx, m, &[]));
    let nested = settings
        .fit_from(ctx.train, ctx.model, &theta)
        .and_then(|m| Refit::of_model(ctx, m, &[]));
    better(scratch, nested)
}

/// The current UDN model's parameters θ extended by `effect`, its new parameters at the values
/// `at` or else at their null value (half-widths and preload steps 0, saturation limits at the
/// 2nd and 98th percentiles of the input, less the dead-zone), in the UDN's parameter order;
/// `None` when the model is not a UDN or the limits are not ordered.
fn nested_start<T: Real>(
    model: &HammersteinModel<T>,
    train: &IoData<T>,
    effect: Effect,
    at: &[(&str, f64)],
) -> Option<Vec<f64>> {
    const ORDER: [&str; 7] = ["p", "a", "b", "z1", "z2", "e1", "e2"];
    let current: BTreeMap<String, f64> = model.parameters().into_iter().collect();
    if current.keys().any(|k| !ORDER.contains(&k.as_str())) {
        return None;
    }
    let mut u: Vec<f64> = train.input(0).iter().map(|x| x.as_f64()).collect();
    u.sort_by(f64::total_cmp);
    let q = |f: f64| u.get(((u.len() - 1) as f64 * f).round() as usize).copied();
    let b = current.get("b").copied().unwrap_or(0.0);
    let (hi, lo) = (q(0.98)? - b, q(0.02)? + b);
    let new = udn_names(effect);
    let names: Vec<&str> = ORDER
        .iter()
        .copied()
        .filter(|n| current.contains_key(*n) || new.contains(n))
        .collect();
    let given = |n: &str| {
        at.iter()
            .find(|(k, v)| *k == n && v.is_finite())
            .map(|(_, v)| *v)
    };
    let theta: Vec<f64> = names
        .iter()
        .map(|&n| match (current.get(n), given(n), n) {
            (Some(v), _, _) => *v,
            (None, Some(v), _) => v,
            (None, None, "z1") => hi,
            (None, None, "z2") => lo,
            _ => 0.0,
        })
        .collect();
    let value = |x: &str| names.iter().position(|n| *n == x).map(|i| theta[i]);
    match (value("z1"), value("z2")) {
        (Some(z1), Some(z2)) if z1 <= z2 => None,
        _ => Some(theta),
    }
}

/// The UDN parameters of an effect.
fn udn_names(e: Effect) -> &'static [&'static str] {
    match e {
        Effect::Hysteresis => &["a"],
        Effect::DeadZone => &["b"],
        Effect::Saturation => &["z1", "z2"],
        Effect::Preload => &["e1", "e2"],
        Effect::PrandtlIshlinskii => &[],
    }
}

/// Linear dynamics deficit: the order is too low (refit with order + 1).
#[derive(Debug, Clone, Copy, Default)]
pub struct Dynamics;

impl<T: Real> MissingEffect<T> for Dynamics {
    fn id(&self) -> CandidateId {
        CandidateId::Dynamics
    }
    fn evidence(&self, a: &ResidualAnalysis) -> Option<Evidence> {
        let t = a.test(TestId::Dynamics)?;
        let w = a.test(TestId::Whiteness);
        Some(Evidence::from_test(
            t,
            format!(
                "a linear filter of the nonlinearity's output still explains part of the residual ({}){}",
                stat_text(t),
                w.map(|w| format!("; whiteness: {}", w.detail))
                    .unwrap_or_default()
            ),
            Estimates::new(),
        ))
    }
    fn apply(&self, model: &HammersteinModel<T>, _a: &ResidualAnalysis) -> Result<Hammerstein<T>> {
        let n = model.linear().order();
        let h = crate::fit::order_selection::candidate_horizon(
            model.settings().options().horizon,
            n + 1,
        );
        Ok(model
            .settings()
            .clone()
            .order(Order::Fixed(n + 1))
            .raise_horizon(h)
            .with_d(model.has_feedthrough()))
    }
    /// Refits at orders n + 1, n + 2, … (at most [`MAX_ORDER_JUMP`] above n, the horizon raised
    /// to 2·order when shorter) while the information criterion on the training part keeps
    /// falling, and keeps the best: a block missing two poles is not judged by the one-pole step.
    fn refit(&self, ctx: &RefitContext<'_, T>) -> Result<Refit<T>> {
        use crate::fit::order_selection::{candidate_horizon, criterion};
        let n = ctx.model.linear().order();
        let var = {
            let y = ctx.train.output(0);
            let m = y.iter().map(|v| v.as_f64()).sum::<f64>() / y.len().max(1) as f64;
            y.iter().map(|v| (v.as_f64() - m).powi(2)).sum::<f64>() / y.len().max(1) as f64
        };
        let nn = ctx.train.len();
        let mut best: Option<(f64, Refit<T>)> = None;
        let mut first_error = None;
        for k in n + 1..=n + MAX_ORDER_JUMP {
            let settings = self
                .apply(ctx.model, ctx.analysis)?
                .order(Order::Fixed(k))
                .raise_horizon(candidate_horizon(ctx.model.settings().options().horizon, k));
            // from the default start and from the current model with poles at 0 added
            let r = match from_scratch_or_nested(ctx, &settings) {
                Ok(r) => r,
                Err(e) => {
                    first_error.get_or_insert(e);
                    break;
                }
            };
            let Some(model) = r.model.as_ref() else { break };
            let crit = criterion(model, r.train_mse, nn, var);
            if best.as_ref().is_some_and(|(b, _)| crit >= *b) {
                break;
            }
            best = Some((crit, r));
        }
        let Some((_, mut r)) = best else {
            return Err(first_error.unwrap_or_else(|| {
                Error::Identification("no higher order could be fitted".into())
            }));
        };
        if let Some(m) = &r.model {
            r.estimate.insert(Estimate::refit(
                Quantity::Order,
                m.linear().order() as f64,
                None,
            ));
        }
        Ok(r)
    }
}

/// Most orders the dynamics candidate adds in one step.
pub const MAX_ORDER_JUMP: usize = 4;

/// Time delay: refit with the input delayed by the shift whose model response best explains the
/// residual.
#[derive(Debug, Clone, Copy, Default)]
pub struct Delay;

impl<T: Real> MissingEffect<T> for Delay {
    fn id(&self) -> CandidateId {
        CandidateId::Delay
    }
    fn evidence(&self, a: &ResidualAnalysis) -> Option<Evidence> {
        let t = a.test(TestId::Delay)?;
        let d = a.delay_estimate();
        let x = a.test(TestId::InputCrossCorrelation);
        Some(Evidence::from_test(
            t,
            format!(
                "the model's response shifted by {d} sample(s) explains part of the residual ({}){}",
                stat_text(t),
                x.map(|x| format!("; cross-correlation with u: {}", x.detail))
                    .unwrap_or_default()
            ),
            Estimates::residual([(Quantity::ExtraDelay, Some(d as f64))]),
        ))
    }
    fn apply(&self, model: &HammersteinModel<T>, a: &ResidualAnalysis) -> Result<Hammerstein<T>> {
        let current = model.settings().options().delay;
        Ok(model
            .settings()
            .clone()
            .delay(current + a.delay_estimate().max(1)))
    }
    /// Refits at the model's order (the horizon raised to 2·order when shorter) from the default
    /// start and from the current model's poles and parameters (nested), keeping the better.
    fn refit(&self, ctx: &RefitContext<'_, T>) -> Result<Refit<T>> {
        use crate::fit::order_selection::candidate_horizon;
        let n = ctx.model.linear().order();
        let settings = self
            .apply(ctx.model, ctx.analysis)?
            .order(Order::Fixed(n))
            .with_d(ctx.model.has_feedthrough())
            .raise_horizon(candidate_horizon(ctx.model.settings().options().horizon, n));
        let d = settings.options().delay;
        let mut r = from_scratch_or_nested(ctx, &settings)?;
        r.estimate
            .insert(Estimate::refit(Quantity::Delay, d as f64, None));
        r.change = format!("delay {} → {d}", ctx.model.settings().options().delay);
        Ok(r)
    }
}

/// Output nonlinearity: the residual follows the predicted output; the model is refitted with a
/// static output map y = g(x) after its linear block (Hammerstein–Wiener): a cubic (`poly3`) and a
/// saturation are both fitted at the model's order, the lower training MSE kept (both add two
/// parameters).
#[derive(Debug, Clone, Copy, Default)]
pub struct OutputNonlinearity;

pub use super::estimate::OUTPUT_MAP_PREFIX;

impl OutputNonlinearity {
    /// The model's settings with the output map `name` added, its order and feed-through kept.
    fn settings_with<T: Real>(model: &HammersteinModel<T>, name: &str) -> Result<Hammerstein<T>> {
        Ok(Hammerstein::at_structure_of(
            model
                .settings()
                .clone()
                .output_nonlinearity(Some(crate::regressors::output_map_from_name::<T>(name)?)),
            model,
        ))
    }
}

impl<T: Real> MissingEffect<T> for OutputNonlinearity {
    fn id(&self) -> CandidateId {
        CandidateId::OutputNonlinearity
    }
    fn applies_to(&self, model: &HammersteinModel<T>) -> bool {
        model.output_map().is_none()
    }
    fn evidence(&self, a: &ResidualAnalysis) -> Option<Evidence> {
        let t = a.test(TestId::OutputLevel)?;
        let lvl = a.test(TestId::InputLevel);
        Some(Evidence::from_test(
            t,
            format!(
                "the residual follows the predicted output ({}){}",
                stat_text(t),
                lvl.map(|l| format!("; against the input level: {}", stat_text(l)))
                    .unwrap_or_default()
            ),
            Estimates::new(),
        ))
    }
    /// The settings with a cubic output map (`poly3`) at the model's order; the refit may choose
    /// a saturation instead (see [`refit`](MissingEffect::refit)).
    fn apply(&self, model: &HammersteinModel<T>, _a: &ResidualAnalysis) -> Result<Hammerstein<T>> {
        Self::settings_with(model, "poly3")
    }
    /// Fits the model with a `poly3` and with a `saturation` output map on the training data,
    /// each from scratch and from the current model, and keeps the one with the lower training
    /// MSE (the same number of added parameters, so the lower MSE is the lower criterion).
    fn refit(&self, ctx: &RefitContext<'_, T>) -> Result<Refit<T>> {
        let mut best: Option<Refit<T>> = None;
        let mut first_error = None;
        for name in ["poly3", "saturation"] {
            // nested: the current model extended by the map, whose training MSE cannot end
            // above the model's
            let refit = Self::settings_with(ctx.model, name)
                .and_then(|settings| from_scratch_or_nested(ctx, &settings));
            let mut r = match refit {
                Ok(r) => r,
                Err(e) => {
                    first_error.get_or_insert(e);
                    continue;
                }
            };
            if let Some(m) = &r.model {
                for (k, v, se) in m.output_map_parameters_with_errors() {
                    r.estimate
                        .insert(Estimate::refit(Quantity::OutputMap(k), v, se));
                }
            }
            r.change = format!("output map {name} added");
            if best.as_ref().is_none_or(|b| r.train_mse < b.train_mse) {
                best = Some(r);
            }
        }
        best.ok_or_else(|| {
            first_error
                .unwrap_or_else(|| Error::Identification("no output map could be fitted".into()))
        })
    }
    /// Null values: every polynomial coefficient within two standard errors of 0 and, together,
    /// not distinguishable from 0 by the F test of the refit against its reference (the model
    /// without the map; as for the play weights: the coefficients and the block can be nearly
    /// collinear, each coefficient undetermined alone while the map lowers the training MSE
    /// several-fold — the DC motor record decimated by 500, 144 203 → 24 929); a saturation
    /// whose limits no sample reaches (their standard errors are then infinite) or that lie
    /// within two standard errors of the largest value (unbounded).
    fn null_parameters(&self, refit: &Refit<T>, train: &IoData<T>) -> Option<String> {
        let params: Vec<(&Quantity, f64, f64)> = refit
            .estimate
            .iter()
            .filter(|e| matches!(e.quantity, Quantity::OutputMap(_)))
            .map(|e| {
                let se = e.standard_error.unwrap_or(0.0);
                (
                    &e.quantity,
                    e.value,
                    if se.is_nan() { f64::INFINITY } else { se },
                )
            })
            .collect();
        if params.is_empty() {
            return None;
        }
        let saturation = params
            .iter()
            .any(|(k, _, _)| matches!(k, Quantity::OutputMap(n) if n.ends_with("lower")));
        let null = if saturation {
            params
                .iter()
                .all(|&(_, v, se)| !se.is_finite() || v.abs() >= T::max_value().as_f64() * 0.5)
        } else {
            let p = super::pi_candidate::joint_p_value(refit, train.len(), params.len());
            params.iter().all(|&(_, v, se)| v.abs() <= 2.0 * se)
                && (p.is_nan() || p >= super::pi_candidate::JOINT_LEVEL)
        };
        null.then(|| {
            let shown: Vec<String> = params
                .iter()
                .map(|(k, v, se)| format!("{k} = {} ± {}", readable(*v), readable(*se)))
                .collect();
            format!(
                "the output map's parameters are at their null value ({})",
                shown.join(", ")
            )
        })
    }
}

fn mean(x: &[f64]) -> f64 {
    if x.is_empty() {
        0.0
    } else {
        x.iter().sum::<f64>() / x.len() as f64
    }
}

/// A number as a person reads it: three decimals in the everyday range, scientific notation
/// for very large or small magnitudes, "n/a" when it could not be estimated.
pub fn readable(x: f64) -> String {
    if !x.is_finite() {
        "n/a".into()
    } else if x != 0.0 && (x.abs() >= 1e4 || x.abs() < 1e-3) {
        format!("{x:.3e}")
    } else {
        format!("{x:.3}")
    }
}

/// A half-width estimate: "none" when the residuals give no positive width.
fn width(w: Option<f64>) -> String {
    match w {
        Some(w) if w.is_finite() && w > 0.0 => readable(w),
        Some(w) if w.is_finite() => "none (the estimate is not positive)".into(),
        _ => "n/a".into(),
    }
}
