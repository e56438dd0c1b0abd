//! The feedback model's file: a JSON object of its own kind (`"kind": "feedback"`, with a
//! format version), beside the Hammerstein model file whose format it leaves unchanged;
//! `compare` and `simulate` tell the two apart by the `kind` field.

use super::FeedbackOn;
use super::model::FeedbackModel;
use crate::error::{Error, Result};
use crate::regressors::{NonlinearitySpec, StaticNonlinearity};
use faer::Mat;
use serde::{Deserialize, Serialize};

/// The newest format version this build writes and reads: 2 adds `state` feedback (its F in
/// `feedback.state_combination`) and the input nonlinearity before the loop
/// (`input_nonlinearity`), 3 the output map after the block (`output_nonlinearity`). A model
/// is written with the lowest version that holds it (1 for `output` and `velocity` alone, 2
/// with `state` or an input nonlinearity, 3 with an output map), so that older builds read
/// what they can and refuse what they would misread.
pub const FEEDBACK_FILE_VERSION: u32 = 3;

/// The `feedback` section: the loop and its nonlinearity.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FeedbackSection {
    /// "output", "velocity" or "state".
    pub on: FeedbackOn,
    /// F of `state` feedback, z = F x (n values; absent for `output` and `velocity`).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub state_combination: Vec<f64>,
    /// E (n).
    pub e: Vec<f64>,
    /// f's basis and parameters (acting on normalised z).
    pub nonlinearity: NonlinearitySpec,
    /// The z range the training record visited (normalised units).
    pub z_range: (f64, f64),
    /// The viscous coefficient of `velocity` feedback (w = f(z) + viscous·z).
    #[serde(default)]
    pub viscous: f64,
}

/// A feedback model as saved (all in normalised units, with the scales).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FeedbackModelFile {
    /// Always "feedback".
    pub kind: String,
    /// Format version.
    pub version: u32,
    /// A (row by row).
    pub a: Vec<Vec<f64>>,
    /// B (n).
    pub b: Vec<f64>,
    /// C (n).
    pub c: Vec<f64>,
    /// D.
    pub d: f64,
    /// Whether D was estimated.
    pub with_d: bool,
    /// The loop.
    pub feedback: FeedbackSection,
    /// Input offset u₀ (normalised).
    pub u_offset: f64,
    /// Output offset y₀ (normalised).
    pub y_offset: f64,
    /// The record's input scale.
    pub u_scale: f64,
    /// The record's output scale.
    pub y_scale: f64,
    /// The training record's initial state (normalised).
    pub x0: Vec<f64>,
    /// The input nonlinearity before the loop (acting on the normalised input), absent
    /// without one.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub input_nonlinearity: Option<NonlinearitySpec>,
    /// The output map g after the linear block (acting on the normalised linear output),
    /// absent without one (format version 3).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub output_nonlinearity: Option<NonlinearitySpec>,
    /// The input and output columns the model was fitted on.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub columns: Option<(String, String)>,
    /// The decimation factor of the training record (1 or absent: none).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub decimation: Option<usize>,
}

impl FeedbackModelFile {
    /// Whether a parsed JSON value is a feedback model file.
    pub fn is_feedback_value(v: &serde_json::Value) -> bool {
        v.get("kind").and_then(|k| k.as_str()) == Some("feedback")
    }

    /// Parses a value; errors on another kind or an unsupported version.
    pub fn from_value(v: serde_json::Value) -> Result<Self> {
        if !Self::is_feedback_value(&v) {
            return Err(Error::ModelFormat(
                "not a feedback model file (kind ≠ \"feedback\")".into(),
            ));
        }
        let file: Self = serde_json::from_value(v)
            .map_err(|e| Error::ModelFormat(format!("feedback model file: {e}")))?;
        if file.version == 0 || file.version > FEEDBACK_FILE_VERSION {
            return Err(Error::UnsupportedVersion {
                found: u64::from(file.version),
                supported: FEEDBACK_FILE_VERSION,
            });
        }
        Ok(file)
    }

    /// Writes the file atomically as pretty JSON.
    pub fn write(&self, path: &std::path::Path) -> Result<()> {
        let text = serde_json::to_string_pretty(self)
            .map_err(|e| Error::ModelFormat(format!("feedback model file: {e}")))?;
        crate::atomic::write_atomic(path, text.as_bytes())
    }
}

impl FeedbackModel {
    /// The model's file (column names and decimation optional).
    pub fn to_file(&self) -> FeedbackModelFile {
        let n = self.order();
        FeedbackModelFile {
            kind: "feedback".into(),
            version: if self.output.is_some() {
                3
            } else if self.on == FeedbackOn::State || self.input.is_some() {
                2
            } else {
                1
            },
            a: (0..n)
                .map(|i| (0..n).map(|j| self.a[(i, j)]).collect())
                .collect(),
            b: self.b.clone(),
            c: self.c.clone(),
            d: self.d,
            with_d: self.with_d,
            feedback: FeedbackSection {
                on: self.on,
                state_combination: if self.on == FeedbackOn::State {
                    self.fz.clone()
                } else {
                    Vec::new()
                },
                e: self.e.clone(),
                nonlinearity: self.f.spec(),
                z_range: self.z_range,
                viscous: self.viscous,
            },
            u_offset: self.u_offset,
            y_offset: self.y_offset,
            u_scale: self.u_scale,
            y_scale: self.y_scale,
            x0: self.x0.clone(),
            input_nonlinearity: self.input.as_ref().map(|nl| nl.spec()),
            output_nonlinearity: self.output.as_ref().map(|g| g.spec()),
            columns: None,
            decimation: None,
        }
    }

    /// Rebuilds a model from its file; `basis` rebuilds the nonlinearity from its spec (use
    /// [`feedback_from_spec`](super::feedback_from_spec) for the built-ins, asked first here).
    pub fn from_file(
        file: &FeedbackModelFile,
        basis: impl Fn(&NonlinearitySpec) -> Result<Box<dyn StaticNonlinearity<f64>>>,
    ) -> Result<Self> {
        let n = file.b.len();
        let bad = |what: &str| Error::ModelFormat(format!("feedback model file: {what}"));
        if n == 0 {
            return Err(bad("B is empty"));
        }
        if file.a.len() != n || file.a.iter().any(|r| r.len() != n) {
            return Err(bad("A is not n × n with n the length of B"));
        }
        if file.c.len() != n || file.feedback.e.len() != n {
            return Err(bad("C and E must have the length of B"));
        }
        let state = file.feedback.on == FeedbackOn::State;
        if state && file.feedback.state_combination.len() != n {
            return Err(bad(
                "state feedback needs its state_combination F with the length of B",
            ));
        }
        if !state && !file.feedback.state_combination.is_empty() {
            return Err(bad(
                "a state_combination F is only read with \"on\": \"state\"",
            ));
        }
        if (state || file.input_nonlinearity.is_some()) && file.version < 2 {
            return Err(bad(
                "state feedback and an input nonlinearity need format version 2",
            ));
        }
        if file.output_nonlinearity.is_some() && file.version < 3 {
            return Err(bad("an output map needs format version 3"));
        }
        let ns = n + usize::from(file.feedback.on == FeedbackOn::Velocity);
        if file.x0.len() != ns {
            return Err(bad("x0 has the wrong length"));
        }
        if !(file.u_scale > 0.0 && file.y_scale > 0.0) {
            return Err(bad("scales must be positive"));
        }
        let all = file
            .a
            .iter()
            .flatten()
            .chain(&file.b)
            .chain(&file.c)
            .chain(&file.feedback.e)
            .chain(&file.feedback.state_combination)
            .chain(&file.x0)
            .chain([&file.d, &file.u_offset, &file.y_offset]);
        if all.into_iter().any(|v| !v.is_finite()) {
            return Err(bad("a non-finite entry"));
        }
        let input = match &file.input_nonlinearity {
            Some(spec) => Some(
                crate::regressors::from_spec::<f64>(spec)
                    .map_err(|e| bad(&format!("the input nonlinearity: {e}")))?,
            ),
            None => None,
        };
        let output = match &file.output_nonlinearity {
            Some(spec) => Some(
                crate::regressors::output_map_from_spec::<f64>(spec)
                    .map_err(|e| bad(&format!("the output map: {e}")))?,
            ),
            None => None,
        };
        let f = match super::feedback_from_spec(&file.feedback.nonlinearity) {
            Some(r) => r?,
            None => basis(&file.feedback.nonlinearity)?,
        };
        Ok(FeedbackModel {
            a: Mat::from_fn(n, n, |i, j| file.a[i][j]),
            b: file.b.clone(),
            c: file.c.clone(),
            d: file.d,
            e: file.feedback.e.clone(),
            f,
            viscous: file.feedback.viscous,
            on: file.feedback.on,
            fz: file.feedback.state_combination.clone(),
            input,
            output,
            with_d: file.with_d,
            u_offset: file.u_offset,
            y_offset: file.y_offset,
            u_scale: file.u_scale,
            y_scale: file.y_scale,
            x0: file.x0.clone(),
            z_range: file.feedback.z_range,
        })
    }
}
