//! Static actuator nonlinearities and their regressors: the [`StaticNonlinearity`] trait, the
//! Unified Discontinuous Nonlinearity (UDN) and its special cases, a polynomial basis and
//! user-defined bases; static output maps after the linear block ([`OutputMap`]). Knows nothing about subspace methods.

mod direction;
mod effect;
mod output_map;
mod polynomial;
mod prandtl_ishlinskii;
mod udn;
mod udn_input;
mod user;
pub(crate) mod zone;

pub use direction::{DirectionTracker, directions, directions_from};
pub use effect::{Effect, EffectSet};
pub use output_map::{
    OutputMap, PiecewiseLinearMap, PolynomialMap, SaturationMap, is_unbounded_limit, limit_text,
    output_map_from_name, output_map_from_spec,
};
pub use polynomial::Polynomial;
pub(crate) use prandtl_ishlinskii::play_checked;
pub use prandtl_ishlinskii::{DEFAULT_PLAYS, PrandtlIshlinskii, grid as play_grid, play};
pub use udn::{HysteresisForm, SaturationSides, Udn};
pub use user::{Augmented, UserBasis, UserColumn};
pub use zone::{MAX_WIDTH_FRACTION, ZONE_FRACTION};

use crate::error::{Error, Result};
use crate::real::Real;
use faer::Mat;

/// A serialisable description of a nonlinearity: enough to rebuild a built-in one.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct NonlinearitySpec {
    /// Kind ("udn", "poly", "backlash", or a user-defined name).
    pub kind: String,
    /// Kind-specific configuration (effect set, degree, …).
    pub config: serde_json::Value,
    /// Parameter names, in the order of `params`.
    pub param_names: Vec<String>,
    /// Physical parameters θ.
    pub params: Vec<f64>,
}

/// Half-width of the secant that replaces the derivative of a [jump
/// parameter](StaticNonlinearity::jump_params), as a fraction of the input spread.
pub const JUMP_SECANT_FRACTION: f64 = 0.01;

/// A static actuator nonlinearity v = N(u; θ) that is linear in a gain vector g once its
/// thresholds are fixed: v(k) = φ(u, k; θ)·g. Its only memory is the input's direction of motion
/// (hysteresis).
///
/// The iterative Hammerstein loop uses it as follows: build φ for the current θ
/// ([`regressors`](Self::regressors)), identify the linear block from (φ, y), factor the rank-one
/// product into the linear block and g (scaled so that v = φ·g), then map g back to θ
/// ([`update_from_gains`](Self::update_from_gains)). Parameters listed by
/// [`searched_params`](Self::searched_params) are not identifiable from g and are found by the
/// loop with a one-dimensional search inside [`search_range`](Self::search_range).
///
/// A user-defined basis needs a dozen one-line methods; the loop then fits it like a built-in one:
///
/// ```
/// use hammerstein::faer::Mat;
/// use hammerstein::regressors::{NonlinearitySpec, StaticNonlinearity};
/// use hammerstein::{Error, Hammerstein, IoData, Result, StateSpace};
///
/// /// v = a·u + c·u³: a gain with a cubic stiffening term.
/// #[derive(Debug, Clone)]
/// struct Cubic { a: f64, c: f64 }
///
/// impl StaticNonlinearity<f64> for Cubic {
///     fn name(&self) -> String { "cubic".into() }
///     fn effects(&self) -> Vec<String> { vec!["stiffening".into()] }
///     fn param_names(&self) -> Vec<String> { vec!["a".into(), "c".into()] }
///     fn params(&self) -> Vec<f64> { vec![self.a, self.c] }
///     fn set_params(&mut self, theta: &[f64]) -> Result<()> {
///         let &[a, c] = theta else {
///             return Err(Error::InvalidParameter("cubic has two parameters".into()));
///         };
///         (self.a, self.c) = (a, c);
///         Ok(())
///     }
///     fn regressor_names(&self) -> Vec<String> { vec!["u".into(), "u^3".into()] }
///     fn regressors(&self, u: &[f64]) -> Mat<f64> {
///         Mat::from_fn(u.len(), 2, |k, j| if j == 0 { u[k] } else { u[k].powi(3) })
///     }
///     fn gains(&self) -> Vec<f64> { vec![self.a, self.c] } // v = φ·g
///     fn update_from_gains(&mut self, g: &[f64], _u: &[f64]) -> Result<()> { self.set_params(g) }
///     fn initialize(&mut self, _u: &[f64]) { (self.a, self.c) = (1.0, 0.0) }
///     fn spec(&self) -> NonlinearitySpec {
///         let (param_names, params) = (self.param_names(), self.params());
///         NonlinearitySpec { kind: "cubic".into(), config: Default::default(), param_names, params }
///     }
///     fn clone_box(&self) -> Box<dyn StaticNonlinearity<f64>> { Box::new(self.clone()) }
/// }
///
/// // truth: v = u + 0.3·u³ into G(z) = z⁻¹/(1 − 0.5z⁻¹)
/// let g = StateSpace::from_rows(&[&[0.5]], &[&[1.0]], &[&[1.0]], &[&[0.0]])?;
/// let u: Vec<f64> = (0..400u64).map(|k| ((k * 7919 + 13) % 101) as f64 / 50.0 - 1.0).collect();
/// let y = g.simulate_siso(&Cubic { a: 1.0, c: 0.3 }.eval(&u), None)?;
///
/// let model = Hammerstein::new(Box::new(Cubic { a: 1.0, c: 0.0 })).fit(&IoData::siso(&u, &y)?)?;
/// let p = model.nonlinearity().params(); // first Markov parameter normalised to 1, as in the truth
/// assert!((p[0] - 1.0).abs() < 1e-6 && (p[1] - 0.3).abs() < 1e-6, "{p:?}");
/// # Ok::<(), hammerstein::Error>(())
/// ```
pub trait StaticNonlinearity<T: Real>: Send + Sync + std::fmt::Debug {
    /// Short name ("udn", "sh", "poly3", or a user's).
    fn name(&self) -> String;
    /// Names of the physical effects it models ("hysteresis", "saturation", …; empty for a pure gain).
    fn effects(&self) -> Vec<String>;
    /// Names of the physical parameters, in the order of [`params`](Self::params).
    fn param_names(&self) -> Vec<String>;
    /// Current physical parameters θ (including the gain).
    fn params(&self) -> Vec<T>;
    /// Sets the physical parameters; errors on a wrong length or an inadmissible value.
    fn set_params(&mut self, theta: &[T]) -> Result<()>;
    /// Names of the regressor columns (r of them).
    fn regressor_names(&self) -> Vec<String>;
    /// Number of regressor columns r.
    fn n_regressors(&self) -> usize {
        self.regressor_names().len()
    }
    /// Regressor matrix φ(u; θ), N×r; the direction of motion is computed from `u` itself.
    fn regressors(&self, u: &[T]) -> Mat<T>;
    /// Gain vector g(θ) (length r) with v = φ·g.
    fn gains(&self) -> Vec<T>;
    /// Updates θ from an estimated gain vector g (already scaled so that v = φ·g), using the
    /// input `u` to keep every threshold inside the data (zone guard).
    fn update_from_gains(&mut self, g: &[T], u: &[T]) -> Result<()>;
    /// Indices (into [`params`](Self::params)) of thresholds the loop must find by a
    /// one-dimensional search because g does not determine them.
    fn searched_params(&self) -> Vec<usize> {
        Vec::new()
    }
    /// Admissible interval of a searched parameter for the input `u`.
    fn search_range(&self, _index: usize, u: &[T]) -> (T, T) {
        let max = u.iter().fold(T::zero(), |m, &x| m.max(x.abs()));
        (T::zero(), max)
    }
    /// Sets initial θ from the input before the first iteration (e.g. from input quantiles).
    fn initialize(&mut self, u: &[T]);
    /// Evaluates v = N(u; θ) (for simulation and plots).
    fn eval(&self, u: &[T]) -> Vec<T> {
        let phi = self.regressors(u);
        let g = self.gains();
        (0..phi.nrows())
            .map(|k| (0..g.len()).fold(T::zero(), |s, j| s + phi[(k, j)] * g[j]))
            .collect()
    }
    /// v = N(u; θ) at one value, memory left out (a feedback loop's simulation evaluates its
    /// nonlinearity one sample at a time). The default is [`eval`](Self::eval) of a
    /// one-sample record; bases override it to evaluate without allocating.
    fn eval_one(&self, u: T) -> T {
        self.eval(&[u])[0]
    }
    /// ∂v/∂θ at one value into `out` (one entry per parameter), memory left out. The default
    /// is the row of [`param_jacobian`](Self::param_jacobian) of a one-sample record; bases
    /// override it to evaluate without allocating.
    fn param_jacobian_one(&self, u: T, out: &mut [T]) {
        let jac = self.param_jacobian(&[u]);
        for (j, o) in out.iter_mut().enumerate().take(jac.ncols()) {
            *o = jac[(0, j)];
        }
    }
    /// ∂v/∂θ, N×(number of parameters), defined almost everywhere (used by the refinement and the
    /// Cramér–Rao bound). The default uses central differences.
    fn param_jacobian(&self, u: &[T]) -> Mat<T> {
        let theta = self.params();
        let mut jac = Mat::<T>::zeros(u.len(), theta.len());
        for j in 0..theta.len() {
            let h = T::lit(1e-6).max(theta[j].abs() * T::lit(1e-6)).sqrt() * T::lit(1e-2);
            let mut plus = self.clone_box();
            let mut minus = self.clone_box();
            let mut tp = theta.clone();
            let mut tm = theta.clone();
            tp[j] += h;
            tm[j] -= h;
            if plus.set_params(&tp).is_err() || minus.set_params(&tm).is_err() {
                continue;
            }
            let vp = plus.eval(u);
            let vm = minus.eval(u);
            for k in 0..u.len() {
                jac[(k, j)] = (vp[k] - vm[k]) / (h + h);
            }
        }
        jac
    }
    /// Indices (into [`params`](Self::params)) of parameters that move a jump of N (e.g. the
    /// UDN's dead-zone width b or hysteresis width a when preload steps sit at the band's edges):
    /// v is not differentiable in them, so the refinement uses secant slopes over
    /// [`JUMP_SECANT_FRACTION`] of the input spread instead of `param_jacobian`.
    fn jump_params(&self) -> Vec<usize> {
        Vec::new()
    }
    /// The values of the jump parameter `index` at which some sample of `u` changes side of a
    /// jump (the other parameters held): the record resolves that parameter only to the interval
    /// between two of them. Empty when unknown; the refinement then leaves the jump where the
    /// optimiser put it.
    fn jump_positions(&self, _index: usize, _u: &[T]) -> Vec<T> {
        Vec::new()
    }
    /// The largest step of N where a sample crosses a jump that the jump parameter `index`
    /// moves; `None` when unknown (the fit then treats the jump as one the record locates).
    fn jump_step(&self, _index: usize) -> Option<T> {
        None
    }
    /// Indices (into [`params`](Self::params)) of parameters that place a kink of N (the UDN's
    /// saturation limits): N is continuous in them, but a fit can stop at a limit that clips
    /// too much or too little with the other parameters compensating, so the refinement also
    /// restarts from other values of them (`fit/numerics/kink_scan.rs`).
    fn kink_params(&self) -> Vec<usize> {
        Vec::new()
    }
    /// The values of the kink parameter `index` at which the samples of `u` reach the kink (the
    /// signal the kink clips: for the UDN's saturation limits the dead-zone output w, one value
    /// per sample). Empty when unknown; no restart is then tried for it.
    fn kink_positions(&self, _index: usize, _u: &[T]) -> Vec<T> {
        Vec::new()
    }
    /// The same nonlinearity for other units: N'(u) = `output`·N(u / `input`) (both scales
    /// positive). `None` when the basis cannot express it; the fit then normalises the output
    /// only (through the linear block) and leaves the input in its units.
    fn rescaled(&self, _input: T, _output: T) -> Option<Box<dyn StaticNonlinearity<T>>> {
        None
    }
    /// The same nonlinearity for an input measured from `shift`: N'(u) = N(u + `shift`) − κ for
    /// every input sequence u, with the constant κ returned beside it. `None` when no constant
    /// does it (a dead-zone or a preload is anchored at u = 0) or the basis does not say; the
    /// fit then leaves a large input offset in the record.
    fn input_shifted(&self, _shift: T) -> Option<(Box<dyn StaticNonlinearity<T>>, T)> {
        None
    }
    /// True when some combination of the regressor columns is constant (e.g. preload without
    /// dead-zone: P1 + P2 = 1 almost everywhere); the loop must then not add its own constant
    /// input column (offset), or the linear step is rank deficient.
    fn spans_constant(&self) -> bool {
        false
    }
    /// The two regressor columns (i, j) whose sum is the constant 1 (wherever the input is
    /// non-zero) when the basis spans the constant that way; `None` otherwise.
    fn constant_pair(&self) -> Option<(usize, usize)> {
        None
    }
    /// Input histories (samples before a record starting at `u0`) that set this nonlinearity's
    /// memory to other states worth trying when a record's start is unknown: the simulation on a
    /// measured record evaluates N behind each and keeps the best fit, as it does for x0. Empty
    /// (the default) when the memory is at most the direction of motion, which the rising and
    /// falling starts already cover.
    fn memory_histories(&self, _u0: T) -> Vec<Vec<T>> {
        Vec::new()
    }
    /// Takes the input as falling (`true`) or rising (`false`, the default) before the record's
    /// first sample in every evaluation; returns whether the nonlinearity has such a memory (the
    /// fit then estimates the initial direction as a nuisance parameter, like x0). The default
    /// has none and ignores the call.
    fn set_initial_falling(&mut self, _falling: bool) -> bool {
        false
    }
    /// Whether the input is taken as falling before the record's first sample.
    fn initial_falling(&self) -> bool {
        false
    }
    /// Whether v(k) depends on u(k) alone, whatever came before (no hysteresis, no play): the
    /// simulation on a measured record then evaluates one start, since every start of a memory
    /// gives the same v. The default says no (a user's basis may keep a memory; the starts
    /// are then all simulated, which gives the same numbers at more cost).
    fn memoryless(&self) -> bool {
        false
    }
    /// Takes over, where it applies, the configuration that [`initialize`](Self::initialize)
    /// fixes from the input and θ does not carry, from the fitted nonlinearity `fitted`
    /// describes: a fit that starts from a fitted model (`Hammerstein::fit_from`) then starts at
    /// that model's θ on that model's configuration, not on one re-derived from another part of
    /// the record (a Prandtl–Ishlinskii grid fixed on a screening window is not the grid of the
    /// whole record). The default has no such configuration and ignores the call.
    fn carry_configuration(&mut self, _fitted: &NonlinearitySpec) {}
    /// A serialisable description (kind, configuration, parameters).
    fn spec(&self) -> NonlinearitySpec;
    /// Clones into a box.
    fn clone_box(&self) -> Box<dyn StaticNonlinearity<T>>;
}

impl<T: Real> Clone for Box<dyn StaticNonlinearity<T>> {
    fn clone(&self) -> Self {
        self.clone_box()
    }
}

/// Rebuilds a built-in nonlinearity ("udn", "backlash", "poly", "prandtl-ishlinskii") from its spec; errors on unknown kinds.
pub fn from_spec<T: Real>(spec: &NonlinearitySpec) -> Result<Box<dyn StaticNonlinearity<T>>> {
    from_spec_with(spec, |_| None)
}

/// Rebuilds a nonlinearity from its spec, asking `user` first (return `None` for kinds it does not
/// know), then the built-in kinds.
pub fn from_spec_with<T: Real>(
    spec: &NonlinearitySpec,
    user: impl Fn(&NonlinearitySpec) -> Option<Result<Box<dyn StaticNonlinearity<T>>>>,
) -> Result<Box<dyn StaticNonlinearity<T>>> {
    if let Some(r) = user(spec) {
        return r;
    }
    match spec.kind.as_str() {
        "udn" | "backlash" => Ok(Box::new(Udn::<T>::from_spec(spec)?)),
        "poly" => Ok(Box::new(Polynomial::<T>::from_spec(spec)?)),
        "prandtl-ishlinskii" => Ok(Box::new(PrandtlIshlinskii::<T>::from_spec(spec)?)),
        other => Err(Error::ModelFormat(format!(
            "unknown nonlinearity kind '{other}' (built-in: udn, backlash, poly, prandtl-ishlinskii; user kinds need \
             from_spec_with and a rebuilding closure)"
        ))),
    }
}
