//! Subcommands of the command line, one file each.

pub mod compare;
pub mod demo;
pub mod diagnose;
pub mod fit;
pub mod paper;
pub mod simulate;
pub mod subspace;
