//! The model file `compare` and `simulate` read: its JSON parsed once, then taken as a
//! several-input model (its `kind` says so) or a single-input one with the column names its
//! file records. Before, the file was parsed up to three times (its kind, the model, its
//! columns).

use crate::cli::Failure;
use hammerstein::Error;
use hammerstein::fit::{ColumnNames, HammersteinModel, ModelFile};
use hammerstein::miso::{MisoModel, MisoModelFile};
use hammerstein::regressors::from_spec;
use std::path::Path;

/// A saved model as read from its file.
pub enum Saved {
    /// A single-input model and the columns it was fitted on (`None`: not recorded).
    Single(Box<HammersteinModel<f64>>, Option<ColumnNames>),
    /// A several-input model.
    Several(MisoModel<f64>),
}

/// A saved model and the factor its record was decimated by (1: not decimated).
pub struct SavedModel {
    /// The model.
    pub model: Saved,
    /// The decimation factor the file records (1 when none).
    pub decimation: usize,
}

impl Saved {
    /// Reads the model file at `path` (built-in nonlinearities). Its errors are those of
    /// `HammersteinModel::load` and `MisoModel::load`: the path named in a format error.
    pub fn read(path: &Path) -> Result<SavedModel, Failure> {
        let text = std::fs::read_to_string(path).map_err(|e| Error::io(path.display(), e))?;
        let at = |e: Error| match e {
            Error::ModelFormat(m) => Error::ModelFormat(format!("{}: {m}", path.display())),
            e => e,
        };
        let value: serde_json::Value = serde_json::from_str(&text)
            .map_err(|e| at(Error::ModelFormat(format!("not valid JSON: {e}"))))?;
        if MisoModelFile::is_miso_value(&value) {
            let file = MisoModelFile::from_value(value).map_err(|e| {
                // a parsed value has no lines: the text, read again on this error path only,
                // gives the message its line and column
                at(MisoModelFile::parse(&text).err().unwrap_or(e))
            })?;
            return Ok(SavedModel {
                model: Saved::Several(MisoModel::from_file(&file, from_spec::<f64>)?),
                decimation: recorded_decimation(file.decimation, path)?,
            });
        }
        let file = ModelFile::from_value(value).map_err(at)?;
        let columns = file.columns.clone();
        let model = HammersteinModel::from_file(&file, from_spec::<f64>)?;
        Ok(SavedModel {
            model: Saved::Single(Box::new(model), columns),
            decimation: recorded_decimation(file.decimation, path)?,
        })
    }
}

/// The decimation factor a model file records (1 when none); 0 is refused, as `--decimate 0`
/// is: no record can be decimated by it.
fn recorded_decimation(k: Option<usize>, path: &Path) -> Result<usize, Failure> {
    match k {
        Some(0) => Err(Error::ModelFormat(format!(
            "{}: \"decimation\": 0 is not a decimation factor (1 or more: every K-th sample kept)",
            path.display()
        ))
        .into()),
        k => Ok(k.unwrap_or(1)),
    }
}
