//! The report of a several-input model: the first input's report (its residual tests and
//! order) with the whole model's output on both records and every other input's
//! nonlinearity. The command line and the Python package both write it.

use super::from_fit::{Context, report_input};
use super::input::{DiagnosisRow, Record, ReportInput};
use crate::data::IoData;
use crate::diagnosis::{MisoDiagnosis, compare_miso};
use crate::error::Result;
use crate::miso::MisoModel;
use crate::real::Real;

/// The [`ReportInput`] of `model` diagnosed as `d` on `train` and `val`, under `ctx` (title,
/// dataset, units, steps).
pub fn miso_report_input<T: Real>(
    model: &MisoModel<T>,
    d: &MisoDiagnosis<T>,
    train: &IoData<T>,
    val: &IoData<T>,
    ctx: Context,
) -> Result<ReportInput> {
    let branch_ctx = Context {
        title: String::new(),
        steps: Vec::new(),
        ..ctx.clone()
    };
    let mut input = report_input(&model.branches()[0], &d.inputs[0].diagnosis, ctx)?;
    let f = |s: &[T]| -> Vec<f64> { s.iter().map(|x| x.as_f64()).collect() };
    let tr = compare_miso(model, train)?;
    let va = compare_miso(model, val)?;
    input.train = Record::new(f(train.input_slice(0)), tr.y, tr.y_hat);
    input.validation = Some(Record::new(f(val.input_slice(0)), va.y, va.y_hat));
    input.referred_residual = None;
    for (i, b) in model.branches().iter().enumerate().skip(1) {
        let ri = report_input(b, &d.inputs[i].diagnosis, branch_ctx.clone())?;
        if let Some(nl) = ri.nonlinearity {
            let name = model.input_names()[i].clone();
            let unit = crate::units::unit_of(&name).unwrap_or_default();
            input.other_inputs.push((name, unit, nl));
        }
    }
    input.diagnosis_summary = d.summary.clone();
    input.diagnosis = d
        .suggestions
        .iter()
        .map(|s| DiagnosisRow {
            effect: format!("{}: {}", s.input, s.suggestion.effect),
            score: s.suggestion.score,
            evidence: s.suggestion.evidence.clone(),
            estimate: String::new(),
            validation_mse_after: s.suggestion.validation_mse_after,
        })
        .collect();
    input.notes.push(format!(
        "Several inputs ({}): one Hammerstein branch per input, their outputs summed; the \
         output plots show the whole model, the nonlinearity plots each input's branch; the \
         residual tests are those of the first input's branch (the residual is the whole \
         model's).",
        model.input_names().join(", ")
    ));
    Ok(input)
}
