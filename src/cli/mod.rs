//! Subcommands of the command line, one file each.

pub mod common;
pub mod compare;
pub mod demo;
pub mod diagnose;
pub mod fit;
pub mod paper;
pub mod simulate;
pub mod subspace;

/// Writes the HTML report of a model and its diagnosis into `dir` (the `--report` option).
pub fn write_model_report<T: hammerstein::Real>(
    dir: &std::path::Path,
    data: &std::path::Path,
    model: &hammerstein::hammerstein::HammersteinModel<T>,
    diagnosis: &hammerstein::diagnosis::Diagnosis,
    sample_time: f64,
) -> Result<(), String> {
    use hammerstein::report::{Context, Step, Units, report_input, write_report};
    let ctx = Context {
        title: format!("Hammerstein model of {}", data.display()),
        dataset: data.display().to_string(),
        units: Units {
            sample_time: (sample_time != 1.0).then_some(sample_time),
            ..Default::default()
        },
        steps: vec![Step {
            label: model.nonlinearity().name(),
            validation_mse: diagnosis.validation.metrics.mse,
            fit_percent: diagnosis.validation.metrics.fit_percent,
        }],
        ..Default::default()
    };
    let input = report_input(model, diagnosis, ctx).map_err(|e| e.to_string())?;
    let path = write_report(dir, &input).map_err(|e| e.to_string())?;
    eprintln!("report written to {}", path.display());
    Ok(())
}
