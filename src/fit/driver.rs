//! The top of the fit: [`Hammerstein::fit`] — long records screened (fitted on a window, polished
//! on the whole), the record normalised, the order and feed-through selected or one fixed-order
//! fit (`order_selection.rs`, `fixed.rs`; the loop itself is `loop_state.rs`), the output map
//! fitted on top, the model brought back to the record's units with its standard errors.

use super::fitted::model::{HammersteinModel, check_siso};
use super::observer::Observer;
use super::scaling::{Scaling, ShiftRefused};
use super::selection::screening::polish;
use super::settings::{Hammerstein, Screening};
use crate::data::IoData;
use crate::error::{Error, Result};
use crate::real::Real;

impl<T: Real> Hammerstein<T> {
    /// Fits the model to a single-input single-output record.
    pub fn fit(&self, data: &IoData<T>) -> Result<HammersteinModel<T>> {
        fit(self, data, None)
    }

    /// Fits the model to a single-input single-output record with `observer` notified after
    /// every iteration, at the end of every fit and at a screened fit's stages (observers are
    /// attached at run time only: the settings hold none).
    pub fn fit_observed(
        &self,
        data: &IoData<T>,
        observer: &dyn Observer,
    ) -> Result<HammersteinModel<T>> {
        fit(self, data, Some(observer))
    }
}

/// Fits a Hammerstein model (the body of [`Hammerstein::fit`]): with `Order::Auto` every
/// candidate order is fitted and compared (`order_selection.rs`), otherwise one fit; `observer`
/// notified.
pub(crate) fn fit<T: Real>(
    settings: &Hammerstein<T>,
    data: &IoData<T>,
    observer: Option<&dyn Observer>,
) -> Result<HammersteinModel<T>> {
    settings.validate()?;
    check_siso(data)?;
    data.check_magnitude()?;
    let raised_settings;
    let settings = match raised_horizon(settings, data)? {
        Some(h) => {
            raised_settings = settings.clone().raise_horizon(h);
            &raised_settings
        }
        None => settings,
    };
    let mut model = fit_at_horizon(settings, data, observer)?;
    // the claim is the fitted model's own: its settings' horizon against the default they
    // were raised from (an automatic order's candidate may have raised it for its order); a
    // screened fit's claim is its window fit's, whose settings the model does not keep
    let claim = model.settings.raised_claim(model.linear.order());
    if claim.is_some() {
        model.report.horizon_raised_from = claim;
    }
    // a model whose simulation from rest does not mean what its fit means carries the
    // departure, for the callers and the model file to say it (`from_rest.rs`)
    let departure = super::from_rest::departure(&model, data);
    model.report.departs_from_rest = departure.filter(|_| super::from_rest::departs(departure));
    Ok(model)
}

/// The horizon a fixed order `n` needs when the settings' horizon is the default and cannot
/// hold it (`max_order(h, 1) < n`): 2n, as for the automatic order's candidates
/// ([`candidate_horizon`](super::selection::order_selection::candidate_horizon)), or, when the record is
/// too short for 2n, the longest horizon above n it allows. `None` when nothing is raised: the
/// order is automatic, the default holds it, the horizon was chosen
/// ([`Hammerstein::horizon_given`]), or the record is too short for any horizon above n: the
/// fit then refuses the order with `Error::OrderTooLarge`, which names `--horizon` and a
/// record long enough.
pub(crate) fn raised_horizon<T: Real>(
    settings: &Hammerstein<T>,
    data: &IoData<T>,
) -> Result<Option<usize>> {
    let crate::subspace::Order::Fixed(n) = settings.options.order else {
        return Ok(None);
    };
    let h = settings.options.horizon;
    // an order no horizon can hold is left to the fit's `OrderTooLarge`
    if settings.horizon_given()
        || crate::subspace::max_order(h, 1) >= n
        || n >= crate::data::MAX_HORIZON
    {
        return Ok(None);
    }
    let r = settings.build_nonlinearity()?.n_regressors();
    let fits = |h: usize| {
        crate::data::min_samples_for_horizon(h, r, 1).saturating_add(settings.options.delay)
            <= data.len()
    };
    let wanted = super::selection::order_selection::candidate_horizon(h, n);
    Ok((n.saturating_add(1)..=wanted).rev().find(|&h| fits(h)))
}

/// [`fit`] at the settings' horizon.
fn fit_at_horizon<T: Real>(
    settings: &Hammerstein<T>,
    data: &IoData<T>,
    observer: Option<&dyn Observer>,
) -> Result<HammersteinModel<T>> {
    if settings.options.screening.applies(data.len()) {
        return fit_screened(settings, data, observer);
    }
    let scaling = Scaling::of(settings, data)?;
    match fit_scaled(settings, data, observer, &scaling)? {
        Ok(model) => Ok(model),
        // a model fitted with the input's offset taken out that cannot carry it back (its
        // block has a pole at 1) is fitted again on the record as it is
        // (unshifted, nothing is carried back: the refusal cannot recur)
        Err(ShiftRefused) => fit_scaled(settings, data, observer, &scaling.without_shift(data))?
            .map_err(|_| {
                Error::Identification(
                    "the input's offset could not be carried back into the model".into(),
                )
            }),
    }
}

/// [`fit_at_horizon`] with the record's scales (`scaling`) given; `Err(ShiftRefused)` inside
/// when the input's offset the scaling took out cannot be carried back into the model.
fn fit_scaled<T: Real>(
    settings: &Hammerstein<T>,
    data: &IoData<T>,
    observer: Option<&dyn Observer>,
    scaling: &Scaling,
) -> Result<std::result::Result<HammersteinModel<T>, ShiftRefused>> {
    let scaled_data;
    let scaled_settings;
    let (s, d) = if scaling.is_identity() {
        (settings, data)
    } else {
        scaled_data = scaling.data(data)?;
        scaled_settings = scaling.settings(settings)?;
        (&scaled_settings, &scaled_data)
    };
    let (model, linear) = if matches!(settings.options.order, crate::subspace::Order::Auto)
        || settings.options.d_auto
    {
        // the linear model an automatic UDN fit is held to (`linear_nested.rs`) is fitted beside
        // the UDN's own fit, on the core that fit leaves idle (it needs the record alone)
        let (own, linear) = rayon::join(
            || super::selection::order_selection::fit_selecting_order(s, d, observer),
            || super::selection::linear_nested::linear_for(s, d),
        );
        // a UDN whose own fit fails is fitted from the linear model
        match own {
            Ok(m) => (m, linear),
            Err(e) => {
                let m =
                    super::selection::linear_nested::instead_of_failure(s, d, linear.as_ref(), e)?;
                (m, None)
            }
        }
    } else {
        (super::fixed::fit_fixed(s, d, observer)?, None)
    };
    // a slow block refitted at the horizon its time constant asks for (`slow_horizon.rs`)
    let model = super::fixed::refit_if_slow(s, d, model);
    // the jump parameters where the record leaves them most likely (`centring.rs`)
    let model = super::refinement::centring::centred(s, d, model)?;
    // a UDN with effects no worse than the linear model it contains (`linear_nested.rs`; a model
    // fitted from the linear one already is, and carries none)
    let model = match &linear {
        Some(linear) => super::selection::linear_nested::no_worse_than_linear(s, d, linear, model)?,
        None => model,
    };
    // a block outside the unit circle pulled inside when the user asked for a stable one
    // (`stability.rs`)
    let model = super::refinement::stability::stabilised(s, d, model)?;
    // Hammerstein–Wiener: the output map is fitted on top of the Hammerstein model
    let model = match &s.output_map {
        Some(map) => super::refinement::output_fit::fit_output_map(s, d, model, map.as_ref())?,
        None => model,
    };
    let mut model = match scaling.unscale(model, settings)? {
        Ok(model) => model,
        Err(refused) => return Ok(Err(refused)),
    };
    super::uncertainty::attach(&mut model, data);
    Ok(Ok(model))
}

/// The fit of a long record: the settings' fit on the screening window (the leading one unless
/// its input barely moves: `screening::window_start`), then the polish on the whole record;
/// when the polished model does not explain the record as well as the window
/// (`screening::carries_over`), again on a window `WINDOW_GROWTH` times longer, and on the whole
/// record when the window would reach it.
pub(crate) fn fit_screened<T: Real>(
    settings: &Hammerstein<T>,
    data: &IoData<T>,
    observer: Option<&dyn Observer>,
) -> Result<HammersteinModel<T>> {
    let s = settings.options.screening;
    let progress = |stage: &str, done: usize| {
        if let Some(obs) = observer {
            obs.progress(stage, done, 2);
        }
    };
    let mut inner = settings.clone();
    inner.options.screening = Screening::off();
    let mut w = s.window;
    // the last window's polished model and its length: what a longer window that fails falls
    // back to (the first window's failure is the user's to see)
    let mut previous: Option<(HammersteinModel<T>, usize)> = None;
    let mut model = loop {
        // the window grown to the record's length is the record: fitted whole, nothing to polish
        let whole = w >= data.len();
        let tried = if whole {
            progress(
                "fitting on the whole record (no window's model carried over)",
                1,
            );
            fit(&inner, data, None).map(|m| (m, true))
        } else {
            if w == s.window {
                progress("fitting on the screening window", 0);
            } else {
                progress(&format!("fitting on a longer window ({w} samples)"), 0);
            }
            let start = super::selection::screening::window_start(data, w);
            data.slice(start, start + w).and_then(|window| {
                let fitted = fit(&inner, &window, None)?;
                progress("polishing on the whole record", 1);
                let polished = polish(&fitted, data, s.polish_iterations)?;
                let carried =
                    super::selection::screening::carries_over(&fitted, &window, &polished, data);
                Ok((polished, carried))
            })
        };
        let (m, carried) = match (tried, previous.take()) {
            (Ok(x), _) => x,
            (Err(_), Some((m, pw))) => {
                w = pw;
                break m;
            }
            (Err(e), None) => return Err(e),
        };
        if carried {
            break m;
        }
        // a longer window whose model explains the record no better than the shorter one's:
        // the misfit is the model class's, not the window's, and the whole record would not
        // show more (`screening::grows_in_vain`); the better of the two is kept
        if let Some((pm, pw)) = &previous
            && super::selection::screening::grows_in_vain(pm, &m)
        {
            if pm.report.train_mse <= m.report.train_mse {
                w = *pw;
                break pm.clone();
            }
            break m;
        }
        previous = Some((m, w));
        // the window's model does not explain the record: a longer window, or the whole record
        w = w
            .saturating_mul(super::selection::screening::WINDOW_GROWTH)
            .min(data.len());
    };
    model.report.screening_window = Some(w);
    // refits from the model's settings (a diagnosis' candidates) start at the window that
    // carried over (the record itself: not screened)
    model.settings = settings.clone();
    model.settings.options.screening.window = w;
    super::uncertainty::attach(&mut model, data);
    progress("fitted", 2);
    Ok(model)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::subspace::Order;

    /// A third-order record (a linear gain into three real poles), long enough for horizon 20.
    fn record() -> IoData<f64> {
        let mut s = 11u64;
        let u: Vec<f64> = (0..1500)
            .map(|_| {
                s = s
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                ((s >> 11) as f64 / (1u64 << 53) as f64) - 0.5
            })
            .collect();
        let (mut x1, mut x2, mut x3) = (0.0, 0.0, 0.0);
        let y: Vec<f64> = u
            .iter()
            .map(|&uk| {
                let y = x3;
                x3 = 0.6 * x3 + x2;
                x2 = 0.3 * x2 + x1;
                x1 = -0.4 * x1 + uk;
                y
            })
            .collect();
        IoData::siso(&u, &y).unwrap()
    }

    /// A refit at a higher order from a model whose default horizon was raised (as
    /// `diagnose --follow`'s dynamics step does: the model's settings, the order up, the horizon
    /// raised for it) says its horizon stands raised from the default; before, a refit from
    /// scratch at the crate's raised horizon said nothing.
    #[test]
    fn a_refit_from_raised_settings_keeps_the_raised_claim() {
        let data = record();
        let first = Hammerstein::<f64>::linear()
            .order(Order::Fixed(8))
            .fit(&data)
            .unwrap();
        assert_eq!(first.report().horizon_raised_from, Some(8));
        let up = first
            .settings()
            .clone()
            .order(Order::Fixed(9))
            .raise_horizon(18);
        let refit = up.fit(&data).unwrap();
        assert_eq!(refit.settings().options().horizon, 18);
        assert_eq!(refit.report().horizon_raised_from, Some(8));
        // a horizon the user chose is never claimed as raised
        let chosen = first.settings().clone().horizon(18).order(Order::Fixed(9));
        assert_eq!(
            chosen.fit(&data).unwrap().report().horizon_raised_from,
            None
        );
    }

    /// The settings remember the default a crate-side raise lifted, not a user's horizon, and
    /// leave a horizon that already fits alone.
    #[test]
    fn raise_horizon_remembers_only_a_raised_default() {
        let s = Hammerstein::<f64>::linear();
        assert!(!s.clone().raise_horizon(8).horizon_given());
        let raised = s.clone().raise_horizon(16);
        assert_eq!(raised.horizon_raised_from, Some(8));
        assert_eq!(raised.raised_claim(8), Some(8));
        // the default holds order 7: nothing to claim
        assert_eq!(raised.raised_claim(7), None);
        // raised again: still from the default
        assert_eq!(
            raised.clone().raise_horizon(20).horizon_raised_from,
            Some(8)
        );
        // the user's horizon clears it, and is not claimed when the crate raises it
        assert_eq!(raised.clone().horizon(12).horizon_raised_from, None);
        assert_eq!(s.horizon(10).raise_horizon(20).horizon_raised_from, None);
    }
}
