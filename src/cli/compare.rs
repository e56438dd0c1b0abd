//! `hammerstein compare`: a saved model's simulated output against a measured record.

use super::common::{metrics_json, read_record};
use super::saved::Saved;
use super::stability::{Stability, spread};
use hammerstein::Error;
use hammerstein::diagnosis::{compare, compare_miso};
use serde_json::json;
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
    #[arg(long, value_parser = super::common::parse_factor, allow_negative_numbers = true, value_name = "K")]
    pub decimate: Option<usize>,
}

/// Runs the subcommand; errors are one-line messages. A model whose simulation diverges is
/// said on standard error and its fit % left out (null in JSON), not printed as a number.
pub fn run(args: Args) -> super::CliResult {
    if let Some(f) = super::feedback::read_saved(&args.model)? {
        return super::feedback::compare(&f, &args.data, &args.input, &args.output, args.json);
    }
    let saved = Saved::read(&args.model)?;
    let factor = args.decimate.unwrap_or(saved.decimation);
    let recorded = saved.decimation;
    // how far the simulation from rest departs from this comparison's (a one-input model)
    let mut departure = None;
    let (metrics, stability) = match saved.model {
        Saved::Several(model) => {
            // a several-input model: its own input names unless --input lists others
            let columns = super::common::miso_columns(model.input_names(), &args.input);
            super::common::check_input_count(&columns, model.input_names().len())?;
            let names: Vec<&str> = columns.iter().map(String::as_str).collect();
            let data = read_record::<f64>(&args.data, &names, &args.output)?;
            let data = super::common::decimated_as_fitted(data, factor, recorded, &args.data)?;
            match compare_miso(&model, &data) {
                Ok(m) => {
                    let reference = Some((m.y_hat.as_slice(), spread(&m.y)));
                    let st = Stability::of_miso(&model, data.len(), reference, None);
                    (Some(m.metrics), st)
                }
                Err(Error::Diverged { index, .. }) => (
                    None,
                    Stability::of_miso(&model, data.len(), None, Some(index)),
                ),
                Err(e) => return Err(e.into()),
            }
        }
        Saved::Single(model, recorded_columns) => {
            let (input, output) =
                super::common::model_columns(recorded_columns.as_ref(), &args.input, &args.output);
            super::common::check_input_count(std::slice::from_ref(&input), 1)?;
            let data = read_record::<f64>(&args.data, &[input.as_str()], &output)?;
            let data = super::common::decimated_as_fitted(data, factor, recorded, &args.data)?;
            match compare(&model, &data) {
                Ok(c) => {
                    let reference = Some((c.y_hat.as_slice(), spread(&c.y)));
                    let st = Stability::of(&model, data.len(), reference, None);
                    if !st.diverges {
                        departure = model.simulate(&c.u).ok().and_then(|rest| {
                            hammerstein::fit::from_rest::departure_between(
                                &model, &c.y, &rest, &c.y_hat,
                            )
                        });
                    }
                    (Some(c.metrics), st)
                }
                Err(Error::Diverged { index, .. }) => {
                    (None, Stability::of(&model, data.len(), None, Some(index)))
                }
                Err(e) => return Err(e.into()),
            }
        }
    };
    if let Some(w) = stability.warning() {
        super::note(&w);
    }
    if let Some(w) = super::common::from_rest_warning(
        departure,
        "its fit on this record (initial state estimated)",
    ) {
        super::note(&w);
    }
    // a diverged simulation's numbers mean nothing: none are printed
    let metrics = metrics.filter(|_| !stability.diverges);
    if let Some(m) = &metrics
        && !m.fit_percent.is_finite()
    {
        return Err(format!(
            "the fit % is undefined on {} (NRMSE {}): the measured output has no variation to \
             compare against",
            args.data.display(),
            m.nrmse
        )
        .into());
    }
    if args.json {
        let mut j = match &metrics {
            Some(m) => metrics_json(m),
            None => json!({"mse": null, "fit_percent": null, "nrmse": null}),
        };
        j["n"] = json!(stability.n);
        j["stability"] = stability.json();
        j["from_rest"] = super::common::from_rest_json(departure);
        outln!("{j}")?;
    } else {
        match &metrics {
            Some(m) => outln!(
                "{} samples: fit {:.2} %  MSE {}  NRMSE {:.4}",
                m.n,
                m.fit_percent,
                super::common::sci(m.mse),
                m.nrmse
            )?,
            None => outln!(
                "{} samples: no fit % (the simulation diverges: spectral radius {:.6})",
                stability.n,
                stability.spectral_radius
            )?,
        }
    }
    Ok(())
}
