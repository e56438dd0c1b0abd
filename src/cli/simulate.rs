//! `hammerstein simulate`: a saved model's output for an input record (CSV out).

use super::saved::Saved;
use super::stability::{Stability, own_reference};
use hammerstein::data::CsvTable;
use hammerstein::miso::MisoModel;
use std::borrow::Cow;
use std::path::PathBuf;

/// Arguments of `hammerstein simulate`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Model file written by `fit --save`.
    pub model: PathBuf,
    /// CSV file with a header row holding the input column.
    pub input_file: PathBuf,
    /// Name of the input column, or its 1-based position when no column has that name (by
    /// default the one the model was fitted on when its file records it, else "u"; a
    /// several-input model: its own input names, or "u1,u2").
    #[arg(long, default_value = "u")]
    pub input: String,
    /// Write the CSV (columns u, y_hat) here instead of standard output.
    #[arg(long, value_name = "OUT.csv")]
    pub out: Option<PathBuf>,
    /// Keep every K-th sample of the record first, as `fit --decimate K` did (by default the
    /// factor the model file records, 1 when it records none: a model saved by the library's
    /// `save` after `IoData::decimate`).
    #[arg(long, value_parser = super::common::parse_factor, allow_negative_numbers = true, value_name = "K")]
    pub decimate: Option<usize>,
}

/// Runs the subcommand; errors are one-line messages. A constant input is allowed here (it is a
/// valid thing to simulate), unlike in the identification subcommands.
pub fn run(args: Args) -> super::CliResult {
    if let Some(p) = &args.out {
        super::paths::check_output_file(p, "--out", &[&args.model, &args.input_file])?;
    }
    if let Some(f) = super::feedback::read_saved(&args.model)? {
        return super::feedback::simulate(&f, &args.input_file, &args.input, args.out.as_deref());
    }
    let saved = Saved::read(&args.model)?;
    let factor = (args.decimate.unwrap_or(saved.decimation), saved.decimation);
    let (model, recorded) = match saved.model {
        Saved::Several(model) => return run_miso(&args, &model, factor),
        Saved::Single(model, recorded) => (model, recorded),
    };
    let (input, _) = super::common::model_columns(recorded.as_ref(), &args.input, "y");
    super::common::check_input_count(std::slice::from_ref(&input), 1)?;
    let table = CsvTable::read(&args.input_file)?;
    let u = picked_as_fitted(vec![table.column(&input)?], factor, &args)?.remove(0);
    // the header's name of a column given by position
    let input = table.names[table.index(&input)?].clone();
    if let Some(i) = u.iter().position(|x| !x.is_finite()) {
        return Err(format!("non-finite value (NaN or infinity) in {input} at sample {i}").into());
    }
    if u.len() < 2 {
        return Err(format!("not enough samples: 2 needed (simulation), got {}", u.len()).into());
    }
    let y = model.simulate(&u)?;
    if let Some(w) = Stability::of(&model, y.len(), Some((&y, own_reference(&y))), None).warning() {
        super::note(&w);
    }
    // what the fit found of the model's simulation from rest on its training record (the model
    // file carries it when it departs)
    let warning = super::common::from_rest_warning(
        model.report().departs_from_rest,
        "its fit on its training record (initial state estimated)",
    );
    if let Some(w) = warning {
        super::note(&w);
    }
    let mut s = format!("{input},y_hat\n");
    for (a, b) in u.iter().zip(&y) {
        s.push_str(&format!("{a},{b}\n"));
    }
    match &args.out {
        Some(p) => hammerstein::atomic::write_atomic(p, s.as_bytes())?,
        None => super::out(&s)?,
    }
    Ok(())
}

/// The input columns `cols` at the sample rate of `factor` = (the factor used, the one the
/// model file records): every factor-th sample (the fit took the input's samples unfiltered
/// too), said once on standard error; a factor that leaves fewer than two samples is refused.
fn picked_as_fitted<'a>(
    cols: Vec<&'a [f64]>,
    (factor, recorded): (usize, usize),
    args: &Args,
) -> Result<Vec<Cow<'a, [f64]>>, super::Failure> {
    if factor <= 1 {
        if let Some(w) = super::common::decimation_mismatch(factor, recorded) {
            super::note(&w);
        }
        return Ok(cols.into_iter().map(Cow::Borrowed).collect());
    }
    let n = cols.first().map_or(0, |c| c.len());
    if n.div_ceil(factor) < 2 {
        return Err(format!(
            "{}: decimating by {factor} leaves fewer than 2 of its {n} samples",
            args.input_file.display()
        )
        .into());
    }
    let picked: Vec<Cow<'a, [f64]>> = cols
        .into_iter()
        .map(|c| Cow::Owned(hammerstein::decimation::pick(c, factor)))
        .collect();
    super::note(&format!(
        "note: {} decimated by {factor}, {}: every {factor}th input sample simulated ({} of \
         {n}), the output at the model's sample rate",
        args.input_file.display(),
        super::common::decimation_source(factor, recorded),
        n.div_ceil(factor)
    ));
    if let Some(w) = super::common::decimation_mismatch(factor, recorded) {
        super::note(&w);
    }
    Ok(picked)
}

/// `simulate` of a several-input model: its inputs read by name (the model's own unless
/// `--input` lists others), the CSV columns the inputs and `y_hat`.
fn run_miso(args: &Args, model: &MisoModel<f64>, factor: (usize, usize)) -> super::CliResult {
    let names = super::common::miso_columns(model.input_names(), &args.input);
    super::common::check_input_count(&names, model.input_names().len())?;
    let table = CsvTable::read(&args.input_file)?;
    let cols = names
        .iter()
        .map(|n| table.column(n))
        .collect::<Result<Vec<_>, _>>()?;
    let cols = picked_as_fitted(cols, factor, args)?;
    // the header's names of columns given by position
    let names = table.names_of(&names.iter().map(String::as_str).collect::<Vec<_>>())?;
    let n = cols.first().map_or(0, |c| c.len());
    for (name, c) in names.iter().zip(&cols) {
        if let Some(i) = c.iter().position(|x| !x.is_finite()) {
            return Err(
                format!("non-finite value (NaN or infinity) in {name} at sample {i}").into(),
            );
        }
    }
    if n < 2 {
        return Err(format!("not enough samples: 2 needed (simulation), got {n}").into());
    }
    let u = hammerstein::faer::Mat::from_fn(n, cols.len(), |k, j| cols[j][k]);
    let y = model.simulate(u.as_ref())?;
    if let Some(w) =
        Stability::of_miso(model, y.len(), Some((&y, own_reference(&y))), None).warning()
    {
        super::note(&w);
    }
    let mut s = format!("{},y_hat\n", names.join(","));
    for k in 0..n {
        let row: Vec<String> = cols.iter().map(|c| c[k].to_string()).collect();
        s.push_str(&format!("{},{}\n", row.join(","), y[k]));
    }
    match &args.out {
        Some(p) => hammerstein::atomic::write_atomic(p, s.as_bytes())?,
        None => super::out(&s)?,
    }
    Ok(())
}
