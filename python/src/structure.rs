//! The structure tools: `design` (a random-phase multisine experiment in the record format),
//! `bla` (the best linear approximation per level) and `structure` (the structure verdict), as
//! `hammerstein design`, `bla` and `structure` compute them (src/cli/experiment/). Records come
//! down as numpy columns and are read by the library's record reader, so a record gives the
//! same answer here as from a CSV file; the answers go up as the command line's JSON.

use hammerstein::Error;
use hammerstein::structure::{
    AmplitudeOptions, MultisineDesign, MultisineKind, Record, StructureOptions, analyze,
    analyze_by_amplitude, bla,
};
use numpy::{PyArray1, PyReadonlyArray1};
use pyo3::prelude::*;

use crate::errors::{IntoPy, input_error, json_error};

/// The columns of a record, as `hammerstein.Experiment` hands them down.
type Columns<'py> = Vec<PyReadonlyArray1<'py, f64>>;

/// A multisine experiment (as `hammerstein design`; `band` in fractions of the sampling
/// frequency): the record format's columns level, realization, period (integers) and u, the
/// excited lines and the samples per period.
#[pyfunction]
#[pyo3(signature = (kind, samples, band, group, levels, realizations, periods, seed))]
pub fn design<'py>(
    py: Python<'py>,
    kind: &str,
    samples: usize,
    band: (f64, f64),
    group: usize,
    levels: Vec<f64>,
    realizations: usize,
    periods: usize,
    seed: u64,
) -> PyResult<(Vec<Bound<'py, PyAny>>, Vec<usize>)> {
    let kind = match kind {
        "random-odd" => MultisineKind::RandomOdd { group },
        "full" => MultisineKind::Full,
        k => {
            return Err(input_error(
                py,
                format!("unknown multisine kind '{k}' (random-odd or full)"),
            ));
        }
    };
    let d = MultisineDesign {
        kind,
        samples,
        band,
        levels,
        realizations,
        periods,
        seed,
    };
    let record = py.detach(|| d.generate()).py_err(py)?;
    let n = record.period();
    let total: usize = record.blocks().iter().map(|b| b.u.len()).sum();
    let (mut lev, mut real, mut per, mut u) = (
        Vec::with_capacity(total),
        Vec::with_capacity(total),
        Vec::with_capacity(total),
        Vec::with_capacity(total),
    );
    for b in record.blocks() {
        for (i, v) in b.u.iter().enumerate() {
            lev.push(b.level as i64);
            real.push(b.realization as i64);
            per.push((i / n) as i64);
            u.push(*v);
        }
    }
    let cols = vec![
        PyArray1::from_vec(py, lev).into_any(),
        PyArray1::from_vec(py, real).into_any(),
        PyArray1::from_vec(py, per).into_any(),
        PyArray1::from_vec(py, u).into_any(),
    ];
    Ok((cols, d.excited_lines()))
}

/// The record from its parts: each `(label, period, columns)` is the record format (`period`
/// None; columns level, realization, period, u, y) or a plain periodic record (`period` its
/// samples per period; columns u, y); several are joined, levels ordered by input RMS (as the
/// command line joins several files).
fn record(parts: Vec<(String, Option<usize>, Columns<'_>)>) -> Result<Record, Error> {
    let mut records = Vec::with_capacity(parts.len());
    for (label, period, cols) in parts {
        let cols: Vec<Vec<f64>> = cols.iter().map(|c| c.as_array().to_vec()).collect();
        let r = match period {
            None => {
                let names: Vec<String> = ["level", "realization", "period", "u", "y"]
                    .iter()
                    .map(|s| s.to_string())
                    .collect();
                if cols.len() != names.len() {
                    return Err(Error::InvalidParameter(format!(
                        "{label}: the record format needs the columns level, realization, period, u, y"
                    )));
                }
                Record::from_columns(&names, &cols, "u", Some("y"), &label)?
            }
            Some(n) => {
                if cols.len() != 2 {
                    return Err(Error::InvalidParameter(format!(
                        "{label}: a periodic record needs u and y"
                    )));
                }
                Record::from_periodic(&cols[0], &cols[1], n, &label)?
            }
        };
        records.push(r);
    }
    Record::merge(records)
}

/// The best linear approximation of the record per level (what `hammerstein bla --json`
/// prints: every excited line's BLA and variances, each level's nonlinearity verdict; `ts` the
/// sampling time or None); with `plot`, the BLA plot of `bla --plot` written there as SVG.
#[pyfunction]
#[pyo3(signature = (parts, ts, plot))]
pub fn bla_json(
    py: Python<'_>,
    parts: Vec<(String, Option<usize>, Columns<'_>)>,
    ts: Option<f64>,
    plot: Option<std::path::PathBuf>,
) -> PyResult<String> {
    let rec = record(parts).py_err(py)?;
    let b = py
        .detach(|| -> Result<_, Error> {
            let b = bla(&rec)?;
            if let Some(p) = &plot {
                let svg = hammerstein::report::bla_plot::bla_svg(&b, ts)?;
                hammerstein::atomic::write_atomic(p, svg.as_bytes())?;
            }
            Ok(b)
        })
        .py_err(py)?;
    let mut v = serde_json::to_value(&b).map_err(json_error)?;
    v["ts"] = ts.map_or(serde_json::Value::Null, |t| serde_json::json!(t));
    serde_json::to_string(&v).map_err(json_error)
}

/// The structure verdict of the record (what `hammerstein structure --json` prints): `order`
/// fixed or chosen up to `max_order`, F tests at `alpha`, only the lines in `band` (Hz with
/// `ts`, else fractions of the sampling frequency).
#[pyfunction]
#[pyo3(signature = (parts, ts, order, max_order, alpha, band))]
pub fn structure_json(
    py: Python<'_>,
    parts: Vec<(String, Option<usize>, Columns<'_>)>,
    ts: Option<f64>,
    order: Option<usize>,
    max_order: usize,
    alpha: f64,
    band: Option<(f64, f64)>,
) -> PyResult<String> {
    let rec = record(parts).py_err(py)?;
    let opts = StructureOptions {
        ts,
        order,
        max_order,
        alpha,
        band,
        ..Default::default()
    };
    let s = py
        .detach(|| bla(&rec).and_then(|b| analyze(&b, &opts)))
        .py_err(py)?;
    serde_json::to_string(&s).map_err(json_error)
}

/// The structure verdict of a non-periodic record (`hammerstein structure --by-rms`): split
/// into `classes` amplitude classes by the input's local RMS over `window` samples, ARX models
/// of the classes compared.
#[pyfunction]
#[pyo3(signature = (u, y, ts, classes, window, order, max_order, alpha))]
pub fn structure_by_rms_json(
    py: Python<'_>,
    u: PyReadonlyArray1<'_, f64>,
    y: PyReadonlyArray1<'_, f64>,
    ts: Option<f64>,
    classes: usize,
    window: usize,
    order: Option<usize>,
    max_order: usize,
    alpha: f64,
) -> PyResult<String> {
    let (u, y) = (u.as_array().to_vec(), y.as_array().to_vec());
    let opts = AmplitudeOptions {
        window,
        classes,
        order,
        // the command line's cap on the ARX orders tried
        max_order: max_order.min(12),
        ts,
        alpha,
    };
    let s = py
        .detach(|| analyze_by_amplitude(&u, &y, &opts))
        .py_err(py)?;
    serde_json::to_string(&s).map_err(json_error)
}
