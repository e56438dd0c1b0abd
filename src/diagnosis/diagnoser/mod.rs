//! The diagnosis: whether a model carries over to the validation part (`generalisation.rs`),
//! what a diagnosis returns (`outcome.rs`), the diagnosis on whole records (`whole.rs`) and on
//! long records screened on a window (`screen.rs`), and the `Diagnoser` (`diagnose.rs`).

pub mod diagnose;
pub mod generalisation;
pub mod outcome;
pub mod screen;
pub(crate) mod whole;
