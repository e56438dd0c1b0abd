//! The commands of the multisine experiment: `design` writes the excitation, `bla` estimates the
//! best linear approximation of the measured record, `structure` gives the structure verdict;
//! `records.rs` reads the record format they share.

pub mod bla;
pub mod design;
pub mod records;
pub mod structure;
