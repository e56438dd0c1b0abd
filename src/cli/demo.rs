//! `hammerstein demo`.

/// Arguments of `hammerstein demo`.
#[derive(clap::Args, Debug)]
pub struct Args {}

/// Runs the subcommand; errors are one-line messages.
pub fn run(_args: Args) -> Result<(), String> {
    Err("`demo` is not implemented yet".into())
}
