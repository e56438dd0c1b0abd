//! The stability constraint's last step (`Hammerstein::stable`): a fitted block with a pole on or
//! outside the unit circle is replaced by the refinement's constrained optimum.
//!
//! Inside the refinement the constraint is a refused step (`refine::Lm::cost`: a trial whose
//! denominator fails the Schur–Cohn test, `solvers/schur_cohn.rs`, counts as a failed step, so
//! the damping grows and the step shrinks towards the boundary) and a start pulled inside (the
//! poles shrunk uniformly to `problem::MAX_POLE_RADIUS`, `refine::start_point`). A refinement
//! keeps its start when it ends above it, so a fit whose start was already unstable (a nested
//! fit from an unstable base, a start the loop did not stabilise) can still end unstable; this
//! step catches those: the refinement from the shrunk block, its result kept whatever its MSE
//! (the constraint is the user's, not a candidate to weigh). MATLAB's `ssest` offers the same
//! choice as `EnforceStability` (default off, as here), SIPPY as `A_stability`.

use super::refine::refine;
use crate::data::IoData;
use crate::error::{Error, Result};
use crate::fit::HammersteinModel;
use crate::fit::fit_report::Stabilised;
use crate::fit::iteration::problem::{Iterate, Problem, adopt_iterate};
use crate::fit::settings::Hammerstein;
use crate::real::Real;
use crate::regressors::StaticNonlinearity;
use crate::statespace::spectral_radius_of;

/// `it` itself when the constraint is off or its block is stable; otherwise the constrained
/// refinement's optimum from its block pulled inside the circle, with the unstable block's
/// spectral radius and MSE.
pub(crate) fn stabilised_iterate<T: Real>(
    problem: &Problem<'_, T>,
    nl: &dyn StaticNonlinearity<T>,
    it: Iterate<T>,
) -> Result<(Iterate<T>, Option<Stabilised>)> {
    if !problem.settings.options.stable {
        return Ok((it, None));
    }
    let rho = spectral_radius_of(it.a.as_ref())?;
    if rho < 1.0 {
        return Ok((it, None));
    }
    let before = Stabilised {
        spectral_radius: rho,
        train_mse: it.mse,
    };
    // the refinement keeps a result only below its iterate's MSE: against +∞ it keeps the
    // constrained optimum from the shrunk start whatever the unstable block reached
    let mut start = it;
    start.mse = f64::INFINITY;
    match refine(problem, nl, &start)? {
        (Some(r), _) if spectral_radius_of(r.a.as_ref())? < 1.0 => Ok((r, Some(before))),
        _ => Err(Error::Identification(format!(
            "the fitted linear block is unstable (a pole of modulus {rho:.6}) and no stable \
             block could be fitted in its place; fit without --stable to keep the unstable one"
        ))),
    }
}

/// `model` (fitted to `data` with `settings`, without an output map) with its block replaced as
/// [`stabilised_iterate`] says; the model unchanged when the constraint is off or the block
/// stable.
pub(crate) fn stabilised<T: Real>(
    settings: &Hammerstein<T>,
    data: &IoData<T>,
    mut model: HammersteinModel<T>,
) -> Result<HammersteinModel<T>> {
    if !settings.options.stable || model.linear.spectral_radius()? < 1.0 {
        return Ok(model);
    }
    // the model's own settings: the order and feed-through the selection chose
    let settings = &model.settings.clone();
    let la = settings.linalg_backend()?;
    let method = settings.subspace_at(settings.options.horizon)?;
    let problem = Problem::new(la.as_ref(), method.as_ref(), settings, data);
    let it = Iterate::of_model(&model, model.report.train_mse);
    let (it, before) = stabilised_iterate(&problem, model.nl.as_ref(), it)?;
    adopt_iterate(&problem, &mut model, it, data.sample_time())?;
    model.report.stabilised = before;
    Ok(model)
}
