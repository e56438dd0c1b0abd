//! Whether a branch's horizon stands raised: the default horizon a fitted branch reports as
//! raised (`FitReport::horizon_raised_from`), decided from the branch as it finished.
//!
//! A branch's final model comes from its first fit (which raises the default horizon for a
//! fixed order it cannot hold, 8 → 2n), a warm refit (`Hammerstein::at_structure_of`: the
//! horizon raised just enough for the order, 8 → n + 1, and then held as a chosen one) or a
//! complete refit; a warm refit copies its base's report. So the report it ends with can
//! describe another fit than the one it finished with: a refit at a horizon the user chose
//! said "raised from 8" (copied from the base), a refit whose default was raised for the
//! base's order said nothing. The claim is therefore decided once, at the end, from the
//! horizon the branch finished with.

use crate::fit::{Hammerstein, HammersteinModel};
use crate::real::Real;
use crate::subspace::max_order;

/// What a base model's branch said about its horizon: the horizon it was fitted at and the
/// default it reported raised (`None` when it reported none).
pub(super) type BaseClaim = Option<(usize, usize)>;

/// The base branch `m`'s claim (its horizon and the default it stands raised from).
pub(super) fn base_claim<T: Real>(m: &HammersteinModel<T>) -> BaseClaim {
    m.report()
        .horizon_raised_from
        .map(|from| (m.settings().options().horizon, from))
}

/// The default horizon `fitted` stands raised from, for a branch fitted with the settings
/// `requested` from a base whose branch claimed `base`: the requested horizon when it was
/// left at its default, or — when the horizon was given — the base's default when the given
/// horizon is the very one the base stood raised at (a refit from a model's own settings, as
/// `diagnose --follow` does); in either case only when the branch finished at a longer horizon
/// and the default cannot hold its order. `None` otherwise: nothing was raised.
pub(super) fn raised_from<T: Real>(
    requested: &Hammerstein<T>,
    base: BaseClaim,
    fitted: &HammersteinModel<T>,
) -> Option<usize> {
    let h = fitted.settings().options().horizon;
    let from = if requested.horizon_given() {
        // raised by the crate for these settings (`Hammerstein::raise_horizon`), or the base's
        requested.horizon_raised_from.or_else(|| {
            base.filter(|&(at, _)| at == requested.options().horizon && at == h)
                .map(|(_, from)| from)
        })
    } else {
        Some(requested.options().horizon)
    };
    let n = fitted.linear().order();
    from.filter(|&f| h > f && max_order(f, 1) < n)
}
