//! `hammerstein compare`.

/// Arguments of `hammerstein compare`.
#[derive(clap::Args, Debug)]
pub struct Args {}

/// Runs the subcommand; errors are one-line messages.
pub fn run(_args: Args) -> Result<(), String> {
    Err("`compare` is not implemented yet".into())
}
