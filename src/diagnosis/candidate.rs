//! Missing-effect candidates: the [`MissingEffect`] trait a user can implement, the evidence a
//! candidate reads from the residual analysis, and the built-in candidates (hysteresis, dead-zone,
//! saturation, preload, dynamics, delay, output-nonlinearity).

use super::analysis::ResidualAnalysis;
use super::compare::{Comparison, compare};
use super::regression::least_squares;
use super::tests::TestResult;
use crate::data::IoData;
use crate::error::{Error, Result};
use crate::hammerstein::{Hammerstein, HammersteinModel};
use crate::real::Real;
use crate::regressors::Effect;
use crate::subspace::Order;
use std::collections::BTreeMap;

/// What the residual analysis says about one candidate.
#[derive(Debug, Clone, serde::Serialize)]
pub struct Evidence {
    /// Name of the test the evidence comes from.
    pub test: String,
    /// p-value of that test alone.
    pub p_value: f64,
    /// p-value after the multiple-testing correction.
    pub p_adjusted: f64,
    /// True when significant after the correction.
    pub significant: bool,
    /// One sentence with the numbers.
    pub sentence: String,
    /// Size estimates read from the residual (input units unless named otherwise).
    pub estimate: BTreeMap<String, f64>,
}

impl Evidence {
    /// Evidence from a test result, with a sentence and size estimates.
    pub fn from_test(t: &TestResult, sentence: String, estimate: BTreeMap<String, f64>) -> Self {
        Self {
            test: t.name.clone(),
            p_value: t.p_value,
            p_adjusted: t.p_adjusted,
            significant: t.significant,
            sentence,
            estimate,
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
    /// estimated, [`crate::hammerstein::order_selection::training_mse`]).
    pub train_mse: f64,
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
    /// Validation MSE of the refitted model (reported, not used to select).
    pub validation_mse: f64,
    /// Validation MSE of the reference (reported).
    pub reference_mse: f64,
    /// What changed ("order 2 → 3", "effects linear → hysteresis").
    pub change: String,
    /// Size estimates from the refitted model's parameters.
    pub estimate: BTreeMap<String, f64>,
    /// Standard errors of those estimates (same keys), when the fit computed them.
    pub standard_errors: BTreeMap<String, f64>,
    /// Why the candidate's own parameters are at their null value (`None`: they are not): such a
    /// candidate is not suggested, whatever its MSE.
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
        use crate::hammerstein::order_selection::{free_parameters, training_mse};
        let validation_mse = compare(&refit, ctx.validation)?.metrics.mse;
        let k = |m: &HammersteinModel<T>| (free_parameters(m) + m.delay()) as i64;
        let mut estimate = BTreeMap::new();
        let mut standard_errors = BTreeMap::new();
        for (name, v, se) in refit.parameters_with_errors() {
            if names.contains(&name.as_str()) {
                estimate.insert(name.clone(), v);
                if let Some(se) = se {
                    standard_errors.insert(name, se);
                }
            }
        }
        Ok(Self {
            train_mse: training_mse(&refit, ctx.train),
            reference_train_mse: ctx.train_mse,
            added_parameters: k(&refit) - k(ctx.model),
            validation_mse,
            reference_mse: ctx.validation_comparison.metrics.mse,
            change: change_text(ctx.model, &refit),
            estimate,
            standard_errors,
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
    /// Name shown to the user ("hysteresis", "dead-zone", …, or a user's).
    fn name(&self) -> String;
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
        let refit = settings.fit(ctx.train)?;
        let params: BTreeMap<String, f64> = refit.parameters().into_iter().collect();
        let mut r = Refit::of_model(ctx, refit, &[])?;
        r.estimate = self.refit_estimate(&params);
        Ok(r)
    }
    /// The size estimates to quote from a refitted model's parameters (default: none).
    fn refit_estimate(&self, _params: &BTreeMap<String, f64>) -> BTreeMap<String, f64> {
        BTreeMap::new()
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

fn pick(params: &BTreeMap<String, f64>, names: &[&str]) -> BTreeMap<String, f64> {
    names
        .iter()
        .filter_map(|n| params.get(*n).map(|v| (n.to_string(), *v)))
        .collect()
}

fn est(pairs: &[(&str, Option<f64>)]) -> BTreeMap<String, f64> {
    pairs
        .iter()
        .filter_map(|(k, v)| v.filter(|x| x.is_finite()).map(|x| (k.to_string(), x)))
        .collect()
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
    fn name(&self) -> String {
        self.0.name().to_string()
    }
    fn applies_to(&self, model: &HammersteinModel<T>) -> bool {
        !has_effect(model, self.0) && model.settings().with_effect(self.0).is_ok()
    }
    fn evidence(&self, a: &ResidualAnalysis) -> Option<Evidence> {
        match self.0 {
            Effect::Hysteresis => {
                let t = a.test("input-direction")?;
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
                    est(&[("half_width", w)]),
                ))
            }
            Effect::Saturation => {
                let t = a.test("input-extremes")?;
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
                    est(&[("upper_input", hi), ("lower_input", lo)]),
                ))
            }
            Effect::DeadZone => {
                let t = a.test("input-near-zero")?;
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
                    est(&[("half_width", w)]),
                ))
            }
            Effect::Preload => {
                let t = a.test("input-zero-step")?;
                let e = a.preload_step();
                Some(Evidence::from_test(
                    t,
                    format!(
                        "the residual steps across u = 0 (input-referred step ±{}; {}): preload ≈ {}",
                        readable(e.unwrap_or(f64::NAN).abs()),
                        stat_text(t),
                        readable(e.unwrap_or(f64::NAN))
                    ),
                    est(&[("step", e)]),
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
        let n = model.linear().order();
        Ok(model
            .settings()
            .with_effect(self.0)?
            .order(Order::Fixed(n))
            .with_d(model.has_feedthrough()))
    }
    /// Refits with the effect added at the model's order.
    fn refit(&self, ctx: &RefitContext<'_, T>) -> Result<Refit<T>> {
        let settings = self.apply(ctx.model, ctx.analysis)?;
        let refit = settings.fit(ctx.train)?;
        Refit::of_model(ctx, refit, udn_names(self.0))
    }
    fn refit_estimate(&self, params: &BTreeMap<String, f64>) -> BTreeMap<String, f64> {
        pick(params, udn_names(self.0))
    }
    /// Null values: a hysteresis or dead-zone half-width, or both preload steps, within two
    /// standard errors of 0; both saturation limits not clearly inside the training input's range
    /// (z1 + 2σ ≥ max u and z2 − 2σ ≤ min u: the saturation never acts).
    fn null_parameters(&self, refit: &Refit<T>, train: &IoData<T>) -> Option<String> {
        let at = |name: &str| -> Option<(f64, f64)> {
            let v = *refit.estimate.get(name)?;
            let se = refit.standard_errors.get(name).copied().unwrap_or(0.0);
            Some((v, if se.is_nan() { f64::INFINITY } else { se }))
        };
        let near_zero = |name: &str| at(name).is_some_and(|(v, se)| v.abs() <= 2.0 * se);
        let show = |name: &str| {
            at(name).map_or(String::new(), |(v, se)| {
                format!("{name} = {} ± {}", readable(v), readable(se))
            })
        };
        match self.0 {
            Effect::Hysteresis | Effect::DeadZone => {
                let name = udn_names(self.0)[0];
                near_zero(name)
                    .then(|| format!("{} is within two standard errors of 0", show(name)))
            }
            Effect::Preload => (near_zero("e1") && near_zero("e2")).then(|| {
                format!(
                    "{} and {} are within two standard errors of 0",
                    show("e1"),
                    show("e2")
                )
            }),
            Effect::Saturation => {
                let u = train.input(0);
                let hi = u
                    .iter()
                    .map(|x| x.as_f64())
                    .fold(f64::NEG_INFINITY, f64::max);
                let lo = u.iter().map(|x| x.as_f64()).fold(f64::INFINITY, f64::min);
                let (z1, s1) = at("z1")?;
                let (z2, s2) = at("z2")?;
                (z1 + 2.0 * s1 >= hi && z2 - 2.0 * s2 <= lo).then(|| {
                    format!(
                        "the limits {} and {} are not clearly inside the input's range [{}, {}]: \
                         the saturation never acts",
                        show("z1"),
                        show("z2"),
                        readable(lo),
                        readable(hi)
                    )
                })
            }
            Effect::PrandtlIshlinskii => None,
        }
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
    fn name(&self) -> String {
        "dynamics".into()
    }
    fn evidence(&self, a: &ResidualAnalysis) -> Option<Evidence> {
        let t = a.test("dynamics")?;
        let w = a.test("whiteness");
        Some(Evidence::from_test(
            t,
            format!(
                "a linear filter of the nonlinearity's output still explains part of the residual ({}){}",
                stat_text(t),
                w.map(|w| format!("; whiteness: {}", w.detail))
                    .unwrap_or_default()
            ),
            BTreeMap::new(),
        ))
    }
    fn apply(&self, model: &HammersteinModel<T>, _a: &ResidualAnalysis) -> Result<Hammerstein<T>> {
        let n = model.linear().order();
        Ok(model
            .settings()
            .clone()
            .order(Order::Fixed(n + 1))
            .with_d(model.has_feedthrough()))
    }
    /// Refits at orders n + 1, n + 2, … (at most [`MAX_ORDER_JUMP`] above n, the horizon raised
    /// to 2·order when shorter) while the information criterion on the training part keeps
    /// falling, and keeps the best: a block missing two poles is not judged by the one-pole step.
    fn refit(&self, ctx: &RefitContext<'_, T>) -> Result<Refit<T>> {
        use crate::hammerstein::order_selection::{candidate_horizon, criterion};
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
                .horizon(candidate_horizon(ctx.model.settings().horizon_value(), k));
            let refit = match settings.fit(ctx.train) {
                Ok(m) => m,
                Err(e) => {
                    first_error.get_or_insert(e);
                    break;
                }
            };
            let r = Refit::of_model(ctx, refit, &[])?;
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
            r.estimate.insert("order".into(), m.linear().order() as f64);
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
    fn name(&self) -> String {
        "delay".into()
    }
    fn evidence(&self, a: &ResidualAnalysis) -> Option<Evidence> {
        let t = a.test("delay")?;
        let d = a.delay_estimate();
        let x = a.test("input-cross-correlation");
        Some(Evidence::from_test(
            t,
            format!(
                "the model's response shifted by {d} sample(s) explains part of the residual ({}){}",
                stat_text(t),
                x.map(|x| format!("; cross-correlation with u: {}", x.detail))
                    .unwrap_or_default()
            ),
            est(&[("extra_delay", Some(d as f64))]),
        ))
    }
    fn apply(&self, model: &HammersteinModel<T>, a: &ResidualAnalysis) -> Result<Hammerstein<T>> {
        let current = model.settings().delay_value();
        Ok(model
            .settings()
            .clone()
            .delay(current + a.delay_estimate().max(1)))
    }
    fn refit(&self, ctx: &RefitContext<'_, T>) -> Result<Refit<T>> {
        let settings = self.apply(ctx.model, ctx.analysis)?;
        let d = settings.delay_value();
        let refit = settings.fit(ctx.train)?;
        let mut r = Refit::of_model(ctx, refit, &[])?;
        r.estimate.insert("delay".into(), d as f64);
        r.change = format!("delay {} → {d}", ctx.model.settings().delay_value());
        Ok(r)
    }
}

/// Output nonlinearity: the residual follows the predicted output; a static cubic map ŷ → y is
/// fitted by least squares on the training data on top of the model.
#[derive(Debug, Clone, Copy, Default)]
pub struct OutputNonlinearity;

impl OutputNonlinearity {
    fn columns(y_hat: &[f64], degree: usize, centre: f64, scale: f64) -> Vec<Vec<f64>> {
        (0..=degree)
            .map(|d| {
                y_hat
                    .iter()
                    .map(|y| ((y - centre) / scale).powi(d as i32))
                    .collect()
            })
            .collect()
    }
    /// Training-fitted polynomial map of the given degree: its training MSE, validation MSE and
    /// coefficients.
    fn map_mse(train: &Comparison, val: &Comparison, degree: usize) -> (f64, f64, Vec<f64>) {
        let n = train.y_hat.len() as f64;
        let centre = train.y_hat.iter().sum::<f64>() / n;
        let scale = (train
            .y_hat
            .iter()
            .map(|y| (y - centre).powi(2))
            .sum::<f64>()
            / n)
            .sqrt()
            .max(1e-300);
        let cols = Self::columns(&train.y_hat, degree, centre, scale);
        let refs: Vec<&[f64]> = cols.iter().map(|c| c.as_slice()).collect();
        let ls = least_squares(&train.y, &refs);
        let mse_on = |c: &Comparison| {
            let cols = Self::columns(&c.y_hat, degree, centre, scale);
            (0..c.y.len())
                .map(|k| {
                    let f: f64 = (0..=degree).map(|d| ls.coefficients[d] * cols[d][k]).sum();
                    (c.y[k] - f).powi(2)
                })
                .sum::<f64>()
                / c.y.len().max(1) as f64
        };
        (mse_on(train), mse_on(val), ls.coefficients)
    }
}

impl<T: Real> MissingEffect<T> for OutputNonlinearity {
    fn name(&self) -> String {
        "output-nonlinearity".into()
    }
    fn evidence(&self, a: &ResidualAnalysis) -> Option<Evidence> {
        let t = a.test("output-level")?;
        let lvl = a.test("input-level");
        Some(Evidence::from_test(
            t,
            format!(
                "the residual follows the predicted output ({}){}",
                stat_text(t),
                lvl.map(|l| format!("; against the input level: {}", stat_text(l)))
                    .unwrap_or_default()
            ),
            BTreeMap::new(),
        ))
    }
    fn apply(&self, model: &HammersteinModel<T>, _a: &ResidualAnalysis) -> Result<Hammerstein<T>> {
        // the model itself is kept; the refit adds a static map on its output
        Ok(model.settings().clone())
    }
    fn refit(&self, ctx: &RefitContext<'_, T>) -> Result<Refit<T>> {
        let train = compare(ctx.model, ctx.train)?;
        let val = ctx.validation_comparison;
        let (cubic_train, cubic, coef) = Self::map_mse(&train, val, 3);
        let (affine_train, affine, _) = Self::map_mse(&train, val, 1);
        if !(cubic.is_finite() && cubic_train.is_finite()) {
            return Err(Error::Identification(
                "output polynomial map is not finite".into(),
            ));
        }
        let mut estimate = BTreeMap::new();
        for (d, c) in coef.iter().enumerate() {
            estimate.insert(format!("c{d}"), *c);
        }
        // an affine map only corrects gain and offset: the nonlinearity must beat it (two more
        // coefficients)
        Ok(Refit {
            train_mse: cubic_train,
            reference_train_mse: affine_train.min(ctx.train_mse),
            added_parameters: 2,
            validation_mse: cubic,
            reference_mse: affine.min(val.metrics.mse),
            change: "static cubic map ŷ → y on the model output (coefficients in standardised ŷ)"
                .into(),
            estimate,
            standard_errors: BTreeMap::new(),
            null_parameters: None,
            model: None,
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
