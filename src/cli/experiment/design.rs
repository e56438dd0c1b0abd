//! `hammerstein design`: a random-phase multisine experiment in the record format
//! (`level,realization,period,u`), to replay on the plant.

use hammerstein::structure::{MultisineDesign, MultisineKind};
use std::path::PathBuf;

/// Which lines the multisine excites.
#[derive(clap::ValueEnum, Clone, Copy, Debug)]
pub enum Kind {
    /// Odd lines, one per group left out as a detection line.
    RandomOdd,
    /// Every line of the band.
    Full,
}

/// Arguments of `hammerstein design`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Full grid or random odd.
    #[arg(long, value_enum, default_value = "random-odd")]
    pub multisine: Kind,
    /// Samples per period.
    #[arg(long, default_value_t = 1024)]
    pub samples: usize,
    /// Band edges lo,hi: fractions of the sampling frequency, or Hz with --ts.
    #[arg(long, default_value = "0.01,0.2", value_parser = parse_pair)]
    pub band: (f64, f64),
    /// Sampling time in seconds: --band is then in Hz.
    #[arg(long)]
    pub ts: Option<f64>,
    /// Odd lines per group of a random-odd multisine (one left out per group).
    #[arg(long, default_value_t = 4)]
    pub group: usize,
    /// RMS value of each level, increasing.
    #[arg(long, default_value = "0.25,0.5,1", value_delimiter = ',')]
    pub levels: Vec<f64>,
    /// Realizations per level (a new random phase each).
    #[arg(long, default_value_t = 4)]
    pub realizations: usize,
    /// Steady periods per realization (one transient period is added before them).
    #[arg(long, default_value_t = 2)]
    pub periods: usize,
    /// Seed of the lines and phases.
    #[arg(long, default_value_t = 7, value_parser = super::super::common::parse_seed)]
    pub seed: u64,
    /// Write the CSV here instead of standard output.
    #[arg(long, value_name = "OUT.csv")]
    pub out: Option<PathBuf>,
}

fn parse_pair(s: &str) -> Result<(f64, f64), String> {
    let v: Vec<&str> = s.split(',').collect();
    let bad = || format!("expected two numbers lo,hi, got '{s}'");
    if v.len() != 2 {
        return Err(bad());
    }
    let lo = v[0].trim().parse::<f64>().map_err(|_| bad())?;
    let hi = v[1].trim().parse::<f64>().map_err(|_| bad())?;
    Ok((lo, hi))
}

/// Runs the subcommand.
pub fn run(args: Args) -> super::super::CliResult {
    if let Some(p) = &args.out {
        super::super::paths::check_output_file(p, "--out", &[])?;
    }
    let band = match args.ts {
        Some(ts) if ts.is_finite() && ts > 0.0 => (args.band.0 * ts, args.band.1 * ts),
        Some(ts) => {
            return Err(format!("--ts must be a positive number of seconds, got {ts}").into());
        }
        None => args.band,
    };
    let design = MultisineDesign {
        kind: match args.multisine {
            Kind::RandomOdd => MultisineKind::RandomOdd { group: args.group },
            Kind::Full => MultisineKind::Full,
        },
        samples: args.samples,
        band,
        levels: args.levels.clone(),
        realizations: args.realizations,
        periods: args.periods,
        seed: args.seed,
    };
    let record = design.generate()?;
    super::super::note(&format!(
        "{} excited lines of {} per period; {} level(s) x {} realization(s) x (1 transient + {}) periods = {} samples",
        design.excited_lines().len(),
        args.samples / 2,
        args.levels.len(),
        args.realizations,
        args.periods,
        args.levels.len() * args.realizations * (args.periods + 1) * args.samples
    ));
    let mut bytes = Vec::new();
    record
        .write_csv(&mut bytes)
        .map_err(|e| format!("cannot format the record: {e}"))?;
    match &args.out {
        Some(p) => hammerstein::atomic::write_atomic(p, &bytes)?,
        None => super::super::out(&String::from_utf8_lossy(&bytes))?,
    }
    Ok(())
}
