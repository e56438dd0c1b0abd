//! The last step of a nested extension of the loop (an input nonlinearity before it,
//! [`super::input_side`]; an output map after it, [`super::output_side`]): each start refined
//! by the output-error Levenberg–Marquardt of all parameters ([`super::refine`]), side by side,
//! and the best kept only when its training error is below the simpler fit's and the Akaike
//! criterion N ln(MSE) + 2p (the rule the fit's order choice uses) prefers it. Otherwise the
//! simpler fit is returned with a stated warning, so an extension is never worse on training
//! than the model it extends, nor chosen on a gain its parameters do not pay for.

use super::model::FeedbackModel;
use super::simulate::{self, Layout};
use super::{FeedbackFit, FeedbackOn, FeedbackSettings, refine, state};
use crate::error::Result;
use rayon::prelude::*;

/// Why an extension is not kept when no start failed.
pub(super) const AKAIKE: &str =
    "it does not lower the training error by more than its parameters' Akaike penalty";

/// Mean squared difference of two signals of the same length.
pub(super) fn mse(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| (x - y).powi(2)).sum::<f64>() / a.len().max(1) as f64
}

/// The training record in the loop's units: input and output divided by their scales, and the
/// output's scale `sy` (an RMS in its units is √MSE · sy).
pub(super) struct Scaled<'a> {
    pub us: &'a [f64],
    pub ys: &'a [f64],
    pub sy: f64,
}

/// The extension of `base` that `starts` refine to, or `base` with a warning naming `what`
/// ("the output map 'poly3' after the loop") and `notes` (why starts were missing; [`AKAIKE`]
/// when there are none). `normalise_state`: a state feedback's F is rescaled to the RMS of
/// C x before the fit is returned ([`state::normalise_scale`]).
pub(super) fn keep_better(
    settings: &FeedbackSettings,
    base: FeedbackFit,
    starts: Vec<FeedbackModel>,
    rec: &Scaled<'_>,
    notes: Vec<String>,
    what: &str,
    normalise_state: bool,
) -> Result<FeedbackFit> {
    let (us, ys, sy) = (rec.us, rec.ys, rec.sy);
    let nn = us.len() as f64;
    let refined: Vec<_> = starts
        .into_par_iter()
        .filter_map(|mut m| {
            let x0 = m.x0.clone();
            let start_mse = mse(ys, &simulate::run(&m, us, &x0, None).ok()?);
            let (x0r, rep) = refine::refine(
                &mut m,
                &x0,
                us,
                ys,
                true,
                settings.max_iterations,
                settings.tolerance / nn,
            )
            .ok()?;
            m.x0 = x0r;
            Some((m, rep, start_mse))
        })
        .collect();
    // the first of equal ones, as the starts are ordered
    let best = refined
        .into_iter()
        .min_by(|a, b| a.1.mse_end.total_cmp(&b.1.mse_end));
    let aic = |mse: f64, m: &FeedbackModel| {
        nn * mse.max(1e-300).ln() + 2.0 * Layout::of(m, true).len() as f64
    };
    let base_mse = (base.rms / sy).powi(2);
    let base_aic = aic(base_mse, &base.model);
    let Some((mut model, rep, start_mse)) =
        best.filter(|b| b.1.mse_end < base_mse && aic(b.1.mse_end, &b.0) < base_aic)
    else {
        let mut base = base;
        let why = if notes.is_empty() {
            AKAIKE.to_string()
        } else {
            notes.join("; ")
        };
        base.warnings.push(format!(
            "{what} is not kept ({why}): the model is the loop without it"
        ));
        return Ok(base);
    };
    if normalise_state && settings.on == FeedbackOn::State {
        state::normalise_scale(&mut model, us)?;
    }
    model.z_range = super::z_visited(&model, us)?;
    model.normalise_e()?;
    let yh = simulate::run(&model, us, &model.x0, None)?;
    let rms = mse(ys, &yh).sqrt() * sy;
    Ok(FeedbackFit {
        model,
        linear_rms: base.linear_rms,
        start_rms: Some(start_mse.sqrt() * sy),
        rms,
        refine: rep,
        warnings: base.warnings,
    })
}
