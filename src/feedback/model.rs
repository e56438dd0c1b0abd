//! The fitted feedback model (a nonlinear LFR, or Lur'e system):
//!
//! x(k+1) = A x(k) + B (u(k) + u₀) + E w(k),  y(k) = C x(k) + D u(k) + y₀,
//! w(k) = f(z(k)),  z(k) = C x(k) (`output`), C x(k) − C x(k−1) (`velocity`) or F x(k)
//! (`state`, F estimated). With an input nonlinearity N (Hammerstein with feedback) the block
//! takes v(k) = N(u(k)) in place of u(k), in B and D alike. With an output map g (the
//! Wiener side) y(k) = g(C x(k) + D v(k)) + y₀; z stays the linear block's own output C x,
//! before the map: the loop acts on the physical signal the map only measures.
//!
//! z is the noise-free output without its feed-through and offset, or its first difference;
//! w never reaches y or z in the same sample, so the loop is never algebraic. The model lives
//! in the units of a normalised record (input and output divided by their RMS, the scales kept
//! beside it); [`FeedbackModel::simulate`] takes and returns the record's own units.

use super::FeedbackOn;
use crate::error::{Error, Result};
use crate::regressors::{OutputMap, StaticNonlinearity};
use faer::Mat;

/// A linear block with a static nonlinearity in feedback.
#[derive(Debug, Clone)]
pub struct FeedbackModel {
    pub(crate) a: Mat<f64>,
    pub(crate) b: Vec<f64>,
    pub(crate) c: Vec<f64>,
    pub(crate) d: f64,
    pub(crate) e: Vec<f64>,
    pub(crate) f: Box<dyn StaticNonlinearity<f64>>,
    /// The viscous term c_v of `velocity` feedback: w = f(z) + c_v z (zero for `output`,
    /// where A holds any linear feedback; the velocity's previous output is a state A lacks).
    pub(crate) viscous: f64,
    pub(crate) on: FeedbackOn,
    /// F of `state` feedback, z = F x (n values; empty otherwise). Its scale is the one f
    /// absorbs: the fit sets it so that z has the RMS of C x on the training record.
    pub(crate) fz: Vec<f64>,
    /// The input nonlinearity before the loop (Hammerstein with feedback): the linear block
    /// takes v = N(u) (u normalised) where it would take u; `None`: v = u.
    pub(crate) input: Option<Box<dyn StaticNonlinearity<f64>>>,
    /// The output map g after the linear block (normalised units, unit slope and zero value
    /// at 0 as every built-in map): y = g(C x + D v) + y₀; `None`: y = C x + D v + y₀.
    pub(crate) output: Option<Box<dyn OutputMap<f64>>>,
    pub(crate) with_d: bool,
    /// Input offset u₀ (normalised units).
    pub(crate) u_offset: f64,
    /// Output offset y₀ (normalised units).
    pub(crate) y_offset: f64,
    /// The record's input scale (model input = u / u_scale).
    pub(crate) u_scale: f64,
    /// The record's output scale (model output = y / y_scale).
    pub(crate) y_scale: f64,
    /// The initial state estimated on the training record (n, plus C x(−1) for `velocity`).
    pub(crate) x0: Vec<f64>,
    /// The range of z visited on the training record (normalised units).
    pub(crate) z_range: (f64, f64),
}

impl FeedbackModel {
    /// The order n of the linear block.
    pub fn order(&self) -> usize {
        self.b.len()
    }
    /// The length of the full initial state (n, plus one for `velocity`: C x(−1)).
    pub fn state_len(&self) -> usize {
        self.order() + usize::from(self.on == FeedbackOn::Velocity)
    }
    /// What z is.
    pub fn feedback_on(&self) -> FeedbackOn {
        self.on
    }
    /// F of `state` feedback (z = F x, in the linear block's state coordinates; `None` for
    /// `output` and `velocity`).
    pub fn state_combination(&self) -> Option<&[f64]> {
        (self.on == FeedbackOn::State).then_some(self.fz.as_slice())
    }
    /// The input nonlinearity N before the loop (acting on the normalised input u / u_scale),
    /// `None` for a loop on a linear block alone.
    pub fn input_nonlinearity(&self) -> Option<&dyn StaticNonlinearity<f64>> {
        self.input.as_deref()
    }
    /// The output map g after the linear block (acting on the normalised linear output C x +
    /// D v), `None` without one.
    pub fn output_map(&self) -> Option<&dyn OutputMap<f64>> {
        self.output.as_deref()
    }
    /// The nonlinearity f (acting on normalised z; see [`eval_physical`](Self::eval_physical)).
    pub fn nonlinearity(&self) -> &dyn StaticNonlinearity<f64> {
        self.f.as_ref()
    }
    /// The linear block (A, [B E], C, [D 0]) in normalised units.
    pub fn linear(&self) -> Result<crate::StateSpace<f64>> {
        let n = self.order();
        crate::StateSpace::new(
            self.a.clone(),
            Mat::from_fn(n, 2, |i, j| if j == 0 { self.b[i] } else { self.e[i] }),
            Mat::from_fn(1, n, |_, j| self.c[j]),
            Mat::from_fn(1, 2, |_, j| if j == 0 { self.d } else { 0.0 }),
        )
    }
    /// The initial state estimated on the training record.
    pub fn training_x0(&self) -> &[f64] {
        &self.x0
    }
    /// The range of z the training record visited, in the output's units (per sample for
    /// `velocity`; for `state`, z = F x scaled to the RMS of C x).
    pub fn z_range(&self) -> (f64, f64) {
        (self.z_range.0 * self.y_scale, self.z_range.1 * self.y_scale)
    }
    /// f over z in the record's units: z in the output's units, w as the input that would act
    /// the same way (E is normalised so that w and u have the same static gain to y).
    pub fn eval_physical(&self, z: &[f64]) -> Vec<f64> {
        let zs: Vec<f64> = z.iter().map(|v| v / self.y_scale).collect();
        self.f
            .eval(&zs)
            .into_iter()
            .map(|w| w * self.u_scale)
            .collect()
    }
    /// Simulates the model on the input `u` (record units) from the initial state `x0`
    /// (normalised units, [`state_len`](Self::state_len) values; `None`: zero). Errors with
    /// [`Error::Diverged`] when the loop blows up.
    pub fn simulate(&self, u: &[f64], x0: Option<&[f64]>) -> Result<Vec<f64>> {
        let us: Vec<f64> = u.iter().map(|v| v / self.u_scale).collect();
        let zero = vec![0.0; self.state_len()];
        let x0 = x0.unwrap_or(&zero);
        if x0.len() != self.state_len() {
            return Err(Error::LengthMismatch {
                what: format!(
                    "initial state: the feedback model has {} states, got {}",
                    self.state_len(),
                    x0.len()
                ),
            });
        }
        let y = super::simulate::run(self, &us, x0, None)?;
        Ok(y.into_iter().map(|v| v * self.y_scale).collect())
    }

    /// Scales E by `alpha` and f's gains by 1/`alpha` (the same loop).
    pub(crate) fn rescale_e(&mut self, alpha: f64) -> Result<()> {
        if !(alpha.is_finite() && alpha != 0.0) {
            return Ok(());
        }
        let g: Vec<f64> = self.f.gains().iter().map(|g| g / alpha).collect();
        self.f.update_from_gains(&g, &[])?;
        self.viscous /= alpha;
        self.e.iter_mut().for_each(|e| *e *= alpha);
        Ok(())
    }

    /// Normalises E so that w reaches y with the static gain of u (w is then an equivalent
    /// input: a force where u is a force); kept as is when either gain is zero or undefined.
    pub(crate) fn normalise_e(&mut self) -> Result<()> {
        let n = self.order();
        // (I − A)⁻¹ [B E] by a dense solve
        let ima = Mat::from_fn(n, n, |i, j| f64::from(i == j) - self.a[(i, j)]);
        let rhs = Mat::from_fn(n, 2, |i, j| if j == 0 { self.b[i] } else { self.e[i] });
        let sol = crate::solvers::LinAlg::solve(
            &crate::solvers::Faer::default(),
            ima.as_ref(),
            rhs.as_ref(),
        )?;
        let gain = |j: usize| (0..n).map(|i| self.c[i] * sol[(i, j)]).sum::<f64>();
        let (gu, ge) = (gain(0), gain(1));
        if gu.is_finite() && ge.is_finite() && gu.abs() > 1e-12 && ge.abs() > 1e-12 {
            self.rescale_e(gu / ge)?;
        }
        Ok(())
    }
}
