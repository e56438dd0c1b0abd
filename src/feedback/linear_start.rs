//! The nested start of a feedback fit: the output-error linear model of the same order (the
//! model `fit --nonlinearity linear --order n` returns), written as a feedback model with the
//! loop open (E = 0). With E = 0 the feedback model IS that linear model, and the refinement
//! only accepts steps that lower the training cost, so a feedback fit that keeps this start
//! among its candidates is never worse on its training record than the linear model.

use super::FeedbackOn;
use super::model::FeedbackModel;
use crate::data::IoData;
use crate::error::{Error, Result};
use crate::fit::{Hammerstein, HammersteinModel};
use crate::regressors::StaticNonlinearity;
use crate::subspace::Order;
use faer::Mat;

/// The output-error linear model on the normalised record (u, y) with the order `order`
/// (`Order::Auto`: chosen as `fit --nonlinearity linear` chooses it, by BIC), the defaults of
/// `fit --nonlinearity linear` otherwise.
pub(crate) fn linear_fit(
    order: Order,
    with_d: bool,
    u: &[f64],
    y: &[f64],
) -> Result<HammersteinModel<f64>> {
    let data = IoData::siso(u, y)?;
    Hammerstein::<f64>::linear()
        .order(order)
        .with_d(with_d)
        .fit(&data)
}

/// A linear model (from [`linear_fit`]) as a feedback model with E = 0 and the nonlinearity
/// `f` (its gains kept, so that E's sensitivity is not zero).
pub(crate) fn linear_start(
    lin: &HammersteinModel<f64>,
    on: FeedbackOn,
    f: Box<dyn StaticNonlinearity<f64>>,
    scales: (f64, f64),
) -> Result<FeedbackModel> {
    if lin.output_map().is_some() || lin.delay() != 0 {
        return Err(Error::Identification(
            "the linear start has an output map or a delay".into(),
        ));
    }
    // the linear gain v = a0 + a1 u, read off the fitted basis
    let v = lin.nonlinearity().eval(&[0.0, 1.0]);
    let (a0, a1) = (v[0], v[1] - v[0]);
    if !(a1.is_finite() && a1.abs() > 1e-12 && a0.is_finite()) {
        return Err(Error::Identification(
            "the linear start's gain is zero".into(),
        ));
    }
    let ss = lin.linear();
    let n = ss.order();
    let b: Vec<f64> = (0..n).map(|i| ss.b[(i, 0)] * a1).collect();
    let c: Vec<f64> = (0..n).map(|j| ss.c[(0, j)]).collect();
    let d = ss.d[(0, 0)];
    let mut x0 = lin.training_x0().to_vec();
    if on == FeedbackOn::Velocity {
        let cx: f64 = (0..n).map(|i| c[i] * x0[i]).sum();
        x0.push(cx);
    }
    Ok(FeedbackModel {
        a: Mat::from_fn(n, n, |i, j| ss.a[(i, j)]),
        b,
        c,
        d: d * a1,
        e: vec![0.0; n],
        f,
        viscous: 0.0,
        on,
        fz: Vec::new(),
        input: None,
        output: None,
        with_d: d != 0.0,
        u_offset: a0 / a1,
        y_offset: lin.output_offset() + d * a0,
        u_scale: scales.0,
        y_scale: scales.1,
        x0,
        z_range: (0.0, 0.0),
    })
}
