//! `hammerstein subspace`: linear subspace identification (MOESP / N4SID) of a CSV record.

use hammerstein::data::CsvTable;
use hammerstein::solvers::{BackendKind, backend};
use hammerstein::statespace::to_rows;
use hammerstein::subspace::{Compression, MethodKind, Order, SubspaceOptions, identify};
use hammerstein::{IoData, Real};
use std::time::Instant;

/// Arguments of `hammerstein subspace`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// CSV file with a header row.
    pub data: std::path::PathBuf,
    /// Input column names, comma separated (a 1-based position where no column has that name).
    #[arg(long, value_delimiter = ',', default_value = "u")]
    pub inputs: Vec<String>,
    /// Output column names, comma separated (a 1-based position where no column has that name).
    #[arg(long, value_delimiter = ',', default_value = "y")]
    pub outputs: Vec<String>,
    /// Subspace method: moesp or n4sid.
    #[arg(long, default_value = "moesp")]
    pub method: String,
    /// Model order: a number, `auto` (largest singular-value log gap) or `threshold:T`.
    #[arg(long, allow_negative_numbers = true, default_value = "auto")]
    pub order: String,
    /// Horizon i (number of block rows). Default: 10, raised to 2n for a fixed order n above
    /// what 10 block rows hold (a horizon given here is never raised).
    #[arg(long, value_parser = super::common::parse_count, allow_negative_numbers = true)]
    pub horizon: Option<usize>,
    /// Force D = 0 (strictly proper model).
    #[arg(long)]
    pub no_d: bool,
    /// Scalar precision: f32 or f64.
    #[arg(long, default_value = "f64")]
    pub precision: String,
    /// Linear-algebra backend: faer or lapack (needs the `lapack` feature).
    #[arg(long, default_value = "faer")]
    pub backend: String,
    /// Data compression: cholesky (fast, falls back to qr on singular data), qr, or semidefinite
    /// (cholesky with zero rows for dependent columns, never qr).
    #[arg(long, default_value = "cholesky")]
    pub compression: String,
    /// Remove each channel's mean before identification (the default).
    #[arg(long, overrides_with = "no_detrend")]
    pub detrend: bool,
    /// Keep the means (identify on the raw record).
    #[arg(long, overrides_with = "detrend")]
    pub no_detrend: bool,
    /// Replace an unstable A by the guaranteed-stable estimate of Maciejowski (1995): every
    /// pole in the closed unit disc, biased towards the origin; a stable A is kept as estimated.
    #[arg(long)]
    pub stable: bool,
    /// Keep every K-th sample of the record before identification (an oversampled record): the
    /// outputs low-pass filtered first (zero phase, unit gain at 0), the inputs taken as they
    /// are, as `fit --decimate` does; --horizon then counts samples of the decimated record.
    #[arg(long, value_parser = super::common::parse_factor, allow_negative_numbers = true, value_name = "K")]
    pub decimate: Option<usize>,
    /// Print the model as JSON.
    #[arg(long)]
    pub json: bool,
}

/// Runs the subcommand; errors are one-line messages.
pub fn run(args: Args) -> super::CliResult {
    let table = CsvTable::read(&args.data)?;
    match args.precision.as_str() {
        "f64" => run_t::<f64>(&args, &table),
        "f32" => run_t::<f32>(&args, &table),
        p => Err(format!("unknown precision '{p}' (f32|f64)").into()),
    }
}

fn run_t<T: Real>(args: &Args, table: &CsvTable) -> super::CliResult {
    let ins: Vec<&str> = args.inputs.iter().map(|s| s.as_str()).collect();
    let outs: Vec<&str> = args.outputs.iter().map(|s| s.as_str()).collect();
    let raw: IoData<T> = table.io_data(&ins, &outs)?;
    raw.check_magnitude_unscaled()?;
    let raw = super::common::decimate_record(raw, args.decimate.unwrap_or(1), &args.data)?;
    let data = if args.no_detrend {
        raw
    } else {
        raw.detrend_mean()?
    };
    let method: MethodKind = args.method.parse()?;
    let order: Order = args.order.parse()?;
    let kind: BackendKind = args.backend.parse()?;
    let compression: Compression = args.compression.parse()?;
    let (horizon, raised) = match args.horizon {
        Some(h) => (h, false),
        None => {
            let h = default_horizon(&data, &order);
            (h, h != DEFAULT_HORIZON)
        }
    };
    data.check_horizon(horizon)?;
    let la = backend::<T>(kind)?;
    let m = method.build_with::<T>(horizon, compression)?;
    let opts = SubspaceOptions {
        order,
        with_d: !args.no_d,
        stable: args.stable,
        ..Default::default()
    };
    let t0 = Instant::now();
    let id = identify(m.as_ref(), la.as_ref(), &[data.view()], &opts)?;
    let ident_time = t0.elapsed().as_secs_f64();
    let yhat = id.model.simulate(data.u(), Some(&id.x0[0]))?;
    // an unstable identified model: say so rather than print NaN or absurd fits
    let div: Vec<Option<(usize, f64)>> = (0..yhat.ncols())
        .map(|o| {
            let col: Vec<T> = (0..yhat.nrows()).map(|k| yhat[(k, o)]).collect();
            hammerstein::fit::divergence(&col)
        })
        .collect();
    let fit: Vec<f64> = fit_percent(&data, &yhat)
        .into_iter()
        .zip(&div)
        .map(|(f, d)| if d.is_some() { f64::NAN } else { f })
        .collect();
    let diverged = div.iter().flatten().next().copied();
    if let Some((k, v)) = diverged {
        super::note(&format!(
            "warning: the identified model's simulation diverges from sample {k} on ({v:e}): \
             the model is unstable; its fit is undefined"
        ));
    }
    let sv: Vec<f64> = id.singular_values.iter().map(|s| s.as_f64()).collect();
    if args.json {
        let j = serde_json::json!({
            "A": to_rows(id.model.a.as_ref()),
            "B": to_rows(id.model.b.as_ref()),
            "C": to_rows(id.model.c.as_ref()),
            "D": to_rows(id.model.d.as_ref()),
            "order": id.model.order(),
            "singular_values": sv,
            "fit_percent": fit.iter().map(|f| super::common::json_number(*f)).collect::<Vec<_>>(),
            "diverged": diverged.is_some(),
            "ident_time_s": ident_time,
            "x0": id.x0[0].iter().map(|v| v.as_f64()).collect::<Vec<_>>(),
            "method": method.name(),
            "horizon": horizon,
            "horizon_raised_from": raised.then_some(DEFAULT_HORIZON),
            "precision": T::NAME,
            "backend": la.name(),
            "detrended": !args.no_detrend,
            "stabilised_from": id.stabilised_from.map(super::common::json_number),
            "decimation": args.decimate.unwrap_or(1),
            "sample_time": data.sample_time(),
        });
        outln!("{j}")?;
    } else {
        outln!(
            "{} (horizon {}{}, {}, {} backend): order {}, {} samples, identified in {:.3} ms",
            method.name(),
            horizon,
            if raised {
                format!(", the default {DEFAULT_HORIZON} raised for the order (--horizon sets it)")
            } else {
                String::new()
            },
            T::NAME,
            la.name(),
            id.model.order(),
            data.len(),
            ident_time * 1e3
        )?;
        if let Some(k) = args.decimate.filter(|&k| k > 1) {
            outln!(
                "record decimated by {k} (outputs low-pass filtered, every {k}th sample kept): \
                 sample time {}",
                super::common::sci(data.sample_time())
            )?;
        }
        let svs: Vec<String> = sv.iter().map(|s| format!("{s:.4e}")).collect();
        outln!("singular values: {}", svs.join(" "))?;
        let poles = id.model.poles()?;
        let ps: Vec<String> = poles
            .iter()
            .map(|(r, i)| {
                if *i == 0.0 {
                    format!("{r:.6}")
                } else {
                    format!("{r:.6}{i:+.6}j")
                }
            })
            .collect();
        outln!("poles: {}", ps.join(", "))?;
        if let Some(rho) = id.stabilised_from {
            outln!(
                "stability enforced (--stable): the shift-invariance estimate of A had a pole of \
                 modulus {rho:.6}; A is the guaranteed-stable estimate (Maciejowski 1995)"
            )?;
        }
        for (name, mat) in [
            ("A", &id.model.a),
            ("B", &id.model.b),
            ("C", &id.model.c),
            ("D", &id.model.d),
        ] {
            outln!("{name} =")?;
            for row in to_rows(mat.as_ref()) {
                let r: Vec<String> = row.iter().map(|v| format!("{v:>12.6}")).collect();
                outln!("  {}", r.join(" "))?;
            }
        }
        for (o, f) in fit.iter().enumerate() {
            if !f.is_finite() {
                outln!(
                    "fit {}: undefined (the simulation diverges)",
                    data.output_names()[o]
                )?;
                continue;
            }
            outln!(
                "fit {}: {:.2} % (simulation from the estimated initial state{})",
                data.output_names()[o],
                f,
                if args.no_detrend {
                    ""
                } else {
                    ", means removed"
                }
            )?;
        }
    }
    Ok(())
}

/// The subspace command's horizon when `--horizon` is not given.
const DEFAULT_HORIZON: usize = 10;

/// The horizon without `--horizon`: [`DEFAULT_HORIZON`], or for a fixed order n it cannot hold
/// 2n (as the fit's automatic order does), the longest horizon that holds n when the record is
/// too short for 2n (the default when none is: the order is then refused naming `--horizon`).
fn default_horizon<T: Real>(data: &IoData<T>, order: &Order) -> usize {
    let l = data.n_outputs();
    let Order::Fixed(n) = *order else {
        return DEFAULT_HORIZON;
    };
    if hammerstein::subspace::max_order(DEFAULT_HORIZON, l) >= n {
        return DEFAULT_HORIZON;
    }
    let wanted = DEFAULT_HORIZON
        .max(n.saturating_mul(2))
        .min(hammerstein::data::MAX_HORIZON);
    (DEFAULT_HORIZON..=wanted)
        .rev()
        .find(|&h| hammerstein::subspace::max_order(h, l) >= n && data.check_horizon(h).is_ok())
        .unwrap_or(DEFAULT_HORIZON)
}

/// Fit % per output: 100·(1 − ‖y − ŷ‖/‖y − ȳ‖) (MATLAB's `compare` definition).
fn fit_percent<T: Real>(data: &IoData<T>, yhat: &faer::Mat<T>) -> Vec<f64> {
    (0..data.n_outputs())
        .map(|o| {
            let y = data.output(o);
            let mean = y.iter().map(|v| v.as_f64()).sum::<f64>() / y.len() as f64;
            let (mut e2, mut d2) = (0.0, 0.0);
            for (k, v) in y.iter().enumerate() {
                let v = v.as_f64();
                e2 += (v - yhat[(k, o)].as_f64()).powi(2);
                d2 += (v - mean).powi(2);
            }
            if d2 > 0.0 {
                100.0 * (1.0 - (e2 / d2).sqrt())
            } else {
                f64::NAN
            }
        })
        .collect()
}
