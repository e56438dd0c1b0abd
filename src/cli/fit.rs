//! `hammerstein fit`: fit a Hammerstein model to a CSV record and print it (text or JSON).

use super::common::{DataArgs, ModelArgs, Precision, input_spread, model_json, model_text};
use super::miso::{model_json_miso, model_text_miso};
use crate::cli::Failure;
use hammerstein::Real;
use hammerstein::diagnosis::{Diagnoser, compare, compare_miso};
use std::path::PathBuf;

/// The spinner's message while `--report` diagnoses the model (every candidate refitted).
pub const REPORT_STAGE: &str = "diagnosing the residuals for the report (every candidate refitted)";

/// Arguments of `hammerstein fit`.
#[derive(clap::Args, Debug)]
pub struct Args {
    #[command(flatten)]
    pub data: DataArgs,
    #[command(flatten)]
    pub model: ModelArgs,
    /// Save the fitted model as JSON.
    #[arg(long, value_name = "MODEL.json")]
    pub save: Option<PathBuf>,
    /// Write an HTML report with plots into this directory.
    #[arg(long, value_name = "DIR")]
    pub report: Option<PathBuf>,
    /// Print a JSON object instead of text.
    #[arg(long)]
    pub json: bool,
    #[command(flatten)]
    pub feedback: super::feedback::FeedbackArgs,
}

/// Runs the subcommand; errors are one-line messages.
pub fn run(args: Args) -> super::CliResult {
    let precision = args.model.precision()?;
    check_outputs(&args)?;
    // columns given by position (--input, --output, --effects NAME:LIST) are read by their
    // header names from here on
    let args = Args {
        data: args.data.resolved(),
        model: args
            .model
            .resolved(&args.data.data)?
            .with_decimation_resolved(&args.data)?,
        ..args
    };
    if let Some(kind) = &args.feedback.feedback_nonlinearity {
        let (save, json) = (args.save.as_deref(), args.json);
        let out = super::feedback::Outputs {
            save,
            report: args.report.as_deref(),
        };
        return super::feedback::fit(&args.data, &args.model, &args.feedback, kind, out, json);
    }
    match precision {
        Precision::F32 => run_t::<f32>(&args),
        Precision::F64 => run_t::<f64>(&args),
    }
}

/// Refuses unwritable outputs and outputs over inputs before the fit starts.
fn check_outputs(args: &Args) -> Result<(), Failure> {
    let mut inputs: Vec<&std::path::Path> = vec![&args.data.data];
    if let Some(v) = &args.model.validation_file {
        inputs.push(v);
    }
    if let Some(p) = &args.save {
        super::paths::check_output_file(p, "--save", &inputs)?;
    }
    if let Some(d) = &args.report {
        super::paths::check_output_dir(d, "--report", &inputs)?;
    }
    Ok(())
}

fn run_t<T: Real>(args: &Args) -> super::CliResult {
    if args.data.inputs().len() > 1 {
        return run_miso::<T>(args);
    }
    let settings = args.model.settings::<T>(&args.data.input, &[])?;
    let (train, val) = args.model.load::<T>(&args.data, None)?;
    if let Some(w) = super::common::anchored_warning(&settings, &train, &args.data.input) {
        eprintln!("{w}");
    }
    let pb = super::spinner("fitting (order selection and refinement)");
    let model = settings.fit(&train)?;
    pb.finish_and_clear();
    let tc = compare(&model, &train)?;
    let vc = match &val {
        Some(v) => Some(compare(&model, v)?),
        None => None,
    };
    if let Some(path) = &args.save {
        // the column names travel with the model: `compare` and `simulate` read them by
        // default; and the decimation, which they apply to their records
        let mut file = model.to_file_with_columns(&args.data.input, &args.data.output);
        file.decimation = recorded_decimation(&args.model);
        file.write(path)?;
    }
    if let Some(dir) = &args.report {
        // the report shows the residual tests: diagnose on the validation record (or the
        // training record when there is none)
        let v = val.as_ref().unwrap_or(&train);
        // every candidate is refitted: on a long record this takes longer than the fit
        let pb = super::spinner(REPORT_STAGE);
        let observer = super::ProgressObserver::new(&pb, "fit --report");
        hammerstein::fit::Observer::progress(observer.as_ref(), REPORT_STAGE, 0, 1);
        let d = Diagnoser::new().diagnose_observed(&model, &train, v, observer.as_ref());
        pb.finish_and_clear();
        let d = d?;
        super::write_model_report(dir, &args.data.data, &model, &d, &train)?;
    }
    // the decimation the block's band allows, on top of the record's own (`None`: not worth it)
    let suggested = args.model.suggested_decimation(model.linear(), train.len());
    // a model whose simulation from rest does not mean what its fit means is said
    let departure = hammerstein::fit::from_rest::departure(&model, &train);
    if let Some(w) = super::common::from_rest_warning(
        departure,
        "its fit on the training record (initial state estimated)",
    ) {
        super::note(&w);
    }
    if args.json {
        let mut j = model_json(&model, &tc.metrics, vc.as_ref().map(|c| &c.metrics))?;
        j["from_rest"] = super::common::from_rest_json(departure);
        j["decimation"] = serde_json::json!(args.model.decimation());
        j["suggested_decimation"] = serde_json::json!(suggested);
        outln!("{j}")?;
    } else {
        outp!(
            "{}",
            args.model.decimation_line(train.len(), train.sample_time())
        )?;
        outp!(
            "{}",
            model_text(
                &model,
                &tc.metrics,
                vc.as_ref().map(|c| &c.metrics),
                input_spread(&train, 0)
            )?
        )?;
        outp!("{}", args.model.oversampled_line(suggested))?;
    }
    Ok(())
}

/// The decimation a model file records (`None` when the record was not decimated, so that
/// the file is the one earlier builds read).
fn recorded_decimation(model: &ModelArgs) -> Option<usize> {
    Some(model.decimation()).filter(|&k| k > 1)
}

/// `fit --input u1,u2`.
fn run_miso<T: Real>(args: &Args) -> super::CliResult {
    let settings = super::miso::settings::<T>(&args.data, &args.model)?;
    let (train, val) = args.model.load::<T>(&args.data, None)?;
    let pb = super::spinner("fitting one branch per input (backfitting)");
    let model = settings.fit(&train)?;
    pb.finish_and_clear();
    let tc = compare_miso(&model, &train)?.metrics;
    let vc = match &val {
        Some(v) => Some(compare_miso(&model, v)?.metrics),
        None => None,
    };
    if let Some(path) = &args.save {
        let mut file = model.to_file();
        file.decimation = recorded_decimation(&args.model);
        file.write(path)?;
    }
    if let Some(dir) = &args.report {
        let v = val.as_ref().unwrap_or(&train);
        let pb = super::spinner(REPORT_STAGE);
        let observer = super::ProgressObserver::new(&pb, "fit --report");
        hammerstein::fit::Observer::progress(observer.as_ref(), REPORT_STAGE, 0, 1);
        let d = Diagnoser::new().diagnose_miso(&model, &train, v);
        pb.finish_and_clear();
        let d = d?;
        super::miso::write_report(dir, &args.data.data, &model, &d, &train, v, "")?;
    }
    let suggested = args.model.suggested_decimation_miso(&model, train.len());
    if args.json {
        let mut j = model_json_miso(&model, &tc, vc.as_ref())?;
        j["decimation"] = serde_json::json!(args.model.decimation());
        j["suggested_decimation"] = serde_json::json!(suggested);
        outln!("{j}")?;
    } else {
        outp!(
            "{}",
            args.model.decimation_line(train.len(), train.sample_time())
        )?;
        outp!("{}", model_text_miso(&model, &tc, vc.as_ref(), &train))?;
        outp!("{}", args.model.oversampled_line(suggested))?;
    }
    Ok(())
}
