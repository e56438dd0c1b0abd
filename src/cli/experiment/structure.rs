//! `hammerstein structure`: the structure verdict (linear, single-branch, parallel, feedback)
//! from the BLAs of multisine records at several levels.

use hammerstein::structure::{StructureOptions, analyze, bla};

/// Arguments of `hammerstein structure`.
#[derive(clap::Args, Debug)]
pub struct Args {
    #[command(flatten)]
    pub records: super::records::RecordArgs,
    /// Model order of every level's BLA (by default chosen from the data, up to --max-order).
    #[arg(long)]
    pub order: Option<usize>,
    /// Highest order tried when the order is chosen from the data.
    #[arg(long, default_value_t = 8)]
    pub max_order: usize,
    /// Level of the F tests between the nested joint fits.
    #[arg(long, default_value_t = 1e-3)]
    pub alpha: f64,
    /// Fit only the lines in this band lo,hi (Hz when the sampling time is known, else fractions
    /// of the sampling frequency), e.g. around one mode.
    #[arg(long, value_parser = parse_pair)]
    pub band: Option<(f64, f64)>,
    /// A non-periodic record (one file): split it into this many amplitude classes by the
    /// input's local RMS and compare ARX models of the classes (weaker evidence; see the notes).
    #[arg(long, value_name = "CLASSES")]
    pub by_rms: Option<usize>,
    /// Window in samples of the local RMS for --by-rms.
    #[arg(long, default_value_t = 1000)]
    pub window: usize,
    /// Use only samples FROM:TO (0-based, TO excluded) of a --by-rms record.
    #[arg(long, value_name = "FROM:TO")]
    pub samples: Option<String>,
    /// Print JSON instead of text.
    #[arg(long)]
    pub json: bool,
}

fn parse_pair(s: &str) -> Result<(f64, f64), String> {
    let v: Vec<&str> = s.split(',').collect();
    let bad = || format!("expected two numbers lo,hi, got '{s}'");
    if v.len() != 2 {
        return Err(bad());
    }
    let lo = v[0].trim().parse::<f64>().map_err(|_| bad())?;
    let hi = v[1].trim().parse::<f64>().map_err(|_| bad())?;
    if !(lo.is_finite() && hi.is_finite() && lo < hi) {
        return Err(format!("expected lo < hi, got '{s}'"));
    }
    Ok((lo, hi))
}

/// Runs the subcommand.
pub fn run(args: Args) -> super::super::CliResult {
    if !(args.alpha > 0.0 && args.alpha < 1.0) {
        return Err(format!("--alpha must lie in (0, 1), got {}", args.alpha).into());
    }
    if args.order == Some(0) || args.max_order == 0 {
        return Err("--order and --max-order must be at least 1".into());
    }
    let s = match args.by_rms {
        Some(classes) => by_rms(&args, classes)?,
        None => periodic(&args)?,
    };
    print(&args, &s)
}

fn by_rms(
    args: &Args,
    classes: usize,
) -> Result<hammerstein::structure::Structure, super::super::Failure> {
    let r = &args.records;
    if r.records.len() != 1 {
        return Err("--by-rms takes one record".into());
    }
    let table = hammerstein::data::CsvTable::read(&r.records[0])?;
    let u = table.column(&r.input)?;
    let y = table.column(&r.output)?;
    let (from, to) = match &args.samples {
        None => (0, u.len()),
        Some(s) => {
            let bad = || format!("--samples expects FROM:TO, got '{s}'");
            let (a, b) = s.split_once(':').ok_or_else(bad)?;
            let a: usize = a.trim().parse().map_err(|_| bad())?;
            let b: usize = b.trim().parse().map_err(|_| bad())?;
            if a >= b || b > u.len() {
                return Err(
                    format!("--samples {a}:{b} lies outside the record's 0:{}", u.len()).into(),
                );
            }
            (a, b)
        }
    };
    let ts = r.ts.or_else(|| {
        let t = table.column("t").ok()?;
        let step = (t[t.len() - 1] - t[0]) / (t.len() - 1).max(1) as f64;
        (step.is_finite() && step > 0.0).then_some(step)
    });
    Ok(hammerstein::structure::analyze_by_amplitude(
        &u[from..to],
        &y[from..to],
        &hammerstein::structure::AmplitudeOptions {
            window: args.window,
            classes,
            order: args.order,
            max_order: args.max_order.min(12),
            ts,
            alpha: args.alpha,
        },
    )?)
}

fn periodic(args: &Args) -> Result<hammerstein::structure::Structure, super::super::Failure> {
    let (record, ts) = args.records.read()?;
    let b = bla(&record)?;
    let mut s = analyze(
        &b,
        &StructureOptions {
            ts,
            order: args.order,
            max_order: args.max_order,
            alpha: args.alpha,
            band: args.band,
            ..Default::default()
        },
    )?;
    if s.verdict == hammerstein::structure::Verdict::SingleBranch {
        eprintln!("fitting hammerstein, wiener and wiener-hammerstein models to rank them ...");
        s.rank_single_branch(&record);
    }
    Ok(s)
}

fn print(args: &Args, s: &hammerstein::structure::Structure) -> super::super::CliResult {
    if args.json {
        return super::super::out(&format!("{}\n", serde_json::to_string_pretty(s)?));
    }
    let u = &s.freq_unit;
    outln!("verdict: {}", s.verdict)?;
    outln!(
        "order {} at every level ({} levels)",
        s.order,
        s.levels.len()
    )?;
    for t in &s.tests {
        outln!(
            "  {}: {:?} against {:?}: F = {:.2}, p = {:.2e}{}",
            t.question,
            t.restricted,
            t.full,
            t.f,
            t.p_value,
            if t.rejected { "  (rejected)" } else { "" }
        )?;
    }
    for (i, l) in s.levels.iter().enumerate() {
        let roots = |r: &[hammerstein::structure::parametric::Root]| {
            r.iter()
                .map(|p| format!("{:.4}±{:.4} {u} (ζ {:.3})", p.freq, p.freq_se, p.damping))
                .collect::<Vec<_>>()
                .join(", ")
        };
        outln!(
            "level {i} (input RMS {}{}): poles {}",
            super::super::common::significant(l.rms),
            l.distortion_db.map_or(String::new(), |d| format!(
                ", distortion {d:.1} dB above noise"
            )),
            roots(&l.poles)
        )?;
        outln!("  zeros {}", roots(&l.zeros))?;
    }
    for m in s.moved.iter().take(8) {
        outln!(
            "{} moved (level {} -> {}): {:.4} {u} (ζ {:.3}) -> {:.4} {u} (ζ {:.3}): frequency {:+.1} standard errors, damping {:+.1}",
            m.kind,
            m.from_level,
            m.to_level,
            m.from.freq,
            m.from.damping,
            m.to.freq,
            m.to.damping,
            m.freq_shift_se,
            m.damping_shift_se
        )?;
    }
    outln!("candidates: {}", s.candidates.join(", "))?;
    if let Some(r) = &s.ranking {
        for (i, c) in r.candidates.iter().enumerate() {
            match &c.error {
                Some(e) => outln!("  {}. {}: fit failed: {e}", i + 1, c.name)?,
                None => outln!(
                    "  {}. {}: validation MSE {} (train {}), {:+.1} standard errors from the best{}",
                    i + 1,
                    c.name,
                    super::super::common::significant(c.validation_mse),
                    super::super::common::significant(c.train_mse),
                    c.dm_vs_best,
                    if c.within_noise { ", within noise" } else { "" }
                )?,
            }
        }
    }
    for n in &s.notes {
        outln!("note: {n}")?;
    }
    Ok(())
}
