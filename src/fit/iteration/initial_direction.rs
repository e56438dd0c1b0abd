//! The nonlinearity's initial memory (the direction of motion before the record's first
//! sample, `StaticNonlinearity::set_initial_falling`) estimated as a nuisance parameter of the
//! loop's and the refinement's output error, like the initial state x0.
//!
//! A hysteresis started on the wrong branch mis-states v on every sample before the input first
//! changes direction; with a held input (PRBS levels) that is a whole hold, and the fit then
//! bends θ and the block to absorb it (or a higher order's extra mode absorbs it). `compare`
//! already takes the better of the rising and falling starts (`HammersteinModel::simulate_on`);
//! the fit minimises the same criterion: the exact minimum over the two starts of the
//! least-squares output error, the initial conditions estimated with the parameters as
//! prediction-error methods do for the initial state (Ljung, *System Identification*, 2nd ed.).

use super::problem::{Iterate, Problem, Workspace, normalise_iterate};
use crate::real::Real;
use crate::regressors::StaticNonlinearity;

/// The iterate for `nl`'s θ and `it`'s (A, C) with the other initial direction (B, D, x0 and
/// the offset refitted), taken (and `nl` switched to it) when its MSE is below `it`'s. True when
/// it was; false too when `nl` has no direction memory.
pub(crate) fn try_other_direction<T: Real>(
    problem: &Problem<'_, T>,
    ws: &mut Workspace<T>,
    nl: &mut dyn StaticNonlinearity<T>,
    it: &mut Iterate<T>,
) -> bool {
    let falling = !nl.initial_falling();
    let mut trial = nl.clone_box();
    if !trial.set_initial_falling(falling) {
        return false;
    }
    let Ok(t) = problem.evaluate(ws, trial.as_ref(), it.a.as_ref(), it.c.as_ref()) else {
        return false;
    };
    if t.mse.partial_cmp(&it.mse) != Some(std::cmp::Ordering::Less) {
        return false;
    }
    nl.set_initial_falling(falling);
    *it = t;
    normalise_iterate(problem, nl, it);
    true
}
