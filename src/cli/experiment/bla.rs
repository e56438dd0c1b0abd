//! `hammerstein bla`: the best linear approximation of multisine records per level, its noise
//! and distortion levels, and whether the system is nonlinear.

use hammerstein::structure::{BlaMethod, bla};

/// Arguments of `hammerstein bla`.
#[derive(clap::Args, Debug)]
pub struct Args {
    #[command(flatten)]
    pub records: super::records::RecordArgs,
    /// Print JSON (every line's BLA and variances) instead of text.
    #[arg(long)]
    pub json: bool,
    /// Write the BLA plot (|BLA|, noise and distortion against frequency, one colour per level)
    /// as SVG here.
    #[arg(long, value_name = "OUT.svg")]
    pub plot: Option<std::path::PathBuf>,
}

fn db(v: f64) -> f64 {
    10.0 * v.max(1e-300).log10()
}

/// Runs the subcommand.
pub fn run(args: Args) -> super::super::CliResult {
    if let Some(p) = &args.plot {
        let inputs: Vec<&std::path::Path> =
            args.records.records.iter().map(|p| p.as_path()).collect();
        super::super::paths::check_output_file(p, "--plot", &inputs)?;
    }
    let (record, ts) = args.records.read()?;
    let b = bla(&record)?;
    if let Some(p) = &args.plot {
        let svg = hammerstein::report::bla_plot::bla_svg(&b, ts)?;
        hammerstein::atomic::write_atomic(p, svg.as_bytes())?;
    }
    if args.json {
        let mut v = serde_json::to_value(&b)?;
        v["ts"] = ts.map_or(serde_json::Value::Null, |t| serde_json::json!(t));
        return super::super::out(&format!("{}\n", serde_json::to_string_pretty(&v)?));
    }
    let (scale, unit) = match ts {
        Some(t) => (1.0 / t, "Hz"),
        None => (1.0, "of fs"),
    };
    outln!(
        "{} excited lines per period of {} samples ({:.4}..{:.4} {unit})",
        b.excited.len(),
        b.period,
        b.excited[0] as f64 / b.period as f64 * scale,
        *b.excited.last().unwrap_or(&0) as f64 / b.period as f64 * scale
    )?;
    for l in &b.levels {
        let method = match l.method {
            BlaMethod::Robust => "robust method",
            BlaMethod::Fast => "fast method",
            BlaMethod::NoiseOnly => "noise only",
            BlaMethod::TotalOnly => "total variance only",
        };
        let mean = |f: &dyn Fn(&hammerstein::structure::LineBla) -> Option<f64>| {
            let v: Vec<f64> = l
                .lines
                .iter()
                .filter_map(f)
                .filter(|v| v.is_finite())
                .collect();
            (!v.is_empty()).then(|| v.iter().sum::<f64>() / v.len() as f64)
        };
        let g = mean(&|x| Some(x.value().norm_sqr())).unwrap_or(f64::NAN);
        outln!(
            "level {} (input RMS {}): {} realization(s) x {} period(s), {method}",
            l.level,
            super::super::common::significant(l.rms),
            l.realizations,
            l.periods
        )?;
        let noise = mean(&|x| x.var_noise).map_or("n/a".into(), |v| format!("{:.1} dB", db(v / g)));
        let dist =
            mean(&|x| x.var_distortion).map_or("n/a".into(), |v| format!("{:.1} dB", db(v / g)));
        outln!(
            "  mean |BLA|^2 {:.1} dB; noise {noise}, distortion {dist} relative to it",
            db(g)
        )?;
        if let Some(e) = l.even_db {
            outln!("  even detection lines {e:.1} dB above the noise")?;
        }
        if let Some(o) = l.odd_db {
            outln!("  odd detection lines {o:.1} dB above the noise")?;
        }
        match &l.nonlinearity {
            Some(n) => outln!(
                "  {}: distortion {:.1} dB above the noise, {} of {} {} significant at 1 % (p = {:.1e})",
                if n.detected {
                    "NONLINEAR"
                } else {
                    "no nonlinearity detected"
                },
                n.db_above_noise,
                n.lines,
                n.of,
                n.basis,
                n.p_value
            )?,
            None => outln!(
                "  nonlinearity not testable: one realization of a full grid (or one period) cannot \
                 separate distortion from noise"
            )?,
        }
    }
    Ok(())
}
