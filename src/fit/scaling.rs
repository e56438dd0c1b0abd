//! Scale invariance of the fit: the record is normalised before the loop (input by its RMS,
//! output by its standard deviation) and the fitted model mapped back to the record's units.
//! An input riding on an offset of `SHIFT_RATIO` standard deviations or more is also measured
//! from its mean first, when the nonlinearity allows it
//! ([`input_shifted`](crate::regressors::StaticNonlinearity::input_shifted): the hysteresis and
//! the saturation move with the input, a dead-zone and a preload do not): otherwise the regressor
//! columns are nearly collinear with the constant and the subspace step's lag products lose
//! their digits (`docs/reliability.md`).
//!
//! With y = s_y·ỹ and u = s_u·ũ, a model ỹ = G̃·Ñ(ũ) + c̃ fitted on the normalised record is the
//! model y = G̃·N(u) + s_y·c̃ with N(u) = s_y·Ñ(u/s_u) (the nonlinearity's
//! [`rescaled`](crate::regressors::StaticNonlinearity::rescaled)), so the linear block and its
//! normalisation are unchanged and x0 scales with s_y. Every tolerance of the loop is then
//! relative to O(1) signals: the same record multiplied by 1e-12 … 1e12 gives the same fit, and
//! f32 records whose squares would overflow (or underflow) f32 are fitted as well. A basis that
//! cannot be rescaled (a user basis without `rescaled`) is fitted in the record's units.

use super::fit_report::FitReport;
use super::fitted::model::HammersteinModel;
use super::numerics::rank_one::{markov_of, markov_rows, scale_for};
use super::settings::{Hammerstein, Init};
use crate::data::{IoData, is_constant};
use crate::error::{Error, Result};
use crate::real::Real;
use crate::regressors::{Effect, StaticNonlinearity};
use faer::Mat;

/// The linear block's input scaled by `s` (B, D and the states, hence x0, times s).
fn scale_block<T: Real>(model: &mut HammersteinModel<T>, s: T) {
    let n = model.linear.order();
    for i in 0..n {
        model.linear.b[(i, 0)] *= s;
    }
    model.linear.d[(0, 0)] *= s;
    for x in model.x0.iter_mut() {
        *x *= s;
    }
}

/// An input whose mean is this many standard deviations from zero or more is measured from its
/// mean inside the fit (when the nonlinearity allows it). Below it the shift would change
/// nothing that matters: offsets up to ~300 standard deviations fit as well as centred inputs
/// (`docs/reliability.md`), so records near zero keep their numerics bit for bit.
pub(crate) const SHIFT_RATIO: f64 = 10.0;

/// The mean of `u` when it lies `SHIFT_RATIO` standard deviations from zero or more (`None`
/// for a constant or non-finite record).
fn far_offset<T: Real>(u: &[T]) -> Option<f64> {
    let nn = u.len().max(1) as f64;
    let mean = u.iter().map(|v| v.as_f64()).sum::<f64>() / nn;
    let sd = super::iteration::problem::variance(u).sqrt();
    (sd > 0.0 && mean.is_finite() && mean.abs() >= SHIFT_RATIO * sd).then_some(mean)
}

/// Root mean square of `u`, in f64.
pub(crate) fn rms<T: Real>(u: &[T]) -> f64 {
    let nn = u.len().max(1) as f64;
    (u.iter().map(|v| v.as_f64().powi(2)).sum::<f64>() / nn).sqrt()
}

/// The input offset m the fit takes out of the record: the input's mean when it lies
/// `SHIFT_RATIO` standard deviations from zero or more and the model can carry it back (the
/// nonlinearity shifts, an output offset absorbs the constant, no output map, no input delay);
/// 0 otherwise.
fn input_shift<T: Real>(settings: &Hammerstein<T>, nl: &dyn StaticNonlinearity<T>, u: &[T]) -> f64 {
    let o = &settings.options;
    if settings.output_map.is_some() || !o.offset || o.delay != 0 {
        return 0.0;
    }
    if nl.input_shifted(T::zero()).is_none() {
        return 0.0;
    }
    far_offset(u).unwrap_or(0.0)
}

/// The input's mean when the settings' UDN has an effect anchored at u = 0 (a dead-zone or a
/// preload) while the record's input lies `SHIFT_RATIO` standard deviations or more from 0:
/// those effects then act only if the actuator's zero is subtracted from the input first (the
/// fit cannot know where it is); `None` otherwise.
pub fn anchored_effects_far_from_input<T: Real>(
    settings: &Hammerstein<T>,
    data: &IoData<T>,
) -> Option<f64> {
    let effects = settings.effects()?;
    if !(effects.contains(Effect::DeadZone) || effects.contains(Effect::Preload)) {
        return None;
    }
    far_offset(&data.input(0))
}

/// The refusal to carry the input's offset back into a model: its block has a pole at 1 (no
/// steady state), or its nonlinearity cannot be shifted.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct ShiftRefused;

/// The model's block input moved by the constant `delta` (v ← v + δ) without changing its
/// output: the steady state x_s = (I − A)⁻¹B·δ (LU with partial pivoting) joins x0 and the
/// steady output G(1)·δ = C·x_s + D·δ leaves the offset. Refused, the model untouched, when
/// I − A is singular to working precision (a pole at 1).
fn shift_block_input<T: Real>(
    model: &mut HammersteinModel<T>,
    delta: T,
    settings: &Hammerstein<T>,
) -> std::result::Result<(), ShiftRefused> {
    let n = model.linear.order();
    if n == 0 {
        model.offset -= model.linear.d[(0, 0)] * delta;
        return Ok(());
    }
    let a = &model.linear.a;
    let i_a = Mat::<T>::from_fn(n, n, |i, j| {
        (if i == j { T::one() } else { T::zero() }) - a[(i, j)]
    });
    let bd = Mat::<T>::from_fn(n, 1, |i, _| model.linear.b[(i, 0)] * delta);
    let xs = settings
        .linalg_backend()
        .and_then(|la| la.solve(i_a.as_ref(), bd.as_ref()))
        .map_err(|_| ShiftRefused)?;
    let mut g1 = model.linear.d[(0, 0)] * delta;
    for i in 0..n {
        g1 += model.linear.c[(0, i)] * xs[(i, 0)];
    }
    if !(g1.is_finite() && (0..n).all(|i| xs[(i, 0)].is_finite())) {
        return Err(ShiftRefused);
    }
    for (x, i) in model.x0.iter_mut().zip(0..n) {
        *x += xs[(i, 0)];
    }
    model.offset -= g1;
    Ok(())
}

/// Scale factors of one record (record = s · normalised record).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Scaling {
    /// Input scale s_u (RMS of u; 1 when the basis cannot be rescaled).
    pub input: f64,
    /// Output scale s_y (standard deviation of y; 1 when the basis cannot be rescaled).
    pub output: f64,
    /// Input offset m taken out before the scaling (ũ = (u − m)/s_u; 0: none).
    pub input_shift: f64,
    /// Samples of the record (for the criterion's shift).
    pub samples: usize,
}

impl Scaling {
    /// The scales of a single-input single-output record for the settings' nonlinearity; an error
    /// for a constant output.
    pub fn of<T: Real>(settings: &Hammerstein<T>, data: &IoData<T>) -> Result<Self> {
        let u = data.input(0);
        let y = data.output(0);
        // constant to round-off (IoData's own rule; `cast` to f32 can make a record constant
        // that was not): nothing to identify
        if is_constant(data.y(), 0) {
            return Err(Error::ConstantOutput {
                name: data
                    .output_names()
                    .first()
                    .cloned()
                    .unwrap_or_else(|| "y".into()),
            });
        }
        let sd = super::iteration::problem::variance(&y).sqrt();
        let rms = rms(&u);
        let nl = settings.build_nonlinearity()?;
        let rescalable = nl.rescaled(T::one(), T::one()).is_some()
            && settings
                .output_map
                .as_ref()
                .is_none_or(|g| g.rescaled(T::one()).is_some());
        if !(rescalable && rms.is_finite() && rms > 0.0 && sd.is_finite() && sd > 0.0) {
            return Ok(Scaling {
                input: 1.0,
                output: 1.0,
                input_shift: 0.0,
                samples: y.len(),
            });
        }
        let input_shift = input_shift(settings, nl.as_ref(), &u);
        let input = if input_shift == 0.0 {
            rms
        } else {
            super::iteration::problem::variance(&u).sqrt()
        };
        Ok(Scaling {
            input,
            output: sd,
            input_shift,
            samples: y.len(),
        })
    }

    /// True when nothing is rescaled.
    pub fn is_identity(&self) -> bool {
        self.input == 1.0 && self.output == 1.0 && self.input_shift == 0.0
    }

    /// These scales without the input shift (the fit's fall-back when a model fitted on the
    /// shifted record cannot be mapped back).
    pub fn without_shift<T: Real>(&self, data: &IoData<T>) -> Self {
        if self.input_shift == 0.0 {
            return *self;
        }
        Scaling {
            input: rms(&data.input(0)),
            input_shift: 0.0,
            ..*self
        }
    }

    /// The normalised record ((u − m)/s_u, y/s_y), names and sample time kept.
    pub fn data<T: Real>(&self, data: &IoData<T>) -> Result<IoData<T>> {
        let (iu, iy) = (T::lit(1.0 / self.input), T::lit(1.0 / self.output));
        let u = data.u();
        let y = data.y();
        let (m, s) = (self.input_shift, self.input);
        let us = if m == 0.0 {
            Mat::from_fn(u.nrows(), u.ncols(), |i, j| u[(i, j)] * iu)
        } else {
            // the offset taken out in f64 (an f32 record keeps the digits it has)
            Mat::from_fn(u.nrows(), u.ncols(), |i, j| {
                T::lit((u[(i, j)].as_f64() - m) / s)
            })
        };
        let ys = Mat::from_fn(y.nrows(), y.ncols(), |i, j| y[(i, j)] * iy);
        IoData::with_names(
            us,
            ys,
            data.input_names().to_vec(),
            data.output_names().to_vec(),
        )?
        .with_sample_time(data.sample_time())
    }

    /// The settings for the normalised record: given initial parameters mapped to its units.
    pub fn settings<T: Real>(&self, settings: &Hammerstein<T>) -> Result<Hammerstein<T>> {
        let Init::Given(theta) = &settings.options().init else {
            return Ok(settings.clone());
        };
        let mut nl = settings.build_nonlinearity()?;
        let th: Vec<T> = theta.iter().map(|&t| T::lit(t)).collect();
        if nl.set_params(&th).is_err() {
            // the fit reports the inadmissible start in the caller's terms
            return Ok(settings.clone());
        }
        if self.input_shift != 0.0 {
            let Some((shifted, _)) = nl.input_shifted(T::lit(self.input_shift)) else {
                return Ok(settings.clone());
            };
            nl = shifted;
        }
        let Some(scaled) = nl.rescaled(T::lit(1.0 / self.input), T::lit(1.0 / self.output)) else {
            return Ok(settings.clone());
        };
        Ok(settings.clone().init(Init::Given(
            scaled.params().iter().map(|t| t.as_f64()).collect(),
        )))
    }

    /// The model fitted on the normalised record, in the record's units, with `settings` (the
    /// caller's, unnormalised) as its settings; `Err(ShiftRefused)` inside when the input's
    /// offset, taken out for the fit, cannot be carried back into it.
    pub fn unscale<T: Real>(
        &self,
        mut model: HammersteinModel<T>,
        settings: &Hammerstein<T>,
    ) -> Result<std::result::Result<HammersteinModel<T>, ShiftRefused>> {
        model.settings = settings.clone();
        if self.is_identity() {
            return Ok(Ok(model));
        }
        let (si, so) = (T::lit(self.input), T::lit(self.output));
        let nl_scaled = model.nl.clone_box();
        let rescale = |nl: &dyn StaticNonlinearity<T>, i: T, o: T| {
            nl.rescaled(i, o).ok_or_else(|| {
                Error::Identification(format!(
                    "the nonlinearity '{}' cannot be rescaled",
                    nl.name()
                ))
            })
        };
        // input units into the nonlinearity, output units into the linear block ...
        model.nl = rescale(nl_scaled.as_ref(), si, T::one())?;
        scale_block(&mut model, so);
        model.offset *= so;
        // the output map's input and output are both in the output's units: g ← s_y·g(·/s_y)
        if let Some(g) = model.output_map.take() {
            model.output_map = Some(g.rescaled(so).ok_or_else(|| {
                Error::Identification(format!("the output map '{}' cannot be rescaled", g.name()))
            })?);
        }
        // the input's offset back into the nonlinearity; the constant that leaves v with it
        // goes through the block into the output offset and the initial state
        if self.input_shift != 0.0 {
            let Some((nl, kappa)) = model.nl.input_shifted(T::lit(-self.input_shift)) else {
                return Ok(Err(ShiftRefused));
            };
            model.nl = nl;
            if let Err(refused) = shift_block_input(&mut model, -kappa, settings) {
                return Ok(Err(refused));
            }
        }
        // ... then the settings' normalisation moves the scale s between them: N ← s·N, G ← G/s
        let n = model.linear.order();
        let b: Vec<T> = (0..n).map(|i| model.linear.b[(i, 0)]).collect();
        let markov = markov_of(
            model.linear.a.as_ref(),
            &b,
            model.linear.c.as_ref(),
            model.linear.d[(0, 0)],
            markov_rows(settings.options.horizon, n),
        );
        if let Ok(s) = scale_for(settings.options.normalization, &model.nl.gains(), &markov)
            && s > T::zero()
            && s.is_finite()
            && s != T::one()
        {
            model.nl = rescale(model.nl.as_ref(), T::one(), s)?;
            // v ← s·v and B ← B/s leave the state's trajectory, hence x0, as it was
            let x0 = model.x0.clone();
            scale_block(&mut model, T::one() / s);
            model.x0 = x0;
        }
        self.unscale_report(&mut model.report, nl_scaled.as_ref());
        Ok(Ok(model))
    }

    /// MSEs and parameter histories of a report in the record's units (θ histories with the
    /// output scale in the nonlinearity, as the Markov normalisation has it).
    fn unscale_report<T: Real>(&self, report: &mut FitReport, nl: &dyn StaticNonlinearity<T>) {
        let v = self.output * self.output;
        report.train_mse *= v;
        let (si, so) = (T::lit(self.input), T::lit(self.output));
        let mut probe = nl.clone_box();
        let back = T::lit(-self.input_shift);
        for it in report.iterations.iter_mut() {
            it.mse *= v;
            let th: Vec<T> = it.params.iter().map(|&p| T::lit(p)).collect();
            if probe.set_params(&th).is_ok()
                && let Some(r) = probe.rescaled(si, so)
            {
                let r = if self.input_shift == 0.0 {
                    Some(r)
                } else {
                    r.input_shifted(back).map(|x| x.0)
                };
                if let Some(r) = r {
                    it.params = r.params().iter().map(|p| p.as_f64()).collect();
                }
            }
        }
        if let Some(b) = report.stabilised.as_mut() {
            b.train_mse *= v;
        }
        if let Some(r) = report.refinement.as_mut() {
            r.mse_before *= v;
            r.mse_after *= v;
        }
        let shift = v.ln();
        for c in report.order_selection.iter_mut() {
            c.train_mse *= v;
            c.criterion += shift * self.samples as f64;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::regressors::EffectSet;

    /// A block with a pole at 1 has no steady state to carry an input offset through: the shift
    /// back is refused (the fit then runs again unshifted), and leaves the model as it was.
    #[test]
    fn a_pole_at_one_cannot_carry_the_input_offset() {
        let u: Vec<f64> = (0..400)
            .map(|k| ((k * 37 % 101) as f64 / 50.0) - 1.0)
            .collect();
        let mut y = vec![0.0; u.len()];
        for k in 1..u.len() {
            y[k] = 0.6 * y[k - 1] + u[k - 1].clamp(-0.5, 0.7);
        }
        let data = IoData::siso(&u, &y).unwrap();
        let settings = Hammerstein::<f64>::udn(EffectSet::of(&[Effect::Saturation]))
            .order(crate::subspace::Order::Fixed(1));
        let mut model = settings.fit(&data).unwrap();
        let mut stuck = model.clone();
        stuck.linear.a[(0, 0)] = 1.0;
        let before = (stuck.offset, stuck.x0.clone());
        // the driver's fall-back is taken on exactly this refusal
        assert_eq!(
            shift_block_input(&mut stuck, 0.3, &settings),
            Err(ShiftRefused)
        );
        assert_eq!((stuck.offset, stuck.x0.clone()), before);
        // a stable block takes it: its steady output leaves the offset
        let offset = model.offset;
        shift_block_input(&mut model, 0.3, &settings).unwrap();
        assert!((model.offset - offset).abs() > 1e-3);
    }
}
