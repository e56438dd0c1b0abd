//! `diagnose` on a record in the record format (`level,realization,period,u,y`): the structure
//! verdict of its levels beside the diagnosis, and the samples the model is fitted on (the
//! highest level's blocks in file order; see `hammerstein::diagnosis::structure_verdict`).

use hammerstein::data::CsvTable;
use hammerstein::diagnosis::structure_verdict::{beyond_class, evidence, fit_rows, verdict_line};
use hammerstein::diagnosis::{DiagnosisOptions, Unexplained};
use hammerstein::structure::{Record, Structure, StructureOptions, analyze, bla};
use serde_json::{Value, json};

/// What the record format adds to a diagnosis.
pub struct StructureBeside {
    /// The structure analysis, or why there is none (one level only, …).
    pub structure: Result<Structure, String>,
    /// The level the model is fitted on (the highest), of how many.
    pub level: usize,
    /// Number of levels.
    pub levels: usize,
    /// Its input RMS.
    pub rms: f64,
    /// The fitted samples: the level's inputs and outputs, its blocks in file order.
    pub u: Vec<f64>,
    /// Its outputs.
    pub y: Vec<f64>,
    /// Sampling time from a `t` column, when the record has one.
    pub ts: Option<f64>,
}

/// Reads `path` when it is in the record format with the output column; `None` otherwise (the
/// plain path then reads it as usual and reports its errors; a file with the format's columns
/// whose blocks are not whole periods is diagnosed as a plain record, with a note).
pub fn read(
    path: &std::path::Path,
    input: &str,
    output: &str,
) -> Result<Option<StructureBeside>, super::super::Failure> {
    let Ok(header) = CsvTable::read_header(path) else {
        return Ok(None);
    };
    if !Record::is_record_format(&header.names) || !header.names.iter().any(|n| n == output) {
        return Ok(None);
    }
    let table = CsvTable::read(path)?;
    let label = path.display().to_string();
    let record =
        match Record::from_columns(&table.names, &table.columns, input, Some(output), &label) {
            Ok(r) => r,
            Err(e) => {
                // the columns without the record's blocks: diagnosed as a plain record, as before
                super::super::note(&format!(
                    "{label} has the record format's columns but is not a multisine record ({e}): \
                 diagnosed as a plain record, without a structure verdict"
                ));
                return Ok(None);
            }
        };
    let ts = table.sample_time();
    let structure = bla(&record)
        .and_then(|b| {
            analyze(
                &b,
                &StructureOptions {
                    ts,
                    ..Default::default()
                },
            )
        })
        .map_err(|e| e.to_string());
    let (u, y) = fit_rows(&record).ok_or("the record has no output column")?;
    let level = record.levels() - 1;
    Ok(Some(StructureBeside {
        structure,
        level,
        levels: record.levels(),
        rms: record.rms(level),
        u,
        y,
        ts,
    }))
}

impl StructureBeside {
    /// The training record: the highest level's rows (with the record's sampling time).
    pub fn data<T: hammerstein::Real>(
        &self,
        input: &str,
        output: &str,
    ) -> Result<hammerstein::IoData<T>, super::super::Failure> {
        let d = hammerstein::IoData::with_names(
            faer::Mat::from_fn(self.u.len(), 1, |i, _| T::lit(self.u[i])),
            faer::Mat::from_fn(self.y.len(), 1, |i, _| T::lit(self.y[i])),
            vec![input.to_string()],
            vec![output.to_string()],
        )?;
        Ok(match self.ts {
            Some(ts) => d.with_sample_time(ts)?,
            None => d,
        })
    }

    /// The `unexplained` entry when the verdict lies outside the fitted class.
    pub fn beyond_class(&self) -> Option<Unexplained> {
        self.structure
            .as_ref()
            .ok()
            .and_then(|s| beyond_class(s, false))
    }

    /// The diagnosis' options with the verdict as evidence beside the residual (the
    /// feedback-nonlinearity candidate cites it); the defaults when there is no verdict.
    pub fn options(&self) -> DiagnosisOptions {
        let mut o = DiagnosisOptions::default();
        o.analysis.structure = self.structure.as_ref().ok().map(evidence);
        o
    }

    /// Which samples were fitted, in words.
    pub fn fitted_on(&self) -> String {
        format!(
            "the record format's level {} of {} (input RMS {}, the highest): its {} samples, blocks \
             in file order",
            self.level,
            self.levels,
            super::super::common::significant(self.rms),
            self.u.len()
        )
    }

    /// The `structure` object of the diagnosis JSON.
    pub fn json(&self) -> Value {
        let mut j = match &self.structure {
            Ok(s) => serde_json::to_value(s).unwrap_or(Value::Null),
            Err(e) => json!({"verdict": Value::Null, "error": e}),
        };
        if let Some(o) = j.as_object_mut() {
            o.insert("fitted_on".into(), json!(self.fitted_on()));
            o.insert("fitted_level".into(), json!(self.level));
            o.insert("fitted_samples".into(), json!(self.u.len()));
        }
        j
    }

    /// The text lines after the diagnosis.
    pub fn text(&self) -> String {
        let mut s = format!("\nstructure (BLAs of the {} levels): ", self.levels);
        match &self.structure {
            Ok(st) => {
                s.push_str(&verdict_line(st));
                s.push_str(&format!("; candidates: {}\n", st.candidates.join(", ")));
                if let Some(u) = self.beyond_class() {
                    s.push_str(&format!(
                        "  unexplained: {} (p = {:.3e}); would need: {}\n",
                        u.test,
                        u.p_adjusted,
                        u.model_classes.join("; ")
                    ));
                }
            }
            Err(e) => s.push_str(&format!("not available: {e}\n")),
        }
        s.push_str(&format!("the model is fitted on {}\n", self.fitted_on()));
        s
    }
}
