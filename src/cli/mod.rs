//! Subcommands of the command line, one file each.

pub mod common;
pub mod compare;
pub mod demo;
pub mod diagnose;
pub mod fit;
pub mod paper;
pub mod simulate;
pub mod subspace;

/// Writes the HTML report of a diagnosed model (`diagnose --report DIR`); returns its path.
pub fn write_diagnosis_report<T: hammerstein::Real>(
    dir: &std::path::Path,
    model: &hammerstein::hammerstein::HammersteinModel<T>,
    diagnosis: &hammerstein::diagnosis::Diagnosis,
    data: &std::path::Path,
    sample_time: f64,
) -> Result<std::path::PathBuf, String> {
    use hammerstein::report::{Context, Units, report_input, write_report};
    let ctx = Context {
        title: format!("hammerstein diagnose: {}", data.display()),
        dataset: data.display().to_string(),
        units: Units {
            sample_time: (sample_time > 0.0 && sample_time != 1.0).then_some(sample_time),
            ..Units::default()
        },
        ..Context::default()
    };
    let input = report_input(model, diagnosis, ctx).map_err(|e| e.to_string())?;
    write_report(dir, &input).map_err(|e| e.to_string())
}

/// The `--report` option of subcommands that have no report yet.
pub fn report_unavailable(dir: &std::path::Path) -> Result<(), String> {
    Err(format!(
        "--report {}: the HTML report module is not available in this build yet",
        dir.display()
    ))
}
