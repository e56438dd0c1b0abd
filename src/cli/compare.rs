//! `hammerstein compare`: a saved model's simulated output against a measured record.

use super::common::{metrics_json, read_record};
use hammerstein::diagnosis::compare;
use hammerstein::fit::HammersteinModel;
use std::path::PathBuf;

/// Arguments of `hammerstein compare`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Model file written by `fit --save`.
    pub model: PathBuf,
    /// CSV file with a header row.
    pub data: PathBuf,
    /// Name of the input column.
    #[arg(long, default_value = "u")]
    pub input: String,
    /// Name of the output column.
    #[arg(long, default_value = "y")]
    pub output: String,
    /// Print a JSON object instead of text.
    #[arg(long)]
    pub json: bool,
}

/// Runs the subcommand; errors are one-line messages.
pub fn run(args: Args) -> super::CliResult {
    let model = HammersteinModel::<f64>::load(&args.model)?;
    let data = read_record::<f64>(&args.data, &args.input, &args.output)?;
    let c = compare(&model, &data)?;
    if !c.metrics.fit_percent.is_finite() {
        return Err(format!(
            "the fit % is undefined on {} (NRMSE {}): the measured output has no variation to \
             compare against",
            args.data.display(),
            c.metrics.nrmse
        )
        .into());
    }
    if args.json {
        let mut j = metrics_json(&c.metrics);
        j["n"] = serde_json::json!(c.metrics.n);
        outln!("{j}")?;
    } else {
        outln!(
            "{} samples: fit {:.2} %  MSE {}  NRMSE {:.4}",
            c.metrics.n,
            c.metrics.fit_percent,
            super::common::sci(c.metrics.mse),
            c.metrics.nrmse
        )?;
    }
    Ok(())
}
