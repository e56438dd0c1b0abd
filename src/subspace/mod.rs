//! Subspace identification of linear state-space models (MOESP, N4SID), order selection and
//! estimation of B, D and the initial state given A and C. Knows nothing about nonlinearities.

mod balanced;
mod bd;
mod hankel;
mod moesp;
mod n4sid;
mod order;
mod realize;

pub(crate) use balanced::{balanced_truncation, hankel_singular_values};
pub(crate) use bd::{BdTerms, bd_x0_least_squares};
pub use bd::{BdX0, estimate_bd_x0};
pub use hankel::{Compression, correlation};
pub use moesp::Moesp;
pub use n4sid::{N4sid, N4sidWeighting};
pub use order::{Order, select_order};
pub use realize::{ac_from_observability, stable_a_from_observability};

use crate::data::IoView;
use crate::error::{Error, Result};
use crate::real::Real;
use crate::solvers::LinAlg;
use crate::statespace::StateSpace;
use faer::Mat;

/// The compressed data of one or more experiments: the triangular factor of the block-Hankel
/// matrix and the singular values from which the order is chosen.
#[derive(Debug, Clone)]
pub struct Decomposition<T: Real> {
    /// Singular values that reveal the order, non-increasing.
    pub singular_values: Vec<T>,
    /// Horizon (block rows) i.
    pub horizon: usize,
    /// Number of inputs m.
    pub n_inputs: usize,
    /// Number of outputs l.
    pub n_outputs: usize,
    /// Total number of samples over all experiments.
    pub n_samples: usize,
    /// Upper-triangular factor R of the block-Hankel matrix (columns ordered U_f, U_p, Y_p, Y_f).
    pub r: Mat<T>,
    /// Left singular vectors of the weighted projection (extended observability basis).
    pub u_obs: Mat<T>,
    /// The compression actually used (Cholesky falls back to QR on numerically singular data).
    pub compression: Compression,
}

/// A subspace method: compresses data into a [`Decomposition`] and realises (A, C) for an order.
pub trait SubspaceMethod<T: Real>: Send + Sync + std::fmt::Debug {
    /// Method name ("moesp", "n4sid").
    fn name(&self) -> &'static str;
    /// Horizon (number of block rows) i.
    fn horizon(&self) -> usize;
    /// R factor and order-revealing SVD of one or more experiments of the same system.
    fn decompose(&self, la: &dyn LinAlg<T>, data: &[IoView<'_, T>]) -> Result<Decomposition<T>>;
    /// A and C of order `n` from a decomposition. Default: shift invariance of the extended
    /// observability basis `dec.u_obs` ([`ac_from_observability`]), what MOESP and N4SID use.
    fn realize_ac(
        &self,
        la: &dyn LinAlg<T>,
        dec: &Decomposition<T>,
        n: usize,
    ) -> Result<(Mat<T>, Mat<T>)> {
        ac_from_observability(la, dec.u_obs.as_ref(), dec.horizon, dec.n_outputs, n)
    }
    /// The same method with another horizon, when it can change it (the Hammerstein loop
    /// re-identifies the linear block with a longer horizon before its refinement); `None`
    /// (default): the method is used with its own horizon.
    fn with_horizon(&self, _horizon: usize) -> Option<Box<dyn SubspaceMethod<T>>> {
        None
    }
}

/// Which subspace method to use, as chosen on the command line or in settings.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum MethodKind {
    /// PO-MOESP (default).
    #[default]
    Moesp,
    /// N4SID with the robust weighting W₂ = Π⊥ (SLICOT IB01ND); with W₁ = I this spans the same
    /// observability subspace as PO-MOESP, so the Hammerstein loop's models coincide.
    N4sid,
    /// N4SID with W₂ = I (the 1994 paper's unweighted oblique projection).
    #[serde(rename = "n4sid-unweighted")]
    N4sidUnweighted,
}

impl std::str::FromStr for MethodKind {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        match s.to_ascii_lowercase().as_str() {
            "moesp" => Ok(Self::Moesp),
            "n4sid" => Ok(Self::N4sid),
            "n4sid-unweighted" => Ok(Self::N4sidUnweighted),
            _ => Err(Error::UnknownName {
                kind: crate::error::NameKind::SubspaceMethod,
                name: s.to_string(),
                expected: "moesp|n4sid|n4sid-unweighted",
            }),
        }
    }
}

impl MethodKind {
    /// Name as the command line spells it.
    pub fn name(self) -> &'static str {
        match self {
            Self::Moesp => "moesp",
            Self::N4sid => "n4sid",
            Self::N4sidUnweighted => "n4sid-unweighted",
        }
    }
    /// A boxed method of this kind with `horizon` block rows (default compression).
    pub fn build<T: Real>(self, horizon: usize) -> Result<Box<dyn SubspaceMethod<T>>> {
        self.build_with(horizon, Compression::default())
    }
    /// A boxed method of this kind with `horizon` block rows and the given data compression.
    pub fn build_with<T: Real>(
        self,
        horizon: usize,
        compression: Compression,
    ) -> Result<Box<dyn SubspaceMethod<T>>> {
        check_horizon_range(horizon)?;
        match self {
            Self::Moesp => Ok(Box::new(Moesp::new(horizon).with_compression(compression))),
            Self::N4sid => Ok(Box::new(N4sid::new(horizon).with_compression(compression))),
            Self::N4sidUnweighted => Ok(Box::new(
                N4sid::new(horizon)
                    .with_compression(compression)
                    .with_weighting(N4sidWeighting::Unweighted),
            )),
        }
    }
}

/// Largest horizon any method accepts (defined beside the record's length check, which needs it).
pub use crate::data::MAX_HORIZON;

/// A horizon is at least 2 (A comes from the shift of i block rows) and at most [`MAX_HORIZON`].
pub fn check_horizon_range(horizon: usize) -> Result<()> {
    if horizon < 2 {
        return Err(Error::HorizonTooSmall { horizon, min: 2 });
    }
    if horizon > MAX_HORIZON {
        return Err(Error::HorizonTooLarge {
            horizon,
            max: MAX_HORIZON,
        });
    }
    Ok(())
}

/// Options of a complete linear identification.
#[derive(Debug, Clone, PartialEq)]
pub struct SubspaceOptions {
    /// How the order is chosen.
    pub order: Order,
    /// Estimate the feed-through D (false forces D = 0).
    pub with_d: bool,
    /// Estimate the initial state of each experiment (false assumes x0 = 0).
    pub estimate_x0: bool,
    /// Replace an unstable A by the guaranteed-stable estimate (Maciejowski 1995,
    /// [`stable_a_from_observability`]); a stable A is kept as estimated.
    pub stable: bool,
}

impl Default for SubspaceOptions {
    fn default() -> Self {
        Self {
            order: Order::Auto,
            with_d: true,
            estimate_x0: true,
            stable: false,
        }
    }
}

/// The result of a linear identification.
#[derive(Debug, Clone)]
pub struct Identified<T: Real> {
    /// The identified model.
    pub model: StateSpace<T>,
    /// Singular values used for the order.
    pub singular_values: Vec<T>,
    /// Estimated initial state of each experiment.
    pub x0: Vec<Vec<T>>,
    /// The spectral radius of the unstable A that `SubspaceOptions::stable` replaced; `None`
    /// when nothing was replaced.
    pub stabilised_from: Option<f64>,
}

/// A numerical failure of the B/D/x0 step explained in the user's terms when its cause is an
/// unstable A (its free response over the record overflows): the order, the pole radius and
/// the order the singular-value gap suggests.
fn explain_unstable<T: Real>(
    e: Error,
    a: faer::MatRef<'_, T>,
    n: usize,
    sv: &[T],
    horizon: usize,
    n_outputs: usize,
) -> Error {
    if !matches!(e, Error::LinAlg(_)) {
        return e;
    }
    let rho = crate::statespace::spectral_radius_of(a).unwrap_or(f64::NAN);
    if rho.is_finite() && rho < 1.0 {
        return e;
    }
    let gap = select_order(sv, &Order::Gap, max_order(horizon, n_outputs)).unwrap_or(1);
    Error::Identification(format!(
        "the order-{n} model is unstable (largest pole radius {rho:.3}): its response over the record overflows; \
         {}: choose a lower order, \
         or ask for the guaranteed-stable estimate (`subspace --stable`, `SubspaceOptions::stable`)",
        unsupported_order_text(n, gap)
    ))
}

/// Why the data do not support order `n`, given the order `gap` of the largest singular-value
/// gap: a lower gap order is named; a gap at `n` itself or above supports nothing (the singular
/// values fall without a clear gap, as for an output unrelated to the input, e.g. white noise).
fn unsupported_order_text(n: usize, gap: usize) -> String {
    if gap < n {
        format!("the data do not support order {n} (the singular-value gap suggests order {gap})")
    } else {
        format!(
            "the singular values show no clear gap (their largest is at order {gap}): the output \
             may not depend linearly on the input (white noise, the wrong columns), and order {n} \
             is not supported"
        )
    }
}

/// Largest order the method can deliver for a horizon and channel counts.
pub fn max_order(horizon: usize, n_outputs: usize) -> usize {
    // the shifted observability matrix Γ (i-1 block rows) must have full column rank
    horizon.saturating_sub(1).saturating_mul(n_outputs).max(1)
}

/// Identifies (A, B, C, D) and initial states from one or more experiments: decomposition,
/// order selection, (A, C) by the method, then (B, D, x0) by linear least squares on the
/// simulation error (as SLICOT IB01CD does).
///
/// ```
/// use hammerstein::subspace::{Moesp, Order, SubspaceOptions, identify};
/// use hammerstein::{Faer, IoData, StateSpace};
///
/// // y(k) = 1.5 y(k−1) − 0.7 y(k−2) + u(k−1) + 0.5 u(k−2), excited by a pseudo-random input
/// let g = StateSpace::from_rows(&[&[1.5, 1.0], &[-0.7, 0.0]], &[&[1.0], &[0.5]], &[&[1.0, 0.0]], &[&[0.0]])?;
/// let u: Vec<f64> = (0..500u64).map(|k| ((k * 7919 + 13) % 101) as f64 / 50.0 - 1.0).collect();
/// let y = g.simulate_siso(&u, None)?;
/// let data = IoData::siso(&u, &y)?;
///
/// let opts = SubspaceOptions { order: Order::Auto, ..Default::default() };
/// let id = identify(&Moesp::new(10), &Faer::default(), &[data.view()], &opts)?;
/// assert_eq!(id.model.order(), 2); // the gap in the singular values gives the order
/// let (re, im) = id.model.poles()?[1]; // the true poles are 0.75 ± 0.37i
/// assert!((re - 0.75).abs() < 1e-6 && (im - 0.3708).abs() < 1e-3, "{re} {im}");
/// # Ok::<(), hammerstein::Error>(())
/// ```
pub fn identify<T: Real>(
    method: &dyn SubspaceMethod<T>,
    la: &dyn LinAlg<T>,
    data: &[IoView<'_, T>],
    opts: &SubspaceOptions,
) -> Result<Identified<T>> {
    if data.is_empty() {
        return Err(Error::NoExperiment);
    }
    let dec = method.decompose(la, data)?;
    let n = select_order(
        &dec.singular_values,
        &opts.order,
        max_order(dec.horizon, dec.n_outputs),
    )?;
    let (mut a, c) = method.realize_ac(la, &dec, n)?;
    // an unstable A replaced by the guaranteed-stable one when asked (a stable A is the better
    // estimate: the stable one is biased towards the origin)
    let mut stabilised_from = None;
    let rho = crate::statespace::spectral_radius_of(a.as_ref())?;
    if opts.stable && (rho.is_nan() || rho >= 1.0) {
        stabilised_from = Some(rho);
        a = stable_a_from_observability(la, dec.u_obs.as_ref(), dec.horizon, dec.n_outputs, n)?;
    }
    let bd = estimate_bd_x0(
        la,
        a.as_ref(),
        c.as_ref(),
        data,
        opts.with_d,
        opts.estimate_x0,
    )
    .map_err(|e| {
        explain_unstable(
            e,
            a.as_ref(),
            n,
            &dec.singular_values,
            dec.horizon,
            dec.n_outputs,
        )
    })?;
    let model = StateSpace::new(a, bd.b, c, bd.d)?;
    Ok(Identified {
        model,
        singular_values: dec.singular_values,
        x0: bd.x0,
        stabilised_from,
    })
}

#[cfg(test)]
mod unsupported_order_tests {
    use super::unsupported_order_text;

    #[test]
    fn a_gap_at_the_order_itself_is_no_suggestion() {
        let t = unsupported_order_text(7, 7);
        assert!(!t.contains("suggests order 7"), "{t}");
        assert!(t.contains("no clear gap"), "{t}");
        let t = unsupported_order_text(7, 2);
        assert!(t.contains("suggests order 2"), "{t}");
    }
}
