//! Initial nonlinearity parameters before the first iteration (the paper's Step 1 leaves them open).
//!
//! `Quantiles` (default) uses the nonlinearity's own input-quantile rule; `Given` configures
//! the nonlinearity on the input as `Quantiles` does (a play grid), then sets θ;
//! `CoarseSearch` runs two iterations from several starts — the quantile start scaled by
//! 0.5, 0.75, 1, 1.25, 1.5 and four seeded random perturbations (each parameter × U[0.5, 1.5]) — and
//! keeps the start whose second iterate has the lowest MSE.

use super::problem::{Problem, Workspace};
use super::search::SearchWidths;
use crate::error::{Error, Result};
use crate::fit::settings::Init;
use crate::real::Real;
use crate::regressors::StaticNonlinearity;
use rand::{RngExt, SeedableRng, rngs::StdRng};

/// Scale factors of the coarse search's deterministic starts.
const COARSE_SCALES: [f64; 5] = [0.5, 0.75, 1.0, 1.25, 1.5];
/// Random starts of the coarse search.
const COARSE_RANDOM: usize = 4;
/// Iterations run from each coarse-search start.
const COARSE_ITERATIONS: usize = 2;

/// Sets the initial θ of `nl` according to the settings (the coarse search's trial passes use
/// `ws` and leave their search brackets in `widths`).
pub(crate) fn initialize<T: Real>(
    problem: &Problem<'_, T>,
    ws: &mut Workspace<T>,
    widths: &mut SearchWidths,
    nl: &mut dyn StaticNonlinearity<T>,
) -> Result<()> {
    match &problem.settings.options.init {
        Init::Quantiles => {
            nl.initialize(&problem.u);
            Ok(())
        }
        Init::Given(theta) => {
            let names = nl.param_names();
            if theta.len() != names.len() {
                return Err(Error::InvalidParameter(format!(
                    "initial parameters: {} given, '{}' has {} ({})",
                    theta.len(),
                    nl.name(),
                    names.len(),
                    names.join(", ")
                )));
            }
            // configured on the record as the default start is (a Prandtl–Ishlinskii grid is
            // fixed from the input), so that θ means what it means in a fitted model; then θ
            nl.initialize(&problem.u);
            let t: Vec<T> = theta.iter().map(|&x| T::lit(x)).collect();
            nl.set_params(&t)
        }
        Init::CoarseSearch => {
            nl.initialize(&problem.u);
            let theta0 = nl.params();
            let mut rng = StdRng::seed_from_u64(problem.settings.options.seed);
            let mut starts: Vec<Vec<T>> = COARSE_SCALES
                .iter()
                .map(|&f| theta0.iter().map(|&t| t * T::lit(f)).collect())
                .collect();
            for _ in 0..COARSE_RANDOM {
                starts.push(
                    theta0
                        .iter()
                        .map(|&t| t * T::lit(rng.random_range(0.5..1.5)))
                        .collect(),
                );
            }
            let mut best: Option<(f64, Vec<T>)> = None;
            for start in starts {
                let mut trial = nl.clone_box();
                if trial.set_params(&start).is_err() {
                    continue;
                }
                let mut order = None;
                let mut last = f64::INFINITY;
                for _ in 0..COARSE_ITERATIONS {
                    match problem.pass(ws, widths, trial.as_mut(), order, None) {
                        Ok((it, n, _)) => {
                            order = Some(n);
                            last = it.mse;
                        }
                        Err(_) => {
                            last = f64::INFINITY;
                            break;
                        }
                    }
                }
                if last.is_finite() && best.as_ref().is_none_or(|b| last < b.0) {
                    best = Some((last, start));
                }
            }
            if let Some((_, theta)) = best {
                nl.set_params(&theta)?;
            }
            Ok(())
        }
    }
}
