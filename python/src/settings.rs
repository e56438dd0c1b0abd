//! The estimator's keyword arguments (as the command line names them) → the library's settings.

use hammerstein::fit::{Feedthrough, Hammerstein};
use hammerstein::miso::MisoHammerstein;
use hammerstein::regressors::{EffectSet, Polynomial, output_map_from_name};
use hammerstein::{BackendKind, Error, MethodKind, Order, Real};
use serde::Deserialize;

/// The settings `hammerstein.Hammerstein(...)` passes down (as JSON): the command line's
/// options, one effect list per input.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FitArgs {
    /// Per input: the UDN's effects, comma-separated ("" or "linear": none); `None`: by
    /// `nonlinearity`.
    pub effects: Vec<Option<String>>,
    /// udn, sh, linear or poly3 for an input without effects (default linear).
    pub nonlinearity: Option<String>,
    /// moesp, n4sid or n4sid-unweighted.
    pub method: String,
    /// A number, "auto" or "gap".
    pub order: String,
    /// Block rows (`None`: the method's default, raised for a fixed order it cannot hold).
    pub horizon: Option<usize>,
    /// Input delay in samples.
    pub delay: usize,
    /// The output-error refinement after the loop.
    pub refine: bool,
    /// Every pole within radius 0.9999.
    pub stable: bool,
    /// auto, on or off.
    pub feedthrough: String,
    /// Seed of every random choice.
    pub seed: u64,
    /// Static map after the linear block: poly3, polyK, saturation, pwl:K.
    pub output_nonlinearity: Option<String>,
    /// faer or lapack.
    pub backend: String,
}

impl FitArgs {
    /// Settings of one branch with the effect list `effects` (`None`: by `nonlinearity`), as
    /// `hammerstein fit` builds them.
    pub fn branch<T: Real>(&self, effects: Option<&str>) -> Result<Hammerstein<T>, Error> {
        let base = match effects {
            Some(list) => Hammerstein::udn(EffectSet::parse(list)?),
            None => match self.nonlinearity.as_deref().unwrap_or("linear") {
                "udn" => Hammerstein::udn(EffectSet::all()),
                "sh" => Hammerstein::sh(),
                "linear" => Hammerstein::linear(),
                "poly3" => Hammerstein::new(Box::new(Polynomial::<T>::new(3)?)),
                other => {
                    return Err(Error::InvalidParameter(format!(
                        "unknown nonlinearity '{other}' (udn, sh, linear or poly3)"
                    )));
                }
            },
        };
        let method: MethodKind = self.method.parse()?;
        let order: Order = self.order.parse()?;
        let backend: BackendKind = self.backend.parse()?;
        let feedthrough: Feedthrough = self.feedthrough.parse()?;
        let mut s = base
            .method(method)
            .order(order)
            .refine(self.refine)
            .stable(self.stable)
            .feedthrough(feedthrough)
            .backend(backend)
            .delay(self.delay)
            .seed(self.seed);
        if let Some(h) = self.horizon {
            s = s.horizon(h);
        }
        if let Some(name) = &self.output_nonlinearity {
            s = s.output_nonlinearity(Some(output_map_from_name::<T>(name)?));
        }
        Ok(s)
    }

    /// The single-input settings (exactly one effect list).
    pub fn single<T: Real>(&self) -> Result<Hammerstein<T>, Error> {
        match self.effects.as_slice() {
            [one] => self.branch(one.as_deref()),
            _ => Err(Error::InvalidParameter(format!(
                "{} effect lists for one input",
                self.effects.len()
            ))),
        }
    }

    /// The several-input settings: one branch per effect list.
    pub fn several<T: Real>(&self) -> Result<MisoHammerstein<T>, Error> {
        let branches = self
            .effects
            .iter()
            .map(|e| self.branch(e.as_deref()))
            .collect::<Result<Vec<_>, _>>()?;
        Ok(MisoHammerstein::new(branches))
    }
}
