//! Saving and loading fitted models as JSON (`ModelFile`, with a `format_version`).
//! The nonlinearity is stored as its `NonlinearitySpec` and rebuilt by `regressors::from_spec`; an
//! output map (format version 2) likewise, rebuilt by `regressors::output_map_from_spec`.

use super::model::HammersteinModel;
use crate::error::{Error, Result};
use crate::fit::fit_report::FitReport;
use crate::fit::settings::{FitOptions, Hammerstein, Screening};
use crate::real::Real;
use crate::regressors::{EffectSet, NonlinearitySpec, OutputMap, StaticNonlinearity};
use crate::statespace::{StateSpace, to_rows};
use faer::Mat;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// Newest version of the model file format this build writes (2: with an `output_map`; a model
/// without one is written as version 1, which older builds read too); it reads every version
/// from [`OLDEST_MODEL_FORMAT_VERSION`] on.
pub const MODEL_FORMAT_VERSION: u32 = 2;

/// Oldest model file format this build still reads (1: no output map).
pub const OLDEST_MODEL_FORMAT_VERSION: u32 = 1;

fn readable_version(v: u64) -> bool {
    (u64::from(OLDEST_MODEL_FORMAT_VERSION)..=u64::from(MODEL_FORMAT_VERSION)).contains(&v)
}

/// The linear block as stored (row-major matrices).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LinearFile {
    /// A, n×n.
    pub a: Vec<Vec<f64>>,
    /// B, n×1.
    pub b: Vec<Vec<f64>>,
    /// C, 1×n.
    pub c: Vec<Vec<f64>>,
    /// D, 1×1.
    pub d: Vec<Vec<f64>>,
    /// Sample time in seconds.
    pub ts: f64,
}

/// The settings as stored: the UDN's effects, the [`FitOptions`] (flattened: one JSON object, the
/// same fields as before the options had a struct of their own) and the names of a user method or
/// backend. Not stored: the observer, and (as before) the screening rule and the automatic
/// feed-through rule (`with_d` records the decision).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SettingsFile {
    /// UDN effects, `None` for other bases.
    pub effects: Option<EffectSet>,
    /// The plain-data settings.
    #[serde(flatten)]
    pub options: FitOptions,
    /// Name of the user's subspace method the fit used (not serialisable: loading falls back
    /// to `method`); absent for the built-in methods.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub user_method: Option<String>,
    /// Name of the user's linear-algebra backend the fit used (loading falls back to
    /// `backend`); absent for the built-in backends.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub user_backend: Option<String>,
}

/// A saved Hammerstein model.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ModelFile {
    /// File format version ([`MODEL_FORMAT_VERSION`]).
    pub format_version: u32,
    /// Scalar type the model was fitted in ("f32" or "f64").
    pub scalar: String,
    /// The nonlinearity.
    pub nonlinearity: NonlinearitySpec,
    /// The linear block.
    pub linear: LinearFile,
    /// Output offset c.
    pub output_offset: f64,
    /// Initial state on the training record.
    pub training_x0: Vec<f64>,
    /// The settings it was fitted with.
    pub settings: SettingsFile,
    /// The fit's report.
    pub report: FitReport,
    /// The static output map after the linear block (`None`: a plain Hammerstein model; always
    /// `None` in version 1 files).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub output_map: Option<NonlinearitySpec>,
    /// The names of the record's input and output columns the model was fitted on (`None`:
    /// not recorded; `compare` and `simulate` then need them named).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub columns: Option<ColumnNames>,
    /// The factor the record was decimated by before the fit ([`IoData::decimate`]; `None`:
    /// not decimated): `compare` and `simulate` decimate the records they are given by it.
    ///
    /// [`IoData::decimate`]: crate::IoData::decimate
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub decimation: Option<usize>,
}

/// The input and output column names a model was fitted on.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct ColumnNames {
    /// The input column.
    pub input: String,
    /// The output column.
    pub output: String,
}

impl ModelFile {
    /// Parses the JSON text of a model file. The `format_version` is checked before the rest, so
    /// a file of another version gets [`Error::UnsupportedVersion`] rather than a message about
    /// the fields that version lacks.
    pub fn parse(text: &str) -> Result<ModelFile> {
        let value: serde_json::Value = serde_json::from_str(text)
            .map_err(|e| Error::ModelFormat(format!("not valid JSON: {e}")))?;
        Self::from_value(value)
    }

    /// The model file in JSON already parsed (checked as [`parse`](Self::parse) checks the
    /// text): for a caller that read the value once to tell the kinds of model file apart.
    pub fn from_value(value: serde_json::Value) -> Result<ModelFile> {
        let object = value
            .as_object()
            .ok_or_else(|| Error::ModelFormat("not a JSON object".into()))?;
        // a single-input file has no "kind"; a several-input one has "kind": "miso"
        // (`miso::MISO_FORMAT_KIND`, a layer above): say which instead of "no format_version"
        if let Some(kind) = object.get("kind") {
            return Err(Error::ModelFormat(match kind.as_str() {
                Some("miso") => "a several-input model file (\"kind\": \"miso\"): load it with \
                                 MisoModel::load"
                    .into(),
                _ => format!(
                    "unknown model kind {kind} (single-input model files have no \"kind\", \
                     several-input ones \"kind\": \"miso\")"
                ),
            }));
        }
        let version = object.get("format_version").ok_or_else(|| {
            Error::ModelFormat(
                "no \"format_version\" field (not a model saved by hammerstein?)".into(),
            )
        })?;
        let found = version.as_u64().ok_or_else(|| {
            Error::ModelFormat(format!(
                "\"format_version\" must be a non-negative integer, got {version}"
            ))
        })?;
        if !readable_version(found) {
            return Err(Error::UnsupportedVersion {
                found,
                supported: MODEL_FORMAT_VERSION,
            });
        }
        serde_json::from_value(value).map_err(|e| Error::ModelFormat(e.to_string()))
    }
}

impl<T: Real> HammersteinModel<T> {
    /// The model as a serialisable file structure.
    pub fn to_file(&self) -> ModelFile {
        let s = &self.settings;
        ModelFile {
            format_version: if self.output_map.is_some() {
                MODEL_FORMAT_VERSION
            } else {
                OLDEST_MODEL_FORMAT_VERSION
            },
            scalar: T::NAME.into(),
            nonlinearity: self.nl.spec(),
            linear: LinearFile {
                a: to_rows(self.linear.a.as_ref()),
                b: to_rows(self.linear.b.as_ref()),
                c: to_rows(self.linear.c.as_ref()),
                d: to_rows(self.linear.d.as_ref()),
                ts: self.linear.ts,
            },
            output_offset: self.offset.as_f64(),
            training_x0: self.x0.iter().map(|x| x.as_f64()).collect(),
            settings: SettingsFile {
                effects: s.effects(),
                options: FitOptions {
                    // the decision of an automatic feed-through rule is kept
                    with_d: s.options.with_d || self.has_feedthrough(),
                    d_auto: false,
                    // not recorded (the file format predates it)
                    screening: Screening::default(),
                    ..s.options.clone()
                },
                user_method: s.user_method.as_ref().map(|m| format!("user:{}", m.name())),
                user_backend: s.user_linalg.as_ref().map(|l| format!("user:{}", l.name())),
            },
            report: self.report.clone(),
            output_map: self.output_map.as_ref().map(|g| g.spec()),
            columns: None,
            decimation: None,
        }
    }

    /// Writes the model as JSON, atomically (temporary file beside `path`, then rename): a
    /// failed save leaves a previous file at `path` intact.
    pub fn save(&self, path: impl AsRef<Path>) -> Result<()> {
        write_file(path.as_ref(), &self.to_file())
    }

    /// [`save`](Self::save) with the names of the input and output columns it was fitted on
    /// recorded in the file (what `compare` and `simulate` read by default).
    pub fn save_with_columns(
        &self,
        path: impl AsRef<Path>,
        input: &str,
        output: &str,
    ) -> Result<()> {
        write_file(path.as_ref(), &self.to_file_with_columns(input, output))
    }

    /// [`to_file`](Self::to_file) with the names of the input and output columns it was fitted
    /// on recorded (what [`save_with_columns`](Self::save_with_columns) writes).
    pub fn to_file_with_columns(&self, input: &str, output: &str) -> ModelFile {
        let mut file = self.to_file();
        file.columns = Some(ColumnNames {
            input: input.into(),
            output: output.into(),
        });
        file
    }
}

impl ModelFile {
    /// Writes the file as JSON at `path`, atomically (temporary file beside `path`, then
    /// rename): for a caller that records more than [`HammersteinModel::save_with_columns`]
    /// does (the record's decimation).
    pub fn write(&self, path: impl AsRef<Path>) -> Result<()> {
        write_file(path.as_ref(), self)
    }
}

/// Writes `file` as JSON at `path`, atomically.
fn write_file(path: &Path, file: &ModelFile) -> Result<()> {
    let text = serde_json::to_string_pretty(file)
        .map_err(|e| Error::ModelFormat(format!("cannot serialise the model: {e}")))?;
    crate::atomic::write_atomic(path, text.as_bytes())
}

/// Serialises the model as its [`ModelFile`] (the JSON of [`HammersteinModel::save`]).
impl<T: Real> Serialize for HammersteinModel<T> {
    fn serialize<S: serde::Serializer>(
        &self,
        serializer: S,
    ) -> std::result::Result<S::Ok, S::Error> {
        self.to_file().serialize(serializer)
    }
}

/// Deserialises a [`ModelFile`] and rebuilds the model (built-in nonlinearities and output maps
/// only, as [`HammersteinModel::from_json`]; user bases: [`HammersteinModel::from_file`]).
impl<'de> Deserialize<'de> for HammersteinModel<f64> {
    fn deserialize<D: serde::Deserializer<'de>>(
        deserializer: D,
    ) -> std::result::Result<Self, D::Error> {
        let file = ModelFile::deserialize(deserializer)?;
        Self::from_file(&file, crate::regressors::from_spec::<f64>)
            .map_err(serde::de::Error::custom)
    }
}

impl HammersteinModel<f64> {
    /// Reads a model saved by [`save`](Self::save); built-in nonlinearities only.
    pub fn load(path: impl AsRef<Path>) -> Result<HammersteinModel<f64>> {
        Self::load_with(path, crate::regressors::from_spec::<f64>)
    }

    /// Reads a saved model, rebuilding its nonlinearity with `build` (for user-defined bases).
    pub fn load_with(
        path: impl AsRef<Path>,
        build: impl Fn(&NonlinearitySpec) -> Result<Box<dyn StaticNonlinearity<f64>>>,
    ) -> Result<HammersteinModel<f64>> {
        let path = path.as_ref();
        let text = std::fs::read_to_string(path).map_err(|e| Error::io(path.display(), e))?;
        let file = ModelFile::parse(&text).map_err(|e| match e {
            Error::ModelFormat(m) => Error::ModelFormat(format!("{}: {m}", path.display())),
            e => e,
        })?;
        Self::from_file(&file, build)
    }

    /// Reads a model from the JSON text of a model file (built-in nonlinearities only).
    pub fn from_json(text: &str) -> Result<HammersteinModel<f64>> {
        Self::from_file(
            &ModelFile::parse(text)?,
            crate::regressors::from_spec::<f64>,
        )
    }

    /// Rebuilds a model from its file structure (built-in output maps only).
    pub fn from_file(
        file: &ModelFile,
        build: impl Fn(&NonlinearitySpec) -> Result<Box<dyn StaticNonlinearity<f64>>>,
    ) -> Result<HammersteinModel<f64>> {
        Self::from_file_with_output_map(file, build, crate::regressors::output_map_from_spec::<f64>)
    }

    /// Rebuilds a model from its file structure, its output map (if any) with `build_map` (for
    /// user-defined maps; `regressors::output_map_from_spec` rebuilds the built-ins).
    pub fn from_file_with_output_map(
        file: &ModelFile,
        build: impl Fn(&NonlinearitySpec) -> Result<Box<dyn StaticNonlinearity<f64>>>,
        build_map: impl Fn(&NonlinearitySpec) -> Result<Box<dyn OutputMap<f64>>>,
    ) -> Result<HammersteinModel<f64>> {
        if !readable_version(file.format_version.into()) {
            return Err(Error::UnsupportedVersion {
                found: file.format_version.into(),
                supported: MODEL_FORMAT_VERSION,
            });
        }
        let spec = &file.nonlinearity;
        if let Some(k) = spec.params.iter().position(|p| !p.is_finite()) {
            return Err(Error::ModelFormat(format!(
                "parameter {k} of the nonlinearity is not finite"
            )));
        }
        let nl = build(spec)?;
        check_nonlinearity(spec, nl.as_ref())?;
        let linear = linear_from_file(&file.linear)?;
        let n = linear.order();
        let settings =
            settings_from_file(&file.settings, nl.as_ref(), file.report.screening_window);
        let map = file.output_map.as_ref().map(&build_map).transpose()?;
        if let (Some(g), Some(spec)) = (&map, &file.output_map)
            && g.params().len() != spec.params.len()
        {
            return Err(Error::ModelFormat(format!(
                "the output map '{}' has {} parameter(s), the file gives {}",
                spec.kind,
                g.params().len(),
                spec.params.len()
            )));
        }
        let mut settings = settings.output_nonlinearity(map.as_ref().map(|g| g.clone_box()));
        // a horizon the fit raised stays raised for refits from the file's model
        settings.horizon_raised_from = file.report.horizon_raised_from;
        let mut model = HammersteinModel::from_parts(
            nl,
            linear,
            file.output_offset,
            settings,
            file.report.clone(),
        )?
        .with_output_map(map)?;
        if file.training_x0.len() == n {
            if file.training_x0.iter().any(|x| !x.is_finite()) {
                return Err(Error::ModelFormat(
                    "training_x0 has non-finite entries".into(),
                ));
            }
            model.x0 = file.training_x0.clone();
        } else if !file.training_x0.is_empty() {
            return Err(Error::ModelFormat(format!(
                "training_x0 has {} entries, the model order is {n}",
                file.training_x0.len()
            )));
        }
        Ok(model)
    }
}

/// Checks the nonlinearity's parameters in the file (`spec`) against the nonlinearity `nl` built
/// from it: as many as it has (the builders take empty params as "defaults": a saved model must
/// carry all of them), the same names when named.
fn check_nonlinearity(spec: &NonlinearitySpec, nl: &dyn StaticNonlinearity<f64>) -> Result<()> {
    let expected = nl.spec();
    if spec.params.len() != expected.params.len() {
        return Err(Error::ModelFormat(format!(
            "the nonlinearity '{}' has {} parameter(s) ({}), the file gives {}",
            spec.kind,
            expected.params.len(),
            expected.param_names.join(", "),
            spec.params.len()
        )));
    }
    if !spec.param_names.is_empty() && spec.param_names != expected.param_names {
        return Err(Error::ModelFormat(format!(
            "the nonlinearity '{}' has parameters ({}), the file names ({})",
            spec.kind,
            expected.param_names.join(", "),
            spec.param_names.join(", ")
        )));
    }
    Ok(())
}

/// The linear block of a model file, its matrices' shapes and entries and the sample time checked.
fn linear_from_file(file: &LinearFile) -> Result<StateSpace<f64>> {
    if !(file.ts.is_finite() && file.ts > 0.0) {
        return Err(Error::ModelFormat(format!(
            "sample time must be positive and finite, got {}",
            file.ts
        )));
    }
    let m = |rows: &Vec<Vec<f64>>, what: &str, nr: usize, nc: usize| -> Result<Mat<f64>> {
        if rows.len() != nr || rows.iter().any(|r| r.len() != nc) {
            return Err(Error::ModelFormat(format!(
                "{what} must be {nr}×{nc} in the model file"
            )));
        }
        if rows.iter().flatten().any(|x| !x.is_finite()) {
            return Err(Error::ModelFormat(format!("{what} has non-finite entries")));
        }
        Ok(Mat::from_fn(nr, nc, |i, j| rows[i][j]))
    };
    let n = file.a.len();
    let mut linear = StateSpace::new(
        m(&file.a, "A", n, n)?,
        m(&file.b, "B", n, 1)?,
        m(&file.c, "C", 1, n)?,
        m(&file.d, "D", 1, 1)?,
    )?;
    linear.ts = file.ts;
    Ok(linear)
}

/// The settings a model file records (a UDN by its effects, otherwise the nonlinearity `nl`), the
/// screening window at least the one the fit chose its structure on (`window`, from the report).
fn settings_from_file(
    s: &SettingsFile,
    nl: &dyn StaticNonlinearity<f64>,
    window: Option<usize>,
) -> Hammerstein<f64> {
    let base = match s.effects {
        Some(set) => Hammerstein::udn(set),
        None => Hammerstein::new(nl.clone_box()),
    };
    let mut screening = Screening::default();
    screening.window = screening.window.max(window.unwrap_or(0));
    // the builders keep what the file cannot record (d_auto off: `with_d` is the decision)
    base.with_options(FitOptions {
        d_auto: false,
        screening,
        ..s.options.clone()
    })
}
