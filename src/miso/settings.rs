//! Settings of a several-input fit: one single-input settings per input, the sweep limit and
//! tolerance.

use crate::error::{Error, Result};
use crate::fit::Hammerstein;
use crate::real::Real;

/// Sweeps over the branches after which the backfitting stops (a guard: the tolerance ends them).
pub const DEFAULT_MAX_SWEEPS: usize = 50;
/// Relative fall of the total training MSE over one sweep below which the backfitting stops.
pub const DEFAULT_SWEEP_TOLERANCE: f64 = 1e-4;

/// Settings of a several-input Hammerstein fit: the settings of each input's branch.
#[derive(Debug, Clone)]
pub struct MisoHammerstein<T: Real> {
    pub(crate) branches: Vec<Hammerstein<T>>,
    pub(crate) max_sweeps: usize,
    pub(crate) tolerance: f64,
    /// Whether the sweeps are followed by the joint refinement of all branches.
    pub(crate) joint: bool,
}

impl<T: Real> MisoHammerstein<T> {
    /// Settings with one branch per input, in the record's input order. Each branch's settings
    /// (nonlinearity, order, delay, horizon, method, refinement, …) apply to its input; the
    /// output offset is estimated once, by the first branch (as the first branch's settings say).
    pub fn new(branches: Vec<Hammerstein<T>>) -> Self {
        Self {
            branches,
            max_sweeps: DEFAULT_MAX_SWEEPS,
            tolerance: DEFAULT_SWEEP_TOLERANCE,
            joint: true,
        }
    }

    /// Sets the sweep limit.
    pub fn max_sweeps(mut self, n: usize) -> Self {
        self.max_sweeps = n;
        self
    }

    /// Sets the relative MSE fall per sweep below which the sweeps stop.
    pub fn tolerance(mut self, t: f64) -> Self {
        self.tolerance = t;
        self
    }

    /// Sets whether the sweeps are followed by a joint Levenberg–Marquardt refinement of all
    /// branches' parameters on the total output error (on by default; it runs when every
    /// branch's settings refine).
    pub fn joint_refinement(mut self, on: bool) -> Self {
        self.joint = on;
        self
    }

    /// The branches' settings, one per input.
    pub fn branches(&self) -> &[Hammerstein<T>] {
        &self.branches
    }

    /// The settings of branch `i` as it is fitted: its own, with the output offset only on the
    /// first branch (one offset for the sum).
    pub fn branch_settings(&self, i: usize) -> Option<Hammerstein<T>> {
        let first_offset = self.branches.first()?.options().offset;
        let mut s = self.branches.get(i)?.clone();
        // the partial residuals change from sweep to sweep: no linear check per branch
        s.linear_check = false;
        Some(s.offset(i == 0 && first_offset))
    }

    /// Checks the settings: at least one branch, every branch valid and without an output map
    /// (a map after the sum is not part of this model class), a sweep limit ≥ 1, a finite
    /// non-negative tolerance.
    pub fn validate(&self) -> Result<()> {
        if self.branches.is_empty() {
            return Err(Error::InvalidParameter(
                "a several-input fit needs one branch per input; none given".into(),
            ));
        }
        for (i, b) in self.branches.iter().enumerate() {
            b.validate()?;
            if b.output_map().is_some() {
                return Err(Error::InvalidParameter(format!(
                    "input {}: an output nonlinearity is not supported with several inputs \
                     (the map would act on one branch, not on the sum)",
                    i + 1
                )));
            }
        }
        if self.max_sweeps == 0 {
            return Err(Error::InvalidParameter(
                "max_sweeps must be at least 1".into(),
            ));
        }
        if !(self.tolerance.is_finite() && self.tolerance >= 0.0) {
            return Err(Error::InvalidParameter(format!(
                "sweep tolerance {} is not a finite non-negative number",
                self.tolerance
            )));
        }
        Ok(())
    }
}
