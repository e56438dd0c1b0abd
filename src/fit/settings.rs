//! Settings of a Hammerstein fit (the builder): which nonlinearity, which subspace method, how the
//! loop iterates, stops, normalises and starts. Validated once, in [`Hammerstein::fit`] (`driver.rs`).

use crate::error::{Error, Result};
use crate::real::Real;
use crate::regressors::{Effect, EffectSet, OutputMap, StaticNonlinearity};
use crate::solvers::{BackendKind, LinAlg};
use crate::subspace::{Compression, MethodKind, Order, SubspaceMethod};
use serde::{Deserialize, Serialize};
use std::sync::Arc;

/// How the scale shared by the nonlinearity and the linear block is fixed (the product
/// G·N is invariant under G → G/s, N → s·N).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Normalization {
    /// The first non-negligible Markov parameter of the linear block is 1 (b1 = 1 as in the
    /// paper's tables); the nonlinearity carries the scale and its sign (p > 0 is not forced).
    #[default]
    MarkovOne,
    /// The first gain of the nonlinearity is 1 (p = 1 for the UDN).
    GainOne,
    /// The gain vector has unit norm with a positive first entry (the paper's V₁).
    UnitGainVector,
}

impl std::str::FromStr for Normalization {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        match s.to_ascii_lowercase().replace('_', "-").as_str() {
            "markov-one" | "markov" | "b1" => Ok(Self::MarkovOne),
            "gain-one" | "gain" | "p" => Ok(Self::GainOne),
            "unit-gain-vector" | "unit" | "v1" => Ok(Self::UnitGainVector),
            _ => Err(Error::UnknownName {
                kind: crate::error::NameKind::Normalization,
                name: s.to_string(),
                expected: "markov-one|gain-one|unit-gain-vector",
            }),
        }
    }
}

/// Whether the linear block has a direct feed-through D (y(k) responds to v(k) in the same
/// sample, as force → acceleration records need).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Feedthrough {
    /// D = 0 (strictly proper block).
    Absent,
    /// D estimated.
    Present,
    /// Both fitted, the one with the lower information criterion on the training record kept
    /// (the order selection's BIC).
    #[default]
    Auto,
}

impl std::str::FromStr for Feedthrough {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        match s.to_ascii_lowercase().as_str() {
            "off" | "absent" | "no" | "false" | "0" => Ok(Self::Absent),
            "on" | "present" | "yes" | "true" | "1" => Ok(Self::Present),
            "auto" => Ok(Self::Auto),
            _ => Err(Error::UnknownName {
                kind: crate::error::NameKind::Feedthrough,
                name: s.to_string(),
                expected: "auto, on or off",
            }),
        }
    }
}

/// How the nonlinearity's parameters are initialised before the first iteration.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Init {
    /// From the input's quantiles (the nonlinearity's own `initialize`).
    #[default]
    Quantiles,
    /// These physical parameters θ (in the nonlinearity's parameter order).
    Given(Vec<f64>),
    /// Several scaled and randomly perturbed (seeded) quantile starts, two iterations each; the
    /// best one is continued.
    CoarseSearch,
}

/// Which nonlinearity the settings describe: a UDN effect subset (built by `regressors`) or a
/// user-supplied basis.
#[derive(Debug, Clone)]
pub(crate) enum NlChoice<T: Real> {
    /// The UDN with these effects (empty: a linear gain).
    Udn(EffectSet),
    /// Any basis, including user-defined ones.
    Custom(Box<dyn StaticNonlinearity<T>>),
}

/// The plain-data settings of a fit, defined once: what the builder methods of [`Hammerstein`]
/// set, what [`Hammerstein::options`] reads and what a model file records (serde; the fields'
/// order is the model file's). The nonlinearity, observer, output map and user method/backend
/// (trait objects) live beside it in [`Hammerstein`].
///
/// ```
/// use hammerstein::{FitOptions, Hammerstein};
/// let settings = Hammerstein::<f64>::sh().horizon(10).delay(1);
/// assert_eq!(settings.options().horizon, 10);
/// let json = serde_json::to_string(settings.options())?;
/// let options: FitOptions = serde_json::from_str(&json)?;
/// let same = Hammerstein::<f64>::sh().with_options(options);
/// assert_eq!(same.options(), settings.options());
/// # Ok::<(), serde_json::Error>(())
/// ```
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FitOptions {
    /// Subspace method of the linear step (a user method set on the builder replaces it).
    pub method: MethodKind,
    /// Horizon (block rows) of the subspace step.
    pub horizon: usize,
    /// Model-order rule (applied at the first iteration; later iterations keep that order).
    pub order: Order,
    /// Iteration limit.
    pub max_iter: usize,
    /// Stopping tolerance λ: stop when |ΔMSE| < λ·MSE.
    pub tolerance: f64,
    /// Whether the Levenberg–Marquardt refinement runs after the loop.
    pub refine: bool,
    /// Linear-algebra backend (a user backend set on the builder replaces it).
    pub backend: BackendKind,
    /// Scale normalisation.
    pub normalization: Normalization,
    /// Whether D is estimated (in an automatic decision: in the candidate being fitted).
    pub with_d: bool,
    /// Input delay nk in samples: v(k) acts on y from k + nk on.
    pub delay: usize,
    /// Whether a constant output offset is estimated.
    pub offset: bool,
    /// Initialisation of the nonlinearity.
    pub init: Init,
    /// Seed of every random choice (coarse-search starts).
    pub seed: u64,
    /// Whether the feed-through is decided by the information criterion (then `with_d` is
    /// ignored); serialised only when true, so a model file (which records the decision in
    /// `with_d`) has no such field.
    #[serde(default, skip_serializing_if = "is_false")]
    pub d_auto: bool,
    /// When long records are screened; serialised only when not the default (model files do not
    /// record it).
    #[serde(default, skip_serializing_if = "Screening::is_default")]
    pub screening: Screening,
    /// Whether the linear block is kept stable (every pole within `STABLE_RADIUS`, as MATLAB's
    /// `EnforceStability`); serialised only when true (files without it load as off).
    #[serde(default, skip_serializing_if = "is_false")]
    pub stable: bool,
}

fn is_false(b: &bool) -> bool {
    !*b
}

impl Default for FitOptions {
    fn default() -> Self {
        Self {
            method: MethodKind::Moesp,
            horizon: DEFAULT_HORIZON,
            order: Order::Auto,
            max_iter: DEFAULT_MAX_ITER,
            tolerance: DEFAULT_TOLERANCE,
            refine: true,
            backend: BackendKind::Faer,
            normalization: Normalization::MarkovOne,
            with_d: false,
            delay: 0,
            offset: true,
            init: Init::Quantiles,
            seed: 0,
            d_auto: true,
            screening: Screening::default(),
            stable: false,
        }
    }
}

impl FitOptions {
    /// The feed-through rule `with_d` and `d_auto` describe.
    pub fn feedthrough(&self) -> Feedthrough {
        match (self.d_auto, self.with_d) {
            (true, _) => Feedthrough::Auto,
            (false, true) => Feedthrough::Present,
            (false, false) => Feedthrough::Absent,
        }
    }

    /// Checks every option once (called by [`Hammerstein::fit`] through
    /// [`Hammerstein::validate`]).
    pub fn validate(&self) -> Result<()> {
        if self.horizon < 2 {
            return Err(Error::InvalidParameter(format!(
                "horizon must be at least 2, got {}",
                self.horizon
            )));
        }
        if self.max_iter == 0 {
            return Err(Error::InvalidParameter(
                "max_iter must be at least 1".into(),
            ));
        }
        if !(self.tolerance.is_finite() && self.tolerance >= 0.0) {
            return Err(Error::InvalidParameter(format!(
                "tolerance must be finite and non-negative, got {}",
                self.tolerance
            )));
        }
        if let Order::Fixed(0) = self.order {
            return Err(Error::ZeroOrder);
        }
        if let Init::Given(theta) = &self.init
            && theta.iter().any(|t| !t.is_finite())
        {
            return Err(Error::InvalidParameter(
                "initial parameters must be finite".into(),
            ));
        }
        Ok(())
    }
}

/// Settings of an iterative subspace Hammerstein fit (the builder): the nonlinearity, the
/// plain-data [`FitOptions`] and the attachable trait objects (observer, output map, user
/// subspace method and backend). Reusable for many fits.
#[derive(Clone)]
pub struct Hammerstein<T: Real> {
    pub(crate) nl: NlChoice<T>,
    pub(crate) options: FitOptions,
    pub(crate) output_map: Option<Box<dyn OutputMap<T>>>,
    /// A user's subspace method, used instead of `options.method` when set.
    pub(crate) user_method: Option<Arc<dyn SubspaceMethod<T>>>,
    /// A user's linear-algebra backend, used instead of `options.backend` when set.
    pub(crate) user_linalg: Option<Arc<dyn LinAlg<T>>>,
    /// Whether the horizon was chosen (see [`Hammerstein::horizon_given`]).
    pub(crate) horizon_given: bool,
    /// The default horizon the crate raised this one from for an order it could not hold
    /// ([`Hammerstein::raise_horizon`]); `None` when the horizon is the default or the user's.
    pub(crate) horizon_raised_from: Option<usize>,
    /// The refinement's relative stopping tolerance when not `refine::LM_TOL` (the order
    /// search's candidates, polished at `LM_TOL` once chosen).
    pub(crate) lm_tol: Option<f64>,
    /// Whether an automatic UDN fit is held to the linear model it contains
    /// (`fit/selection/linear_nested.rs`); off for the branches of a several-input fit, whose partial
    /// residuals change from sweep to sweep (on two-input record 127 the check moved the backfit
    /// to 18× the noise on validation).
    pub(crate) linear_check: bool,
}

impl<T: Real> std::fmt::Debug for Hammerstein<T> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Hammerstein")
            .field("nonlinearity", &self.nonlinearity_name())
            .field("options", &self.options)
            .field("output_map", &self.output_map.as_ref().map(|m| m.name()))
            .field("user_method", &self.user_method.as_ref().map(|m| m.name()))
            .field("user_linalg", &self.user_linalg.as_ref().map(|l| l.name()))
            .field("horizon_given", &self.horizon_given)
            .finish()
    }
}

/// Default horizon (block rows) of the subspace step: enough for orders up to 7 with one output,
/// small enough that the r-input block-Hankel compression stays cheap (2·i·(r+1) columns).
pub const DEFAULT_HORIZON: usize = 8;
/// Default iteration limit.
pub const DEFAULT_MAX_ITER: usize = 50;
/// Default stopping tolerance λ on the relative MSE change.
pub const DEFAULT_TOLERANCE: f64 = 1e-4;

impl<T: Real> Hammerstein<T> {
    fn with_choice(nl: NlChoice<T>) -> Self {
        Self {
            nl,
            options: FitOptions::default(),
            output_map: None,
            user_method: None,
            user_linalg: None,
            horizon_given: false,
            horizon_raised_from: None,
            lm_tol: None,
            linear_check: true,
        }
    }

    /// The UDN with these effects (the empty set is a linear gain).
    pub fn udn(effects: EffectSet) -> Self {
        Self::with_choice(NlChoice::Udn(effects))
    }
    /// Saturation with hysteresis (the paper's SH, DN4).
    pub fn sh() -> Self {
        Self::udn(EffectSet::of(&[Effect::Hysteresis, Effect::Saturation]))
    }
    /// A linear gain (a linear model identified by the same loop).
    pub fn linear() -> Self {
        Self::udn(EffectSet::empty())
    }
    /// Any nonlinearity basis, including user-defined ones.
    pub fn new(nl: Box<dyn StaticNonlinearity<T>>) -> Self {
        Self::with_choice(NlChoice::Custom(nl))
    }

    /// Subspace method of the linear step (replaces a user method set before).
    pub fn method(mut self, m: MethodKind) -> Self {
        self.options.method = m;
        self.user_method = None;
        self
    }
    /// Any subspace method (e.g. a user's own) for the linear step; the horizon becomes the
    /// method's. Steps that need another horizon (the re-identification before the refinement, a
    /// later [`horizon`](Self::horizon)) ask [`SubspaceMethod::with_horizon`] and use the method
    /// as it is when it returns `None`. Not serialisable: a settings or model file records
    /// `"user"` with the method's name, and loading it falls back to the enum `method`.
    pub fn subspace_method(mut self, m: Arc<dyn SubspaceMethod<T>>) -> Self {
        self.options.horizon = m.horizon();
        self.horizon_given = true;
        self.user_method = Some(m);
        self
    }
    /// Horizon (block rows) of the subspace step. A horizon set here is kept as it is: a fixed
    /// order it cannot hold is refused ([`crate::Error::OrderTooLarge`]), whereas the default
    /// one is raised for it (see [`horizon_given`](Self::horizon_given)).
    pub fn horizon(mut self, i: usize) -> Self {
        self.options.horizon = i;
        self.horizon_given = true;
        self.horizon_raised_from = None;
        self
    }
    /// The horizon `i` set by the crate itself (an order the horizon cannot hold, a refit at a
    /// model's structure): held from now on as a chosen one, and, when it lifts a default
    /// horizon, that default is remembered (`horizon_raised_from`) so that every later fit from
    /// these settings can say its horizon stands raised. Setting the horizon it already has
    /// changes nothing (a default stays a default).
    pub(crate) fn raise_horizon(mut self, i: usize) -> Self {
        if i == self.options.horizon {
            return self;
        }
        if i > self.options.horizon && !self.horizon_given {
            self.horizon_raised_from = Some(self.options.horizon);
        }
        self.options.horizon = i;
        self.horizon_given = true;
        self
    }
    /// The default horizon a model fitted with these settings at order `n` stands raised from:
    /// the remembered default, when the horizon is longer and the default cannot hold `n`.
    pub(crate) fn raised_claim(&self, n: usize) -> Option<usize> {
        self.horizon_raised_from
            .filter(|&f| self.options.horizon > f && crate::subspace::max_order(f, 1) < n)
    }
    /// Whether the horizon was chosen — by [`horizon`](Self::horizon), by
    /// [`subspace_method`](Self::subspace_method), or by [`with_options`](Self::with_options)
    /// with a horizon other than [`DEFAULT_HORIZON`] — rather than left at the default. A
    /// fixed order above what the default horizon holds raises it (to 2n, as the automatic
    /// order's candidates do: [`crate::fit::order_selection::candidate_horizon`]); a chosen
    /// horizon is never raised for a fixed order.
    pub fn horizon_given(&self) -> bool {
        self.horizon_given
    }
    /// Model-order rule (applied at the first iteration; later iterations keep that order).
    pub fn order(mut self, o: Order) -> Self {
        self.options.order = o;
        self
    }
    /// Iteration limit.
    pub fn max_iter(mut self, n: usize) -> Self {
        self.options.max_iter = n;
        self
    }
    /// Stopping tolerance λ: stop when |ΔMSE| < λ·MSE (with the refinement on, the loop stops
    /// at |ΔMSE| < max(λ, 1e-3)·MSE: its iterate is only the refinement's start).
    pub fn tolerance(mut self, lambda: f64) -> Self {
        self.options.tolerance = lambda;
        self
    }
    /// Run the Levenberg–Marquardt refinement after the loop (default on: the loop is its
    /// initialisation; off gives the paper's loop alone).
    pub fn refine(mut self, on: bool) -> Self {
        self.options.refine = on;
        self
    }
    /// Keep the linear block stable: every refinement step is confined to blocks whose poles lie
    /// within [`STABLE_RADIUS`](crate::fit::STABLE_RADIUS), and a fitted block that is not stable is pulled inside and
    /// refined under that constraint (default off: an integrating mode or a drift of the record
    /// is then fitted as it is, and the output says when the block is unstable).
    pub fn stable(mut self, on: bool) -> Self {
        self.options.stable = on;
        self
    }
    /// Linear-algebra backend (replaces a user backend set before).
    pub fn backend(mut self, b: BackendKind) -> Self {
        self.options.backend = b;
        self.user_linalg = None;
        self
    }
    /// Any linear-algebra backend (e.g. a user's own) for every factorisation of the fit, its
    /// refinement, simulation and standard errors. Not serialisable: files record `"user"` with
    /// the backend's name, and loading falls back to the enum `backend`.
    pub fn linalg(mut self, la: Arc<dyn LinAlg<T>>) -> Self {
        self.user_linalg = Some(la);
        self
    }
    /// Scale normalisation.
    pub fn normalization(mut self, n: Normalization) -> Self {
        self.options.normalization = n;
        self
    }
    /// Estimate the feed-through D (true) or hold D = 0 (false); switches the automatic
    /// decision off.
    pub fn with_d(mut self, on: bool) -> Self {
        self.options.with_d = on;
        self.options.d_auto = false;
        self
    }
    /// Feed-through rule (default [`Feedthrough::Auto`]).
    pub fn feedthrough(mut self, f: Feedthrough) -> Self {
        self.options.with_d = f == Feedthrough::Present;
        self.options.d_auto = f == Feedthrough::Auto;
        self
    }
    /// Input delay nk in samples: v(k) acts on y from k + nk on.
    pub fn delay(mut self, nk: usize) -> Self {
        self.options.delay = nk;
        self
    }
    /// Estimate a constant output offset (default true).
    pub fn offset(mut self, on: bool) -> Self {
        self.options.offset = on;
        self
    }
    /// Initialisation of the nonlinearity.
    pub fn init(mut self, init: Init) -> Self {
        self.options.init = init;
        self
    }
    /// Seed of every random choice (coarse-search starts).
    pub fn seed(mut self, s: u64) -> Self {
        self.options.seed = s;
        self
    }
    /// A static output map y = g(x) after the linear block (a Hammerstein–Wiener model; see
    /// [`OutputMap`] for the built-ins and the normalisation); `None` removes it.
    pub fn output_nonlinearity(mut self, map: Option<Box<dyn OutputMap<T>>>) -> Self {
        self.output_map = map;
        self
    }
    /// The output map the fit adds after the linear block, if any.
    pub fn output_map(&self) -> Option<&dyn OutputMap<T>> {
        self.output_map.as_deref()
    }
    /// Sets when long records are screened (structure on a window, parameters polished
    /// on the whole record); `Screening::off()` fits every record whole.
    pub fn screening(mut self, s: Screening) -> Self {
        self.options.screening = s;
        self
    }

    /// The plain-data settings (horizon, order, tolerance, …): `settings.options().horizon`.
    pub fn options(&self) -> &FitOptions {
        &self.options
    }
    /// The same nonlinearity and trait objects with these plain-data settings (e.g. read from a
    /// file with serde).
    pub fn with_options(mut self, options: FitOptions) -> Self {
        self.horizon_given |= options.horizon != DEFAULT_HORIZON;
        if options.horizon != self.options.horizon {
            self.horizon_raised_from = None;
        }
        self.options = options;
        self
    }

    /// The same settings with `e` added to the UDN's effects; an error for non-UDN bases.
    pub fn with_effect(&self, e: Effect) -> Result<Self> {
        match &self.nl {
            NlChoice::Udn(set) => {
                let mut out = self.clone();
                out.nl = NlChoice::Udn(set.with(e));
                Ok(out)
            }
            NlChoice::Custom(nl) => Err(Error::NotUdn {
                what: format!("cannot add the effect '{e}' to"),
                name: nl.name(),
            }),
        }
    }
    /// The same settings with the UDN's effects replaced by `effects` (an error for non-UDN bases).
    pub fn with_effects(&self, effects: EffectSet) -> Result<Self> {
        match &self.nl {
            NlChoice::Udn(_) => {
                let mut out = self.clone();
                out.nl = NlChoice::Udn(effects);
                Ok(out)
            }
            NlChoice::Custom(nl) => Err(Error::NotUdn {
                what: "effects cannot be chosen for".into(),
                name: nl.name(),
            }),
        }
    }
    /// The UDN's effects, `None` for other bases.
    pub fn effects(&self) -> Option<EffectSet> {
        match &self.nl {
            NlChoice::Udn(s) => Some(*s),
            NlChoice::Custom(_) => None,
        }
    }

    /// Name of the nonlinearity (`udn[saturation,hysteresis]` or the basis' own name).
    pub fn nonlinearity_name(&self) -> String {
        match &self.nl {
            NlChoice::Udn(s) => format!("udn[{}]", s.label()),
            NlChoice::Custom(nl) => nl.name(),
        }
    }
    /// The user's subspace method, when one was set with [`subspace_method`](Self::subspace_method).
    pub fn user_method(&self) -> Option<&Arc<dyn SubspaceMethod<T>>> {
        self.user_method.as_ref()
    }
    /// The user's backend, when one was set with [`linalg`](Self::linalg).
    pub fn user_linalg(&self) -> Option<&Arc<dyn LinAlg<T>>> {
        self.user_linalg.as_ref()
    }
    /// Name of the subspace method in use ("moesp", …, or the user method's own name).
    pub fn method_name(&self) -> &'static str {
        self.user_method
            .as_ref()
            .map_or(self.options.method.name(), |m| m.name())
    }
    /// The backend the fit uses: the user's, or one of the enum's kind.
    pub fn linalg_backend(&self) -> Result<Arc<dyn LinAlg<T>>> {
        match &self.user_linalg {
            Some(la) => Ok(Arc::clone(la)),
            None => Ok(Arc::from(crate::solvers::backend::<T>(
                self.options.backend,
            )?)),
        }
    }
    /// The subspace method the fit uses at `horizon`: the user's (at that horizon when it can
    /// change it, else as it is), or one of the enum's kind with the rank-revealing
    /// semidefinite compression (noise-free records make the outputs exactly dependent near
    /// convergence: zero rows of R rather than the 5× dearer QR fallback).
    pub(crate) fn subspace_at(&self, horizon: usize) -> Result<Arc<dyn SubspaceMethod<T>>> {
        match &self.user_method {
            Some(m) if m.horizon() == horizon => Ok(Arc::clone(m)),
            Some(m) => Ok(m
                .with_horizon(horizon)
                .map_or_else(|| Arc::clone(m), Arc::from)),
            None => Ok(Arc::from(
                self.options
                    .method
                    .build_with::<T>(horizon, Compression::Semidefinite)?,
            )),
        }
    }

    /// A fresh nonlinearity of the chosen kind (UDN built by `regressors`).
    pub fn build_nonlinearity(&self) -> Result<Box<dyn StaticNonlinearity<T>>> {
        match &self.nl {
            NlChoice::Udn(set) => build_udn::<T>(*set),
            NlChoice::Custom(nl) => Ok(nl.clone_box()),
        }
    }

    /// Checks every setting once (called by [`fit`](Self::fit)).
    pub fn validate(&self) -> Result<()> {
        self.options.validate()
    }
}

/// The UDN with `set` from the regressors module (shift-form hysteresis, untied widths), with
/// [`DEFAULT_PLAYS`](crate::regressors::DEFAULT_PLAYS) Prandtl–Ishlinskii play operators added
/// when the set has that effect.
fn build_udn<T: Real>(set: EffectSet) -> Result<Box<dyn StaticNonlinearity<T>>> {
    let udn = Box::new(crate::regressors::Udn::<T>::new(set.udn_part()));
    if set.contains(Effect::PrandtlIshlinskii) {
        return Ok(Box::new(crate::regressors::PrandtlIshlinskii::new(
            udn,
            crate::regressors::DEFAULT_PLAYS,
        )?));
    }
    Ok(udn)
}

/// When and how a long record is screened.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct Screening {
    /// Records longer than this (samples) are screened; `usize::MAX`: never.
    pub threshold: usize,
    /// Samples of the window the structure is chosen on (the leading one unless its input
    /// barely moves there; then the earliest window whose input varies well).
    pub window: usize,
    /// Most Levenberg–Marquardt iterations of the polish on the whole record.
    pub polish_iterations: usize,
}

/// Default threshold: records above 50 000 samples are screened.
pub const DEFAULT_SCREEN_THRESHOLD: usize = 50_000;
/// Default window: the first 10 000 samples.
pub const DEFAULT_SCREEN_WINDOW: usize = 10_000;
/// Default polish: at most 3 LM iterations on the whole record.
pub const DEFAULT_POLISH_ITERATIONS: usize = 3;

impl Default for Screening {
    fn default() -> Self {
        Self {
            threshold: DEFAULT_SCREEN_THRESHOLD,
            window: DEFAULT_SCREEN_WINDOW,
            polish_iterations: DEFAULT_POLISH_ITERATIONS,
        }
    }
}

impl Screening {
    /// True for the default rule ([`Screening::default`]).
    pub fn is_default(&self) -> bool {
        *self == Self::default()
    }

    /// Never screen (every fit on the whole record).
    pub fn off() -> Self {
        Self {
            threshold: usize::MAX,
            ..Self::default()
        }
    }

    /// True when a record of `len` samples is screened.
    pub fn applies(&self, len: usize) -> bool {
        len > self.threshold && self.window >= 2 && self.window < len
    }
}
