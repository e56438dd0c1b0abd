//! The last step of a fit: a global step over the jump parameters (`jump_scan.rs`: restarts
//! from their order statistics, where the jumps matter to the record) and the saturation limits
//! (`kink_scan.rs`: restarts at other clipped shares, where the residual says a limit is
//! misplaced), then the jump parameters
//! moved to where the training record leaves them most likely (`jump_centre.rs`; on the profile
//! over the other parameters where a jump matters, else the block held and the free response
//! and offset refitted: `refine::centre_jumps`).
//!
//! Done once on the fit's final model (the order selection's candidates are compared before it:
//! the move changes a training MSE by less than 3.84/N relative, far below the criterion's
//! ln N per parameter), and only with the refinement on (`--no-refine` is the paper's loop).

use super::refine::{centre_jumps, scan_restarts};
use crate::data::IoData;
use crate::error::Result;
use crate::fit::HammersteinModel;
use crate::fit::iteration::problem::{Iterate, Problem, adopt_iterate};
use crate::fit::numerics::jump_scan::SCAN_ROUNDS;
use crate::fit::settings::Hammerstein;
use crate::real::Real;

/// `model` (fitted to `data` with `settings`) restarted over its jump and kink parameters and
/// with its jump parameters centred; the model unchanged when it has neither, the refinement is
/// off, or nothing moved.
pub(crate) fn centred<T: Real>(
    settings: &Hammerstein<T>,
    data: &IoData<T>,
    mut model: HammersteinModel<T>,
) -> Result<HammersteinModel<T>> {
    if !settings.options.refine
        || (model.nl.jump_params().is_empty() && model.nl.kink_params().is_empty())
    {
        return Ok(model);
    }
    // the model's own settings: the order and feed-through the selection chose
    let settings = &model.settings.clone();
    let la = settings.linalg_backend()?;
    let method = settings.subspace_at(settings.options.horizon)?;
    let problem = Problem::new(la.as_ref(), method.as_ref(), settings, data);
    // a global step over the jump and kink parameters first (`jump_scan.rs`, `kink_scan.rs`),
    // then the jumps' centring
    let mut it = Iterate::of_model(&model, model.report.train_mse);
    let mut rescanned = false;
    for _ in 0..SCAN_ROUNDS {
        match scan_restarts(&problem, model.nl.as_ref(), &it) {
            Some(better) => {
                it = better;
                rescanned = true;
            }
            None => break,
        }
    }
    let theta = model.nl.params();
    let moved = centre_jumps(&problem, model.nl.as_ref(), it);
    if !rescanned && moved.theta == theta {
        return Ok(model);
    }
    adopt_iterate(&problem, &mut model, moved, data.sample_time())?;
    Ok(model)
}
