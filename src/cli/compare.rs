//! `hammerstein compare`: a saved model's simulated output against a measured record.

use super::common::{metrics_json, read_record};
use super::saved::Saved;
use hammerstein::diagnosis::{Metrics, compare, compare_miso};

/// The metrics of either kind of model.
struct Compared {
    metrics: Metrics,
}
use std::path::PathBuf;

/// Arguments of `hammerstein compare`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Model file written by `fit --save`.
    pub model: PathBuf,
    /// CSV file with a header row.
    pub data: PathBuf,
    /// Name of the input column, or its 1-based position when no column has that name (by
    /// default the one the model was fitted on when its file records it, else "u"; a
    /// several-input model: its own input names, or "u1,u2").
    #[arg(long, default_value = "u")]
    pub input: String,
    /// Name of the output column, or its 1-based position when no column has that name (by
    /// default the one the model was fitted on when its file records it, else "y").
    #[arg(long, default_value = "y")]
    pub output: String,
    /// Print a JSON object instead of text.
    #[arg(long)]
    pub json: bool,
    /// Keep every K-th sample of the record first, as `fit --decimate K` did (by default the
    /// factor the model file records, 1 when it records none: a model saved by the library's
    /// `save` after `IoData::decimate`).
    #[arg(long, value_parser = super::common::parse_factor, value_name = "K")]
    pub decimate: Option<usize>,
}

/// Runs the subcommand; errors are one-line messages.
pub fn run(args: Args) -> super::CliResult {
    if let Some(f) = super::feedback::read_saved(&args.model)? {
        return super::feedback::compare(&f, &args.data, &args.input, &args.output, args.json);
    }
    let saved = Saved::read(&args.model)?;
    let factor = args.decimate.unwrap_or(saved.decimation);
    let c = match saved.model {
        Saved::Several(model) => {
            // a several-input model: its own input names unless --input lists others
            let columns = super::common::miso_columns(model.input_names(), &args.input);
            let names: Vec<&str> = columns.iter().map(String::as_str).collect();
            let data = read_record::<f64>(&args.data, &names, &args.output)?;
            let data = super::common::decimated_as_fitted(data, factor, &args.data)?;
            let m = compare_miso(&model, &data)?;
            Metrics { ..m.metrics }
        }
        Saved::Single(model, recorded) => {
            let (input, output) =
                super::common::model_columns(recorded.as_ref(), &args.input, &args.output);
            let data = read_record::<f64>(&args.data, &[input.as_str()], &output)?;
            let data = super::common::decimated_as_fitted(data, factor, &args.data)?;
            compare(&model, &data)?.metrics
        }
    };
    let c = Compared { metrics: c };
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
