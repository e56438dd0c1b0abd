//! Subcommands of the command line, one file each.

pub mod common;
pub mod compare;
pub mod demo;
pub mod diagnose;
pub mod fit;
pub mod paper;
pub mod simulate;
pub mod subspace;

/// The `--report` option until the report module's `write_report` is merged.
pub fn report_unavailable(dir: &std::path::Path) -> Result<(), String> {
    Err(format!(
        "--report {}: the HTML report module is not available in this build yet",
        dir.display()
    ))
}
