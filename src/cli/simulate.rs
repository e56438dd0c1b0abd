//! `hammerstein simulate`.

/// Arguments of `hammerstein simulate`.
#[derive(clap::Args, Debug)]
pub struct Args {}

/// Runs the subcommand; errors are one-line messages.
pub fn run(_args: Args) -> Result<(), String> {
    Err("`simulate` is not implemented yet".into())
}
