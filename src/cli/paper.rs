//! `hammerstein paper`.

/// Arguments of `hammerstein paper`.
#[derive(clap::Args, Debug)]
pub struct Args {}

/// Runs the subcommand; errors are one-line messages.
pub fn run(_args: Args) -> Result<(), String> {
    Err("`paper` is not implemented yet".into())
}
