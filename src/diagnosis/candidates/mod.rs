//! The missing-effect candidates: typed size estimates (`estimate.rs`), whether the input can
//! identify an effect at all (`identifiability.rs`), the `MissingEffect` trait and the built-in
//! candidates (`candidate.rs`), a nonlinearity in feedback (`feedback_candidate.rs`), dynamic hysteresis (`pi_candidate.rs`, `pi_one_sign.rs`) and the
//! registry (`registry.rs`).

pub mod candidate;
pub mod estimate;
pub mod feedback_candidate;
pub mod identifiability;
pub mod pi_candidate;
pub(crate) mod pi_one_sign;
pub mod registry;
