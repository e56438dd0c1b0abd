//! Options shared by the model-fitting subcommands (`fit`, `diagnose`): data columns, model
//! structure, validation split, precision and backend; and the JSON/text rendering they share.

use crate::cli::Failure;
use hammerstein::diagnosis::Metrics;
use hammerstein::fit::{Hammerstein, HammersteinModel};
use hammerstein::regressors::{Effect, EffectSet};
use hammerstein::{BackendKind, IoData, MethodKind, Order, Real};
use serde_json::{Value, json};
use std::path::PathBuf;

/// The record to read.
#[derive(clap::Args, Debug, Clone)]
pub struct DataArgs {
    /// CSV file with a header row.
    pub data: PathBuf,
    /// Name of the input column, or its 1-based position when no column has that name ("2":
    /// the second column, as `cut -f` counts); several comma-separated ("u1,u2") fit one
    /// Hammerstein branch per input, their outputs summed (`fit`, `diagnose`).
    #[arg(long, default_value = "u")]
    pub input: String,
    /// Name of the output column, or its 1-based position when no column has that name.
    #[arg(long, default_value = "y")]
    pub output: String,
}

impl DataArgs {
    /// The same arguments with each column given by position replaced by its header name, so
    /// that what follows (the validation file, `--effects NAME:LIST`, the model file's column
    /// names) sees names. Anything else is kept as given, to be reported by the record's
    /// reading as before (an unknown name, a position out of range, an unreadable file).
    pub fn resolved(&self) -> Self {
        let Ok(header) = hammerstein::CsvTable::read_header(&self.data) else {
            return self.clone();
        };
        let name = |spec: &str| match header.names_of(&[spec]) {
            Ok(mut v) if v.len() == 1 => v.remove(0),
            _ => spec.to_string(),
        };
        Self {
            data: self.data.clone(),
            input: self
                .inputs()
                .into_iter()
                .map(name)
                .collect::<Vec<_>>()
                .join(","),
            output: name(&self.output),
        }
    }

    /// The input column names (`--input u1,u2` gives two).
    pub fn inputs(&self) -> Vec<&str> {
        self.input
            .split(',')
            .map(str::trim)
            .filter(|s| !s.is_empty())
            .collect()
    }
}

/// Model structure and estimation options.
#[derive(clap::Args, Debug, Clone)]
pub struct ModelArgs {
    /// Effects of the UDN nonlinearity: comma-separated subset of
    /// hysteresis,dead-zone,saturation,preload ("linear" or empty: none), optionally with
    /// prandtl-ishlinskii (dynamic hysteresis: 6 weighted play operators added to the UDN).
    /// Overrides --nonlinearity. With several inputs, one `--effects NAME:LIST` per input
    /// ("--effects u1:saturation,hysteresis --effects u2:linear"); inputs without one get
    /// --nonlinearity. NAME is taken as --input takes it: the column's name, or its 1-based
    /// position when no column has that name ("--input 2,3 --effects 2:saturation").
    #[arg(long, value_name = "[NAME:]LIST")]
    pub effects: Vec<String>,
    /// Nonlinearity when --effects is not given: udn (all four effects), sh (saturation +
    /// hysteresis), linear (a gain), poly3 (cubic polynomial). Default: linear.
    #[arg(long)]
    pub nonlinearity: Option<String>,
    /// Subspace method: moesp, n4sid or n4sid-unweighted.
    #[arg(long, default_value = "moesp")]
    pub method: String,
    /// Model order: a number, "auto" (every order fitted, the lowest BIC on the training part
    /// kept) or "gap" (the largest singular-value gap of the first subspace step).
    #[arg(long, allow_negative_numbers = true, default_value = "auto")]
    pub order: String,
    /// Subspace horizon (block rows); default: the method's (8), raised to 2n for a fixed
    /// --order n it cannot hold (above 7). A horizon given here is never raised.
    #[arg(long, value_parser = parse_count, allow_negative_numbers = true)]
    pub horizon: Option<usize>,
    /// Input delay in samples (dead time before the nonlinearity acts on the linear block).
    #[arg(long, value_parser = parse_count, allow_negative_numbers = true, default_value_t = 0)]
    pub delay: usize,
    /// Keep every K-th sample of the record (and of --validation-file) before anything else:
    /// for oversampled records. The output is low-pass filtered first (zero phase, unit gain at
    /// 0), the input taken as it is (the nonlinearity acts on its values); --delay, --horizon
    /// and the model's sample time then count samples of the decimated record. A saved model
    /// records K: `compare` and `simulate` decimate their records by it. "auto": the factor the
    /// band of a linear subspace model of the record allows (the one `fit` suggests after a
    /// fit; 1 when the record is not oversampled), said on standard error.
    #[arg(long, value_parser = parse_decimate, allow_negative_numbers = true, value_name = "K|auto")]
    pub decimate: Option<Decimate>,
    /// Hold out the last FRACTION of the record for validation (0 < FRACTION < 1).
    #[arg(long, allow_negative_numbers = true, value_name = "FRACTION")]
    pub validate: Option<f64>,
    /// A second CSV file (same columns) for validation.
    #[arg(long, value_name = "FILE")]
    pub validation_file: Option<PathBuf>,
    /// Scalar type: f32 or f64.
    #[arg(long, default_value = "f64")]
    pub precision: String,
    /// Linear-algebra backend: faer or lapack (needs the `lapack` feature).
    #[arg(long, default_value = "faer")]
    pub backend: String,
    /// Skip the output-error refinement after the iterative loop (on by default; the loop alone
    /// is the paper's method and faster, but biased).
    #[arg(long)]
    pub no_refine: bool,
    /// Keep the linear block stable: every pole within radius 0.9999 (the refinement confined
    /// to such blocks; an unstable fit pulled inside and refined again). Off by
    /// default: an integrating mode or a drift of the record is fitted as it is, and the output
    /// says when the block is unstable.
    #[arg(long)]
    pub stable: bool,
    /// Accepted for compatibility: the refinement is on by default.
    #[arg(long, hide = true)]
    pub refine: bool,
    /// Direct feed-through D of the linear block: auto (decided by the information criterion on
    /// the training part), on or off.
    #[arg(long, default_value = "auto")]
    pub feedthrough: String,
    /// Seed of every random choice of the fit.
    #[arg(long, value_parser = parse_seed, allow_negative_numbers = true, default_value_t = 0)]
    pub seed: u64,
    /// Static map after the linear block (Hammerstein–Wiener): poly3 (cubic; polyK for degree
    /// K), saturation, or pwl:K (piecewise linear, K knots). Default: none.
    #[arg(long, value_name = "MAP")]
    pub output_nonlinearity: Option<String>,
}

/// Scalar precision requested on the command line.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Precision {
    /// Single precision.
    F32,
    /// Double precision.
    F64,
}

impl ModelArgs {
    /// Parsed precision.
    pub fn precision(&self) -> Result<Precision, Failure> {
        match self.precision.as_str() {
            "f32" => Ok(Precision::F32),
            "f64" => Ok(Precision::F64),
            p => Err(format!("unknown precision '{p}' (f32 or f64)").into()),
        }
    }

    /// The same arguments with the NAME of each `--effects NAME:LIST` given by position replaced
    /// by the header name of the record `data` (as [`DataArgs::resolved`] does for `--input`:
    /// a header name always wins), so that it matches the resolved inputs. A position outside
    /// the header is refused (`ColumnOutOfRange`, naming the columns); a NAME that is neither a
    /// column nor a position, or a header that cannot be read, is kept as given, to be reported
    /// as before (not one of the inputs; the record's reading).
    pub fn resolved(&self, data: &std::path::Path) -> Result<Self, Failure> {
        let Ok(header) = hammerstein::CsvTable::read_header(data) else {
            return Ok(self.clone());
        };
        let effects = self
            .effects
            .iter()
            .map(|e| {
                let Some((name, list)) = e.split_once(':') else {
                    return Ok(e.clone());
                };
                match header.names_of(&[name.trim()]) {
                    Ok(v) if v.len() == 1 => Ok(format!("{}:{list}", v[0])),
                    Err(err @ hammerstein::Error::ColumnOutOfRange { .. }) => Err(err.into()),
                    _ => Ok(e.clone()),
                }
            })
            .collect::<Result<Vec<_>, Failure>>()?;
        Ok(Self {
            effects,
            ..self.clone()
        })
    }

    /// The effect set asked for by --effects for the single input `input`, if any (plus `extra`
    /// effects): a bare list, or one `NAME:LIST` naming that input.
    pub fn effect_set(&self, input: &str, extra: &[String]) -> Result<Option<EffectSet>, Failure> {
        let mut set = match self.effects.as_slice() {
            [] => None,
            [one] => {
                let list = match one.split_once(':') {
                    Some((name, list)) if name.trim() == input => list,
                    Some((name, _)) => {
                        return Err(format!(
                            "--effects {one}: '{}' is not the input (--input {input})",
                            name.trim()
                        )
                        .into());
                    }
                    None => one.as_str(),
                };
                Some(EffectSet::parse(list)?)
            }
            _ => {
                return Err(
                    "several --effects need several inputs (--input u1,u2 --effects u1:LIST …)"
                        .into(),
                );
            }
        };
        for e in extra {
            let eff: Effect = e.parse()?;
            set = Some(set.unwrap_or_default().with(eff));
        }
        Ok(set)
    }

    /// Settings of the Hammerstein fit of the single input `input`.
    pub fn settings<T: Real>(
        &self,
        input: &str,
        extra_effects: &[String],
    ) -> Result<Hammerstein<T>, Failure> {
        self.settings_with(self.effect_set(input, extra_effects)?)
    }

    /// Each input's effect set from `--effects NAME:LIST` (`None`: none given for it).
    pub fn branch_effect_sets(&self, inputs: &[&str]) -> Result<Vec<Option<EffectSet>>, Failure> {
        let mut sets: Vec<Option<EffectSet>> = vec![None; inputs.len()];
        for e in &self.effects {
            let Some((name, list)) = e.split_once(':') else {
                return Err(format!(
                    "--effects {e}: with several inputs name the input: --effects {}:{e}",
                    inputs[0]
                )
                .into());
            };
            let name = name.trim();
            let Some(i) = inputs.iter().position(|n| *n == name) else {
                return Err(format!(
                    "--effects {e}: '{name}' is not one of the inputs ({})",
                    inputs.join(", ")
                )
                .into());
            };
            if sets[i].is_some() {
                return Err(format!("--effects given twice for input '{name}'").into());
            }
            sets[i] = Some(EffectSet::parse(list)?);
        }
        Ok(sets)
    }

    /// Settings of one Hammerstein branch with the effect set `effects` (`None`: by
    /// --nonlinearity).
    pub fn settings_with<T: Real>(
        &self,
        effects: Option<EffectSet>,
    ) -> Result<Hammerstein<T>, Failure> {
        let base = match effects {
            Some(set) => Hammerstein::udn(set),
            None => match self.nonlinearity.as_deref().unwrap_or("linear") {
                "udn" => Hammerstein::udn(EffectSet::all()),
                "sh" => Hammerstein::sh(),
                "linear" => Hammerstein::linear(),
                "poly3" => {
                    Hammerstein::new(Box::new(hammerstein::regressors::Polynomial::<T>::new(3)?))
                }
                other => {
                    return Err(format!(
                        "unknown nonlinearity '{other}' (udn, sh, linear or poly3)"
                    )
                    .into());
                }
            },
        };
        let method: MethodKind = self.method.parse()?;
        let order: Order = self.order.parse()?;
        let backend: BackendKind = self.backend.parse()?;
        let feedthrough: hammerstein::fit::Feedthrough = self.feedthrough.parse()?;
        let mut s = base
            .method(method)
            .order(order)
            .refine(!self.no_refine)
            .stable(self.stable)
            .feedthrough(feedthrough)
            .backend(backend)
            .delay(self.delay)
            .seed(self.seed);
        if let Some(h) = self.horizon {
            s = s.horizon(h);
        }
        if let Some(name) = &self.output_nonlinearity {
            let map = hammerstein::regressors::output_map_from_name::<T>(name)?;
            s = s.output_nonlinearity(Some(map));
        }
        Ok(s)
    }

    /// The decimation factor asked for (1: none).
    pub fn decimation(&self) -> usize {
        match self.decimate {
            Some(Decimate::By(k)) => k,
            // resolved by `with_decimation_resolved` before the record is read
            Some(Decimate::Auto) | None => 1,
        }
    }

    /// The text output's line on a decimated record (empty when it was not).
    /// (`n` training samples at sample time `ts` after the decimation.)
    pub fn decimation_line(&self, n: usize, ts: f64) -> String {
        match self.decimation() {
            1 => String::new(),
            k => format!(
                "record decimated by {k} (output low-pass filtered, every {k}th sample kept): {n} \
                 training samples, sample time {}\n",
                sci(ts)
            ),
        }
    }

    /// The decimation factor, counted from the record as read, that the fitted single-input
    /// block `g` and its `n` training samples allow beyond `--decimate`
    /// (`decimation::suggested_factor`); `None` when it is not worth it.
    pub fn suggested_decimation<T: Real>(
        &self,
        g: &hammerstein::StateSpace<T>,
        n: usize,
    ) -> Option<usize> {
        hammerstein::decimation::suggested_factor(g, n).map(|k| k * self.decimation())
    }

    /// [`Self::suggested_decimation`] of a several-input model: the smallest over its branches
    /// (the widest band sets it); `None` when a branch's is.
    pub fn suggested_decimation_miso<T: Real>(
        &self,
        model: &hammerstein::MisoModel<T>,
        n: usize,
    ) -> Option<usize> {
        model
            .branches()
            .iter()
            .map(|b| self.suggested_decimation(b.linear(), n))
            .try_fold(usize::MAX, |k, s| s.map(|s| k.min(s)))
            .filter(|&k| k != usize::MAX)
    }

    /// The text output's line on an oversampled record (`suggested`: from
    /// [`Self::suggested_decimation`]; empty when `None`).
    pub fn oversampled_line(&self, suggested: Option<usize>) -> String {
        let Some(k) = suggested else {
            return String::new();
        };
        let more = k / self.decimation();
        let below = more as f64 * hammerstein::decimation::SUGGEST_MARGIN;
        format!(
            "oversampled: the linear block's gain is 20 dB below its peak above 1/{below} of the \
             Nyquist frequency; --decimate {k} keeps its band with {more}× fewer samples (a \
             faster fit, the output's noise filtered)\n"
        )
    }

    /// The same arguments with `--decimate auto` replaced by the factor the record `data`
    /// allows: the band of a linear MOESP model of its (mean-removed) inputs and output,
    /// identified at horizon `AUTO_DECIMATION_HORIZON` with the order of the largest singular-value gap
    /// (milliseconds, even on long records), read by `decimation::suggested_factor`. Said on
    /// standard error; unchanged without `auto`.
    pub fn with_decimation_resolved(&self, data: &DataArgs) -> Result<Self, Failure> {
        if self.decimate != Some(Decimate::Auto) {
            return Ok(self.clone());
        }
        let record: IoData<f64> = read_record(&data.data, &data.inputs(), &data.output)?;
        let centred = record.detrend_mean()?;
        let id = hammerstein::subspace::identify(
            &hammerstein::Moesp::new(AUTO_DECIMATION_HORIZON),
            &hammerstein::Faer::default(),
            &[centred.view()],
            &hammerstein::SubspaceOptions::default(),
        )
        .ok();
        let k = id
            .and_then(|id| hammerstein::decimation::suggested_factor(&id.model, record.len()))
            .unwrap_or(1);
        super::note(&format!(
            "--decimate auto: {k} ({}; from the band of a linear subspace model of the record)",
            if k > 1 {
                format!(
                    "{} of {} samples kept",
                    record.len().div_ceil(k),
                    record.len()
                )
            } else {
                "the record is not oversampled".to_string()
            }
        ));
        Ok(Self {
            decimate: Some(Decimate::By(k)),
            ..self.clone()
        })
    }

    /// Reads the estimation record and the validation record (if asked for, or `default_fraction`).
    pub fn load<T: Real>(
        &self,
        data: &DataArgs,
        default_fraction: Option<f64>,
    ) -> Result<(IoData<T>, Option<IoData<T>>), Failure> {
        let inputs = data.inputs();
        let all: IoData<T> = read_record(&data.data, &inputs, &data.output)?;
        self.load_from(all, data, default_fraction)
    }

    /// As [`load`](Self::load), with the estimation record already read (`all`, before the
    /// decimation and the validation split).
    pub fn load_from<T: Real>(
        &self,
        all: IoData<T>,
        data: &DataArgs,
        default_fraction: Option<f64>,
    ) -> Result<(IoData<T>, Option<IoData<T>>), Failure> {
        let inputs = data.inputs();
        let all = decimate_record(all, self.decimation(), &data.data)?;
        if self.delay >= all.len() / 2 {
            return Err(format!(
                "input delay {} is not shorter than half the record ({} samples)",
                self.delay,
                all.len()
            )
            .into());
        }
        match (&self.validation_file, self.validate) {
            (Some(_), Some(_)) => {
                Err("give either --validate or --validation-file, not both".into())
            }
            (Some(f), None) => {
                let val = IoData::from_csv(f, &inputs, &[&data.output]).map_err(|e| {
                    let part = format!("the validation file {}", f.display());
                    match e {
                        hammerstein::Error::ConstantInput { name } => {
                            hammerstein::Error::ConstantIn {
                                channel: "input".into(),
                                name,
                                part,
                            }
                        }
                        hammerstein::Error::ConstantOutput { name } => {
                            hammerstein::Error::ConstantIn {
                                channel: "output".into(),
                                name,
                                part,
                            }
                        }
                        e => e,
                    }
                    .to_string()
                })?;
                Ok((all, Some(decimate_record(val, self.decimation(), f)?)))
            }
            (None, fraction) => match fraction.or(default_fraction) {
                Some(f) => {
                    let (a, b) = all.split_validation(f)?;
                    Ok((a, Some(b)))
                }
                None => Ok((all, None)),
            },
        }
    }
}

/// Horizon of the linear subspace model `--decimate auto` reads the band from (`subspace`'s
/// default).
const AUTO_DECIMATION_HORIZON: usize = 10;

/// `--decimate`: a factor, or the one the record's band allows.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Decimate {
    /// The factor a linear subspace model of the record allows (`decimation::suggested_factor`).
    Auto,
    /// This factor (≥ 1).
    By(usize),
}

/// Parses `--decimate`: "auto" or a factor ≥ 1.
pub fn parse_decimate(s: &str) -> Result<Decimate, String> {
    if s.trim().eq_ignore_ascii_case("auto") {
        return Ok(Decimate::Auto);
    }
    parse_factor(s)
        .map(Decimate::By)
        .map_err(|e| format!("{e} (or \"auto\")"))
}

/// Parses a factor ≥ 1 (`--decimate`).
pub fn parse_factor(s: &str) -> Result<usize, String> {
    if s.trim().starts_with('-') {
        return Err(format!("'{s}' is negative: a factor ≥ 1 is needed"));
    }
    match parse_whole::<usize>(s)? {
        0 => Err(format!("'{s}' is 0: a factor ≥ 1 is needed")),
        k => Ok(k),
    }
}

/// Parses a whole number ≥ 0 (`--horizon`, `--delay`, `--samples`…) with a message that says
/// what is wrong ("-3" is negative) instead of "invalid digit found in string".
pub fn parse_count(s: &str) -> Result<usize, String> {
    parse_whole(s)
}

/// [`parse_count`] for 64-bit values (`--seed`).
pub fn parse_seed(s: &str) -> Result<u64, String> {
    parse_whole(s)
}

fn parse_whole<N: std::str::FromStr>(s: &str) -> Result<N, String> {
    let t = s.trim();
    if t.starts_with('-') {
        return Err(format!("'{s}' is negative: a whole number ≥ 0 is needed"));
    }
    t.parse().map_err(|_| {
        if !t.is_empty() && t.bytes().all(|b| b.is_ascii_digit()) {
            format!("'{s}' is too large")
        } else {
            format!("'{s}' is not a whole number")
        }
    })
}

/// `data` (read from `path`) decimated by `factor` (`--decimate` of `fit`, `diagnose`,
/// `subspace`), a refusal naming the file; as it is when `factor` is 1.
pub fn decimate_record<T: Real>(
    data: IoData<T>,
    factor: usize,
    path: &std::path::Path,
) -> Result<IoData<T>, Failure> {
    match factor {
        1 => Ok(data),
        k => data
            .decimate(k)
            .map_err(|e| Failure::Message(format!("{}: {e}", path.display()))),
    }
}

/// `data` (read from `path`) decimated by `factor` (`compare --decimate`, by default `recorded`:
/// the decimation the model file records), said on standard error; as it is when `factor` is 1.
pub fn decimated_as_fitted<T: Real>(
    data: IoData<T>,
    factor: usize,
    recorded: usize,
    path: &std::path::Path,
) -> Result<IoData<T>, Failure> {
    if factor <= 1 {
        if let Some(w) = decimation_mismatch(factor, recorded) {
            super::note(&w);
        }
        return Ok(data);
    }
    let d = data
        .decimate(factor)
        .map_err(|e| Failure::Message(format!("{}: {e}", path.display())))?;
    super::note(&format!(
        "note: {} decimated by {factor}, {} ({} of {} samples kept)",
        path.display(),
        decimation_source(factor, recorded),
        d.len(),
        data.len()
    ));
    if let Some(w) = decimation_mismatch(factor, recorded) {
        super::note(&w);
    }
    Ok(d)
}

/// Where a decimation factor of `compare`/`simulate` comes from: the model file's (`recorded`)
/// or the command line's.
pub fn decimation_source(factor: usize, recorded: usize) -> &'static str {
    if factor == recorded {
        "as the model's record was"
    } else {
        "as --decimate asks"
    }
}

/// The warning when `--decimate` differs from the factor the model was fitted at: the record
/// then runs at another sample rate than the model's; `None` when they agree.
pub fn decimation_mismatch(factor: usize, recorded: usize) -> Option<String> {
    (factor != recorded).then(|| {
        let fitted = match recorded {
            1 => "a record that was not decimated".to_string(),
            k => format!("a record decimated by {k}"),
        };
        format!(
            "warning: the model was fitted on {fitted}: decimated by {factor}, this record runs \
             at another sample rate than the model's"
        )
    })
}

/// Refuses input columns `columns` (`--input`) whose count is not the model's `inputs`.
pub fn check_input_count(columns: &[String], inputs: usize) -> Result<(), Failure> {
    let given: Vec<&str> = columns
        .iter()
        .flat_map(|c| c.split(','))
        .map(str::trim)
        .filter(|c| !c.is_empty())
        .collect();
    if given.len() == inputs {
        return Ok(());
    }
    let model = match inputs {
        1 => "one input".to_string(),
        k => format!("{k} inputs"),
    };
    Err(format!(
        "the model has {model}, but --input {} names {}: give {} column{}",
        given.join(","),
        given.len(),
        inputs,
        if inputs == 1 { "" } else { "s" }
    )
    .into())
}

/// Reads a record with the given input columns and one output from a CSV file.
pub fn read_record<T: Real>(
    path: &PathBuf,
    inputs: &[&str],
    output: &str,
) -> Result<IoData<T>, Failure> {
    // streamed into the channels: the file's other columns are not kept
    Ok(IoData::from_csv(path, inputs, &[output])?)
}

/// JSON of a metric pair {"mse", "fit_percent", "nrmse"}.
pub fn metrics_json(m: &Metrics) -> Value {
    json!({"mse": m.mse, "fit_percent": m.fit_percent, "nrmse": m.nrmse})
}

/// The `fit --json` object of a model (validation may be absent).
pub fn model_json<T: Real>(
    model: &HammersteinModel<T>,
    train: &Metrics,
    validation: Option<&Metrics>,
) -> Result<Value, Failure> {
    let lin = model.linear();
    let poles = lin.poles()?;
    let tf = model.transfer_function()?;
    let params: serde_json::Map<String, Value> = model
        .parameters()
        .into_iter()
        .map(|(k, v)| (k, json_number(v)))
        .collect();
    let errors: serde_json::Map<String, Value> = model
        .parameters_with_errors()
        .into_iter()
        .filter_map(|(k, _, se)| se.map(|se| (k, json_number(se))))
        .collect();
    let report = model.report();
    let output_map = model.output_map().map(|g| {
        let pe = model.output_map_parameters_with_errors();
        json!({
            "name": g.name(),
            "parameters": pe
                .iter()
                .map(|(k, v, _)| (k.clone(), json_number(*v)))
                .collect::<serde_json::Map<String, Value>>(),
            "standard_errors": pe
                .iter()
                .filter_map(|(k, _, se)| se.map(|se| (k.clone(), json_number(se))))
                .collect::<serde_json::Map<String, Value>>(),
        })
    });
    Ok(json!({
        "nonlinearity": model.nonlinearity().name(),
        "output_nonlinearity": output_map.unwrap_or(Value::Null),
        "effects": model.nonlinearity().effects(),
        "parameters": params,
        "standard_errors": errors,
        "order": lin.order(),
        "horizon": model.settings().options().horizon,
        "horizon_raised_from": report.horizon_raised_from,
        "delay": model.delay(),
        "poles": poles.iter().map(|(re, im)| json!([re, im])).collect::<Vec<_>>(),
        "spectral_radius": json_number(model.linear().spectral_radius()?),
        "stable_enforced": model.settings().options().stable,
        "stabilised_from": report.stabilised.map(|b| json!({
            "spectral_radius": json_number(b.spectral_radius),
            "train_mse": json_number(b.train_mse),
        })),
        "numerator": tf.numerator,
        "denominator": tf.denominator,
        "iterations": report.iterations.len(),
        "converged": report.converged,
        "termination": report.termination.name(),
        "refined": report.refinement.as_ref().is_some_and(|r| r.accepted),
        "screening_window": report.screening_window,
        "order_selection": report
            .order_selection
            .iter()
            .map(|c| json!({
                "order": c.order,
                "feedthrough": c.feedthrough,
                "criterion": json_number(c.criterion),
                "train_mse": json_number(c.train_mse),
                "refused_from_rest": c.refused_from_rest.map(json_number),
            }))
            .collect::<Vec<_>>(),
        "train": metrics_json(train),
        "validation": validation.map(metrics_json).unwrap_or(Value::Null),
    }))
}

/// A number in scientific notation with 4 significant digits ("NaN" spelled out).
pub fn sci(v: f64) -> String {
    if v.is_finite() {
        format!("{v:.4e}")
    } else {
        format!("{v}")
    }
}

/// Units of a record's input and output from its column names ("force_N", "y [mm]"), and its
/// sampling time, for the report's axes.
pub fn units_of<T: Real>(data: &hammerstein::IoData<T>) -> hammerstein::report::Units {
    use hammerstein::units::unit_of;
    let first = |names: &[String]| names.first().and_then(|n| unit_of(n)).unwrap_or_default();
    let ts = data.sample_time();
    hammerstein::report::Units {
        input: first(data.input_names()),
        output: first(data.output_names()),
        sample_time: (ts != 1.0).then_some(ts),
    }
}

/// A parameter value with six significant digits: fixed notation from 1e-3 to 1e6, scientific
/// outside (so 1.2e-6 is not printed as 0.000001).
pub fn value_text(v: f64) -> String {
    if v == 0.0 || !v.is_finite() {
        return format!("{v}");
    }
    let mag = v.abs().log10().floor() as i32;
    if !(-3..6).contains(&mag) {
        format!("{v:.5e}")
    } else {
        format!("{v:.*}", (5 - mag).max(0) as usize)
    }
}

/// The spread (max − min) of input `j` of `data`: the natural scale of the parameters in input
/// units, which [`value_text_resolving`] prints to 1e-4 of it.
pub fn input_spread<T: Real>(data: &IoData<T>, j: usize) -> f64 {
    let (lo, hi) = data
        .input_slice(j)
        .iter()
        .map(|v| v.as_f64())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
            (lo.min(v), hi.max(v))
        });
    hi - lo
}

/// Relative resolution of a parameter against the input's spread:
/// [`value_text_resolving`] prints digits down to this fraction of the spread.
pub const PARAMETER_RESOLUTION: f64 = 1e-4;

/// A parameter value as [`value_text`] prints it (six significant digits), with more digits
/// when six do not resolve [`PARAMETER_RESOLUTION`] of `spread` (the training input's spread):
/// a jump position z1 = 1000000.0123 on an input of spread 10 is printed "1000000.012", not
/// "1.00000e6". Values of the order of the spread or below print as [`value_text`] does; at
/// most 15 significant digits (what f64 carries).
pub fn value_text_resolving(v: f64, spread: f64) -> String {
    let resolution = PARAMETER_RESOLUTION * spread;
    if v == 0.0 || !v.is_finite() || !(resolution > 0.0 && resolution.is_finite()) {
        return value_text(v);
    }
    let mag = v.abs().log10().floor() as i32;
    // the sixth significant digit is fine enough
    if 10f64.powi(mag - 5) <= resolution {
        return value_text(v);
    }
    let decimals = (-resolution.log10()).ceil() as i32;
    let significant = mag + 1 + decimals;
    if significant > 15 {
        format!("{v:.14e}")
    } else if mag < -3 {
        format!("{v:.*e}", (significant - 1).max(0) as usize)
    } else {
        format!("{v:.*}", decimals.max(0) as usize)
    }
}

/// A standard error with two significant digits ("0.0012", "3.4e-7").
pub fn significant(v: f64) -> String {
    if v == 0.0 || !v.is_finite() {
        return format!("{v}");
    }
    let mag = v.abs().log10().floor() as i32;
    if !(-4..5).contains(&mag) {
        format!("{v:.1e}")
    } else {
        format!("{v:.*}", (1 - mag).max(0) as usize)
    }
}

/// A finite number as JSON, or null.
pub fn json_number(v: f64) -> Value {
    if v.is_finite() { json!(v) } else { Value::Null }
}

/// Human-readable model summary; `input_spread` ([`input_spread`] of the training record) sets
/// the digits of the parameters ([`value_text_resolving`]).
pub fn model_text<T: Real>(
    model: &HammersteinModel<T>,
    train: &Metrics,
    validation: Option<&Metrics>,
    input_spread: f64,
) -> Result<String, Failure> {
    let mut s = String::new();
    let eff = model.nonlinearity().effects();
    s.push_str(&format!(
        "nonlinearity: {} (effects: {})\n",
        model.nonlinearity().name(),
        if eff.is_empty() {
            "none".into()
        } else {
            eff.join(", ")
        }
    ));
    for (k, v, se) in model.parameters_with_errors() {
        let pm = error_text(se);
        s.push_str(&format!(
            "  {k:>4} = {}{pm}\n",
            value_text_resolving(v, input_spread)
        ));
    }
    // a one-sided saturation's absent limit: "z2 = -inf (none)"
    if let Some((k, v)) =
        hammerstein::regressors::SaturationSides::of_spec(&model.nonlinearity().spec()).absent()
    {
        s.push_str(&format!("  {k:>4} = {v} (none)\n"));
    }
    if let Some(g) = model.output_map() {
        s.push_str(&format!("output nonlinearity: {}\n", g.name()));
        for (k, v, se) in model.output_map_parameters_with_errors() {
            // an unbounded saturation limit: "-inf (none)", no error
            let text = if hammerstein::regressors::is_unbounded_limit(v) {
                format!("{} (none)", hammerstein::regressors::limit_text(v, 6))
            } else {
                format!("{v:.6}{}", error_text(se))
            };
            s.push_str(&format!("  {k:>6} = {text}\n"));
        }
    }
    let tf = model.transfer_function()?;
    s.push_str(&format!(
        "linear block: order {}\n  numerator   {:?}\n  denominator {:?}\n",
        model.linear().order(),
        tf.numerator
            .iter()
            .map(|x| (x * 1e6).round() / 1e6)
            .collect::<Vec<_>>(),
        tf.denominator
            .iter()
            .map(|x| (x * 1e6).round() / 1e6)
            .collect::<Vec<_>>()
    ));
    if let Some(w) = unstable_text(model)? {
        s.push_str(&w);
    }
    if let Some(w) = stabilised_text(model) {
        s.push_str(&w);
    }
    let r = model.report();
    if let Some(from) = r.horizon_raised_from {
        s.push_str(&format!(
            "horizon: {} (the default {from} raised: order {} needs a longer one; --horizon sets it)\n",
            model.settings().options().horizon,
            model.linear().order()
        ));
    }
    s.push_str(&format!(
        "iterations: {} ({}){}\n",
        r.iterations.len(),
        r.termination.name(),
        match &r.refinement {
            Some(rf) if rf.accepted => format!(
                ", refined: training MSE {} -> {}",
                sci(rf.mse_before),
                sci(rf.mse_after)
            ),
            Some(_) => ", refinement found nothing better".into(),
            None => String::new(),
        }
    ));
    if let Some(best) = r.order_selection.iter().min_by(|a, b| a.preference(b)) {
        let has = |d: bool| r.order_selection.iter().any(|c| c.feedthrough == d);
        // the rows the order line lists: those without D, or with D when every one has it
        // (`--feedthrough on`, or a refit that keeps an earlier decision)
        let base = !has(false);
        let mut orders: Vec<usize> = r
            .order_selection
            .iter()
            .filter(|c| c.feedthrough == base)
            .map(|c| c.order)
            .collect();
        orders.sort_unstable();
        orders.dedup();
        let list = |d: bool| {
            r.order_selection
                .iter()
                .filter(|c| c.feedthrough == d)
                .map(|c| {
                    let refused = if c.refused() { " refused" } else { "" };
                    format!("{}: {:.1}{refused}", c.order, c.criterion)
                })
                .collect::<Vec<_>>()
                .join(", ")
        };
        if orders.len() > 1 {
            s.push_str(&format!(
                "order {} chosen automatically: lowest BIC on the training part (BIC by order: {})\n",
                best.order,
                list(base)
            ));
        }
        if let Some(worst) = r
            .order_selection
            .iter()
            .filter_map(|c| c.refused_from_rest)
            .reduce(f64::max)
        {
            s.push_str(&format!(
                "candidates refused: their simulation from rest departs from their fit (initial \
                 state estimated) by up to {} times the output's excursion (more than {}): modes \
                 the input does not excite, whose response to the record's start the estimated \
                 initial state cancels\n",
                significant(worst),
                hammerstein::fit::from_rest::REST_LIMIT
            ));
        }
        if base {
            s.push_str(
                "feed-through D included (fixed: every candidate had one, not chosen by BIC)\n",
            );
        } else if has(true) {
            s.push_str(&format!(
                "feed-through D {} by BIC (with D: {}; without: {})\n",
                if best.feedthrough {
                    "estimated"
                } else {
                    "left out"
                },
                list(true),
                list(false)
            ));
        }
    }
    if let Some(w) = r.screening_window {
        let default = hammerstein::fit::DEFAULT_SCREEN_WINDOW;
        s.push_str(&if w > default {
            format!(
                "long record: the structure chosen on {w} samples of it (the models of shorter \
                 screening windows, from {default} samples, did not explain the whole record)\n"
            )
        } else if model.output_map().is_some() {
            // a Hammerstein–Wiener model's joint refinement is not polished on the whole record
            format!(
                "long record: the structure and the parameters fitted on a screening window of \
                 {w} samples (a model with an output map is not polished on the whole record)\n"
            )
        } else {
            format!(
                "long record: the structure chosen on a screening window of {w} samples, the \
                 parameters polished on the whole record\n"
            )
        });
    }
    s.push_str(&fit_lines(train, validation));
    Ok(s)
}

/// The line saying that the fitted linear block is unstable (a pole outside the unit circle), how
/// fast its free response grows, and what that means for the model's use; `None` for a stable
/// block.
pub fn unstable_text<T: Real>(model: &HammersteinModel<T>) -> Result<Option<String>, Failure> {
    let rho = model.linear().spectral_radius()?;
    if rho < 1.0 {
        return Ok(None);
    }
    let growth = if rho > 1.0 {
        format!(
            ", its free response growing by a factor e every {:.0} samples",
            1.0 / rho.ln()
        )
    } else {
        String::new()
    };
    // a pole just outside the circle is most often a drift or an integrating mode of the record
    let why = if rho < 1.01 {
        " (a drift or an integrating mode the record holds, fitted just outside the unit circle)"
    } else {
        ""
    };
    Ok(Some(format!(
        "linear block unstable: a pole of modulus {rho:.6}{growth}; the model fits this record, \
         but a simulation much longer than it diverges{why}; --stable fits a stable block\n"
    )))
}

/// The warning (for standard error) that a model's simulation from rest departs from `what` (its
/// fit on a record with the initial state estimated, or its simulation from the steady state of
/// the input's first sample) by `departure` times the output's excursion
/// (`hammerstein::fit::from_rest`); `None` within the limit or undefined.
pub fn from_rest_warning(departure: Option<f64>, what: &str) -> Option<String> {
    use hammerstein::fit::from_rest::{REST_LIMIT, departs};
    let d = departure.filter(|_| departs(departure))?;
    Some(format!(
        "warning: the model's simulation from rest departs from {what} by {} times the output's \
         excursion (limit {REST_LIMIT}): its response to the step from rest to the first input \
         rings through modes the input does not excite (an initial state estimated on a record \
         cancels it); `simulate` (from rest) is not usable, and a fit % holds only with the \
         initial state estimated (a lower --order, or --decimate auto on an oversampled record, \
         fits a model without such modes)",
        significant(d)
    ))
}

/// The JSON object {"departure", "departs"} of a from-rest departure (`from_rest_warning`).
pub fn from_rest_json(departure: Option<f64>) -> Value {
    json!({
        "departure": departure.map(json_number),
        "departs": hammerstein::fit::from_rest::departs(departure),
    })
}

/// The line saying what `--stable` did: the largest pole modulus it kept the block to, or the
/// unstable block it replaced and what that cost in training MSE; `None` without `--stable`.
pub fn stabilised_text<T: Real>(model: &HammersteinModel<T>) -> Option<String> {
    if !model.settings().options().stable {
        return None;
    }
    let Some(b) = model.report().stabilised else {
        let rho = model.linear().spectral_radius().ok()?;
        return Some(format!(
            "stability enforced (--stable): every refinement kept its poles within radius {}; \
             largest pole modulus {rho:.6}\n",
            hammerstein::fit::STABLE_RADIUS
        ));
    };
    let after = model.report().train_mse;
    let cost = if b.train_mse > 0.0 {
        format!(" ({:+.2} %)", 100.0 * (after / b.train_mse - 1.0))
    } else {
        String::new()
    };
    Some(format!(
        "stability enforced (--stable): the unconstrained block had a pole of modulus {:.6}; the \
         stable block's training MSE {} against {}{cost}\n",
        b.spectral_radius,
        significant(after),
        significant(b.train_mse)
    ))
}

/// " ± SE" after a parameter value ("± ∞ (not determined by the record)", nothing without one).
pub fn error_text(se: Option<f64>) -> String {
    match se {
        Some(se) if se.is_finite() => format!(" ± {}", significant(se)),
        Some(_) => " ± ∞ (not determined by the record)".into(),
        None => String::new(),
    }
}

/// The "train: fit … MSE …" line and, when given, the validation line.
pub fn fit_lines(train: &Metrics, validation: Option<&Metrics>) -> String {
    let mut s = format!(
        "train:      fit {:6.2} %  MSE {}\n",
        train.fit_percent,
        sci(train.mse)
    );
    if let Some(v) = validation {
        s.push_str(&format!(
            "validation: fit {:6.2} %  MSE {}\n",
            v.fit_percent,
            sci(v.mse)
        ));
    }
    s
}

/// The warning printed after a followed sequence whose validation MSE rose at `steps`
/// (nothing when it never rose).
pub fn rose_warning(steps: &[usize]) -> Option<String> {
    if steps.is_empty() {
        return None;
    }
    let list: Vec<String> = steps.iter().map(|i| i.to_string()).collect();
    Some(format!(
        "warning: the validation MSE rose at step {}: the training-part criterion that chose the \
         step and the validation data disagree (the system may be outside this model class, or \
         the validation record unlike the training one)",
        list.join(", ")
    ))
}

/// The warning for a dead-zone or preload asked of an input that stays far from 0, where those
/// effects sit (`anchored_effects_far_from_input`); `None` otherwise.
pub fn anchored_warning<T: Real>(
    settings: &hammerstein::Hammerstein<T>,
    data: &hammerstein::IoData<T>,
    input: &str,
) -> Option<String> {
    let mean = hammerstein::fit::anchored_effects_far_from_input(settings, data)?;
    Some(format!(
        "warning: the input '{input}' stays near {mean:.6e}, far from 0, where the dead-zone and \
         the preload sit: if the actuator's zero is not at {input} = 0, subtract it from the \
         input before fitting (hysteresis and saturation follow the input by themselves)"
    ))
}

/// The model's effects as a table cell ("linear", "hysteresis + saturation").
pub fn effects_text<T: Real>(model: &HammersteinModel<T>) -> String {
    let e = model.nonlinearity().effects();
    if e.is_empty() {
        "linear".into()
    } else {
        e.join(" + ")
    }
}

/// The diagnosis' top suggestion as a table cell.
pub fn top_suggestion_text<T: Real>(d: &hammerstein::diagnosis::Diagnosis<T>) -> String {
    match d.suggestions.first() {
        Some(s) => format!("{} (score {:.2})", s.effect, s.score),
        None if d.adequate => "none: residuals consistent with noise".into(),
        None => "none helps (residual tests still fail)".into(),
    }
}

/// The input and output column names to read for a single-input model whose file records
/// `recorded`: the ones given on the command line, or, where they are the defaults ("u", "y"),
/// the names the file records (`fit --save` writes them); the defaults for files without them.
pub fn model_columns(
    recorded: Option<&hammerstein::fit::ColumnNames>,
    input: &str,
    output: &str,
) -> (String, String) {
    match recorded {
        Some(c) => (
            if input == "u" {
                c.input.clone()
            } else {
                input.into()
            },
            if output == "y" {
                c.output.clone()
            } else {
                output.into()
            },
        ),
        None => (input.into(), output.into()),
    }
}

/// The input columns to read for a several-input model whose branches are `model_inputs`:
/// those given (`--input u1,u2`; "u", the default, gives the model's own), each branch reading
/// the column of its own name when the names given are the model's in another order (by
/// position otherwise: a record whose columns are named differently).
pub fn miso_columns(model_inputs: &[String], given: &str) -> Vec<String> {
    if given == "u" {
        return model_inputs.to_vec();
    }
    let names: Vec<String> = given.split(',').map(|s| s.trim().to_string()).collect();
    let (mut a, mut b) = (names.clone(), model_inputs.to_vec());
    a.sort();
    b.sort();
    if a == b { model_inputs.to_vec() } else { names }
}
