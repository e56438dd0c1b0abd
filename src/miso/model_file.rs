//! The file of a several-input model: one single-input model file per branch, named by its
//! input, and the backfitting's report.

use super::model::MisoModel;
use super::report::MisoReport;
use crate::error::{Error, Result};
use crate::fit::{HammersteinModel, ModelFile};
use crate::real::Real;
use crate::regressors::{NonlinearitySpec, StaticNonlinearity};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// The `kind` field that marks a several-input model file.
pub const MISO_FORMAT_KIND: &str = "miso";

/// One branch of a several-input model file.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct MisoBranchFile {
    /// The input's column name.
    pub input: String,
    /// The branch's single-input model.
    pub model: ModelFile,
}

/// A several-input model as a serialisable file structure.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct MisoModelFile {
    /// Always [`MISO_FORMAT_KIND`].
    pub kind: String,
    /// The output's column name.
    pub output: String,
    /// The branches, in input order.
    pub inputs: Vec<MisoBranchFile>,
    /// The backfitting's report.
    pub report: MisoReport,
    /// The factor the record was decimated by before the fit (`None`: not decimated), as in
    /// the single-input [`ModelFile`](crate::fit::ModelFile).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub decimation: Option<usize>,
}

impl MisoModelFile {
    /// Parses the JSON text of a several-input model file.
    pub fn parse(text: &str) -> Result<Self> {
        let file: MisoModelFile = serde_json::from_str(text)
            .map_err(|e| Error::ModelFormat(format!("not a several-input model file: {e}")))?;
        file.checked()
    }

    /// The several-input model file in JSON already parsed (its `kind` checked as
    /// [`parse`](Self::parse) checks it): for a caller that read the value once to tell the
    /// kinds of model file apart. A value has no lines: its errors name no line and column.
    pub fn from_value(value: serde_json::Value) -> Result<Self> {
        let file: MisoModelFile = serde_json::from_value(value)
            .map_err(|e| Error::ModelFormat(format!("not a several-input model file: {e}")))?;
        file.checked()
    }

    /// The file when its `kind` is [`MISO_FORMAT_KIND`].
    fn checked(self) -> Result<Self> {
        if self.kind != MISO_FORMAT_KIND {
            return Err(Error::ModelFormat(format!(
                "kind '{}' where a several-input model file has '{MISO_FORMAT_KIND}'",
                self.kind
            )));
        }
        Ok(self)
    }

    /// Whether JSON text is a several-input model file (its `kind` says so).
    pub fn is_miso(text: &str) -> bool {
        serde_json::from_str::<serde_json::Value>(text).is_ok_and(|v| Self::is_miso_value(&v))
    }

    /// Whether parsed JSON is a several-input model file (its `kind` says so).
    pub fn is_miso_value(value: &serde_json::Value) -> bool {
        value.get("kind").and_then(|k| k.as_str()) == Some(MISO_FORMAT_KIND)
    }
}

impl MisoModelFile {
    /// Writes the file as JSON at `path`, atomically (temporary file beside `path`, then
    /// rename): for a caller that records more than [`MisoModel::save`] does (the record's
    /// decimation).
    pub fn write(&self, path: impl AsRef<Path>) -> Result<()> {
        let text = serde_json::to_string_pretty(self)
            .map_err(|e| Error::ModelFormat(format!("cannot serialise the model: {e}")))?;
        crate::atomic::write_atomic(path.as_ref(), text.as_bytes())
    }
}

impl<T: Real> MisoModel<T> {
    /// The model as a serialisable file structure.
    pub fn to_file(&self) -> MisoModelFile {
        MisoModelFile {
            kind: MISO_FORMAT_KIND.into(),
            output: self.output_name.clone(),
            inputs: self
                .input_names
                .iter()
                .zip(&self.branches)
                .map(|(input, b)| MisoBranchFile {
                    input: input.clone(),
                    model: b.to_file(),
                })
                .collect(),
            report: self.report.clone(),
            decimation: None,
        }
    }

    /// Writes the model as JSON, atomically (temporary file beside `path`, then rename).
    pub fn save(&self, path: impl AsRef<Path>) -> Result<()> {
        self.to_file().write(path)
    }
}

impl MisoModel<f64> {
    /// Rebuilds a model from its file structure, each branch's nonlinearity with `build`.
    pub fn from_file(
        file: &MisoModelFile,
        build: impl Fn(&NonlinearitySpec) -> Result<Box<dyn StaticNonlinearity<f64>>> + Copy,
    ) -> Result<Self> {
        let branches = file
            .inputs
            .iter()
            .map(|b| HammersteinModel::from_file(&b.model, build))
            .collect::<Result<Vec<_>>>()?;
        let names = file.inputs.iter().map(|b| b.input.clone()).collect();
        MisoModel::from_branches(branches, names, file.output.clone(), file.report.clone())
    }

    /// Reads a model saved by [`save`](Self::save) (built-in nonlinearities).
    pub fn load(path: impl AsRef<Path>) -> Result<Self> {
        let path = path.as_ref();
        let text = std::fs::read_to_string(path).map_err(|e| Error::io(path.display(), e))?;
        let file = MisoModelFile::parse(&text).map_err(|e| match e {
            Error::ModelFormat(m) => Error::ModelFormat(format!("{}: {m}", path.display())),
            e => e,
        })?;
        Self::from_file(&file, crate::regressors::from_spec::<f64>)
    }
}
