//! Hammerstein with feedback: an input nonlinearity N before the loop,
//!
//! x(k+1) = A x(k) + B (N(u(k)) + u₀) + E f(z(k)),  y(k) = C x(k) + D N(u(k)) + y₀,
//!
//! N any input-side [`StaticNonlinearity`] (the UDN's saturation or dead-zone, a polynomial,
//! a user's basis), acting on the input divided by its RMS.
//!
//! **The fit is nested.** The loop without N is fitted first ([`super::fit`], every start and
//! order rule of it): the simpler optimum. Then two starts with N:
//!
//! 1. the Hammerstein model with N at the loop's order (`fit --nonlinearity …`), written as a
//!    feedback model with the loop open (E = 0, f's shape and F from the simpler fit) — the
//!    nested start of [`super::linear_start`] with N in place of a gain;
//! 2. the loop fitted on the Hammerstein model's intermediate signal v = N̂(u) as its input
//!    (the Wiener–Hammerstein practice of identifying the blocks around a fixed static map
//!    first, then all jointly: Schoukens & Tiels, "Identification of block-oriented nonlinear
//!    systems starting from linear approximations: a survey", Automatica 85, 2017, §5), N̂ put
//!    in front.
//!
//! Each is refined by the output-error Levenberg–Marquardt of all parameters, θ_N among them
//! with exact sensitivities ([`super::simulate`]). The best is kept only when its training
//! error is below the simpler fit's and the Akaike criterion N ln(MSE) + 2p (the rule the
//! fit's order choice uses) prefers it: an input nonlinearity that only fits the noise would
//! place its thresholds at the training record's extremes and clip a validation record
//! beyond them. Otherwise the simpler fit is returned with a stated warning. So the fit with
//! N is never worse on training than the loop without it.

use super::model::FeedbackModel;
use super::nested::{self, Scaled};
use super::{FeedbackFit, FeedbackOn, FeedbackSettings, scale_of, siso};
use crate::data::IoData;
use crate::error::{Error, Result};
use crate::fit::Hammerstein;
use crate::regressors::StaticNonlinearity;
use crate::subspace::Order;
use faer::Mat;

/// The fit with the input nonlinearity `settings.input` (the module's method).
pub(crate) fn fit(settings: &FeedbackSettings, data: &IoData<f64>) -> Result<FeedbackFit> {
    let nl = settings
        .input
        .as_ref()
        .ok_or_else(|| Error::InvalidParameter("no input nonlinearity".into()))?;
    let mut plain = settings.clone();
    plain.input = None;
    let base = super::fit(&plain, data)?;
    let (u, y) = siso(data)?;
    let (su, sy) = (scale_of(&u), scale_of(&y));
    let us: Vec<f64> = u.iter().map(|v| v / su).collect();
    let ys: Vec<f64> = y.iter().map(|v| v / sy).collect();
    let scaled = IoData::siso(&us, &ys)?;
    let n = base.model.order();
    let mut starts: Vec<FeedbackModel> = Vec::new();
    let mut notes: Vec<String> = Vec::new();
    let ham = Hammerstein::new(nl.clone_box())
        .order(Order::Fixed(n))
        .with_d(settings.with_d)
        .delay(0)
        .fit(&scaled);
    match ham {
        Ok(h) if h.output_map().is_none() => {
            let ss = h.linear();
            let nh = h.nonlinearity().clone_box();
            // 1. the Hammerstein model with the loop open
            let mut x0 = h.training_x0().to_vec();
            let c: Vec<f64> = (0..n).map(|j| ss.c[(0, j)]).collect();
            if settings.on == FeedbackOn::Velocity {
                x0.push((0..n).map(|i| c[i] * x0[i]).sum());
            }
            let d = ss.d[(0, 0)];
            starts.push(FeedbackModel {
                a: Mat::from_fn(n, n, |i, j| ss.a[(i, j)]),
                b: (0..n).map(|i| ss.b[(i, 0)]).collect(),
                c,
                d,
                e: vec![0.0; n],
                f: base.model.f.clone_box(),
                viscous: 0.0,
                on: settings.on,
                fz: base.model.fz.clone(),
                input: Some(nh.clone_box()),
                output: None,
                with_d: d != 0.0,
                u_offset: 0.0,
                y_offset: h.output_offset(),
                u_scale: su,
                y_scale: sy,
                x0,
                z_range: base.model.z_range,
            });
            // 2. the loop fitted on v = N̂(u), N̂ put in front
            let v = nh.eval(&us);
            if let Ok(on_v) = IoData::siso(&v, &ys).and_then(|d| super::fit(&plain, &d)) {
                let m1 = on_v.model;
                let s1 = m1.u_scale;
                // the loop's own output scale is the record's (ys has RMS 1)
                if (m1.y_scale - 1.0).abs() < 1e-9 && s1 > 0.0 {
                    let mut m = m1;
                    m.b.iter_mut().for_each(|b| *b /= s1);
                    m.d /= s1;
                    m.u_offset *= s1;
                    m.u_scale = su;
                    m.y_scale = sy;
                    m.input = Some(nh);
                    starts.push(m);
                }
            }
        }
        Ok(_) => notes.push("the Hammerstein start has an output map".into()),
        Err(e) => notes.push(format!("the Hammerstein start failed: {e}")),
    }
    let what = format!("the input nonlinearity '{}' before the loop", nl.name());
    let rec = Scaled {
        us: &us,
        ys: &ys,
        sy,
    };
    nested::keep_better(settings, base, starts, &rec, notes, &what, true)
}

impl FeedbackModel {
    /// The input nonlinearity's values v = N(u) over `u` in the record's units (the input the
    /// block receives, in the input's units), `None` without one.
    pub fn eval_input(&self, u: &[f64]) -> Option<Vec<f64>> {
        let nl: &dyn StaticNonlinearity<f64> = self.input.as_deref()?;
        let us: Vec<f64> = u.iter().map(|v| v / self.u_scale).collect();
        Some(nl.eval(&us).into_iter().map(|v| v * self.u_scale).collect())
    }
}
