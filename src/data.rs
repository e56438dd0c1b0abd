//! Input/output records: the measured data every estimator consumes.

use crate::error::{Error, Result};
use crate::real::Real;
use faer::{Mat, MatRef};
#[cfg(feature = "csv")]
use std::path::Path;

/// A measured input/output record: `u` is N×m (inputs), `y` is N×l (outputs).
///
/// Construction checks finite values, equal lengths, at least two samples and that no input is
/// constant; method-specific checks (enough samples for a horizon) happen where the horizon is known.
#[derive(Debug, Clone)]
pub struct IoData<T: Real> {
    u: Mat<T>,
    y: Mat<T>,
    ts: f64,
    input_names: Vec<String>,
    output_names: Vec<String>,
}

/// A borrowed input/output record without validation, used inside the algorithms.
#[derive(Debug, Clone, Copy)]
pub struct IoView<'a, T: Real> {
    /// Inputs, N×m.
    pub u: MatRef<'a, T>,
    /// Outputs, N×l.
    pub y: MatRef<'a, T>,
}

impl<'a, T: Real> IoView<'a, T> {
    /// Wraps two matrices with the same number of rows.
    pub fn new(u: MatRef<'a, T>, y: MatRef<'a, T>) -> Result<Self> {
        if u.nrows() != y.nrows() {
            return Err(Error::LengthMismatch {
                what: format!("input has {} samples, output has {}", u.nrows(), y.nrows()),
            });
        }
        Ok(Self { u, y })
    }
    /// Number of samples N.
    pub fn len(&self) -> usize {
        self.u.nrows()
    }
    /// True when the record has no samples.
    pub fn is_empty(&self) -> bool {
        self.u.nrows() == 0
    }
}

fn check_finite<T: Real>(m: MatRef<'_, T>, names: &[String]) -> Result<()> {
    for j in 0..m.ncols() {
        for i in 0..m.nrows() {
            if !m[(i, j)].is_finite() {
                return Err(Error::NonFinite {
                    what: names[j].clone(),
                    index: i,
                });
            }
        }
    }
    Ok(())
}

/// True when column `j` is constant up to 16 ε of its largest magnitude.
/// True when column `j` is constant to round-off (16ε relative to its largest magnitude).
pub(crate) fn is_constant<T: Real>(m: MatRef<'_, T>, j: usize) -> bool {
    let first = m[(0, j)];
    let scale = (0..m.nrows())
        .map(|i| m[(i, j)].abs())
        .fold(T::zero(), T::max);
    let tol = T::epsilon() * T::lit(16.0) * scale.max(T::min_positive_value());
    (0..m.nrows()).all(|i| (m[(i, j)] - first).abs() <= tol)
}

/// "30" for 0.3, "33.33" for 1/3: a fraction as a short percentage.
fn percent(f: f64) -> String {
    let p = f * 100.0;
    if (p - p.round()).abs() < 1e-9 {
        format!("{:.0}", p.round())
    } else {
        format!("{p:.2}")
    }
}

fn default_names(prefix: &str, n: usize) -> Vec<String> {
    if n == 1 {
        vec![prefix.to_string()]
    } else {
        (1..=n).map(|k| format!("{prefix}{k}")).collect()
    }
}

impl<T: Real> IoData<T> {
    /// Builds a record from N×m inputs and N×l outputs (sample time 1, names u1.., y1..).
    ///
    /// ```
    /// use hammerstein::faer::Mat;
    /// use hammerstein::{Error, IoData};
    ///
    /// let u = Mat::from_fn(100, 2, |k, j| ((k * (j + 3)) % 7) as f64);
    /// let y = Mat::from_fn(100, 1, |k, _| (k % 5) as f64);
    /// let data = IoData::new(u.clone(), y)?;
    /// assert_eq!((data.len(), data.n_inputs(), data.n_outputs()), (100, 2, 1));
    /// assert_eq!(data.input_names(), ["u1", "u2"]);
    ///
    /// // a NaN is a typed error naming the channel and the sample
    /// let bad = Mat::from_fn(100, 1, |k, _| if k == 42 { f64::NAN } else { k as f64 });
    /// assert!(matches!(IoData::new(u, bad), Err(Error::NonFinite { index: 42, .. })));
    /// # Ok::<(), hammerstein::Error>(())
    /// ```
    pub fn new(u: Mat<T>, y: Mat<T>) -> Result<Self> {
        let input_names = default_names("u", u.ncols());
        let output_names = default_names("y", y.ncols());
        Self::with_names(u, y, input_names, output_names)
    }

    /// Builds a single-input single-output record from two slices.
    pub fn siso(u: &[T], y: &[T]) -> Result<Self> {
        if u.len() != y.len() {
            return Err(Error::LengthMismatch {
                what: format!("input has {} samples, output has {}", u.len(), y.len()),
            });
        }
        Self::new(
            Mat::from_fn(u.len(), 1, |i, _| u[i]),
            Mat::from_fn(y.len(), 1, |i, _| y[i]),
        )
    }

    /// Builds a record with channel names.
    pub fn with_names(
        u: Mat<T>,
        y: Mat<T>,
        input_names: Vec<String>,
        output_names: Vec<String>,
    ) -> Result<Self> {
        if u.nrows() != y.nrows() {
            return Err(Error::LengthMismatch {
                what: format!("input has {} samples, output has {}", u.nrows(), y.nrows()),
            });
        }
        if input_names.len() != u.ncols() || output_names.len() != y.ncols() {
            return Err(Error::Dimension(format!(
                "{} input names for {} inputs, {} output names for {} outputs",
                input_names.len(),
                u.ncols(),
                output_names.len(),
                y.ncols()
            )));
        }
        if u.ncols() == 0 || y.ncols() == 0 {
            return Err(Error::NoChannels {
                what: "a record needs at least one input and one output",
            });
        }
        if u.nrows() < 2 {
            return Err(Error::TooFewSamples {
                needed: 2,
                got: u.nrows(),
                reason: "a record needs at least two samples".into(),
            });
        }
        check_finite(u.as_ref(), &input_names)?;
        check_finite(y.as_ref(), &output_names)?;
        if let Some(j) = (0..u.ncols()).find(|&j| is_constant(u.as_ref(), j)) {
            return Err(Error::ConstantInput {
                name: input_names[j].clone(),
            });
        }
        if let Some(j) = (0..y.ncols()).find(|&j| is_constant(y.as_ref(), j)) {
            return Err(Error::ConstantOutput {
                name: output_names[j].clone(),
            });
        }
        Ok(Self {
            u,
            y,
            ts: 1.0,
            input_names,
            output_names,
        })
    }

    /// Sets the sample time in seconds.
    pub fn with_sample_time(mut self, ts: f64) -> Result<Self> {
        if !(ts.is_finite() && ts > 0.0) {
            return Err(Error::SampleTime(ts));
        }
        self.ts = ts;
        Ok(self)
    }

    /// Inputs, N×m.
    pub fn u(&self) -> MatRef<'_, T> {
        self.u.as_ref()
    }
    /// Outputs, N×l.
    pub fn y(&self) -> MatRef<'_, T> {
        self.y.as_ref()
    }
    /// Input column `j` as a vector.
    pub fn input(&self, j: usize) -> Vec<T> {
        (0..self.u.nrows()).map(|i| self.u[(i, j)]).collect()
    }
    /// Output column `j` as a vector.
    pub fn output(&self, j: usize) -> Vec<T> {
        (0..self.y.nrows()).map(|i| self.y[(i, j)]).collect()
    }
    /// Input column `j`, borrowed (no copy; panics when `j` is not a channel).
    pub fn input_slice(&self, j: usize) -> &[T] {
        self.u.col_as_slice(j)
    }
    /// Output column `j`, borrowed (no copy; panics when `j` is not a channel).
    pub fn output_slice(&self, j: usize) -> &[T] {
        self.y.col_as_slice(j)
    }
    /// Borrowed view for the algorithms.
    pub fn view(&self) -> IoView<'_, T> {
        IoView {
            u: self.u.as_ref(),
            y: self.y.as_ref(),
        }
    }
    /// Number of samples N.
    pub fn len(&self) -> usize {
        self.u.nrows()
    }
    /// Always false: a valid record has at least two samples.
    pub fn is_empty(&self) -> bool {
        self.u.nrows() == 0
    }
    /// Number of inputs m.
    pub fn n_inputs(&self) -> usize {
        self.u.ncols()
    }
    /// Number of outputs l.
    pub fn n_outputs(&self) -> usize {
        self.y.ncols()
    }
    /// Sample time in seconds (1 when unknown).
    pub fn sample_time(&self) -> f64 {
        self.ts
    }
    /// Input channel names.
    pub fn input_names(&self) -> &[String] {
        &self.input_names
    }
    /// Output channel names.
    pub fn output_names(&self) -> &[String] {
        &self.output_names
    }

    /// Checks that the record is long enough for a subspace horizon of `i` block rows.
    /// A horizon below 2 is [`Error::HorizonTooSmall`] (A comes from the shift of i block rows);
    /// one whose sample count overflows is [`Error::HorizonTooLarge`].
    pub fn check_horizon(&self, i: usize) -> Result<()> {
        if i < 2 {
            return Err(Error::HorizonTooSmall { horizon: i, min: 2 });
        }
        let (m, l) = (self.n_inputs(), self.n_outputs());
        let needed = checked_min_samples_for_horizon(i, m, l)?;
        if self.len() < needed {
            return Err(Error::TooFewSamples {
                needed,
                got: self.len(),
                reason: format!("horizon {i} with {m} input(s) and {l} output(s)"),
            });
        }
        Ok(())
    }

    /// Samples `start..end` as a new record (validated again).
    pub fn slice(&self, start: usize, end: usize) -> Result<Self> {
        if start >= end || end > self.len() {
            return Err(Error::SampleRange {
                start,
                end,
                len: self.len(),
            });
        }
        let u = Mat::from_fn(end - start, self.n_inputs(), |i, j| self.u[(start + i, j)]);
        let y = Mat::from_fn(end - start, self.n_outputs(), |i, j| self.y[(start + i, j)]);
        Self::with_names(u, y, self.input_names.clone(), self.output_names.clone())
            .and_then(|d| d.with_sample_time(self.ts))
    }

    /// Splits into (estimation, validation), holding out the last `fraction` of the samples.
    pub fn split_validation(&self, fraction: f64) -> Result<(Self, Self)> {
        if !(fraction > 0.0 && fraction < 1.0) {
            return Err(Error::ValidationFraction(fraction));
        }
        let n_val = ((self.len() as f64) * fraction).round() as usize;
        let cut = self.len().saturating_sub(n_val);
        if n_val < 2 || cut < 2 {
            return Err(Error::TooFewSamples {
                needed: 4,
                got: self.len(),
                reason: format!("splitting off a validation fraction of {fraction}"),
            });
        }
        // a channel constant in one part only: say which part
        let part = |e: Error, what: String| match e {
            Error::ConstantInput { name } => Error::ConstantIn {
                channel: "input".into(),
                name,
                part: what,
            },
            Error::ConstantOutput { name } => Error::ConstantIn {
                channel: "output".into(),
                name,
                part: what,
            },
            e => e,
        };
        let est = self.slice(0, cut).map_err(|e| {
            part(
                e,
                format!(
                    "the estimation part (first {} % of the record)",
                    percent(1.0 - fraction)
                ),
            )
        })?;
        let val = self.slice(cut, self.len()).map_err(|e| {
            part(
                e,
                format!(
                    "the validation part (last {} % of the record)",
                    percent(fraction)
                ),
            )
        })?;
        Ok((est, val))
    }

    /// Per-channel means of inputs and outputs.
    pub fn means(&self) -> (Vec<T>, Vec<T>) {
        let n = T::from_usize(self.len());
        let mu = (0..self.n_inputs())
            .map(|j| (0..self.len()).fold(T::zero(), |s, i| s + self.u[(i, j)]) / n)
            .collect();
        let my = (0..self.n_outputs())
            .map(|j| (0..self.len()).fold(T::zero(), |s, i| s + self.y[(i, j)]) / n)
            .collect();
        (mu, my)
    }

    /// The record with the given offsets subtracted from inputs and outputs.
    pub fn remove_offsets(&self, u_off: &[T], y_off: &[T]) -> Result<Self> {
        if u_off.len() != self.n_inputs() || y_off.len() != self.n_outputs() {
            return Err(Error::Dimension(
                "offset vector lengths do not match channels".into(),
            ));
        }
        let u = Mat::from_fn(self.len(), self.n_inputs(), |i, j| {
            self.u[(i, j)] - u_off[j]
        });
        let y = Mat::from_fn(self.len(), self.n_outputs(), |i, j| {
            self.y[(i, j)] - y_off[j]
        });
        Self::with_names(u, y, self.input_names.clone(), self.output_names.clone())
            .and_then(|d| d.with_sample_time(self.ts))
    }

    /// The record with every channel's mean removed.
    pub fn detrend_mean(&self) -> Result<Self> {
        let (mu, my) = self.means();
        self.remove_offsets(&mu, &my)
    }

    /// Converts to another scalar type.
    pub fn cast<S: Real>(&self) -> IoData<S> {
        IoData {
            u: Mat::from_fn(self.len(), self.n_inputs(), |i, j| {
                S::lit(self.u[(i, j)].as_f64())
            }),
            y: Mat::from_fn(self.len(), self.n_outputs(), |i, j| {
                S::lit(self.y[(i, j)].as_f64())
            }),
            ts: self.ts,
            input_names: self.input_names.clone(),
            output_names: self.output_names.clone(),
        }
    }

    /// Reads a record from a CSV file with a header row, picking input and output columns by
    /// name or 1-based position ([`CsvTable::index`]); the channels carry the header's names.
    ///
    /// Same rules, checks and messages as [`CsvTable::read`] followed by [`CsvTable::io_data`],
    /// but the rows are streamed into the chosen channels: the other columns are parsed (every
    /// cell must be a number) and not kept, so the memory is that of the record itself.
    #[cfg(feature = "csv")]
    pub fn from_csv(path: impl AsRef<Path>, inputs: &[&str], outputs: &[&str]) -> Result<Self> {
        let p = path.as_ref();
        let ps = p.display().to_string();
        let file = std::fs::File::open(p).map_err(|e| Error::io(&ps, e))?;
        read_channels(
            std::io::BufReader::with_capacity(1 << 16, file),
            &ps,
            inputs,
            outputs,
        )
    }

    /// [`from_csv`](Self::from_csv) of CSV text; `label` names it in messages.
    #[cfg(feature = "csv")]
    pub fn parse_csv(text: &[u8], label: &str, inputs: &[&str], outputs: &[&str]) -> Result<Self> {
        read_channels(text, label, inputs, outputs)
    }
}

/// The CSV reader of [`CsvTable`] (header, trimmed cells, `#` comments).
#[cfg(feature = "csv")]
fn csv_reader<R: std::io::Read>(reader: R) -> csv::Reader<R> {
    csv::ReaderBuilder::new()
        .has_headers(true)
        .trim(csv::Trim::All)
        .comment(Some(b'#'))
        .from_reader(reader)
}

/// The header's column names; an empty header is an error.
#[cfg(feature = "csv")]
fn csv_header<R: std::io::Read>(rdr: &mut csv::Reader<R>, label: &str) -> Result<Vec<String>> {
    let names: Vec<String> = rdr
        .headers()
        .map_err(|e| csv_error(label, e))?
        .iter()
        .map(|s| s.to_string())
        .collect();
    if names.is_empty() || names.iter().all(|n| n.is_empty()) {
        return Err(Error::Csv {
            path: label.to_string(),
            msg: "no header row".into(),
            source: None,
        });
    }
    // a file separated by semicolons or tabs reads as one column: say so, instead of
    // "line 2, column 't;u;y': '0;1.5;2' is not a number" (not spaces: a one-column input
    // file for `simulate` may well be named "drive voltage")
    if let [only] = names.as_slice()
        && let Some((sep, name)) = [(';', "';'"), ('\t', "tabs")]
            .into_iter()
            .find(|(c, _)| only.contains(*c))
    {
        return Err(Error::Csv {
            path: label.to_string(),
            msg: format!(
                "the header '{only}' is one column: the file seems separated by {name}, \
                 but columns must be separated by commas (e.g. `tr '{}' ','`)",
                sep.escape_default()
            ),
            source: None,
        });
    }
    Ok(names)
}

/// Every cell of data row `row` (0-based) parsed into `values`; a row of the wrong width or a
/// cell that is not a number is an error with the file's line number.
#[cfg(feature = "csv")]
fn parse_row(
    rec: &csv::StringRecord,
    row: usize,
    names: &[String],
    label: &str,
    values: &mut Vec<f64>,
) -> Result<()> {
    if rec.len() != names.len() {
        return Err(Error::Csv {
            path: label.to_string(),
            msg: format!(
                "line {}: {} fields, header has {}",
                row + 2,
                rec.len(),
                names.len()
            ),
            source: None,
        });
    }
    values.clear();
    for (j, cell) in rec.iter().enumerate() {
        let v: f64 = cell.parse().map_err(|_| Error::Csv {
            path: label.to_string(),
            msg: not_a_number(row + 2, &names[j], cell),
            source: None,
        })?;
        values.push(v);
    }
    Ok(())
}

/// Longest part of a cell a message quotes.
#[cfg(feature = "csv")]
const CELL_SHOWN: usize = 40;

/// The message for a cell of file line `line` that is not a number: the cell cut to
/// [`CELL_SHOWN`] characters; a cell over several lines said as the unclosed double quote it
/// comes from (the reader takes the rest of the file into it), not quoted whole.
#[cfg(feature = "csv")]
fn not_a_number(line: usize, column: &str, cell: &str) -> String {
    let short = |t: &str| {
        let mut c = t.chars();
        let head: String = c.by_ref().take(CELL_SHOWN).collect();
        if c.next().is_some() {
            format!("{head}…")
        } else {
            head
        }
    };
    let lines = cell.lines().count();
    if lines > 1 {
        format!(
            "line {line}, column '{column}': a double quote (\") opens a field that is never \
             closed, so it takes in the {} lines after it ('{}'): remove the stray quote",
            lines - 1,
            short(cell.lines().next().unwrap_or(""))
        )
    } else {
        format!(
            "line {line}, column '{column}': '{}' is not a number",
            short(cell)
        )
    }
}

/// Streams a CSV into the record of the named channels (see [`IoData::from_csv`]): the errors
/// come in the order of [`CsvTable::read`] then [`CsvTable::io_data`] (reading, channel names,
/// precision, validation).
#[cfg(feature = "csv")]
fn read_channels<T: Real>(
    reader: impl std::io::Read,
    label: &str,
    inputs: &[&str],
    outputs: &[&str],
) -> Result<IoData<T>> {
    let mut rdr = csv_reader(reader);
    let names = csv_header(&mut rdr, label)?;
    // the channels' columns (a naming error is reported after the rows, as `io_data` does)
    let lookup = CsvTable {
        path: label.to_string(),
        names: names.clone(),
        columns: Vec::new(),
    };
    let wanted: Result<Vec<usize>> = if inputs.is_empty() || outputs.is_empty() {
        Err(Error::InvalidParameter(
            "at least one input and one output column are needed".into(),
        ))
    } else {
        inputs
            .iter()
            .chain(outputs)
            .map(|n| lookup.index(n))
            .collect::<Result<Vec<usize>>>()
            .and_then(|c| {
                repeated_channel(&c[..inputs.len()], &c[inputs.len()..], &names)?;
                Ok(c)
            })
    };
    let channels: &[usize] = wanted.as_deref().unwrap_or(&[]);
    let t_col = names.iter().position(|n| n == "t" || n == "time");
    let mut data: Vec<Vec<T>> = vec![Vec::new(); channels.len()];
    // per channel: the first finite value the scalar type cannot hold (row, value)
    let mut overflow: Vec<Option<(usize, f64)>> = vec![None; channels.len()];
    // per channel: its rounding in the scalar type against its spread
    let mut rounding = vec![Rounding::new(); channels.len()];
    let (mut t_first, mut t_last) = (f64::NAN, f64::NAN);
    let mut rec = csv::StringRecord::new();
    let mut values = Vec::with_capacity(names.len());
    let mut rows = 0;
    while rdr.read_record(&mut rec).map_err(|e| csv_error(label, e))? {
        parse_row(&rec, rows, &names, label, &mut values)?;
        for (((&c, col), over), round) in channels
            .iter()
            .zip(&mut data)
            .zip(&mut overflow)
            .zip(&mut rounding)
        {
            let v = values[c];
            let x = T::lit(v);
            if over.is_none() && v.is_finite() && !x.is_finite() {
                *over = Some((rows, v));
            }
            round.add(v, x);
            col.push(x);
        }
        if let Some(tc) = t_col {
            if rows == 0 {
                t_first = values[tc];
            }
            t_last = values[tc];
        }
        rows += 1;
    }
    if rows == 0 {
        return Err(Error::Csv {
            path: label.to_string(),
            msg: "no data rows".into(),
            source: None,
        });
    }
    let channels = wanted?;
    if let Some((c, (row, value))) = overflow
        .iter()
        .enumerate()
        .find_map(|(c, o)| o.map(|o| (c, o)))
    {
        return Err(Error::PrecisionOverflow {
            value,
            column: names[channels[c]].clone(),
            row: row + 1,
            precision: T::NAME,
        });
    }
    for (round, &c) in rounding.iter().zip(&channels) {
        round.check::<T>(&names[c])?;
    }
    let m = inputs.len();
    let u = Mat::from_fn(rows, m, |i, j| data[j][i]);
    data.drain(..m);
    let y = Mat::from_fn(rows, outputs.len(), |i, j| data[j][i]);
    drop(data);
    // the channels carry the header's names (a column given by position too)
    let d = IoData::with_names(
        u,
        y,
        channels[..m].iter().map(|&c| names[c].clone()).collect(),
        channels[m..].iter().map(|&c| names[c].clone()).collect(),
    )?;
    // as `CsvTable::sample_time`
    let ts = (t_last - t_first) / (rows - 1) as f64;
    match t_col {
        Some(_) if rows >= 2 && ts.is_finite() && ts > 0.0 => d.with_sample_time(ts),
        _ => Ok(d),
    }
}

/// The largest rounding error of a column's values in the requested precision, relative to the
/// column's spread (max − min), that the CSV readers accept: beyond it the conversion (to f32)
/// would blur the signal riding on a large offset ([`Error::PrecisionLoss`]). f32 resolves a
/// relative 6e-8, so the limit is reached at an offset about 1700 times the spread. In the 48
/// CSV files of the 26 records of the project's shared data set the worst column (a reactor
/// temperature) is at 7.8e-7, a factor 127 below the limit.
pub const PRECISION_LOSS_LIMIT: f64 = 1e-4;

/// What a CSV reader gathers of one channel's values, in f64 before the conversion, to tell
/// whether the scalar type keeps its detail ([`PRECISION_LOSS_LIMIT`]).
#[cfg(feature = "csv")]
#[derive(Debug, Clone, Copy)]
struct Rounding {
    min: f64,
    max: f64,
    magnitude: f64,
    rounding: f64,
}

#[cfg(feature = "csv")]
impl Rounding {
    fn new() -> Self {
        Self {
            min: f64::INFINITY,
            max: f64::NEG_INFINITY,
            magnitude: 0.0,
            rounding: 0.0,
        }
    }

    /// Takes the value `v` and its conversion `x` (non-finite values are left to the record's
    /// own checks).
    fn add<T: Real>(&mut self, v: f64, x: T) {
        let xf = x.as_f64();
        if !(v.is_finite() && xf.is_finite()) {
            return;
        }
        self.min = self.min.min(v);
        self.max = self.max.max(v);
        self.magnitude = self.magnitude.max(v.abs());
        self.rounding = self.rounding.max((v - xf).abs());
    }

    /// [`Error::PrecisionLoss`] for `column` when the rounding exceeds the limit of the spread
    /// (a constant column is left to the record's constant-channel check).
    fn check<T: Real>(&self, column: &str) -> Result<()> {
        let spread = self.max - self.min;
        if spread > 0.0 && self.rounding > PRECISION_LOSS_LIMIT * spread {
            return Err(Error::PrecisionLoss {
                column: column.to_string(),
                precision: T::NAME,
                rounding: self.rounding,
                spread,
                magnitude: self.magnitude,
            });
        }
        Ok(())
    }
}

/// Largest horizon any subspace method accepts: 2²⁰ block rows. The R factor of the
/// block-Hankel matrix is 2i(m+l) square, so even one input and one output at this horizon would
/// need 2⁴⁴ entries (128 TiB in f64); the bound keeps every sample-count product far from
/// `usize` overflow. (Here, beside the record's length check, so that `data` needs nothing of
/// `subspace`; `subspace::MAX_HORIZON` re-exports it.)
pub const MAX_HORIZON: usize = 1 << 20;

/// Smallest N for a subspace horizon of `i` block rows with m inputs and l outputs:
/// the block-Hankel matrix needs at least 2·i·(m+l) columns (SLICOT IB01AD's condition).
/// Saturates at `usize::MAX` instead of overflowing; [`checked_min_samples_for_horizon`] makes
/// the overflow an error.
pub fn min_samples_for_horizon(i: usize, m: usize, l: usize) -> usize {
    checked_min_samples_for_horizon(i, m, l).unwrap_or(usize::MAX)
}

/// [`min_samples_for_horizon`] with checked arithmetic: a horizon above
/// [`MAX_HORIZON`] or a sample count that overflows `usize` is
/// [`Error::HorizonTooLarge`].
pub fn checked_min_samples_for_horizon(i: usize, m: usize, l: usize) -> Result<usize> {
    let max = MAX_HORIZON;
    let too_large = Error::HorizonTooLarge { horizon: i, max };
    if i > max {
        return Err(too_large);
    }
    m.checked_add(l)
        .and_then(|c| c.checked_add(1))
        .and_then(|c| c.checked_mul(i))
        .and_then(|c| c.checked_mul(2))
        .map(|c| c.saturating_sub(1))
        .ok_or(too_large)
}

/// [`Error::RepeatedChannel`] when one column (by index) is chosen for two channels.
#[cfg(feature = "csv")]
fn repeated_channel(inputs: &[usize], outputs: &[usize], names: &[String]) -> Result<()> {
    let all: Vec<(usize, bool)> = inputs
        .iter()
        .map(|&c| (c, true))
        .chain(outputs.iter().map(|&c| (c, false)))
        .collect();
    for (k, &(c, input)) in all.iter().enumerate() {
        if let Some(&(_, other)) = all[k + 1..].iter().find(|(d, _)| *d == c) {
            return Err(Error::RepeatedChannel {
                name: names[c].clone(),
                roles: match (input, other) {
                    (true, true) => "two inputs",
                    (false, false) => "two outputs",
                    _ => "input and output",
                },
            });
        }
    }
    Ok(())
}

/// A CSV reader's error: a failed read (e.g. the path is a directory) is [`Error::Io`] with its
/// cause, anything else [`Error::Csv`].
#[cfg(feature = "csv")]
fn csv_error(path: &str, e: csv::Error) -> Error {
    let msg = e.to_string();
    if !matches!(e.kind(), csv::ErrorKind::Io(_)) {
        return Error::Csv {
            path: path.to_string(),
            msg,
            source: Some(crate::error::CsvCause::new(e)),
        };
    }
    match e.into_kind() {
        csv::ErrorKind::Io(io) => Error::io(path, io),
        _ => Error::Csv {
            path: path.to_string(),
            msg,
            source: None,
        },
    }
}

/// A numeric CSV table with a header row, read whole.
#[cfg(feature = "csv")]
#[derive(Debug, Clone)]
pub struct CsvTable {
    /// Where it was read from (for messages).
    pub path: String,
    /// Column names from the header.
    pub names: Vec<String>,
    /// Column data.
    pub columns: Vec<Vec<f64>>,
}

#[cfg(feature = "csv")]
impl CsvTable {
    /// Reads a CSV with a header; every cell must parse as a number (NaN is reported later, by column).
    pub fn read(path: impl AsRef<Path>) -> Result<Self> {
        let p = path.as_ref();
        let ps = p.display().to_string();
        let file = std::fs::File::open(p).map_err(|e| Error::io(&ps, e))?;
        Self::from_reader(std::io::BufReader::new(file), &ps)
    }

    /// Parses CSV text (same rules as [`read`](Self::read)); `label` names it in messages.
    pub fn parse(text: &[u8], label: &str) -> Result<Self> {
        Self::from_reader(text, label)
    }

    fn from_reader(reader: impl std::io::Read, label: &str) -> Result<Self> {
        let ps = label.to_string();
        let mut rdr = csv_reader(reader);
        let names = csv_header(&mut rdr, &ps)?;
        let mut columns = vec![Vec::new(); names.len()];
        // one record buffer for every row
        let mut rec = csv::StringRecord::new();
        let mut values = Vec::with_capacity(names.len());
        let mut row = 0;
        while rdr.read_record(&mut rec).map_err(|e| csv_error(&ps, e))? {
            parse_row(&rec, row, &names, &ps, &mut values)?;
            for (col, &v) in columns.iter_mut().zip(&values) {
                col.push(v);
            }
            row += 1;
        }
        if columns[0].is_empty() {
            return Err(Error::Csv {
                path: ps,
                msg: "no data rows".into(),
                source: None,
            });
        }
        Ok(Self {
            path: ps,
            names,
            columns,
        })
    }

    /// Index of a column by name, or — when no column has that name — by its 1-based position
    /// as `cut -f` takes it ("2": the second column; a header name always wins). A name the
    /// header does not hold is [`Error::UnknownColumn`] listing the available ones, a position
    /// outside 1..=columns [`Error::ColumnOutOfRange`], a name that the header holds more than
    /// once [`Error::DuplicateColumn`].
    pub fn index(&self, name: &str) -> Result<usize> {
        let Some(idx) = self.names.iter().position(|n| n == name) else {
            return self.position(name);
        };
        let count = self.names.iter().filter(|n| *n == name).count();
        if count > 1 {
            return Err(Error::DuplicateColumn {
                name: name.to_string(),
                count,
                path: self.path.clone(),
            });
        }
        Ok(idx)
    }

    /// The index of the column at the 1-based position `spec` (no column is named so).
    fn position(&self, spec: &str) -> Result<usize> {
        let unknown = || Error::UnknownColumn {
            name: spec.to_string(),
            available: self.names.join(", "),
        };
        let t = spec.trim();
        if t.is_empty() || !t.bytes().all(|b| b.is_ascii_digit()) {
            return Err(unknown());
        }
        let columns = self.names.len();
        match t.parse::<usize>() {
            Ok(k) if (1..=columns).contains(&k) => Ok(k - 1),
            _ => Err(Error::ColumnOutOfRange {
                position: t.parse().unwrap_or(usize::MAX),
                columns,
                available: self.names.join(", "),
            }),
        }
    }

    /// The header names of the columns `specs` give (names or 1-based positions, as
    /// [`index`](Self::index) takes them), in their order.
    pub fn names_of(&self, specs: &[&str]) -> Result<Vec<String>> {
        specs
            .iter()
            .map(|s| self.index(s).map(|i| self.names[i].clone()))
            .collect()
    }

    /// The header of the CSV file at `path` (read alone, without the rows) as a table without
    /// data: for [`index`](Self::index) and [`names_of`](Self::names_of).
    pub fn read_header(path: impl AsRef<Path>) -> Result<Self> {
        let p = path.as_ref();
        let ps = p.display().to_string();
        let file = std::fs::File::open(p).map_err(|e| Error::io(&ps, e))?;
        let mut rdr = csv_reader(std::io::BufReader::new(file));
        let names = csv_header(&mut rdr, &ps)?;
        Ok(Self {
            path: ps,
            names,
            columns: Vec::new(),
        })
    }

    /// A column by name (or 1-based position, as [`index`](Self::index) takes it).
    pub fn column(&self, name: &str) -> Result<&[f64]> {
        self.check_shape()?;
        Ok(&self.columns[self.index(name)?])
    }

    /// The public fields agree: one column per name, all of one length.
    fn check_shape(&self) -> Result<()> {
        let n = self.columns.first().map_or(0, |c| c.len());
        if self.columns.len() != self.names.len() || self.columns.iter().any(|c| c.len() != n) {
            return Err(Error::Dimension(format!(
                "CSV table {}: {} names for {} columns of unequal or mismatched lengths",
                self.path,
                self.names.len(),
                self.columns.len()
            )));
        }
        Ok(())
    }

    /// Names of the data columns, without index columns (`t`, `k`, `time`, `index`).
    pub fn data_columns(&self) -> Vec<&str> {
        self.names
            .iter()
            .map(|s| s.as_str())
            .filter(|n| {
                !matches!(
                    n.to_ascii_lowercase().as_str(),
                    "t" | "k" | "time" | "index"
                )
            })
            .collect()
    }

    /// Sample time from a `t`/`time` column when present and uniform.
    pub fn sample_time(&self) -> Option<f64> {
        let idx = self.names.iter().position(|n| n == "t" || n == "time")?;
        let t = &self.columns[idx];
        if t.len() < 2 {
            return None;
        }
        let dt = (t[t.len() - 1] - t[0]) / (t.len() - 1) as f64;
        (dt.is_finite() && dt > 0.0).then_some(dt)
    }

    /// Builds a validated record from columns given by name or 1-based position
    /// ([`index`](Self::index)); the channels carry the header's names.
    pub fn io_data<T: Real>(&self, inputs: &[&str], outputs: &[&str]) -> Result<IoData<T>> {
        if inputs.is_empty() || outputs.is_empty() {
            return Err(Error::NoChannels {
                what: "at least one input and one output column are needed",
            });
        }
        self.check_shape()?;
        let ui: Vec<usize> = inputs
            .iter()
            .map(|n| self.index(n))
            .collect::<Result<_>>()?;
        let yi: Vec<usize> = outputs
            .iter()
            .map(|n| self.index(n))
            .collect::<Result<_>>()?;
        repeated_channel(&ui, &yi, &self.names)?;
        let n = self.columns.first().map_or(0, |c| c.len());
        // a finite value beyond the scalar type's range would become infinite: say so
        for &c in ui.iter().chain(&yi) {
            let col = &self.columns[c];
            if let Some(row) = col
                .iter()
                .position(|&v| v.is_finite() && !T::lit(v).is_finite())
            {
                return Err(Error::PrecisionOverflow {
                    value: col[row],
                    column: self.names[c].clone(),
                    row: row + 1,
                    precision: T::NAME,
                });
            }
        }
        // a signal on a large offset that the scalar type would blur: say so
        for &c in ui.iter().chain(&yi) {
            let mut round = Rounding::new();
            for &v in &self.columns[c] {
                round.add(v, T::lit(v));
            }
            round.check::<T>(&self.names[c])?;
        }
        let u = Mat::from_fn(n, ui.len(), |i, j| T::lit(self.columns[ui[j]][i]));
        let y = Mat::from_fn(n, yi.len(), |i, j| T::lit(self.columns[yi[j]][i]));
        // the channels carry the header's names (a column given by position too)
        let d = IoData::with_names(
            u,
            y,
            ui.iter().map(|&c| self.names[c].clone()).collect(),
            yi.iter().map(|&c| self.names[c].clone()).collect(),
        )?;
        match self.sample_time() {
            Some(ts) => d.with_sample_time(ts),
            None => Ok(d),
        }
    }
}
