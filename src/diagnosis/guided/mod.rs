//! The guided loop of `diagnose --follow`: fit, diagnose, take the top suggestion, refit
//! (`follow.rs`), and the check of the model it ends with: null parts dropped, effects the
//! input cannot identify refused, a step that trains worse than its base not taken
//! (`final_check.rs`).

pub mod final_check;
pub mod follow;
