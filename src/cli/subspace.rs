//! `hammerstein subspace`.

/// Arguments of `hammerstein subspace`.
#[derive(clap::Args, Debug)]
pub struct Args {}

/// Runs the subcommand; errors are one-line messages.
pub fn run(_args: Args) -> Result<(), String> {
    Err("`subspace` is not implemented yet".into())
}
