//! `hammerstein diagnose`: fit, analyse the residuals, and name the physical effects the model is
//! missing, each checked by a refit (text table or JSON).

use super::common::{
    DataArgs, ModelArgs, Precision, effects_text, input_spread, json_number, metrics_json,
    model_json, model_text, top_suggestion_text,
};
use super::experiment::diagnose_hook::StructureBeside;
use hammerstein::Real;
use hammerstein::diagnosis::feedback_model::{
    FeedbackStep, diagnose_feedback, feedback_step, suggests_feedback,
};
use hammerstein::diagnosis::{Diagnoser, Diagnosis, FollowStep, FollowStop};
use serde_json::{Value, json};
use std::path::PathBuf;

/// Arguments of `hammerstein diagnose`.
#[derive(clap::Args, Debug)]
pub struct Args {
    #[command(flatten)]
    pub data: DataArgs,
    #[command(flatten)]
    pub model: ModelArgs,
    /// Add an effect to the model before diagnosing (repeatable): the one flag that takes a
    /// suggestion on board ("--add-effect hysteresis"); same as extending --effects.
    #[arg(long = "add-effect", value_name = "EFFECT")]
    pub add_effect: Vec<String>,
    /// Write an HTML report with plots into this directory.
    #[arg(long, value_name = "DIR")]
    pub report: Option<PathBuf>,
    /// Print a JSON object instead of text.
    #[arg(long)]
    pub json: bool,
    /// Follow the top suggestion (add the effect, raise the order, add a delay, …) and refit,
    /// until the residuals are consistent with noise or nothing helps; prints every step.
    #[arg(long)]
    pub follow: bool,
    /// Most steps --follow takes.
    #[arg(long, value_parser = super::common::parse_count, allow_negative_numbers = true, default_value_t = 6, value_name = "N")]
    pub max_steps: usize,
    /// Save the diagnosed model as JSON (with --follow: the model the guided loop ends with,
    /// after its final check); `compare` and `simulate` read it.
    #[arg(long, value_name = "MODEL.json")]
    pub save: Option<PathBuf>,
    /// With --follow: stop after the step in progress once this many seconds have passed; the
    /// last model is kept (and reported, as every step).
    #[arg(long, value_name = "SECONDS", value_parser = positive_seconds)]
    pub time_budget: Option<f64>,
    /// With --follow: take every step the training criterion chooses, without confirming it on
    /// the held-back quarters of the training part.
    #[arg(long)]
    pub no_confirm: bool,
    #[command(flatten)]
    pub feedback: super::feedback::FeedbackArgs,
}

/// Writes `model` to `--save`'s file (the columns and the decimation with it, as `fit --save`).
fn save_model<T: Real>(args: &Args, model: &hammerstein::HammersteinModel<T>) -> super::CliResult {
    if let Some(path) = &args.save {
        let mut file = model.to_file_with_columns(&args.data.input, &args.data.output);
        file.decimation = Some(args.model.decimation()).filter(|&k| k > 1);
        file.write(path)?;
    }
    Ok(())
}

/// A time budget in seconds: a finite positive number.
fn positive_seconds(s: &str) -> Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(x) if x.is_finite() && x > 0.0 && x < 1e9 => Ok(x),
        Ok(_) => Err(format!("'{s}' is not a positive number of seconds")),
        Err(_) => Err(format!("'{s}' is not a number of seconds")),
    }
}

/// Validation fraction used when neither --validate nor --validation-file is given.
pub const DEFAULT_VALIDATION_FRACTION: f64 = 0.3;

/// Runs the subcommand; errors are one-line messages.
pub fn run(args: Args) -> super::CliResult {
    let precision = args.model.precision()?;
    if let Some(d) = &args.report {
        let mut inputs: Vec<&std::path::Path> = vec![&args.data.data];
        if let Some(v) = &args.model.validation_file {
            inputs.push(v);
        }
        super::paths::check_output_dir(d, "--report", &inputs)?;
    }
    if let Some(p) = &args.save {
        let mut inputs: Vec<&std::path::Path> = vec![&args.data.data];
        if let Some(v) = &args.model.validation_file {
            inputs.push(v);
        }
        super::paths::check_output_file(p, "--save", &inputs)?;
    }
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
    match precision {
        Precision::F32 => run_t::<f32>(&args),
        Precision::F64 => run_t::<f64>(&args),
    }
}

fn run_t<T: Real>(args: &Args) -> super::CliResult {
    if let Some(kind) = &args.feedback.feedback_nonlinearity {
        return run_feedback(args, kind);
    }
    if args.data.inputs().len() > 1 {
        return run_miso::<T>(args);
    }
    let settings = args
        .model
        .settings::<T>(&args.data.input, &args.add_effect)?;
    let pb = super::spinner("reading the record");
    // long records report their stages (reading, window fit, polish, screening, re-checks) on
    // the spinner
    let observer = super::ProgressObserver::new(&pb, "diagnose");
    hammerstein::fit::Observer::progress(observer.as_ref(), "reading the record", 0, 1);
    // a record in the record format: its structure verdict, and its highest level fitted
    let hook = super::experiment::diagnose_hook::read(
        &args.data.data,
        &args.data.input,
        &args.data.output,
    );
    let loaded = hook.and_then(|beside| {
        let loaded = match &beside {
            Some(b) => b
                .data::<T>(&args.data.input, &args.data.output)
                .and_then(|all| {
                    args.model
                        .load_from(all, &args.data, Some(DEFAULT_VALIDATION_FRACTION))
                }),
            None => args
                .model
                .load::<T>(&args.data, Some(DEFAULT_VALIDATION_FRACTION)),
        };
        loaded.map(|(t, v)| (t, v, beside))
    });
    let (train, val, beside) = match loaded {
        Ok(x) => x,
        Err(e) => {
            pb.finish_and_clear();
            return Err(e);
        }
    };
    let Some(val) = val else {
        pb.finish_and_clear();
        return Err("diagnose needs validation data".into());
    };
    if let Some(w) = super::common::anchored_warning(&settings, &train, &args.data.input) {
        pb.suspend(|| eprintln!("{w}"));
    }
    if args.follow {
        pb.finish_and_clear();
        return run_follow(args, &settings, &train, &val, beside.as_ref());
    }
    hammerstein::fit::Observer::progress(
        observer.as_ref(),
        "fitting and diagnosing (every candidate refitted)",
        0,
        1,
    );
    // attached at run time: the fit (its screened stages) and the diagnosis (its stages and
    // refits)
    let model = settings.fit_observed(&train, observer.as_ref())?;
    let d = Diagnoser::<T>::new()
        .options(
            beside
                .as_ref()
                .map(StructureBeside::options)
                .unwrap_or_default(),
        )
        .diagnose_observed(&model, &train, &val, observer.as_ref())?;
    pb.finish_and_clear();
    save_model(args, &model)?;
    if let Some(dir) = &args.report {
        super::write_model_report(dir, &args.data.data, &model, &d, &train)?;
    }
    print_diagnosis(args, &model, &d, None, &train, &json!([]), beside.as_ref())
}

/// `--follow`: the library's guided loop from the user's starting settings.
fn run_follow<T: Real>(
    args: &Args,
    settings: &hammerstein::Hammerstein<T>,
    train: &hammerstein::IoData<T>,
    val: &hammerstein::IoData<T>,
    beside: Option<&StructureBeside>,
) -> super::CliResult {
    let diagnoser =
        Diagnoser::<T>::new().options(beside.map(StructureBeside::options).unwrap_or_default());
    let pb = super::spinner("following the diagnosis (fit, diagnose, apply, refit)");
    let options = hammerstein::diagnosis::FollowOptions {
        max_steps: args.max_steps,
        confirm: (!args.no_confirm).then(Default::default),
        time_budget: args.time_budget.map(std::time::Duration::from_secs_f64),
    };
    let followed = diagnoser.follow_with(settings, train, val, &options, None)?;
    pb.finish_and_clear();
    if followed.stop == FollowStop::TimeBudget {
        super::note(&format!(
            "the time budget ({} s) was spent: stopped after step {}; its model is the one reported",
            args.time_budget.unwrap_or_default(),
            followed.steps.len().saturating_sub(1)
        ));
    }
    let last = followed.last().ok_or("no model was fitted")?;
    let fb_step = feedback_step_of(args, &diagnoser, &followed, train, val)?;
    match fb_step.as_ref().filter(|(_, s)| s.taken()) {
        Some((_, s)) => save_feedback(args, &s.fit.model)?,
        None => save_model(args, &last.model)?,
    }
    let label = |st: &FollowStep<T>| {
        format!(
            "{}, order {}",
            effects_text(&st.model),
            st.model.linear().order()
        )
    };
    if let Some(dir) = &args.report {
        use hammerstein::report::{Context, Step, report_input, write_report};
        let steps: Vec<Step> = followed
            .steps
            .iter()
            .enumerate()
            .map(|(i, st)| Step {
                label: if i == 0 { label(st) } else { st.change.clone() },
                validation_mse: st.diagnosis.validation.metrics.mse,
                fit_percent: st.diagnosis.validation.metrics.fit_percent,
            })
            .collect();
        let ctx = Context {
            title: format!(
                "Hammerstein model of {} (followed diagnosis)",
                args.data.data.display()
            ),
            dataset: args.data.data.display().to_string(),
            units: super::common::units_of(train),
            steps,
            ..Default::default()
        };
        let input = report_input(&last.model, &last.diagnosis, ctx)?;
        let path = write_report(dir, &input)?;
        super::note(&format!("report written to {}", path.display()));
    }
    let stop = match (&followed.stop, &fb_step) {
        (_, Some((_, s))) if s.taken() => format!(
            "the feedback model was added ({}): a model outside the Hammerstein class, the guided loop ends there",
            s.command
        ),
        (_, Some((_, s))) => format!(
            "the feedback step ({}) is not confirmed on the held-back part of the training record: {}",
            s.command,
            s.confirmation
                .as_ref()
                .map(|c| c.text())
                .unwrap_or_default()
        ),
        (FollowStop::MaxSteps, _) => {
            format!("the step limit ({}) was reached", args.max_steps)
        }
        (stop, _) => stop.to_string(),
    };
    let mut steps_json: Vec<serde_json::Value> = followed
        .steps
        .iter()
        .map(|st| {
            json!({
                "change": st.change,
                "effects": st.model.nonlinearity().effects(),
                "order": st.model.linear().order(),
                "validation": {
                    "mse": json_number(st.diagnosis.validation.metrics.mse),
                    "fit_percent": json_number(st.diagnosis.validation.metrics.fit_percent),
                },
                "suggestion": st.diagnosis.suggestions.first().map(|s| s.effect.clone()),
                "confirmation": st.confirmation,
            })
        })
        .collect();
    if let Some((from, st)) = &fb_step {
        steps_json.push(feedback_step_json(*from, st));
    }
    let refused = followed
        .refused
        .as_ref()
        .map(|(change, c)| json!({"change": change, "confirmation": c}));
    // which model the loop ends with: the feedback model of a taken feedback step (the
    // top-level fields then describe the Hammerstein model it extends), or that model itself
    let final_model = match &fb_step {
        Some((from, st)) if st.taken() => json!({
            "kind": "feedback",
            "command": st.command,
            "from_step": from,
            "order": st.fit.model.order(),
            "validation_mse": json_number(st.validation_mse),
            "note": "the top-level model fields describe the Hammerstein model the feedback step extends",
        }),
        _ => json!({"kind": "hammerstein"}),
    };
    if !args.json {
        outln!(
            "{:<5} {:<48} {:>14} {:>8}  top suggestion",
            "step",
            "model",
            "val MSE",
            "fit %"
        )?;
        for (i, st) in followed.steps.iter().enumerate() {
            outln!(
                "{:<5} {:<48} {:>14.6e} {:>8.2}  {}",
                i,
                if i == 0 {
                    label(st)
                } else {
                    format!("{} ({})", st.change, label(st))
                },
                st.diagnosis.validation.metrics.mse,
                st.diagnosis.validation.metrics.fit_percent,
                top_suggestion_text(&st.diagnosis)
            )?;
        }
        for (i, st) in followed.steps.iter().enumerate() {
            if let Some(c) = &st.confirmation {
                outln!("step {i} on the held-back part of training: {}", c.text())?;
            }
        }
        if let Some((from, st)) = &fb_step {
            outln!("{}", feedback_step_text(*from, st))?;
        }
        outln!("stopped: {stop}")?;
        for note in &followed.final_check {
            outln!("final check: {note}")?;
        }
        if let Some(w) = super::common::rose_warning(&followed.validation_rose()) {
            outln!("{w}")?;
        }
        outln!()?;
    }
    print_diagnosis(
        args,
        &last.model,
        &last.diagnosis,
        Some((
            json!(steps_json),
            json!(stop),
            json!(followed.validation_rose()),
            json!(refused),
            final_model,
        )),
        train,
        &json!(followed.final_check),
        beside,
    )
}

/// The model and its diagnosis as text or JSON (`follow`: the steps and why they stopped).
fn print_diagnosis<T: Real>(
    args: &Args,
    model: &hammerstein::HammersteinModel<T>,
    d: &Diagnosis<T>,
    follow: Option<(Value, Value, Value, Value, Value)>,
    train: &hammerstein::IoData<T>,
    final_check: &serde_json::Value,
    beside: Option<&StructureBeside>,
) -> super::CliResult {
    let input_spread = input_spread(train, 0);
    // a model whose simulation from rest does not mean what its fit means is said
    let departure = hammerstein::fit::from_rest::departure(model, train);
    if let Some(w) = super::common::from_rest_warning(
        departure,
        "its fit on the training record (initial state estimated)",
    ) {
        super::note(&w);
    }
    let suggested = args
        .model
        .suggested_decimation(model.linear(), d.train.metrics.n);
    if args.json {
        let mut j = model_json(model, &d.train.metrics, Some(&d.validation.metrics))?;
        let obj = j
            .as_object_mut()
            .ok_or("internal: model JSON is not an object")?;
        obj.insert("adequate".into(), json!(d.adequate));
        let mut unexplained = d.unexplained.clone();
        unexplained.extend(beside.and_then(StructureBeside::beyond_class));
        obj.insert("unexplained".into(), serde_json::to_value(&unexplained)?);
        if let Some(b) = beside {
            obj.insert("structure".into(), b.json());
        }
        obj.insert(
            "suggestions".into(),
            suggestions_json(d, args.data.inputs().first().copied().unwrap_or("u")),
        );
        obj.insert(
            "null_parameters".into(),
            serde_json::Value::Array(
                null_candidates(d)
                    .into_iter()
                    .map(|(effect, reason)| json!({"effect": effect, "reason": reason}))
                    .collect(),
            ),
        );
        obj.insert("summary".into(), json!(d.summary));
        obj.insert("tests".into(), serde_json::to_value(&d.tests)?);
        obj.insert(
            "generalisation".into(),
            serde_json::to_value(&d.generalisation)?,
        );
        if let Some((steps, stop, rose, refused, final_model)) = follow {
            obj.insert("final_model".into(), final_model);
            obj.insert("steps".into(), steps);
            obj.insert("stop".into(), stop);
            obj.insert("final_check".into(), final_check.clone());
            obj.insert("refused_step".into(), refused);
            obj.insert("validation_rose_at".into(), rose);
        }
        obj.insert("from_rest".into(), super::common::from_rest_json(departure));
        obj.insert("decimation".into(), json!(args.model.decimation()));
        obj.insert("suggested_decimation".into(), json!(suggested));
        outln!("{j}")?;
    } else {
        outp!(
            "{}",
            args.model
                .decimation_line(d.train.metrics.n, model.linear().ts)
        )?;
        outp!(
            "{}",
            model_text(
                model,
                &d.train.metrics,
                Some(&d.validation.metrics),
                input_spread
            )?
        )?;
        outp!("{}", args.model.oversampled_line(suggested))?;
        outp!("{}", diagnosis_text(d))?;
        if let Some(b) = beside {
            outp!("{}", b.text())?;
        }
    }
    Ok(())
}

/// The suggestions as JSON, each naming the input it concerns (`input`, the column name, as in
/// a several-input diagnosis).
fn suggestions_json<T: Real>(d: &Diagnosis<T>, input: &str) -> serde_json::Value {
    serde_json::Value::Array(
        d.suggestions
            .iter()
            .map(|s| {
                let est: serde_json::Map<String, serde_json::Value> = s
                    .estimate
                    .iter()
                    .map(|e| (e.key(), json_number(e.value)))
                    .collect();
                json!({
                    "input": input,
                    "effect": s.effect,
                    "score": json_number(s.score),
                    "evidence": s.evidence,
                    "estimate": est,
                    "train_mse_after": json_number(s.train_mse_after),
                    "train_mse_before": json_number(s.train_mse_before),
                    "criterion_change": json_number(s.criterion_change),
                    "validation_mse_after": json_number(s.validation_mse_after),
                    "validation_mse_before": json_number(s.validation_mse_before),
                    "change": s.change,
                    "action": serde_json::to_value(&s.action).unwrap_or(serde_json::Value::Null),
                })
            })
            .collect(),
    )
}

/// Candidates left out because their refit does not credit the effect (its parameters at their
/// null value, or physically implausible).
fn null_candidates<T: Real>(d: &Diagnosis<T>) -> Vec<(String, String)> {
    d.candidates
        .iter()
        .filter_map(|c| {
            let r = c.refit.as_ref()?.null_parameters.as_ref()?;
            Some((c.effect.to_string(), r.clone()))
        })
        .collect()
}

/// Candidates refitted (or tried) but neither suggested nor at their null value, and why: the
/// training criterion, the minimum improvement, or a failed refit.
fn rejected_candidates<T: Real>(d: &Diagnosis<T>) -> Vec<(String, String)> {
    d.candidates
        .iter()
        .filter(|c| c.applicable && !d.suggestions.iter().any(|s| s.effect == c.effect))
        .filter_map(|c| {
            if let Some(e) = &c.refit_error {
                return Some((c.effect.to_string(), format!("its refit failed: {e}")));
            }
            let r = c.refit.as_ref()?;
            if r.null_parameters.is_some() {
                return None;
            }
            Some((
                c.effect.to_string(),
                format!(
                    "refit: training MSE {} → {} ({:+.1} %), ΔBIC {}",
                    super::common::sci(r.reference_train_mse),
                    super::common::sci(r.train_mse),
                    -100.0 * c.improvement.unwrap_or(f64::NAN),
                    c.criterion_change
                        .map_or("n/a".into(), |b| format!("{b:+.1}"))
                ),
            ))
        })
        .collect()
}

/// The readable table of tests and suggestions.
pub fn diagnosis_text<T: Real>(d: &Diagnosis<T>) -> String {
    let mut s = String::from("\nresidual tests (Bonferroni-adjusted p-values):\n");
    for t in &d.tests {
        s.push_str(&format!(
            "  {:<24} p = {:<9.3e} {}\n",
            t.name,
            t.p_adjusted,
            if t.significant { "SIGNIFICANT" } else { "" }
        ));
    }
    s.push('\n');
    if let Some(g) = d.generalisation.as_ref().filter(|g| g.notable) {
        s.push_str(&format!("{}\n\n", g.text()));
    }
    for (effect, reason) in null_candidates(d) {
        s.push_str(&format!(
            "not suggested: {effect} (its refit does not credit it: {reason})\n"
        ));
    }
    for (effect, why) in rejected_candidates(d) {
        s.push_str(&format!("not suggested: {effect} ({why})\n"));
    }
    if d.adequate {
        s.push_str(&format!("{}\n", d.summary));
        return s;
    }
    if d.suggestions.is_empty() {
        s.push_str(&format!("{}\n", d.summary));
        for u in &d.unexplained {
            s.push_str(&format!(
                "  unexplained: {} (p = {:.3e}); would need: {}\n",
                u.test,
                u.p_adjusted,
                u.model_classes.join("; ")
            ));
        }
        return s;
    }
    s.push_str("selected on the training part (BIC); validation only reported\n");
    s.push_str(&format!(
        "{:<4} {:<20} {:>8} {:>11} {:>14} {:>14} {:>14}\n",
        "rank", "effect", "score", "ΔBIC", "train MSE now", "train after", "val MSE after"
    ));
    for (i, g) in d.suggestions.iter().enumerate() {
        s.push_str(&format!(
            "{:<4} {:<20} {:>8.3} {:>11.1} {:>14} {:>14} {:>14}\n",
            i + 1,
            g.effect,
            g.score,
            g.criterion_change,
            hammerstein::diagnosis::candidate::readable(g.train_mse_before),
            hammerstein::diagnosis::candidate::readable(g.train_mse_after),
            hammerstein::diagnosis::candidate::readable(g.validation_mse_after)
        ));
    }
    s.push('\n');
    for (i, g) in d.suggestions.iter().enumerate() {
        s.push_str(&format!(
            "{}. {}: {}\n   estimate: {}\n   refit: {}\n",
            i + 1,
            g.effect,
            g.evidence,
            if g.estimate.is_empty() {
                "-".into()
            } else {
                g.estimate.text()
            },
            g.change
        ));
    }
    s
}

/// `diagnose --input u1,u2` (with or without `--follow`).
fn run_miso<T: Real>(args: &Args) -> super::CliResult {
    if !args.add_effect.is_empty() {
        return Err("with several inputs add effects with --effects NAME:LIST".into());
    }
    let settings = super::miso::settings::<T>(&args.data, &args.model)?;
    let (train, val) = args
        .model
        .load::<T>(&args.data, Some(DEFAULT_VALIDATION_FRACTION))?;
    let val = val.ok_or("diagnose needs validation data")?;
    let diagnoser = Diagnoser::<T>::new();
    if args.follow {
        let pb = super::spinner("following the diagnosis (several inputs)");
        let followed = diagnoser.follow_miso(&settings, &train, &val, args.max_steps)?;
        pb.finish_and_clear();
        let last = followed.steps.last().ok_or("no model was fitted")?;
        if let Some(path) = &args.save {
            let mut file = last.model.to_file();
            file.decimation = Some(args.model.decimation()).filter(|&k| k > 1);
            file.write(path)?;
        }
        if let Some(dir) = &args.report {
            super::miso::write_report(
                dir,
                &args.data.data,
                &last.model,
                &last.diagnosis,
                &train,
                &val,
                " (followed diagnosis)",
            )?;
        }
        let steps: Vec<Value> = followed
            .steps
            .iter()
            .map(|st| {
                json!({
                    "change": st.change,
                    "model": super::miso::structure_text(&st.model),
                    "validation": metrics_json(&st.diagnosis.validation),
                    "suggestion": st.diagnosis.suggestions.first().map(|s| json!({
                        "input": s.input, "effect": s.suggestion.effect.to_string()
                    })),
                })
            })
            .collect();
        let rose = followed.validation_rose();
        if args.json {
            let mut j = super::miso::diagnosis_json(&last.model, &last.diagnosis)?;
            j["validation_rose_at"] = json!(rose);
            j["steps"] = json!(steps);
            j["stopped"] = json!(followed.stop.to_string());
            j["decimation"] = json!(args.model.decimation());
            j["suggested_decimation"] = json!(
                args.model
                    .suggested_decimation_miso(&last.model, train.len())
            );
            outln!("{j}")?;
            return Ok(());
        }
        outln!(
            "{:<5} {:<60} {:>14} {:>8}  top suggestion",
            "step",
            "model",
            "val MSE",
            "fit %"
        )?;
        for (i, st) in followed.steps.iter().enumerate() {
            let label = if i == 0 {
                super::miso::structure_text(&st.model)
            } else {
                format!("{} ({})", st.change, super::miso::structure_text(&st.model))
            };
            outln!(
                "{:<5} {:<60} {:>14.6e} {:>8.2}  {}",
                i,
                label,
                st.diagnosis.validation.mse,
                st.diagnosis.validation.fit_percent,
                super::miso::top_text(&st.diagnosis)
            )?;
        }
        outln!("stopped: {}", followed.stop)?;
        if let Some(w) = super::common::rose_warning(&rose) {
            outln!("{w}")?;
        }
        outln!()?;
        return super::miso::print_diagnosis(&last.model, &last.diagnosis);
    }
    let pb = super::spinner("fitting and diagnosing every input (every candidate refitted)");
    let model = settings.fit(&train)?;
    if let Some(path) = &args.save {
        let mut file = model.to_file();
        file.decimation = Some(args.model.decimation()).filter(|&k| k > 1);
        file.write(path)?;
    }
    let d = diagnoser.diagnose_miso(&model, &train, &val)?;
    pb.finish_and_clear();
    if let Some(dir) = &args.report {
        super::miso::write_report(dir, &args.data.data, &model, &d, &train, &val, "")?;
    }
    let suggested = args.model.suggested_decimation_miso(&model, train.len());
    if args.json {
        let mut j = super::miso::diagnosis_json(&model, &d)?;
        j["decimation"] = json!(args.model.decimation());
        j["suggested_decimation"] = json!(suggested);
        outln!("{j}")?;
        return Ok(());
    }
    super::miso::print_diagnosis(&model, &d)?;
    outp!("{}", args.model.oversampled_line(suggested))
}

/// `--follow` whose loop stopped at a `feedback-nonlinearity` suggestion: the step that adds
/// the feedback model (from the step `from` whose diagnosis named it), confirmed on the
/// held-back quarters of the training record unless --no-confirm.
fn feedback_step_of<T: Real>(
    args: &Args,
    diagnoser: &Diagnoser<T>,
    followed: &hammerstein::diagnosis::Followed<T>,
    train: &hammerstein::IoData<T>,
    val: &hammerstein::IoData<T>,
) -> Result<Option<(usize, FeedbackStep)>, super::Failure> {
    if !matches!(followed.stop, FollowStop::CannotApply(_)) {
        return Ok(None);
    }
    let Some((from, st)) = followed
        .steps
        .iter()
        .enumerate()
        .rev()
        .find(|(_, s)| suggests_feedback(&s.diagnosis))
    else {
        return Ok(None);
    };
    let pb = super::spinner("fitting the feedback model the diagnosis names");
    let rule = (!args.no_confirm).then(Default::default);
    let step = feedback_step(diagnoser, &st.model, train, val, rule);
    pb.finish_and_clear();
    Ok(Some((from, step?)))
}

fn feedback_step_text(from: usize, s: &FeedbackStep) -> String {
    let mut t = format!(
        "from step {from}: + feedback-nonlinearity ({}): order {} linear block, {} on the {}; training RMS \
         error {:.4e}, validation MSE {:.6e}",
        s.command,
        s.fit.model.order(),
        s.fit.model.nonlinearity().name(),
        s.on.name(),
        s.fit.rms,
        s.validation_mse
    );
    if let Some(c) = &s.confirmation {
        t.push_str(&format!(
            "\nthe feedback step on the held-back part of training: {}",
            c.text()
        ));
    }
    t
}

fn feedback_step_json(from: usize, s: &FeedbackStep) -> serde_json::Value {
    json!({
        "change": format!("+ feedback-nonlinearity ({})", s.command),
        "from_step": from,
        "kind": "feedback",
        "feedback_nonlinearity": s.fit.model.nonlinearity().name(),
        "feedback_on": s.on.name(),
        "command": s.command,
        "order": s.fit.model.order(),
        "train_rms": json_number(s.fit.rms),
        "validation": {"mse": json_number(s.validation_mse)},
        "confirmation": s.confirmation,
        "taken": s.taken(),
    })
}

/// Writes a feedback model to `--save`'s file (as `fit --feedback-nonlinearity --save`).
fn save_feedback(args: &Args, model: &hammerstein::feedback::FeedbackModel) -> super::CliResult {
    if let Some(path) = &args.save {
        let mut file = model.to_file();
        file.columns = Some((args.data.input.clone(), args.data.output.clone()));
        let dec = args.model.decimation();
        file.decimation = (dec > 1).then_some(dec);
        file.write(path)?;
    }
    Ok(())
}

/// `diagnose --feedback-nonlinearity KIND`: fits the feedback model on the training part and
/// runs the residual tests on its residual (`hammerstein::diagnosis::feedback_model`).
fn run_feedback(args: &Args, kind: &str) -> super::CliResult {
    use hammerstein::feedback::{FeedbackKind, FeedbackOn, FeedbackSettings};
    if args.data.inputs().len() != 1 {
        return Err("a feedback model has one input: give one --input column".into());
    }
    if args.follow || args.report.is_some() || !args.add_effect.is_empty() {
        return Err(
            "diagnose --feedback-nonlinearity runs the residual tests of a feedback model; --follow, --report \
             and --add-effect act on Hammerstein models (run `diagnose --follow` without it: it adds the \
             feedback model when the diagnosis names one)"
                .into(),
        );
    }
    let kind: FeedbackKind = kind.parse()?;
    let on: FeedbackOn = args.feedback.feedback_on.parse()?;
    let mut s = FeedbackSettings::new(kind, on);
    // the combined model, as `fit` builds it: an input nonlinearity before the loop and an
    // output map after it
    if !args.model.effects.is_empty() || args.model.nonlinearity.is_some() {
        s.input = Some(
            args.model
                .settings::<f64>(&args.data.input, &[])?
                .build_nonlinearity()?,
        );
    }
    if let Some(name) = &args.model.output_nonlinearity {
        s.output = Some(hammerstein::regressors::output_map_from_name::<f64>(name)?);
    }
    s.order = args.model.order.parse()?;
    if let Some(h) = args.model.horizon {
        s.horizon = h;
    }
    s.with_d = matches!(
        args.model
            .feedthrough
            .parse::<hammerstein::fit::Feedthrough>()?,
        hammerstein::fit::Feedthrough::Present
    );
    let (train, val) = args
        .model
        .load::<f64>(&args.data, Some(DEFAULT_VALIDATION_FRACTION))?;
    let val = val.ok_or("diagnose needs validation data")?;
    let pb = super::spinner("fitting the feedback model and testing its residuals");
    let result = hammerstein::feedback::fit(&s, &train).and_then(|fit| {
        let d = diagnose_feedback(&fit.model, &train, &val, &Default::default())?;
        Ok((fit, d))
    });
    pb.finish_and_clear();
    let (fit, d) = result?;
    for w in &fit.warnings {
        super::note(&format!("warning: {w}"));
    }
    save_feedback(args, &fit.model)?;
    let m = &fit.model;
    if args.json {
        let j = json!({
            "kind": "feedback",
            "nonlinearity": m.nonlinearity().name(),
            "feedback_on": on.name(),
            "order": m.order(),
            "input_nonlinearity": m.input_nonlinearity().map(|nl| nl.name()),
            "output_nonlinearity": m.output_map().map(|g| g.name()),
            "train_rms": json_number(d.train_rms),
            "validation_rms": json_number(d.validation_rms),
            "validation_fit_percent": json_number(d.validation_fit_percent),
            "adequate": d.adequate,
            "unexplained": d.unexplained,
            "tests": d.tests,
            "summary": d.summary,
        });
        outln!("{j}")?;
        return Ok(());
    }
    outln!(
        "feedback model: order {} linear block, {} on the {}",
        m.order(),
        m.nonlinearity().name(),
        on.variable()
    )?;
    if let Some(nl) = m.input_nonlinearity() {
        outln!("  input nonlinearity before the loop: {}", nl.name())?;
    }
    if let Some(g) = m.output_map() {
        outln!("  output map after the loop: {}", g.name())?;
    }
    outln!(
        "  training RMS error {:.4e}; validation RMS error {:.4e}, fit {:.2} % (initial states estimated)",
        d.train_rms,
        d.validation_rms,
        d.validation_fit_percent
    )?;
    outln!("\nresidual tests (Bonferroni-adjusted p-values):")?;
    for t in &d.tests {
        outln!(
            "  {:<24} p = {:<9.3e} {}",
            t.name,
            t.p_adjusted,
            if t.significant { "SIGNIFICANT" } else { "" }
        )?;
    }
    outln!("\n{}", d.summary)?;
    for u in &d.unexplained {
        outln!(
            "  unexplained: {} (p = {:.3e}); would need: {}",
            u.test,
            u.p_adjusted,
            u.model_classes.join("; ")
        )?;
    }
    Ok(())
}
