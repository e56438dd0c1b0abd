//! The commands of the multisine experiment: `design` writes the excitation, `bla` estimates the
//! best linear approximation of the measured record, `structure` gives the structure verdict;
//! `records.rs` reads the record format they share; `diagnose_hook.rs` gives `diagnose` the
//! structure verdict of a record in that format.

pub mod bla;
pub mod design;
pub mod diagnose_hook;
pub mod records;
pub mod structure;
