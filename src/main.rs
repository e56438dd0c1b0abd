//! The `hammerstein` command line: identification, diagnosis and reports on CSV records.

mod cli;

use clap::{Parser, Subcommand};

/// Identify Hammerstein systems and find what a model still gets wrong.
#[derive(Parser, Debug)]
#[command(name = "hammerstein", version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Linear subspace identification (MOESP / N4SID) of a CSV record.
    Subspace(Box<cli::subspace::Args>),
    /// Fit a Hammerstein model (nonlinearity + linear block) to a CSV record.
    Fit(cli::fit::Args),
    /// Fit, analyse the residuals and name the physical effects the model is missing.
    Diagnose(cli::diagnose::Args),
    /// Compare a saved model with measured data.
    Compare(cli::compare::Args),
    /// Simulate a saved model on an input record.
    Simulate(cli::simulate::Args),
    /// The main job on built-in data: hidden effect, diagnosis, refit, report.
    Demo(cli::demo::Args),
    /// Reproduce the paper's Example 1 Monte Carlo study (Tables 2 and 3).
    Paper(cli::paper::Args),
    /// Design a random-phase multisine experiment (the record format, to replay on the plant).
    Design(cli::design::Args),
    /// Best linear approximation of multisine records: noise, distortion, nonlinearity verdict.
    Bla(cli::bla::Args),
    /// Structure verdict (linear, single-branch, parallel, feedback) from BLAs at several levels.
    Structure(cli::structure::Args),
}

fn main() {
    cli::single_allocator_arena();
    cli::ignore_file_size_signal();
    let cli = Cli::parse();
    let res = match cli.command {
        Command::Subspace(a) => cli::subspace::run(*a),
        Command::Fit(a) => cli::fit::run(a),
        Command::Diagnose(a) => cli::diagnose::run(a),
        Command::Compare(a) => cli::compare::run(a),
        Command::Simulate(a) => cli::simulate::run(a),
        Command::Demo(a) => cli::demo::run(a),
        Command::Paper(a) => cli::paper::run(a),
        Command::Design(a) => cli::design::run(a),
        Command::Bla(a) => cli::bla::run(a),
        Command::Structure(a) => cli::structure::run(a),
    };
    match res {
        Ok(()) => {}
        // standard output closed early (`… | head`): stop quietly with the status a process
        // killed by SIGPIPE has in the shell (128 + 13), as `cat`, `yes` or `seq` do
        Err(cli::Failure::Output(e)) if e.kind() == std::io::ErrorKind::BrokenPipe => {
            std::process::exit(EXIT_BROKEN_PIPE)
        }
        Err(e) => {
            cli::note(&format!("error: {e}"));
            std::process::exit(1);
        }
    }
}

/// Exit status when standard output is closed early: 128 + SIGPIPE (13).
const EXIT_BROKEN_PIPE: i32 = 141;
