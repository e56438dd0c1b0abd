//! Whether a model's simulation from rest means what its fit does: the departure of the
//! simulation from rest (what `simulate` and a model used as a simulator run) from the simulation
//! with the initial state estimated on the record (what the fit, the order's criterion and
//! `compare` measure).
//!
//! The two differ by the free response C Aᵏ x̂₀ of the estimated initial state x̂₀ (for a
//! Hammerstein model without an output map: the nonlinearity's output v drives both from the
//! same sample on). An initial state the record can explain is the state that the inputs before
//! the record left (the state is reachable: Kalman, Ho & Narendra 1963), and its free response
//! is of the size of the output's own excursion from the model's offset — at most a few times
//! it, for a resonant block. A free response orders of magnitude beyond that is not a state the
//! plant was in: it cancels, over the record, the model's own response to the record's start
//! (the step from rest to v(0)). That happens when the block has modes the input does not
//! excite — a slow oversampled record fitted at an order above what its narrow band supports,
//! whose extra poles sit near the unit circle at frequencies the input does not reach, behind
//! zeros clustered at z = 1 and a huge gain (issue 40, decimation battery seed 32: order 6, a
//! pole pair of modulus 0.9995 at 1.37 rad per sample, gain 3.8e6, a free response 30 000 times
//! the output's excursion). With x̂₀ estimated such a model fits the record; from rest its
//! response to the first sample rings far beyond the output's range, for thousands of samples.
//! The same check is MATLAB's `compare` with `InitialCondition` `'z'` against `'e'`, reduced
//! to one number ([`departure`]).
//!
//! The automatic order's selection refuses a candidate whose departure exceeds [`REST_LIMIT`]
//! (`order_selection.rs`); `fit`, `compare` and `simulate` say it of a model that exceeds it.

use crate::data::IoData;
use crate::fit::fitted::model::HammersteinModel;
use crate::real::Real;
use crate::statespace::StateSpace;

/// The departure ([`departure`]) beyond which a model's simulation from rest does not mean what
/// its fit means: 100 times the output's excursion from the model's offset. An initial state
/// that past inputs like the record's left has a free response of at most a few times it.
pub const REST_LIMIT: f64 = 100.0;

/// The peak over `n` samples of the free response |C Aᵏ x0| (k = 0 … n − 1) of the linear block
/// `lin` (first output) from `x0`, by the recursion x ← A x (O(n·order²) operations, no
/// storage beyond two states). Stops early at a non-finite value (returned as +∞).
pub fn free_response_peak<T: Real>(lin: &StateSpace<T>, x0: &[T], n: usize) -> f64 {
    let order = lin.order();
    if x0.len() != order || order == 0 {
        return 0.0;
    }
    let a = &lin.a;
    let mut x: Vec<f64> = x0.iter().map(|v| v.as_f64()).collect();
    let c: Vec<f64> = (0..order).map(|j| lin.c[(0, j)].as_f64()).collect();
    let am: Vec<f64> = (0..order * order)
        .map(|k| a[(k / order, k % order)].as_f64())
        .collect();
    let mut next = vec![0.0; order];
    let mut peak = 0.0f64;
    for _ in 0..n {
        let y: f64 = c.iter().zip(&x).map(|(ci, xi)| ci * xi).sum();
        if !y.is_finite() {
            return f64::INFINITY;
        }
        peak = peak.max(y.abs());
        for (i, out) in next.iter_mut().enumerate() {
            *out = am[i * order..(i + 1) * order]
                .iter()
                .zip(&x)
                .map(|(aij, xj)| aij * xj)
                .sum();
        }
        std::mem::swap(&mut x, &mut next);
    }
    peak
}

/// The output's excursion from the model's offset: max |y(k) − c| over the record (the scale
/// [`departure`] is measured in).
pub fn excursion<T: Real>(model: &HammersteinModel<T>, y: &[T]) -> f64 {
    let c = model.output_offset();
    y.iter().fold(0.0f64, |m, v| m.max((v.as_f64() - c).abs()))
}

/// How far the simulation from rest of `model` departs from its simulation with its initial state
/// estimated, on its training record `train`, in units of the output's [`excursion`]: the peak of
/// the free response of the model's training initial state over the record, divided by the
/// excursion. `None` when it is not defined: a model with an output map (the departure is then
/// not the free response alone), an output without excursion, or a record of another length
/// than the model's training state can start.
pub fn departure<T: Real>(model: &HammersteinModel<T>, train: &IoData<T>) -> Option<f64> {
    if model.output_map().is_some() || train.n_outputs() != 1 {
        return None;
    }
    let reference = excursion(model, train.output_slice(0));
    if !(reference > 0.0 && reference.is_finite()) {
        return None;
    }
    let peak = free_response_peak(model.linear(), model.training_x0(), train.len());
    Some(peak / reference)
}

/// [`departure`] from the two simulations themselves: the peak of |`from_rest` − `estimated`|
/// over the record, in units of the [`excursion`] of the measured output `y` from the model's
/// offset (`compare`, which has both). `None` when the output has no excursion or the lengths
/// differ.
pub fn departure_between<T: Real>(
    model: &HammersteinModel<T>,
    y: &[f64],
    from_rest: &[f64],
    estimated: &[f64],
) -> Option<f64> {
    let c = model.output_offset();
    let reference = y.iter().fold(0.0f64, |m, v| m.max((v - c).abs()));
    if !(reference > 0.0 && reference.is_finite()) || from_rest.len() != estimated.len() {
        return None;
    }
    let peak = from_rest
        .iter()
        .zip(estimated)
        .map(|(a, b)| (a - b).abs())
        .fold(
            0.0f64,
            |m, d| if d.is_nan() { f64::INFINITY } else { m.max(d) },
        );
    Some(peak / reference)
}

/// Whether a departure (from [`departure`] or [`departure_between`]) exceeds [`REST_LIMIT`].
pub fn departs(departure: Option<f64>) -> bool {
    departure.is_some_and(|d| d.is_nan() || d > REST_LIMIT)
}
