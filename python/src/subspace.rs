//! `subspace`: a linear state-space model of a record by MOESP or N4SID (what `hammerstein
//! subspace` prints), its matrices as JSON for the Python layer to make arrays of.

use hammerstein::solvers::backend;
use hammerstein::statespace::to_rows;
use hammerstein::subspace::{Compression, MethodKind, Order, SubspaceOptions, identify, max_order};
use hammerstein::{Error, IoData, Real};
use pyo3::prelude::*;
use serde_json::json;

use crate::arrays::record;
use crate::errors::{IntoPy, input_error, json_error};
use crate::fit::Precision;

/// The horizon without one given: 10, or for a fixed order n that 10 block rows cannot hold
/// the shortest longer horizon that holds it (at most 2n), as `hammerstein subspace` chooses.
fn default_horizon<T: Real>(data: &IoData<T>, order: &Order) -> usize {
    const DEFAULT: usize = 10;
    let l = data.n_outputs();
    let Order::Fixed(n) = *order else {
        return DEFAULT;
    };
    if max_order(DEFAULT, l) >= n {
        return DEFAULT;
    }
    let wanted = DEFAULT
        .max(n.saturating_mul(2))
        .min(hammerstein::data::MAX_HORIZON);
    (DEFAULT..=wanted)
        .rev()
        .find(|&h| max_order(h, l) >= n && data.check_horizon(h).is_ok())
        .unwrap_or(DEFAULT)
}

/// The options of one identification.
struct Ask<'a> {
    method: &'a str,
    order: &'a str,
    horizon: Option<usize>,
    stable: bool,
    detrend: bool,
    with_d: bool,
}

fn subspace_t<T: Precision>(
    py: Python<'_>,
    u: &Bound<'_, PyAny>,
    y: &Bound<'_, PyAny>,
    ts: f64,
    ask: &Ask<'_>,
) -> PyResult<String> {
    let raw: IoData<T> = record(py, u, y, ts)?;
    let run = || -> Result<serde_json::Value, Error> {
        let data = if ask.detrend {
            raw.detrend_mean()?
        } else {
            raw.clone()
        };
        let method: MethodKind = ask.method.parse()?;
        let order: Order = ask.order.parse()?;
        let horizon = ask
            .horizon
            .unwrap_or_else(|| default_horizon(&data, &order));
        data.check_horizon(horizon)?;
        let la = backend::<T>(Default::default())?;
        let m = method.build_with::<T>(horizon, Compression::default())?;
        let opts = SubspaceOptions {
            order,
            with_d: ask.with_d,
            stable: ask.stable,
            ..Default::default()
        };
        let id = identify(m.as_ref(), la.as_ref(), &[data.view()], &opts)?;
        Ok(json!({
            "A": to_rows(id.model.a.as_ref()),
            "B": to_rows(id.model.b.as_ref()),
            "C": to_rows(id.model.c.as_ref()),
            "D": to_rows(id.model.d.as_ref()),
            "x0": id.x0[0].iter().map(|v| v.as_f64()).collect::<Vec<_>>(),
            "singular_values": id.singular_values.iter().map(|s| s.as_f64()).collect::<Vec<_>>(),
            "order": id.model.order(),
            "horizon": horizon,
            "method": method.name(),
            "stabilised_from": id.stabilised_from,
            "sample_time": data.sample_time(),
        }))
    };
    let v = py.detach(run).py_err(py)?;
    serde_json::to_string(&v).map_err(json_error)
}

/// Identifies a linear state-space model of inputs `u` (N × m) and outputs `y` (N × l) by
/// `method` (moesp, n4sid, n4sid-unweighted) with `order` (a number, "auto", "gap",
/// "threshold:T"), `horizon` block rows (default: 10, raised for a fixed order that needs
/// more); `stable`: the guaranteed-stable A; `detrend`: each channel's mean removed first;
/// `with_d`: estimate D. Returns JSON (A, B, C, D, x0, singular values, order, horizon).
#[pyfunction]
#[pyo3(signature = (u, y, ts, precision, method, order, horizon, stable, detrend, with_d))]
pub fn subspace(
    py: Python<'_>,
    u: &Bound<'_, PyAny>,
    y: &Bound<'_, PyAny>,
    ts: f64,
    precision: &str,
    method: &str,
    order: &str,
    horizon: Option<usize>,
    stable: bool,
    detrend: bool,
    with_d: bool,
) -> PyResult<String> {
    let ask = Ask {
        method,
        order,
        horizon,
        stable,
        detrend,
        with_d,
    };
    match precision {
        "f64" => subspace_t::<f64>(py, u, y, ts, &ask),
        "f32" => subspace_t::<f32>(py, u, y, ts, &ask),
        p => Err(input_error(
            py,
            format!("unknown precision '{p}' (f32 or f64)"),
        )),
    }
}
