//! The guided loop of `diagnose --follow`: fit, diagnose, take the top suggestion, refit
//! (`follow.rs`).

pub mod follow;
