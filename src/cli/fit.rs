//! `hammerstein fit`.

/// Arguments of `hammerstein fit`.
#[derive(clap::Args, Debug)]
pub struct Args {}

/// Runs the subcommand; errors are one-line messages.
pub fn run(_args: Args) -> Result<(), String> {
    Err("`fit` is not implemented yet".into())
}
