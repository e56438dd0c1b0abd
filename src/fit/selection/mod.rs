//! Choosing among fits: the order and feed-through candidates (`order_selection.rs`), fits
//! nested in a fitted model (`nested.rs`), the UDN fit held to the linear model it contains
//! (`linear_nested.rs`), long records fitted on a window and polished (`screening.rs`), and the
//! effect subsets ranked (`structure.rs`).

pub mod from_rest;
pub(crate) mod linear_nested;
pub(crate) mod nested;
pub mod order_selection;
pub(crate) mod screening;
pub(crate) mod structure;
