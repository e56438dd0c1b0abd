//! What `fit` and `diagnose` with several inputs (`--input u1,u2`) share: the settings from the
//! command line (one Hammerstein branch per input, each with its own effects, `--effects
//! u1:LIST`), the model's and the diagnosis' text and JSON, the report. The subcommands' own
//! several-input paths are `fit::run_miso` and `diagnose::run_miso`.

use super::common::{
    effects_text, error_text, fit_lines, input_spread, json_number, metrics_json, model_json, sci,
    value_text, value_text_resolving,
};
use crate::cli::Failure;
use hammerstein::diagnosis::{Metrics, MisoDiagnosis};
use hammerstein::miso::{MisoHammerstein, MisoModel};
use hammerstein::{IoData, Real};
use serde_json::{Value, json};

/// The several-input settings from the command line: each input's effects from
/// `--effects NAME:LIST`, the other options shared.
pub(super) fn settings<T: Real>(
    data: &super::common::DataArgs,
    model: &super::common::ModelArgs,
) -> Result<MisoHammerstein<T>, Failure> {
    let inputs = data.inputs();
    let sets = model.branch_effect_sets(&inputs)?;
    let branches = sets
        .into_iter()
        .map(|set| model.settings_with::<T>(set))
        .collect::<Result<Vec<_>, _>>()?;
    Ok(MisoHammerstein::new(branches))
}

/// "u1: saturation, order 2 | u2: linear, order 3".
pub(super) fn structure_text<T: Real>(model: &MisoModel<T>) -> String {
    model
        .input_names()
        .iter()
        .zip(model.branches())
        .map(|(n, b)| format!("{n}: {}, order {}", effects_text(b), b.linear().order()))
        .collect::<Vec<_>>()
        .join(" | ")
}

/// The top suggestion as a table cell.
pub(super) fn top_text<T: Real>(d: &MisoDiagnosis<T>) -> String {
    match d.suggestions.first() {
        Some(s) => format!(
            "{}: {} (score {:.2})",
            s.input, s.suggestion.effect, s.suggestion.score
        ),
        None if d.adequate => "none: residuals consistent with noise".into(),
        None => "none helps (residual tests still fail)".into(),
    }
}

pub(super) fn print_diagnosis<T: Real>(
    model: &MisoModel<T>,
    d: &MisoDiagnosis<T>,
) -> super::CliResult {
    outln!("model: {}", structure_text(model))?;
    outln!(
        "train:      fit {:6.2} %  MSE {}\nvalidation: fit {:6.2} %  MSE {}",
        d.train.fit_percent,
        sci(d.train.mse),
        d.validation.fit_percent,
        sci(d.validation.mse)
    )?;
    outln!("adequate: {}", if d.adequate { "yes" } else { "no" })?;
    if d.suggestions.is_empty() {
        outln!("no suggestion")?;
    } else {
        outln!("suggestions (best first; each names its input):")?;
    }
    for (k, s) in d.suggestions.iter().enumerate() {
        let g = &s.suggestion;
        outln!(
            "  {}. input {}: {}  score {:.3}  training MSE {} -> {}  validation MSE {} -> {}",
            k + 1,
            s.input,
            g.action.label(),
            g.score,
            sci(g.train_mse_before),
            sci(g.train_mse_after),
            sci(g.validation_mse_before),
            sci(g.validation_mse_after)
        )?;
        outln!("     evidence: {}", g.evidence)?;
    }
    for s in &d.outside_class {
        outln!(
            "  not in this model class: input {}: {} (a map after the sum of the branches)",
            s.input,
            s.suggestion.effect
        )?;
    }
    if !d.adequate && d.suggestions.is_empty() {
        for inp in &d.inputs {
            for u in &inp.diagnosis.unexplained {
                outln!(
                    "  unexplained on input {}: {} (p = {:.2e}); would need: {}",
                    inp.input,
                    u.test,
                    u.p_adjusted,
                    u.model_classes.join(", ")
                )?;
            }
        }
    }
    outln!("{}", d.summary)?;
    Ok(())
}

pub(super) fn diagnosis_json<T: Real>(
    model: &MisoModel<T>,
    d: &MisoDiagnosis<T>,
) -> Result<Value, Failure> {
    Ok(json!({
        "model": model_json_miso(model, &d.train, Some(&d.validation))?,
        "adequate": d.adequate,
        "summary": d.summary,
        "suggestions": serde_json::to_value(&d.suggestions).map_err(|e| e.to_string())?,
        "outside_class": serde_json::to_value(&d.outside_class).map_err(|e| e.to_string())?,
        "unexplained": d.inputs.iter().flat_map(|i| i.diagnosis.unexplained.iter().map(move |u| json!({
            "input": i.input, "test": u.test.to_string(), "p_adjusted": json_number(u.p_adjusted),
            "model_classes": u.model_classes,
        }))).collect::<Vec<_>>(),
        "train": metrics_json(&d.train),
        "validation": metrics_json(&d.validation),
    }))
}

/// The `fit --json` object of a several-input model.
pub(super) fn model_json_miso<T: Real>(
    model: &MisoModel<T>,
    train: &Metrics,
    validation: Option<&Metrics>,
) -> Result<Value, Failure> {
    let mut inputs = Vec::new();
    for (name, b) in model.input_names().iter().zip(model.branches()) {
        let mut j = model_json(b, train, None)?;
        if let Some(o) = j.as_object_mut() {
            o.remove("train");
            o.remove("validation");
            o.insert("input".into(), json!(name));
        }
        inputs.push(j);
    }
    let r = model.report();
    Ok(json!({
        "inputs": inputs,
        "output": model.output_name(),
        "order": model.order(),
        "output_offset": json_number(model.output_offset()),
        "sweeps": r.sweeps.iter().map(|s| json_number(s.train_mse)).collect::<Vec<_>>(),
        "converged": r.converged,
        "joint_refinement": r.joint_refinement.as_ref().map_or(Value::Null, |j| json!({
            "iterations": j.iterations,
            "mse_before": json_number(j.mse_before),
            "mse_after": json_number(j.mse_after),
            "accepted": j.accepted,
        })),
        "train": metrics_json(train),
        "validation": validation.map(metrics_json).unwrap_or(Value::Null),
    }))
}

/// Human-readable summary of a several-input model.
pub(super) fn model_text_miso<T: Real>(
    model: &MisoModel<T>,
    train: &Metrics,
    validation: Option<&Metrics>,
    record: &IoData<T>,
) -> String {
    let r = model.report();
    let joint = r.joint_refinement.as_ref().map_or_else(String::new, |j| {
        if j.accepted {
            format!(
                "; joint refinement: {}, training MSE {} -> {}",
                counted(j.iterations, "iteration"),
                value_text(j.mse_before),
                value_text(j.mse_after)
            )
        } else {
            format!(
                "; joint refinement: {}, not kept",
                counted(j.iterations, "iteration")
            )
        }
    });
    let mut s = format!(
        "inputs: {} (one Hammerstein branch per input, outputs summed; backfitting: {}, {}{joint})\n",
        model.input_names().join(", "),
        counted(r.sweeps.len(), "sweep"),
        if r.converged {
            "converged"
        } else {
            "sweep limit reached"
        }
    );
    for (j, (name, b)) in model.input_names().iter().zip(model.branches()).enumerate() {
        // each branch's parameters to 1e-4 of its own input's spread
        let spread = if j < record.n_inputs() {
            input_spread(record, j)
        } else {
            f64::NAN
        };
        s.push_str(&format!(
            "input {name}: {} (effects: {}), linear block order {}{}\n",
            b.nonlinearity().name(),
            effects_text(b),
            b.linear().order(),
            if b.delay() > 0 {
                format!(", delay {}", b.delay())
            } else {
                String::new()
            }
        ));
        for (k, v, se) in b.parameters_with_errors() {
            let pm = error_text(se);
            s.push_str(&format!(
                "  {k:>4} = {}{pm}\n",
                value_text_resolving(v, spread)
            ));
        }
        if let Some(from) = b.report().horizon_raised_from {
            s.push_str(&format!(
                "  horizon: {} (the default {from} raised: order {} needs a longer one; --horizon sets it)\n",
                b.settings().options().horizon,
                b.linear().order()
            ));
        }
        if let Ok(tf) = b.transfer_function() {
            let round = |x: &Vec<f64>| {
                x.iter()
                    .map(|x| (x * 1e6).round() / 1e6)
                    .collect::<Vec<_>>()
            };
            s.push_str(&format!(
                "  numerator   {:?}\n  denominator {:?}\n",
                round(&tf.numerator),
                round(&tf.denominator)
            ));
        }
        // the branch's block unstable, or held stable by --stable (as for one input)
        let lines = [
            super::common::unstable_text(b).ok().flatten(),
            super::common::stabilised_text(b),
        ];
        for line in lines.into_iter().flatten() {
            s.push_str(&format!("  {line}"));
        }
    }
    s.push_str(&format!(
        "output offset: {}\n",
        value_text(model.output_offset())
    ));
    s.push_str(&fit_lines(train, validation));
    s
}

/// The report of a several-input model: the first input's report (residual tests, order)
/// with the whole model's output and every input's nonlinearity.
pub(super) fn write_report<T: Real>(
    dir: &std::path::Path,
    data_path: &std::path::Path,
    model: &MisoModel<T>,
    d: &MisoDiagnosis<T>,
    train: &IoData<T>,
    val: &IoData<T>,
    what: &str,
) -> Result<(), Failure> {
    use hammerstein::report::{Context, miso_report_input, write_report};
    let title = format!(
        "Several-input Hammerstein model of {}{what}",
        data_path.display()
    );
    let ctx = Context {
        title,
        dataset: data_path.display().to_string(),
        units: super::common::units_of(train),
        ..Default::default()
    };
    let input = miso_report_input(model, d, train, val, ctx)?;
    let path = write_report(dir, &input)?;
    super::note(&format!("report written to {}", path.display()));
    Ok(())
}

/// "1 sweep", "4 sweeps": a count with its noun in the right number.
fn counted(n: usize, noun: &str) -> String {
    if n == 1 {
        format!("1 {noun}")
    } else {
        format!("{n} {noun}s")
    }
}
