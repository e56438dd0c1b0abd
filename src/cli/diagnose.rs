//! `hammerstein diagnose`.

/// Arguments of `hammerstein diagnose`.
#[derive(clap::Args, Debug)]
pub struct Args {}

/// Runs the subcommand; errors are one-line messages.
pub fn run(_args: Args) -> Result<(), String> {
    Err("`diagnose` is not implemented yet".into())
}
