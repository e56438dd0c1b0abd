//! Which input nonlinearities a record's input can identify.
//!
//! An input of two levels (a PRBS, a relay test) meets any static map N only at N(u₁) and
//! N(u₂), which an affine map reproduces; a hysteresis of any kind only adds to each level the
//! branch its direction of arrival selects, and on two levels each level is always reached from
//! the same side. So no static or rate-independent hysteretic map beyond an affine one is
//! identifiable from such a record: the diagnosis' candidates that add one are not refitted
//! (`candidate.rs`, `pi_candidate.rs`) and the guided loop's final model keeps none
//! (`final_check.rs`). An output map stays identifiable: the linear block's output takes a
//! continuum of values.

use crate::data::IoData;
use crate::error::{Error, Result};
use crate::real::Real;
use crate::regressors::Effect;

/// The first input's smallest and largest values on `train` (`None` for an empty or non-finite one).
pub fn input_extremes<T: Real>(train: &IoData<T>) -> Option<(f64, f64)> {
    let u = train.input_slice(0);
    let lo = u.iter().map(|x| x.as_f64()).fold(f64::INFINITY, f64::min);
    let hi = u
        .iter()
        .map(|x| x.as_f64())
        .fold(f64::NEG_INFINITY, f64::max);
    (lo.is_finite() && hi.is_finite() && lo <= hi).then_some((lo, hi))
}

/// Number of distinct levels of the record's first input, counted up to `cap`: values closer
/// than 1e-9 of the input's range to a level already seen are that level (a level written with
/// a rounding difference is still one level).
pub fn input_levels<T: Real>(data: &IoData<T>, cap: usize) -> usize {
    let Some((lo, hi)) = input_extremes(data) else {
        return 0;
    };
    let tol = 1e-9 * (hi - lo);
    let mut levels: Vec<f64> = Vec::new();
    for x in data.input_slice(0) {
        let x = x.as_f64();
        if !levels.iter().any(|l| (l - x).abs() <= tol) {
            levels.push(x);
            if levels.len() >= cap {
                break;
            }
        }
    }
    levels.len()
}

/// `Ok` when the training input can identify `effect` (an input nonlinearity); an
/// [`Error::Identification`] naming the levels when the input takes at most two values (see
/// the module).
pub fn identifiable<T: Real>(train: &IoData<T>, effect: Effect) -> Result<()> {
    let levels = input_levels(train, 3);
    if levels <= 2 {
        return Err(Error::Identification(format!(
            "the input takes {levels} level(s): no static map beyond an affine one (and no \
             {effect}) is identifiable from it"
        )));
    }
    Ok(())
}
