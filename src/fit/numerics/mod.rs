//! Numerical pieces the loop and the refinement share: the B/D/x0 least squares and the block's
//! simulation, golden section, the jump and saturation-kink scans, the output offset of a basis
//! spanning the constant, the horizon a slow block asks for, and the rank-one factor.

pub(crate) mod golden;
pub(crate) mod jump_centre;
pub(crate) mod jump_scan;
pub(crate) mod kink_scan;
pub(crate) mod linear_ls;
pub(crate) mod offset_fold;
pub(crate) mod rank_one;
pub(crate) mod slow_horizon;
