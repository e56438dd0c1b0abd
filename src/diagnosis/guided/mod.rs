//! The guided loop of `diagnose --follow`: fit, diagnose, take the top suggestion, refit
//! (`follow.rs`, its options `follow_options.rs`); each step confirmed on a held-back part of
//! the training record before it is taken (`confirm.rs`); and the check of the model it ends with: null parts dropped, effects the
//! input cannot identify refused, a step that trains worse than its base not taken
//! (`final_check.rs`).

pub mod confirm;
pub mod final_check;
pub mod follow;
pub mod follow_options;
