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
pub fn run(args: Args) -> super::CliResult {
    if !(args.alpha > 0.0 && args.alpha < 1.0) {
        return Err(format!("--alpha must lie in (0, 1), got {}", args.alpha).into());
    }
    if args.order == Some(0) || args.max_order == 0 {
        return Err("--order and --max-order must be at least 1".into());
    }
    let (record, ts) = args.records.read()?;
    let b = bla(&record)?;
    let s = analyze(
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
    if args.json {
        return super::out(&format!("{}\n", serde_json::to_string_pretty(&s)?));
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
            super::common::significant(l.rms),
            l.distortion_db.map_or(String::new(), |d| format!(
                ", distortion {d:.1} dB above noise"
            )),
            roots(&l.poles)
        )?;
        outln!("  zeros {}", roots(&l.zeros))?;
    }
    for m in s.moved.iter().take(5) {
        outln!(
            "{} moved: {:.4} {u} (ζ {:.3}) -> {:.4} {u} (ζ {:.3}): frequency {:+.1} standard errors, damping {:+.1}",
            m.kind,
            m.from.freq,
            m.from.damping,
            m.to.freq,
            m.to.damping,
            m.freq_shift_se,
            m.damping_shift_se
        )?;
    }
    outln!("candidates: {}", s.candidates.join(", "))?;
    for n in &s.notes {
        outln!("note: {n}")?;
    }
    Ok(())
}
