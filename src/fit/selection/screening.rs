//! Screening of long records: the structure (order, feed-through, the loop's iterations) is
//! chosen on a leading window of the record, and the parameters are then polished on the whole
//! record by a few Levenberg–Marquardt steps whose least squares are chunked (`refine.rs`,
//! `solvers/tsqr.rs`).
//!
//! Why: everything the fit does before the refinement (order selection with a fit per
//! candidate order, the b search of the loop, the restarts) costs a multiple of the record's
//! length, while a well-excited window of tens of thousands of samples already determines the
//! structure; the last percent of accuracy comes from the whole record, which the polish uses.
//! What is approximated: the order and feed-through are those the window's BIC chose, and the
//! loop's start comes from the window; the polish then minimises the simulation error of the
//! whole record from there. Measured loss against the full fit: `docs/algorithm.md`.
//!
//! The window is the leading one unless the input barely moves there: real records often start
//! with a silent stretch (the piezo record's input is 0 V for its first 3.26 s, a third of it),
//! and a window inside it would be refused as a constant input. Then the earliest window of the
//! same length whose inputs vary well is taken ([`window_start`]).
//!
//! The rule ([`Screening`](crate::fit::Screening)) is a setting (`settings.rs`); the screened fit itself
//! (`fit_screened`, which fits the window) is in `driver.rs`.

use crate::data::IoData;
use crate::error::Result;
use crate::fit::fitted::model::HammersteinModel;
use crate::fit::iteration::problem::{Iterate, Problem, adopt_iterate, variance};
use crate::fit::numerics::linear_ls::{mse, simulate_in_place};
use crate::real::Real;

/// A window whose input variance is at least this share of the best window's counts as
/// excited ([`window_start`]).
const EXCITED_SHARE: f64 = 0.5;

/// The first sample of the screening window of `w` samples in `data`: the earliest of the starts
/// 0, w/2, w, … and len − w whose inputs' variance (summed over the inputs, each relative to its
/// variance on the whole record) is at least `EXCITED_SHARE` of the best start's — 0 for
/// a record excited from its start. The earliest such window keeps the fit nearest the record's
/// start, where the polish on the whole record begins (on the piezo record it includes the
/// input's start from rest; the best-excited window, further in, gave an order-3 model whose
/// near-integrator drifted over the silent stretch: 57 % training fit after the polish).
pub(crate) fn window_start<T: Real>(data: &IoData<T>, w: usize) -> usize {
    let len = data.len();
    if w == 0 || w >= len {
        return 0;
    }
    let inputs: Vec<&[T]> = (0..data.n_inputs()).map(|j| data.input_slice(j)).collect();
    let whole: Vec<f64> = inputs.iter().map(|u| variance(u)).collect();
    let score = |start: usize| -> f64 {
        inputs
            .iter()
            .zip(&whole)
            .filter(|(_, v)| **v > 0.0)
            .map(|(u, v)| variance(&u[start..start + w]) / v)
            .sum()
    };
    let step = (w / 2).max(1);
    let mut starts: Vec<usize> = (0..=(len - w) / step).map(|k| k * step).collect();
    if starts.last() != Some(&(len - w)) {
        starts.push(len - w);
    }
    let scored: Vec<(usize, f64)> = starts.iter().map(|&s| (s, score(s))).collect();
    let best = scored
        .iter()
        .map(|x| x.1)
        .filter(|v| v.is_finite())
        .fold(0.0, f64::max);
    scored
        .iter()
        .find(|(_, v)| *v >= EXCITED_SHARE * best)
        .map_or(0, |x| x.0)
}

/// How many times the window's relative training error (MSE over the output's variance) the
/// polished model's on the whole record may be, beside `CARRY_SLACK`, for the window's model to
/// count as carried over ([`carries_over`]).
pub const CARRY_RATIO: f64 = 2.0;
/// The relative training error the whole record may add beyond `CARRY_RATIO` times the
/// window's (1 % of the output's variance): a window fitted to round-off is not held to
/// round-off on the whole record.
pub const CARRY_SLACK: f64 = 0.01;
/// The factor by which the window grows when its model does not carry over.
pub const WINDOW_GROWTH: usize = 4;

/// The share by which a [`WINDOW_GROWTH`] times longer window's polished model must lower the
/// whole record's training MSE for the window to grow again ([`grows_in_vain`]).
pub const GROWTH_GAIN: f64 = 0.1;

/// Whether the model of a window [`WINDOW_GROWTH`] times longer (`longer`, polished on the whole
/// record) lowers the whole record's training MSE by less than [`GROWTH_GAIN`] against the
/// shorter window's (`shorter`, polished on the same record). Then the window is not what
/// keeps the model from carrying over — a model class that misses an effect (a linear model
/// of a saturated record) fits every window better than the record — and fitting longer
/// windows, up to the whole record, costs minutes for nothing (a linear model of a
/// 10⁶-sample saturated record: 354 s of CPU, of which the whole-record fit and the
/// candidates' refits on it took nearly all).
pub(crate) fn grows_in_vain<T: Real>(
    shorter: &HammersteinModel<T>,
    longer: &HammersteinModel<T>,
) -> bool {
    let (a, b) = (shorter.report.train_mse, longer.report.train_mse);
    a.is_finite() && b.is_finite() && b > (1.0 - GROWTH_GAIN) * a
}

/// Whether the model fitted on `window` (`window_model`), polished on the whole record `data`
/// (`polished`), explains the whole record about as well as it explains the window: its
/// training MSE relative to the output's variance at most `CARRY_RATIO` times the window's plus
/// `CARRY_SLACK`. A window that shows a different system than the record — a slow drift or a
/// near-integrating mode it cannot see, a record sampled so fast that the window holds a few
/// input steps — gives a model that fits the window and not the record (the DC motor record
/// `dc_motor_generator_prbs`, 500 000 samples with input steps of ≥ 500: 92 % on its 10 000-sample
/// window, −68 % on the whole record after the polish); the fit then tries a longer window
/// (`driver::fit_screened`). False when an error is not finite.
pub(crate) fn carries_over<T: Real>(
    window_model: &HammersteinModel<T>,
    window: &IoData<T>,
    polished: &HammersteinModel<T>,
    data: &IoData<T>,
) -> bool {
    let relative = |m: &HammersteinModel<T>, d: &IoData<T>| {
        let var = variance(d.output_slice(0));
        if var > 0.0 {
            m.report.train_mse / var
        } else {
            0.0
        }
    };
    let r_w = relative(window_model, window);
    let r = relative(polished, data);
    r.is_finite() && r_w.is_finite() && r <= CARRY_RATIO * r_w + CARRY_SLACK
}

/// `model` (fitted on a window of `data`) polished on the whole of `data`, with its
/// standard errors there (what the diagnosis' re-check of a screened candidate uses).
pub(crate) fn polish_on<T: Real>(
    model: &HammersteinModel<T>,
    data: &IoData<T>,
    iterations: usize,
) -> Result<HammersteinModel<T>> {
    let mut m = polish(model, data, iterations)?;
    crate::fit::uncertainty::attach(&mut m, data);
    Ok(m)
}

/// `model` (fitted on a part of `data`) refined on the whole of `data` by at most `iterations` LM
/// steps, its initial state re-estimated there (the refinement's free response); the model
/// itself when they do not lower its MSE.
pub(crate) fn polish<T: Real>(
    model: &HammersteinModel<T>,
    data: &IoData<T>,
    iterations: usize,
) -> Result<HammersteinModel<T>> {
    // the polish is the Hammerstein refinement: a model with an output map keeps its
    // window fit (its joint refinement, `output_fit.rs`, is not chunked yet)
    if model.output_map.is_some() {
        // its report's MSE is the window's: the whole record's, from the model's simulation
        let mut out = model.clone();
        out.report.train_mse =
            crate::fit::order_selection::simulated_mse(model, data).unwrap_or(f64::INFINITY);
        return Ok(out);
    }
    let settings = model.settings();
    let la = settings.linalg_backend()?;
    let method = settings.subspace_at(settings.options.horizon)?;
    let problem = Problem::new(la.as_ref(), method.as_ref(), settings, data);
    let lin = model.linear();
    let n = lin.order();
    let b: Vec<T> = (0..n).map(|i| lin.b[(i, 0)]).collect();
    let d = lin.d[(0, 0)];
    // the start's output written over its intermediate signal (one signal of the record)
    let mut y_hat = model.nl.eval(&problem.u);
    simulate_in_place(
        lin.a.as_ref(),
        &b,
        lin.c.as_ref(),
        d,
        &model.x0,
        model.offset,
        &mut y_hat,
    );
    let it = Iterate {
        theta: model.nl.params(),
        a: lin.a.clone(),
        b,
        c: lin.c.clone(),
        d,
        x0: model.x0.clone(),
        offset: model.offset,
        mse: {
            let m = mse(&problem.y, &y_hat);
            if m.is_finite() { m } else { f64::INFINITY }
        },
    };
    drop(y_hat);
    let (refined, rep) =
        crate::fit::refinement::refine::refine_with(&problem, model.nl.as_ref(), &it, iterations)?;
    let mut out = model.clone();
    out.report.train_mse = it.mse;
    if let Some(rf) = refined {
        adopt_iterate(&problem, &mut out, rf, data.sample_time())?;
    }
    let mut total = out.report.refinement.clone().unwrap_or(rep.clone());
    total.iterations += rep.iterations;
    total.mse_after = out.report.train_mse;
    total.accepted = total.accepted || rep.accepted;
    out.report.refinement = Some(total);
    Ok(out)
}
