//! Compare a model's simulated output (not a one-step prediction; initial state estimated) with the
//! measured output: fit %, MSE, NRMSE and the residual series.

use crate::data::IoData;
use crate::error::{Error, Result};
use crate::fit::HammersteinModel;
use crate::real::Real;
use serde::Serialize;

/// Goodness-of-fit numbers of one record.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Metrics {
    /// Number of samples.
    pub n: usize,
    /// Mean squared error (1/N)‖y − ŷ‖².
    pub mse: f64,
    /// Normalised root-mean-square error ‖y − ŷ‖ / ‖y − ȳ‖.
    pub nrmse: f64,
    /// MATLAB `compare` fit: 100·(1 − NRMSE) per cent.
    pub fit_percent: f64,
}

impl Metrics {
    /// Metrics of a simulated output against the measured one.
    pub fn of(y: &[f64], y_hat: &[f64]) -> Result<Self> {
        metrics_of(y, y_hat)
    }
}

/// [`Metrics::of`] of series in any scalar type, each value taken as f64 where it is read (the
/// same numbers as converting the series first, without the copies).
pub(crate) fn metrics_of<T: Real>(y: &[T], y_hat: &[T]) -> Result<Metrics> {
    if y.len() != y_hat.len() {
        return Err(Error::LengthMismatch {
            what: format!(
                "measured output has {} samples, simulated {}",
                y.len(),
                y_hat.len()
            ),
        });
    }
    if y.is_empty() {
        return Err(Error::TooFewSamples {
            needed: 1,
            got: 0,
            reason: "comparing outputs".into(),
        });
    }
    for (what, s) in [("measured output", y), ("simulated output", y_hat)] {
        if let Some(index) = s.iter().position(|v| !v.as_f64().is_finite()) {
            return Err(Error::NonFinite {
                what: what.into(),
                index,
            });
        }
    }
    let n = y.len();
    // sums of squares of the series scaled by a power of two to at most 1 in magnitude (exact,
    // so ordinary records give the same bits): huge finite values give an honest NRMSE and
    // fit % (only the MSE, scaled back, may overflow to infinity)
    let f = |v: &T| v.as_f64();
    let big = y.iter().chain(y_hat).fold(0.0f64, |m, v| m.max(f(v).abs()));
    let scale = if big > 1.0 {
        2f64.powi((big.log2().ceil() as i32).min(1023))
    } else {
        1.0
    };
    let mean = y.iter().map(|a| f(a) / scale).sum::<f64>() / n as f64;
    let sse: f64 = y
        .iter()
        .zip(y_hat)
        .map(|(a, b)| (f(a) / scale - f(b) / scale).powi(2))
        .sum();
    let sst: f64 = y.iter().map(|a| (f(a) / scale - mean).powi(2)).sum();
    let nrmse = if sst > 0.0 {
        (sse / sst).sqrt()
    } else {
        f64::INFINITY
    };
    Ok(Metrics {
        n,
        mse: sse / n as f64 * scale * scale,
        nrmse,
        fit_percent: 100.0 * (1.0 - nrmse),
    })
}

/// A model's simulated output next to the measured one, with its residual and metrics.
#[derive(Debug, Clone, Serialize)]
pub struct Comparison {
    /// Input u(k) (first input channel).
    pub u: Vec<f64>,
    /// Measured output y(k).
    pub y: Vec<f64>,
    /// Simulated output ŷ(k).
    pub y_hat: Vec<f64>,
    /// Residual y(k) − ŷ(k).
    pub residual: Vec<f64>,
    /// The nonlinearity's output v̂(k) driving the linear block.
    pub v_hat: Vec<f64>,
    /// Fit %, MSE, NRMSE.
    pub metrics: Metrics,
}

impl Comparison {
    /// Builds a comparison from series (all of one length).
    pub fn from_series(u: &[f64], y: &[f64], y_hat: &[f64], v_hat: &[f64]) -> Result<Self> {
        let metrics = Metrics::of(y, y_hat)?;
        if u.len() != y.len() || v_hat.len() != y.len() {
            return Err(Error::LengthMismatch {
                what: "comparison series differ in length".into(),
            });
        }
        Ok(Self {
            u: u.to_vec(),
            y: y.to_vec(),
            y_hat: y_hat.to_vec(),
            residual: y.iter().zip(y_hat).map(|(a, b)| a - b).collect(),
            v_hat: v_hat.to_vec(),
            metrics,
        })
    }
}

/// Simulates `model` on `data` (initial state estimated from the record) and compares with the
/// measured output (first input and output channel).
pub fn compare<T: Real>(model: &HammersteinModel<T>, data: &IoData<T>) -> Result<Comparison> {
    let (sim, metrics) = simulate_and_measure(model, data)?;
    // the series built once each (as `Comparison::from_series` of the f64 series)
    let f64s = |s: &[T]| -> Vec<f64> { s.iter().map(|x| x.as_f64()).collect() };
    let y_hat = f64s(&sim.y_hat);
    drop(sim.y_hat);
    let v_hat = f64s(&sim.v);
    drop(sim.v);
    let y = f64s(data.output_slice(0));
    let residual = y.iter().zip(&y_hat).map(|(a, b)| a - b).collect();
    Ok(Comparison {
        u: f64s(data.input_slice(0)),
        y,
        y_hat,
        residual,
        v_hat,
        metrics,
    })
}

/// The fewest samples a comparison of `model` needs: twice the unknowns the simulation
/// estimates from the record (the initial state, and the intermediate values its input delay
/// hides) plus two, so that the fit is not made by those estimates alone.
pub fn min_compare_samples<T: Real>(model: &HammersteinModel<T>) -> usize {
    2 * (model.linear().order() + model.delay()) + 2
}

/// [`Error::TooFewSamples`] when `data` is shorter than [`min_compare_samples`].
pub(crate) fn check_length<T: Real>(model: &HammersteinModel<T>, data: &IoData<T>) -> Result<()> {
    let needed = min_compare_samples(model);
    if data.len() < needed {
        return Err(Error::TooFewSamples {
            needed,
            got: data.len(),
            reason: format!(
                "comparing a model of order {} and delay {} (its initial state is estimated \
                 from the record)",
                model.linear().order(),
                model.delay()
            ),
        });
    }
    Ok(())
}

/// The [`Metrics`] of [`compare`] without its series (the memory of the simulation only).
pub fn compare_metrics<T: Real>(model: &HammersteinModel<T>, data: &IoData<T>) -> Result<Metrics> {
    check_length(model, data)?;
    // the simulation is not kept (long records: two signals at a time, not three)
    model.on_simulated(data, |y_hat| {
        if let Some((index, value)) = crate::fit::divergence(y_hat) {
            return Err(Error::Diverged { index, value });
        }
        metrics_of(data.output_slice(0), y_hat)
    })?
}

/// The simulation of [`compare`] (a diverging output is an error) and its metrics against the
/// record's first output.
pub(crate) fn simulate_and_measure<T: Real>(
    model: &HammersteinModel<T>,
    data: &IoData<T>,
) -> Result<(crate::fit::Simulation<T>, Metrics)> {
    check_length(model, data)?;
    let sim = model.simulate_on(data)?;
    if let Some((index, value)) = crate::fit::divergence(&sim.y_hat) {
        return Err(Error::Diverged { index, value });
    }
    let metrics = metrics_of(data.output_slice(0), &sim.y_hat)?;
    Ok((sim, metrics))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn metrics_match_the_definitions() {
        let y = [1.0, 2.0, 3.0, 4.0];
        let m = Metrics::of(&y, &y).unwrap();
        assert_eq!(m.mse, 0.0);
        assert_eq!(m.fit_percent, 100.0);
        // ŷ = ȳ gives fit 0 %
        let m = Metrics::of(&y, &[2.5; 4]).unwrap();
        assert!((m.fit_percent).abs() < 1e-12);
        assert!((m.mse - 1.25).abs() < 1e-12);
        let m = Metrics::of(&y, &[1.0, 2.0, 3.0, 5.0]).unwrap();
        assert!((m.nrmse - (1.0f64 / 5.0).sqrt()).abs() < 1e-12);
        assert!(Metrics::of(&y, &[1.0]).is_err());
    }
}
