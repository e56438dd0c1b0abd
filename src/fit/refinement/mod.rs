//! The output-error refinement after the loop: Levenberg–Marquardt on all parameters
//! (`refine.rs`), several branches jointly (`joint_refine.rs`), the jump positions centred
//! (`centring.rs`), the stability constraint (`stability.rs`), the output map's fit
//! (`output_fit.rs`) and the linear output read block by block (`linear_output.rs`).

pub(crate) mod centring;
pub(crate) mod joint_refine;
pub(crate) mod linear_output;
pub(crate) mod output_fit;
pub(crate) mod refine;
pub(crate) mod stability;
