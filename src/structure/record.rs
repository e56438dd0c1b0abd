//! The multisine record format: blocks of constant (level, realization), each a transient period
//! followed by steady periods of the same length.
//!
//! As CSV (fixed, so that other tools can write it): the header `level,realization,period,u` and
//! `y` once measured (more columns allowed and ignored). Rows come in contiguous blocks of constant
//! (level, realization); within a block `period` counts 0..P and period 0 is the transient the
//! analysis discards; `level` counts 0..L−1 from the lowest RMS. Plain periodic records (one level
//! each, the first period a transient) are accepted by [`Record::from_periodic`] and joined by
//! [`Record::merge`], which numbers the levels by the input's RMS.

use crate::error::{Error, Result};
use std::io::Write;

/// One (level, realization): all its periods, the transient first.
#[derive(Debug, Clone, PartialEq)]
pub struct Block {
    /// Level index (0 = lowest RMS).
    pub level: usize,
    /// Realization index within the level.
    pub realization: usize,
    /// Input, `periods + 1` whole periods.
    pub u: Vec<f64>,
    /// Measured output, the same length as `u`, once measured.
    pub y: Option<Vec<f64>>,
}

impl Block {
    /// Number of periods, the transient included.
    pub fn periods(&self, period: usize) -> usize {
        self.u.len() / period
    }
}

/// A multisine record: the period length and the blocks.
#[derive(Debug, Clone, PartialEq)]
pub struct Record {
    period: usize,
    blocks: Vec<Block>,
}

fn invalid(label: &str, msg: String) -> Error {
    Error::Csv {
        path: label.to_string(),
        msg,
        source: None,
    }
}

impl Record {
    /// A record from blocks; every block holds whole periods (at least two: the transient and
    /// one steady), `y` (when present) as long as `u`, and the levels count 0..L−1.
    pub fn new(period: usize, blocks: Vec<Block>) -> Result<Self> {
        if period < 4 {
            return Err(Error::InvalidParameter(format!(
                "a period of {period} samples is too short (at least 4)"
            )));
        }
        if blocks.is_empty() {
            return Err(Error::InvalidParameter("the record has no block".into()));
        }
        for b in &blocks {
            let what = format!("level {} realization {}", b.level, b.realization);
            if !b.u.len().is_multiple_of(period) {
                return Err(Error::InvalidParameter(format!(
                    "{what}: {} samples are not whole periods of {period} ({} periods and {} samples left over)",
                    b.u.len(),
                    b.u.len() / period,
                    b.u.len() % period
                )));
            }
            if b.u.len() < 2 * period {
                return Err(Error::TooFewSamples {
                    needed: 2 * period,
                    got: b.u.len(),
                    reason: format!("{what}: one transient and at least one steady period"),
                });
            }
            if let Some(y) = &b.y
                && y.len() != b.u.len()
            {
                return Err(Error::LengthMismatch {
                    what: format!("{what}: u has {} samples, y {}", b.u.len(), y.len()),
                });
            }
            let bad =
                b.u.iter()
                    .chain(b.y.iter().flatten())
                    .position(|v| !v.is_finite());
            if let Some(index) = bad {
                return Err(Error::NonFinite { what, index });
            }
        }
        let levels = blocks.iter().map(|b| b.level).max().unwrap_or(0) + 1;
        for l in 0..levels {
            if !blocks.iter().any(|b| b.level == l) {
                return Err(Error::InvalidParameter(format!(
                    "levels must count 0..{}: level {l} has no block",
                    levels - 1
                )));
            }
        }
        Ok(Self { period, blocks })
    }

    /// Samples per period.
    pub fn period(&self) -> usize {
        self.period
    }

    /// The blocks in record order.
    pub fn blocks(&self) -> &[Block] {
        &self.blocks
    }

    /// Number of levels.
    pub fn levels(&self) -> usize {
        self.blocks.iter().map(|b| b.level).max().unwrap_or(0) + 1
    }

    /// Whether every block carries a measured output.
    pub fn has_output(&self) -> bool {
        self.blocks.iter().all(|b| b.y.is_some())
    }

    /// RMS of the steady input of a level (all its realizations).
    pub fn rms(&self, level: usize) -> f64 {
        let (mut s, mut n) = (0.0, 0usize);
        for b in self.blocks.iter().filter(|b| b.level == level) {
            let steady = &b.u[self.period..];
            let m = steady.iter().sum::<f64>() / steady.len() as f64;
            s += steady.iter().map(|v| (v - m) * (v - m)).sum::<f64>();
            n += steady.len();
        }
        (s / n.max(1) as f64).sqrt()
    }

    /// The record with each block's output set by `plant` (a simulation of the whole block's
    /// input, transient period included).
    pub fn replayed(&self, mut plant: impl FnMut(&Block) -> Vec<f64>) -> Result<Self> {
        let blocks = self
            .blocks
            .iter()
            .map(|b| Block {
                y: Some(plant(b)),
                ..b.clone()
            })
            .collect();
        Self::new(self.period, blocks)
    }

    /// Writes the record as CSV: `level,realization,period,u[,y]`.
    pub fn write_csv(&self, mut w: impl Write) -> std::io::Result<()> {
        let with_y = self.has_output();
        writeln!(
            w,
            "level,realization,period,u{}",
            if with_y { ",y" } else { "" }
        )?;
        for b in &self.blocks {
            for (i, u) in b.u.iter().enumerate() {
                let p = i / self.period;
                match (&b.y, with_y) {
                    (Some(y), true) => {
                        writeln!(w, "{},{},{},{:e},{:e}", b.level, b.realization, p, u, y[i])?
                    }
                    _ => writeln!(w, "{},{},{},{:e}", b.level, b.realization, p, u)?,
                }
            }
        }
        Ok(())
    }

    /// Whether a header names the record format's columns `level`, `realization`, `period`.
    pub fn is_record_format(names: &[String]) -> bool {
        ["level", "realization", "period"]
            .iter()
            .all(|c| names.iter().any(|n| n == c))
    }

    /// Reads the record format from parsed columns (`label` names the source in errors); `input`
    /// and `output` name the signal columns (`u`, `y`), the output optional.
    pub fn from_columns(
        names: &[String],
        columns: &[Vec<f64>],
        input: &str,
        output: Option<&str>,
        label: &str,
    ) -> Result<Self> {
        let col = |name: &str| -> Result<&[f64]> {
            names
                .iter()
                .position(|n| n == name)
                .map(|i| columns[i].as_slice())
                .ok_or_else(|| Error::UnknownColumn {
                    name: name.to_string(),
                    available: names.join(", "),
                })
        };
        let (lev, real, per, u) = (
            col("level")?,
            col("realization")?,
            col("period")?,
            col(input)?,
        );
        let y = output.map(col).transpose()?;
        let count = |v: f64, row: usize, what: &str| -> Result<usize> {
            if v.is_finite() && v >= 0.0 && v.fract() == 0.0 {
                Ok(v as usize)
            } else {
                Err(invalid(
                    label,
                    format!(
                        "row {}: {what} must be a whole number >= 0, got {v}",
                        row + 2
                    ),
                ))
            }
        };
        let mut blocks: Vec<Block> = Vec::new();
        let mut period_len: Option<usize> = None;
        let mut row = 0;
        let n = u.len();
        while row < n {
            let (l, r) = (
                count(lev[row], row, "level")?,
                count(real[row], row, "realization")?,
            );
            if blocks.iter().any(|b| b.level == l && b.realization == r) {
                return Err(invalid(
                    label,
                    format!(
                        "row {}: level {l} realization {r} appears again after other blocks; \
                         each (level, realization) must be one contiguous block",
                        row + 2
                    ),
                ));
            }
            let start = row;
            let mut end = row;
            while end < n && lev[end] == lev[row] && real[end] == real[row] {
                end += 1;
            }
            // the period column counts 0, 1, …, P in runs of equal length
            let mut lens = Vec::new();
            let mut expect = 0usize;
            let mut i = start;
            while i < end {
                let p = count(per[i], i, "period")?;
                if p != expect {
                    return Err(invalid(
                        label,
                        format!(
                            "row {}: the period column does not count up in level {l} realization {r}: \
                             expected period {expect}, got {p} (periods count 0, 1, 2, … within a block)",
                            i + 2
                        ),
                    ));
                }
                let s = i;
                while i < end && per[i] == per[s] {
                    i += 1;
                }
                lens.push(i - s);
                expect += 1;
            }
            let first = lens[0];
            if let Some((p, &len)) = lens.iter().enumerate().find(|(_, len)| **len != first) {
                return Err(invalid(
                    label,
                    format!(
                        "level {l} realization {r}: the block is not whole periods: period {p} has {len} rows, \
                         period 0 has {first}"
                    ),
                ));
            }
            match period_len {
                None => period_len = Some(first),
                Some(pl) if pl != first => {
                    return Err(invalid(
                        label,
                        format!(
                            "level {l} realization {r}: periods of {first} samples, other blocks have {pl}"
                        ),
                    ));
                }
                _ => {}
            }
            if lens.len() < 2 {
                return Err(invalid(
                    label,
                    format!(
                        "level {l} realization {r}: only period 0 (the transient); at least one steady period is needed"
                    ),
                ));
            }
            blocks.push(Block {
                level: l,
                realization: r,
                u: u[start..end].to_vec(),
                y: y.map(|y| y[start..end].to_vec()),
            });
            row = end;
        }
        let period = period_len.ok_or_else(|| invalid(label, "no data rows".into()))?;
        Self::new(period, blocks).map_err(|e| invalid(label, e.to_string()))
    }

    /// A plain periodic record of one level and one realization: `period` samples per period,
    /// the first period a transient.
    pub fn from_periodic(u: &[f64], y: &[f64], period: usize, label: &str) -> Result<Self> {
        if u.len() != y.len() {
            return Err(Error::LengthMismatch {
                what: format!("{label}: u has {} samples, y {}", u.len(), y.len()),
            });
        }
        if period == 0 || !u.len().is_multiple_of(period) {
            return Err(invalid(
                label,
                format!(
                    "{} samples are not whole periods of {period} ({} left over); give the period with --period",
                    u.len(),
                    if period == 0 {
                        u.len()
                    } else {
                        u.len() % period
                    }
                ),
            ));
        }
        Self::new(
            period,
            vec![Block {
                level: 0,
                realization: 0,
                u: u.to_vec(),
                y: Some(y.to_vec()),
            }],
        )
        .map_err(|e| invalid(label, e.to_string()))
    }

    /// Joins records of the same period length; the levels of all of them are renumbered by
    /// the input's RMS, lowest first (a record's own levels stay distinct levels).
    pub fn merge(records: Vec<Record>) -> Result<Self> {
        let Some(period) = records.first().map(|r| r.period) else {
            return Err(Error::NoExperiment);
        };
        if let Some(r) = records.iter().find(|r| r.period != period) {
            return Err(Error::InvalidParameter(format!(
                "records of different period lengths ({period} and {}) cannot be joined",
                r.period
            )));
        }
        let mut keyed = Vec::new();
        for (i, r) in records.iter().enumerate() {
            for l in 0..r.levels() {
                keyed.push((r.rms(l), i, l));
            }
        }
        keyed.sort_by(|a, b| a.0.total_cmp(&b.0));
        let mut blocks = Vec::new();
        for (new, &(_, i, l)) in keyed.iter().enumerate() {
            blocks.extend(
                records[i]
                    .blocks
                    .iter()
                    .filter(|b| b.level == l)
                    .map(|b| Block {
                        level: new,
                        ..b.clone()
                    }),
            );
        }
        Self::new(period, blocks)
    }
}
