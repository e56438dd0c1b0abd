//! An output map after the loop (a Wiener side): the linear block's output passes through a
//! static map g before it is measured,
//!
//! x(k+1) = A x(k) + B (v(k) + u₀) + E f(z(k)),  y(k) = g(C x(k) + D v(k)) + y₀,
//!
//! g from the output-map family of `fit --output-nonlinearity` ([`OutputMap`]: polyK,
//! saturation, pwl:K or a user's map; unit slope and zero value at 0), acting on the
//! normalised linear output. **z is the linear block's output before g** (C x for `output`,
//! its difference for `velocity`, F x for `state`): the loop acts on the physical signal (the
//! spring's displacement), the map only on its measurement (a sensor's curvature or
//! saturation).
//!
//! **The fit is nested** (as [`super::input_side`]). The model without g is fitted first
//! ([`super::fit`], with its input nonlinearity if any): the simpler optimum. Then two starts
//! with g, each refined by the output-error Levenberg–Marquardt of all parameters, θ_g among
//! them with exact sensitivities (the chain rule through g′, [`chain`]):
//!
//! 1. the simpler optimum with g the identity (g initialised on the pair (ℓ, ℓ), ℓ the linear
//!    output: every built-in map then is exactly the identity), so that the refinement starts
//!    where the simpler fit ended and can only lower the training error;
//! 2. g initialised by its own least squares of the measured y on ℓ (`OutputMap::initialize`,
//!    the start `fit --output-nonlinearity` uses: y ≈ g(s ℓ) + c), the block's C and D
//!    scaled by s and f rescaled so that the loop is unchanged (the Wiener–Hammerstein
//!    practice of fitting the static map on the linear block's output first, then all
//!    jointly: Schoukens & Tiels, Automatica 85, 2017, §5).
//!
//! The better is kept only when its training error is below the simpler fit's and the Akaike
//! criterion N ln(MSE) + 2p (the fit's order rule) prefers it; otherwise the simpler fit is
//! returned with a stated warning. So the fit with g is never worse on training than the
//! model without it, nor chosen on a gain its parameters do not pay for.

use super::model::FeedbackModel;
use super::nested::{self, Scaled};
use super::simulate::Layout;
use super::{FeedbackFit, FeedbackOn, FeedbackSettings, simulate, siso};
use crate::data::IoData;
use crate::error::{Error, Result};
use faer::Mat;

/// g(ℓ) and g′(ℓ) at the linear output ℓ of `m` (ℓ and 1 without a map).
pub(crate) fn apply(m: &FeedbackModel, lin: f64) -> (f64, f64) {
    match &m.output {
        Some(g) => (g.eval(&[lin])[0], g.derivative(&[lin])[0]),
        None => (lin, 1.0),
    }
}

/// Row `k` of the Jacobian through the map: the linear output's sensitivities (already in the
/// row, y₀'s column included) times g′(ℓ), y₀'s column 1 and θ_g's columns ∂g/∂θ_g (at ℓ).
/// Nothing to do without a map.
pub(crate) fn chain(
    m: &FeedbackModel,
    lay: &Layout,
    lin: f64,
    slope: f64,
    jm: &mut Mat<f64>,
    k: usize,
) {
    let Some(g) = &m.output else {
        return;
    };
    for j in 0..lay.len() {
        jm[(k, j)] *= slope;
    }
    if lay.model_free {
        jm[(k, lay.offsets()[7])] = 1.0;
        let dg = g.param_jacobian(&[lin]);
        let og = lay.theta_g();
        for i in 0..lay.qg.min(dg.ncols()) {
            jm[(k, og + i)] = dg[(0, i)];
        }
    }
}

/// The fit with the output map `settings.output` (the module's method).
pub(crate) fn fit(settings: &FeedbackSettings, data: &IoData<f64>) -> Result<FeedbackFit> {
    let g0 = settings
        .output
        .as_ref()
        .ok_or_else(|| Error::InvalidParameter("no output map".into()))?;
    let mut plain = settings.clone();
    plain.output = None;
    let base = super::fit(&plain, data)?;
    let (u, y) = siso(data)?;
    let bm = &base.model;
    let (su, sy) = (bm.u_scale, bm.y_scale);
    let us: Vec<f64> = u.iter().map(|v| v / su).collect();
    let ys: Vec<f64> = y.iter().map(|v| v / sy).collect();
    // the simpler model's linear output ℓ along the training record
    let yh = simulate::run(bm, &us, &bm.x0, None)?;
    let lin: Vec<f64> = yh.iter().map(|v| v - bm.y_offset).collect();
    let mut starts: Vec<FeedbackModel> = Vec::new();
    // the Akaike rule is always among the reasons a map is not kept
    let mut notes: Vec<String> = vec![nested::AKAIKE.to_string()];
    // 1. the simpler optimum with g the identity
    let mut g = g0.clone_box();
    match g.initialize(&lin, &lin) {
        Ok((s, c)) if (s - 1.0).abs() < 1e-6 && c.abs() < 1e-6 => {
            let mut m = bm.clone();
            m.output = Some(g);
            starts.push(m);
        }
        Ok(_) => notes.push("the map's identity start is not the identity".into()),
        Err(e) => notes.push(format!("the map's identity start failed: {e}")),
    }
    // 2. g by least squares of y on ℓ, the block scaled by s and f rescaled to keep the loop
    let mut g = g0.clone_box();
    match g.initialize(&lin, &ys) {
        Ok((s, c)) if s > 0.0 && s.is_finite() => {
            let mut m = bm.clone();
            let f = if m.on == FeedbackOn::State {
                Some(m.f.clone_box())
            } else {
                m.f.rescaled(s, 1.0)
            };
            if let Some(f) = f {
                m.f = f;
                m.c.iter_mut().for_each(|v| *v *= s);
                m.d *= s;
                if m.on == FeedbackOn::Velocity {
                    m.viscous /= s;
                    let n = m.order();
                    m.x0[n] *= s;
                }
                m.y_offset = c;
                m.output = Some(g);
                starts.push(m);
            } else {
                notes.push("the feedback basis cannot be rescaled for the map's start".into());
            }
        }
        Ok(_) => notes.push("the map's least-squares start has a non-positive slope".into()),
        Err(e) => notes.push(format!("the map's least-squares start failed: {e}")),
    }
    let what = format!("the output map '{}' after the loop", g0.name());
    let rec = Scaled {
        us: &us,
        ys: &ys,
        sy,
    };
    nested::keep_better(settings, base, starts, &rec, notes, &what, false)
}

impl FeedbackModel {
    /// The linear output ℓ = C x + D v in the output's units (y before the output map and the
    /// offset) along a simulation of `u` (record units) from `x0` (normalised units, as
    /// [`simulate`](Self::simulate) takes it; `None`: zero). Without a map it is y − y₀.
    pub fn linear_output(&self, u: &[f64], x0: Option<&[f64]>) -> Result<Vec<f64>> {
        let mut m = self.clone();
        m.output = None;
        m.y_offset = 0.0;
        m.simulate(u, x0)
    }
    /// The output offset y₀ in the output's units (added after the map).
    pub fn output_offset(&self) -> f64 {
        self.y_offset * self.y_scale
    }
    /// The output map's values g(ℓ) over `l` in the output's units (the linear output ℓ =
    /// C x + D v, as y would be without the map and the offset), `None` without one.
    pub fn eval_output(&self, l: &[f64]) -> Option<Vec<f64>> {
        let g = self.output.as_deref()?;
        let ls: Vec<f64> = l.iter().map(|v| v / self.y_scale).collect();
        Some(g.eval(&ls).into_iter().map(|v| v * self.y_scale).collect())
    }
}

#[cfg(test)]
mod tests {
    use super::super::simulate::{Layout, worst_sensitivity_error};
    use super::super::{FeedbackKind, FeedbackOn, feedback_basis};
    use super::*;
    use crate::regressors::output_map_from_name;

    /// A second-order loop on `on` with a cubic f, an input feed-through and a poly3 map.
    fn model(on: FeedbackOn) -> FeedbackModel {
        let mut f = feedback_basis(FeedbackKind::Poly3, &[-1.0, 1.0]).unwrap();
        f.set_params(&[-0.3]).unwrap();
        let mut g = output_map_from_name::<f64>("poly3").unwrap();
        g.set_params(&[0.2, -0.15]).unwrap();
        let velocity = on == FeedbackOn::Velocity;
        FeedbackModel {
            a: Mat::from_fn(2, 2, |i, j| [[1.2, 1.0], [-0.5, 0.1]][i][j]),
            b: vec![1.0, 0.4],
            c: vec![1.0, 0.2],
            d: if velocity { 0.0 } else { 0.1 },
            e: vec![0.7, 0.3],
            f,
            viscous: if velocity { 0.2 } else { 0.0 },
            on,
            fz: if on == FeedbackOn::State {
                vec![0.5, -0.8]
            } else {
                Vec::new()
            },
            input: None,
            output: Some(g),
            with_d: !velocity,
            u_offset: 0.05,
            y_offset: -0.1,
            u_scale: 1.0,
            y_scale: 1.0,
            x0: if velocity {
                vec![0.2, -0.1, 0.05]
            } else {
                vec![0.2, -0.1]
            },
            z_range: (-1.0, 1.0),
        }
    }

    #[test]
    fn the_sensitivities_through_the_map_are_the_finite_differences() {
        for on in [FeedbackOn::Output, FeedbackOn::Velocity, FeedbackOn::State] {
            let m = model(on);
            let u: Vec<f64> = (0..60).map(|k| 0.3 * (0.37 * k as f64).sin()).collect();
            assert_eq!(Layout::of(&m, true).qg, 2);
            let worst = worst_sensitivity_error(&m, &u);
            assert!(
                worst < 1e-5,
                "{on:?}: largest relative Jacobian error {worst}"
            );
        }
    }

    #[test]
    fn the_map_acts_after_the_loop_and_z_before_it() {
        let m = model(FeedbackOn::Output);
        let mut plain = m.clone();
        plain.output = None;
        let u: Vec<f64> = (0..80).map(|k| 0.4 * (0.21 * k as f64).cos()).collect();
        let mut z = Vec::new();
        let y = simulate::run_z(&m, &u, &m.x0, None, Some(&mut z)).unwrap();
        let mut z0 = Vec::new();
        let y0 = simulate::run_z(&plain, &u, &plain.x0, None, Some(&mut z0)).unwrap();
        // the same loop: the same z; the output is the map of the linear output
        assert_eq!(z, z0);
        let g = m.output.as_ref().unwrap();
        for k in 0..u.len() {
            let lin = y0[k] - m.y_offset;
            assert!((y[k] - (g.eval(&[lin])[0] + m.y_offset)).abs() < 1e-12);
        }
        assert!(y.iter().zip(&y0).any(|(a, b)| (a - b).abs() > 1e-3));
    }
}
