//! What `bla` and `structure` share: reading multisine records (the record format, or plain
//! periodic records with `--period`, one level per file) and the sampling time.

use hammerstein::data::CsvTable;
use hammerstein::structure::Record;
use std::path::PathBuf;

/// Options naming the records and their columns.
#[derive(clap::Args, Debug)]
pub struct RecordArgs {
    /// Records: the record format (`level,realization,period,u,y`), or plain periodic records
    /// (one level each, with --period); several files are joined, levels ordered by input RMS.
    #[arg(required = true, value_name = "RECORD")]
    pub records: Vec<PathBuf>,
    /// Input column.
    #[arg(long, default_value = "u")]
    pub input: String,
    /// Output column.
    #[arg(long, default_value = "y")]
    pub output: String,
    /// Samples per period of a plain periodic record (its first period is the transient the
    /// analysis discards); not needed for the record format.
    #[arg(long, value_name = "N")]
    pub period: Option<usize>,
    /// Sampling time in seconds (frequencies then in Hz); by default the step of a `t` column
    /// when the record has one, else frequencies are fractions of the sampling frequency.
    #[arg(long)]
    pub ts: Option<f64>,
}

impl RecordArgs {
    /// Reads and joins the records; returns the record and the sampling time (if known).
    pub fn read(&self) -> Result<(Record, Option<f64>), super::super::Failure> {
        if let Some(ts) = self.ts
            && !(ts.is_finite() && ts > 0.0)
        {
            return Err(format!("--ts must be a positive number of seconds, got {ts}").into());
        }
        let mut records = Vec::new();
        let mut ts = self.ts;
        for path in &self.records {
            let table = CsvTable::read(path)?;
            let label = path.display().to_string();
            if Record::is_record_format(&table.names) {
                records.push(Record::from_columns(
                    &table.names,
                    &table.columns,
                    &self.input,
                    Some(&self.output),
                    &label,
                )?);
            } else {
                let Some(n) = self.period else {
                    return Err(format!(
                        "{label} has no level,realization,period columns: give its period with --period N \
                         (a plain periodic record, the first period a transient); a non-periodic record: \
                         `structure --by-rms CLASSES`"
                    )
                    .into());
                };
                let u = table.column(&self.input)?;
                let y = table.column(&self.output)?;
                records.push(Record::from_periodic(u, y, n, &label)?);
            }
            if ts.is_none()
                && let Ok(t) = table.column("t")
                && t.len() > 1
            {
                let step = (t[t.len() - 1] - t[0]) / (t.len() - 1) as f64;
                if step.is_finite() && step > 0.0 {
                    ts = Some(step);
                }
            }
        }
        if ts.is_some() && self.ts.is_none() {
            super::super::note(&format!(
                "sampling time {:e} s from the records' t column (frequencies in Hz)",
                ts.unwrap_or(1.0)
            ));
        }
        Ok((Record::merge(records)?, ts))
    }
}
