//! The backfitting's start: each input's contribution from one linear several-input subspace
//! identification (MOESP, order by the singular-value gap, means removed), so that the first
//! branch fits see the other inputs' linear part removed rather than the raw output.

use crate::data::IoData;
use crate::fit::scaling::rms;
use crate::real::Real;
use crate::solvers::Faer;
use crate::subspace::{Moesp, Order, SubspaceOptions, identify};
use faer::Mat;

/// Horizon of the linear start's identification.
const START_HORIZON: usize = 20;

/// Largest RMS of one input's start contribution, relative to the output's (100 times its
/// power).
const MAX_CONTRIBUTION_RMS: f64 = 10.0;

/// Each input's linear contribution to the output (the first with the output's mean and the
/// free response of the estimated initial state); `None` when the record is too short for the
/// horizon, the identification fails, or the identified block is unstable or its contributions
/// cancel (each far above the output's power): the backfitting then starts from zero
/// contributions.
pub(crate) fn linear_start<T: Real>(data: &IoData<T>) -> Option<Vec<Vec<T>>> {
    let centred = data.detrend_mean().ok()?;
    let (_, y_mean) = data.means();
    let opts = SubspaceOptions {
        order: Order::Gap,
        with_d: false,
        estimate_x0: true,
        stable: false,
    };
    let mut h = START_HORIZON;
    while h > 2 && centred.check_horizon(h).is_err() {
        h -= 1;
    }
    let id = identify(&Moesp::new(h), &Faer::default(), &[centred.view()], &opts).ok()?;
    let g = &id.model;
    // an unstable start's contributions grow without bound and cancel each other in the sum
    // (a random two-input record, seed 127 of the battery: radius 1.009, each contribution
    // ~1e13 times the output's power): no start at all is better than that
    if !matches!(g.spectral_radius(), Ok(r) if r < 1.0) {
        return None;
    }
    let nn = data.len();
    let m = data.n_inputs();
    let largest = MAX_CONTRIBUTION_RMS * rms(data.output_slice(0));
    let mut out = Vec::with_capacity(m);
    for i in 0..m {
        let ui = centred.input_slice(i);
        let u = Mat::from_fn(nn, m, |k, j| if j == i { ui[k] } else { T::zero() });
        let x0 = (i == 0)
            .then(|| id.x0.first().map(|x| x.as_slice()))
            .flatten();
        let y = g.simulate(u.as_ref(), x0).ok()?;
        let shift = if i == 0 { y_mean[0] } else { T::zero() };
        let yi: Vec<T> = (0..nn).map(|k| y[(k, 0)] + shift).collect();
        if yi.iter().any(|v| !v.is_finite()) {
            return None;
        }
        // a contribution far above the output itself is cancellation, not explanation
        if rms(&yi) > largest {
            return None;
        }
        out.push(yi);
    }
    Some(out)
}
