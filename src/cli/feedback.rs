//! The feedback-model paths of `fit`, `compare` and `simulate` (`--feedback-nonlinearity`, a
//! model file of kind "feedback"): the hooks in those subcommands' files call these.

use super::common::{DataArgs, ModelArgs};
use crate::cli::Failure;
use hammerstein::feedback::{
    self, FeedbackKind, FeedbackModel, FeedbackModelFile, FeedbackOn, FeedbackSettings,
};
use hammerstein::fit::Feedthrough;
use std::path::Path;

/// The options of a feedback model (`fit`).
#[derive(clap::Args, Debug, Clone)]
pub struct FeedbackArgs {
    /// Fit a linear block with this static nonlinearity in feedback instead of a Hammerstein
    /// model: poly3 (z³), poly5 (z³ + z⁵), coulomb (smoothed sign), dead-zone, saturation or
    /// pwl:K (K linear segments). --effects/--nonlinearity put an input nonlinearity before the
    /// loop, --output-nonlinearity a map after it.
    #[arg(long, value_name = "KIND")]
    pub feedback_nonlinearity: Option<String>,
    /// What the feedback nonlinearity acts on: output (stiffness), velocity (the output's
    /// first difference: friction) or state (a combination z = F x of the linear block's
    /// states, F estimated by the fit).
    #[arg(long, default_value = "output", value_name = "VARIABLE")]
    pub feedback_on: String,
}

/// Where `fit --feedback-nonlinearity` writes: the model file and the report directory.
pub struct Outputs<'a> {
    /// `--save`.
    pub save: Option<&'a Path>,
    /// `--report`.
    pub report: Option<&'a Path>,
}

/// `fit --feedback-nonlinearity`: fits, prints, saves, writes the report.
pub fn fit(
    data: &DataArgs,
    model: &ModelArgs,
    fb: &FeedbackArgs,
    kind: &str,
    out: Outputs<'_>,
    json: bool,
) -> super::CliResult {
    let save = out.save;
    if data.inputs().len() != 1 {
        return Err("a feedback model has one input: give one --input column".into());
    }
    let kind: FeedbackKind = kind.parse()?;
    let on: FeedbackOn = fb.feedback_on.parse()?;
    let mut s = FeedbackSettings::new(kind, on);
    // an input nonlinearity before the loop (Hammerstein with feedback)
    if !model.effects.is_empty() || model.nonlinearity.is_some() {
        s.input = Some(
            model
                .settings::<f64>(&data.input, &[])?
                .build_nonlinearity()?,
        );
    }
    // an output map after the loop (the linear output C x + D v measured through it)
    if let Some(name) = &model.output_nonlinearity {
        s.output = Some(hammerstein::regressors::output_map_from_name::<f64>(name)?);
    }
    s.order = model.order.parse()?;
    if let Some(h) = model.horizon {
        s.horizon = h;
    }
    s.with_d = matches!(
        model.feedthrough.parse::<Feedthrough>()?,
        Feedthrough::Present
    );
    let (train, val) = model.load::<f64>(data, None)?;
    let pb = super::spinner("fitting the feedback model (linear start, then the refinement)");
    let fit = feedback::fit(&s, &train);
    pb.finish_and_clear();
    let fit = fit?;
    for w in &fit.warnings {
        super::note(&format!("warning: {w}"));
    }
    // a model that diverges on the validation record is said, not returned silently
    let vc = match &val {
        Some(v) => Some(fit.model.compare(v)?),
        None => None,
    };
    if let Some(path) = save {
        let mut file = fit.model.to_file();
        file.columns = Some((data.input.clone(), data.output.clone()));
        let dec = model.decimation();
        file.decimation = (dec > 1).then_some(dec);
        file.write(path)?;
    }
    if let Some(dir) = out.report {
        write_report(
            dir,
            &data.data,
            &fit.model,
            &train,
            val.as_ref(),
            vc.as_ref(),
        )?;
    }
    let m = &fit.model;
    let (lo, hi) = m.z_range();
    if json {
        let j = serde_json::json!({
            "kind": "feedback",
            "nonlinearity": m.nonlinearity().name(),
            "feedback_on": on.name(),
            "order": m.order(),
            "linear_rms": fit.linear_rms,
            "start_rms": fit.start_rms,
            "train_rms": fit.rms,
            "validation_rms": vc.as_ref().map(|c| c.rms),
            "validation_fit_percent": vc.as_ref().map(|c| c.fit_percent),
            "iterations": fit.refine.iterations,
            "refused_diverging_steps": fit.refine.diverged_steps,
            "z_range": [lo, hi],
            "state_combination": m.state_combination(),
            "input_nonlinearity": m.input_nonlinearity().map(|nl| nl.name()),
            "output_nonlinearity": m.output_map().map(|g| g.name()),
            "warnings": fit.warnings,
        });
        outln!("{j}")?;
    } else {
        outln!(
            "feedback model: order {} linear block, {} on the {} (z visited [{lo:.4e}, {hi:.4e}])",
            m.order(),
            m.nonlinearity().name(),
            on.variable()
        )?;
        if let Some(nl) = m.input_nonlinearity() {
            outln!(
                "  input nonlinearity before the loop: {} ({})",
                nl.name(),
                nl.param_names()
                    .iter()
                    .zip(nl.params())
                    .map(|(n, p)| format!("{n} = {p:.4e}"))
                    .collect::<Vec<_>>()
                    .join(", ")
            )?;
        }
        if let Some(g) = m.output_map() {
            outln!(
                "  output map after the loop: {} ({}; on the linear output in normalised units)",
                g.name(),
                g.param_names()
                    .iter()
                    .zip(g.params())
                    .map(|(n, p)| format!("{n} = {p:.4e}"))
                    .collect::<Vec<_>>()
                    .join(", ")
            )?;
        }
        if let Some(f) = m.state_combination() {
            let f: Vec<String> = f.iter().map(|v| format!("{v:.4e}")).collect();
            outln!(
                "  F = [{}] (the linear block's state coordinates; z scaled to the RMS of C x)",
                f.join(", ")
            )?;
        }
        outln!(
            "  training RMS error: linear {:.4e}, start {}, refined {:.4e} ({} steps, {} diverging steps refused)",
            fit.linear_rms,
            fit.start_rms
                .map_or("diverged".into(), |r| format!("{r:.4e}")),
            fit.rms,
            fit.refine.iterations,
            fit.refine.diverged_steps
        )?;
        if let Some(c) = &vc {
            outln!(
                "  validation ({} samples, x0 estimated): RMS error {:.4e}, fit {:.2} %",
                c.simulated.len(),
                c.rms,
                c.fit_percent
            )?;
        }
        let z = [lo, 0.5 * lo, 0.5 * hi, hi];
        let w = m.eval_physical(&z);
        let pairs: Vec<String> = z
            .iter()
            .zip(&w)
            .map(|(z, w)| format!("f({z:.3e}) = {w:.3e}"))
            .collect();
        outln!("  f in input units: {}", pairs.join(", "))?;
    }
    Ok(())
}

/// The feedback model saved at `path`, `None` when the file is of another kind (then the
/// caller reads it as before).
pub fn read_saved(path: &Path) -> Result<Option<FeedbackModelFile>, Failure> {
    let Ok(text) = std::fs::read_to_string(path) else {
        return Ok(None); // the caller's reader reports it
    };
    let Ok(value) = serde_json::from_str::<serde_json::Value>(&text) else {
        return Ok(None);
    };
    if !FeedbackModelFile::is_feedback_value(&value) {
        return Ok(None);
    }
    let file = FeedbackModelFile::from_value(value).map_err(|e| match e {
        hammerstein::Error::ModelFormat(m) => {
            hammerstein::Error::ModelFormat(format!("{}: {m}", path.display()))
        }
        e => e,
    })?;
    Ok(Some(file))
}

fn rebuild(file: &FeedbackModelFile) -> Result<FeedbackModel, Failure> {
    Ok(FeedbackModel::from_file(file, |spec| {
        Err(hammerstein::Error::ModelFormat(format!(
            "unknown feedback nonlinearity kind '{}'",
            spec.kind
        )))
    })?)
}

fn columns(file: &FeedbackModelFile, input: &str, output: &str) -> (String, String) {
    match &file.columns {
        Some((i, o)) => (
            if input == "u" {
                i.clone()
            } else {
                input.to_string()
            },
            if output == "y" {
                o.clone()
            } else {
                output.to_string()
            },
        ),
        None => (input.to_string(), output.to_string()),
    }
}

/// `compare` of a feedback model: x0 estimated on the record, RMS error and fit.
pub fn compare(
    file: &FeedbackModelFile,
    data: &Path,
    input: &str,
    output: &str,
    json: bool,
) -> super::CliResult {
    let model = rebuild(file)?;
    let (i, o) = columns(file, input, output);
    let rec = super::common::read_record::<f64>(&data.to_path_buf(), &[i.as_str()], &o)?;
    let rec = {
        let k = file.decimation.unwrap_or(1);
        super::common::decimated_as_fitted(rec, k, k, data)
    }?;
    let c = model.compare(&rec)?;
    if json {
        outln!(
            "{}",
            serde_json::json!({"n": c.simulated.len(), "rms": c.rms, "fit_percent": c.fit_percent})
        )?;
    } else {
        outln!(
            "{} samples: fit {:.2} %  RMS error {:.4e}  MSE {:.4e}",
            c.simulated.len(),
            c.fit_percent,
            c.rms,
            c.rms * c.rms
        )?;
    }
    Ok(())
}

/// `simulate` of a feedback model from rest (zero state): the CSV columns input and `y_hat`.
pub fn simulate(
    file: &FeedbackModelFile,
    input_file: &Path,
    input: &str,
    out: Option<&Path>,
) -> super::CliResult {
    let model = rebuild(file)?;
    let (i, _) = columns(file, input, "y");
    let table = hammerstein::CsvTable::read(input_file)?;
    let mut u = table.column(&i)?.to_vec();
    let factor = file.decimation.unwrap_or(1);
    if factor > 1 {
        u = hammerstein::decimation::pick(&u, factor);
    }
    if let Some(k) = u.iter().position(|x| !x.is_finite()) {
        return Err(format!("non-finite value (NaN or infinity) in {i} at sample {k}").into());
    }
    let y = model.simulate(&u, None).map_err(|e| match e {
        hammerstein::Error::Diverged { index, .. } => Failure::Message(format!(
            "the feedback model's simulation diverges at sample {index}: the loop is unstable at this input's \
             amplitude; no output written"
        )),
        e => e.into(),
    })?;
    let mut s = format!("{i},y_hat\n");
    for (a, b) in u.iter().zip(&y) {
        s.push_str(&format!("{a},{b}\n"));
    }
    match out {
        Some(p) => hammerstein::atomic::write_atomic(p, s.as_bytes())?,
        None => super::out(&s)?,
    }
    Ok(())
}

/// The report of a feedback fit: the output against the measurement (training and validation)
/// and f(z) over the visited range with its uncertainty band.
fn write_report(
    dir: &Path,
    data: &Path,
    m: &FeedbackModel,
    train: &hammerstein::IoData<f64>,
    val: Option<&hammerstein::IoData<f64>>,
    vc: Option<&feedback::FeedbackComparison>,
) -> Result<(), Failure> {
    use hammerstein::report::{FeedbackCurve, OutputMapCurve, Record, ReportInput, write_report};
    let tc = m.compare(train)?;
    let band = m.nonlinearity_band(train, 200)?;
    // the output map over the linear output the training record visits (as for a
    // Hammerstein–Wiener model)
    let output_map = match m.output_map() {
        Some(g) => {
            let lin = m.linear_output(&train.input(0), Some(&tc.x0))?;
            let (lo, hi) = lin
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
                    (a.min(v), b.max(v))
                });
            let pad = 0.05 * (hi - lo).max(f64::MIN_POSITIVE);
            let grid: Vec<f64> = (0..=200)
                .map(|i| lo - pad + (hi - lo + 2.0 * pad) * f64::from(i) / 200.0)
                .collect();
            let c = m.output_offset();
            let y_grid = m
                .eval_output(&grid)
                .unwrap_or_default()
                .into_iter()
                .map(|v| v + c)
                .collect();
            Some(OutputMapCurve {
                name: g.name(),
                x_grid: grid,
                y_grid,
                data_x: lin,
                data_y: train.output(0),
            })
        }
        None => None,
    };
    let input = ReportInput {
        title: format!("Feedback model of {}", data.display()),
        dataset: data.display().to_string(),
        units: super::common::units_of(train),
        train: Record::new(train.input(0), train.output(0), tc.simulated),
        validation: val
            .zip(vc)
            .map(|(v, c)| Record::new(v.input(0), v.output(0), c.simulated.clone())),
        feedback: Some(FeedbackCurve {
            name: format!(
                "{} on the {}",
                m.nonlinearity().name(),
                m.feedback_on().variable()
            ),
            z_grid: band.z,
            w: band.w,
            se: band.se,
            data_z: band.data_z,
            method: "Method: the covariance σ²(JᵀJ)⁺ of all parameters (J the exact output \
                     sensitivities on the training record, the pseudo-inverse dropping the \
                     directions the full state-space parametrisation does not identify), its block \
                     of f's coefficients propagated to f(z) by the delta method."
                .into(),
        }),
        output_map,
        ..Default::default()
    };
    let path = write_report(dir, &input)?;
    super::note(&format!("report written to {}", path.display()));
    Ok(())
}
