//! Whether a saved model's simulation means anything: the spectral radius of its linear block(s)
//! and whether the simulation of a record diverges, for `compare` and `simulate` to say on
//! standard error (and `compare --json` to carry) instead of printing numbers from a diverged
//! simulation as if they meant something.

use hammerstein::Real;
use hammerstein::fit::{HammersteinModel, divergence};
use hammerstein::miso::MisoModel;

/// Growth of the free response over the record (as a power of ten) beyond which an unstable
/// model's simulation can diverge: 10⁶.
pub const DIVERGED_GROWTH_LOG10: f64 = 6.0;

/// How many times its reference (the measured output's largest deviation from its mean, or the
/// simulation's own over its first tenth) the simulated output must leave for an unstable
/// model's simulation to be said to diverge: 10³.
pub const DIVERGED_RATIO: f64 = 1e3;

/// The largest |v − mean| of a series (0 for an empty one).
pub fn spread(v: &[f64]) -> f64 {
    if v.is_empty() {
        return 0.0;
    }
    let mean = v.iter().sum::<f64>() / v.len() as f64;
    v.iter().fold(0.0f64, |m, x| m.max((x - mean).abs()))
}

/// The reference [`Stability`] measures a simulation `y_hat` against when no measured output
/// is at hand: its own [`spread`] over its first tenth.
pub fn own_reference(y_hat: &[f64]) -> f64 {
    spread(&y_hat[..y_hat.len().div_ceil(10).min(y_hat.len())])
}

/// The stability of a model on a record of `n` samples.
#[derive(Debug, Clone, Copy)]
pub struct Stability {
    /// The largest modulus of the linear block's poles (the largest over the branches of a
    /// several-input model).
    pub spectral_radius: f64,
    /// Samples of the record simulated.
    pub n: usize,
    /// The simulation diverges: the output overflowed (from this sample on), or the model is
    /// unstable, its free response grows by more than 10^[`DIVERGED_GROWTH_LOG10`] over the
    /// record and the simulated output leaves [`DIVERGED_RATIO`] times its reference.
    pub diverges: bool,
    /// The first sample whose simulated value overflowed, when one did.
    pub from: Option<usize>,
}

impl Stability {
    /// Of a single-input model on `n` samples whose simulation is `y_hat` measured against
    /// `reference` (see [`DIVERGED_RATIO`]); `y_hat` `None`: the simulation failed by overflow
    /// at `overflow`.
    pub fn of<T: Real>(
        model: &HammersteinModel<T>,
        n: usize,
        y_hat: Option<(&[f64], f64)>,
        overflow: Option<usize>,
    ) -> Self {
        let rho = model.linear().spectral_radius().unwrap_or(f64::NAN);
        Self::with_radius(rho, n, y_hat, overflow)
    }

    /// Of a several-input model (its branches' largest spectral radius).
    pub fn of_miso(
        model: &MisoModel<f64>,
        n: usize,
        y_hat: Option<(&[f64], f64)>,
        overflow: Option<usize>,
    ) -> Self {
        let rho = model
            .linear()
            .and_then(|g| g.spectral_radius())
            .unwrap_or(f64::NAN);
        Self::with_radius(rho, n, y_hat, overflow)
    }

    fn with_radius(
        rho: f64,
        n: usize,
        y_hat: Option<(&[f64], f64)>,
        overflow: Option<usize>,
    ) -> Self {
        let from = overflow.or_else(|| y_hat.and_then(|(y, _)| divergence(y)).map(|(k, _)| k));
        let grows = rho > 1.0
            && n as f64 * rho.log10() > DIVERGED_GROWTH_LOG10
            && y_hat.is_none_or(|(y, reference)| spread(y) > DIVERGED_RATIO * reference);
        Self {
            spectral_radius: rho,
            n,
            diverges: from.is_some() || grows,
            from,
        }
    }

    /// The warning for standard error: `None` for a stable model whose simulation stayed finite.
    pub fn warning(&self) -> Option<String> {
        let rho = self.spectral_radius;
        if self.diverges {
            let at = self
                .from
                .map(|k| format!(" from sample {k} on (its output overflows)"))
                .unwrap_or_default();
            let why = if rho > 1.0 {
                format!(
                    "the model is unstable (spectral radius {rho:.6} of its linear block, above 1; \
                     its free response grows by a factor 1e{:.0} over these {} samples)",
                    self.n as f64 * rho.log10(),
                    self.n
                )
            } else {
                format!("its entries are too large (spectral radius {rho:.6})")
            };
            return Some(format!(
                "warning: the simulation diverges{at}: {why}; its output is not usable"
            ));
        }
        (rho > 1.0).then(|| {
            format!(
                "warning: the model is unstable (spectral radius {rho:.6} of its linear block, above \
                 1): its free response grows by a factor {} over these {} samples; a longer \
                 simulation diverges",
                super::common::sci(rho.powf(self.n as f64)),
                self.n
            )
        })
    }

    /// The JSON fields `spectral_radius` (null when it could not be computed), `unstable` and
    /// `diverges`.
    pub fn json(&self) -> serde_json::Value {
        serde_json::json!({
            "spectral_radius": super::common::json_number(self.spectral_radius),
            "unstable": self.spectral_radius > 1.0,
            "diverges": self.diverges,
        })
    }
}
