//! `hammerstein paper`: reproduces the paper's Example 1 Monte Carlo study (Tables 2 and 3) and
//! prints every parameter's mean ± std beside the paper's and the Cramér–Rao bound.

use hammerstein::study::crlb::{SnrDefinition, crlb_from_information, expected_information};
use hammerstein::study::example1::snr_key;
use hammerstein::study::{
    Crlb, Example1, SettingResult, Strategy, StudyConfig, check_targets, paper_value, run_study,
};
use hammerstein::subspace::MethodKind;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::io::IsTerminal;

/// Arguments of `hammerstein paper`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Monte Carlo runs per setting.
    #[arg(long, value_parser = super::common::parse_count, allow_negative_numbers = true, default_value_t = 50)]
    runs: usize,
    /// Base seed (run k uses seed + k).
    #[arg(long, value_parser = super::common::parse_seed, allow_negative_numbers = true, default_value_t = 1)]
    seed: u64,
    /// Subspace method of the loop (moesp|n4sid|n4sid-unweighted).
    #[arg(long, default_value = "moesp")]
    method: String,
    /// The paper's loop alone: no refinement, no structure decision.
    #[arg(long)]
    paper_loop: bool,
    /// Print JSON instead of tables.
    #[arg(long)]
    json: bool,
}

/// Input draws averaged for the Cramér–Rao bound.
const CRLB_DRAWS: usize = 20;

/// Runs the subcommand; errors are one-line messages.
pub fn run(args: Args) -> super::CliResult {
    let method: MethodKind = args.method.parse()?;
    let config = StudyConfig {
        runs: args.runs,
        seed: args.seed,
        method,
        strategy: if args.paper_loop {
            Strategy::PaperLoop
        } else {
            Strategy::Best
        },
        ..StudyConfig::default()
    };
    let total = (config.runs * config.settings.len()) as u64;
    let bar = if args.json || !std::io::stderr().is_terminal() {
        ProgressBar::hidden()
    } else {
        let b = ProgressBar::with_draw_target(Some(total), ProgressDrawTarget::stderr());
        if let Ok(style) = ProgressStyle::with_template("{bar:40} {pos}/{len} runs  {elapsed}") {
            b.set_style(style);
        }
        b
    };
    let t0 = std::time::Instant::now();
    let results = run_study::<f64>(&config, &|| bar.inc(1))?;
    bar.finish_and_clear();
    let elapsed = t0.elapsed().as_secs_f64();
    let design = Example1::new(Some(10.0));
    let (info, var_y) = expected_information(&design, CRLB_DRAWS, 1_000_000)?;
    let crlb_def =
        |snr: f64, def: SnrDefinition| crlb_from_information(&info, var_y, design.n, snr, def).ok();
    let crlb = |snr: f64| crlb_def(snr, SnrDefinition::Power);
    let checks = check_targets(&results, &crlb);
    if args.json {
        let mut root = serde_json::Map::new();
        for r in &results {
            let key = format!("table{}", r.setting.table.number());
            let tab = root
                .entry(key)
                .or_insert_with(|| serde_json::Value::Object(Default::default()));
            let bound = r.setting.snr_db.and_then(crlb);
            let mut params = serde_json::Map::new();
            for p in &r.params {
                let c = match r.setting.snr_db {
                    None => Some(0.0),
                    Some(_) => bound.as_ref().and_then(|b| b.get(&p.name)),
                };
                let paper = paper_value(r.setting.table.number(), r.setting.snr_db, &p.name);
                params.insert(
                    p.name.clone(),
                    serde_json::json!({
                        "mean": p.mean, "std": p.std, "crlb": c, "rmse": p.rmse,
                        "true": p.truth,
                        "paper_mean": paper.map(|x| x.0), "paper_std": paper.map(|x| x.1),
                    }),
                );
            }
            params.insert(
                "_runs".into(),
                serde_json::json!({"successes": r.successes, "failures": r.failures.len(),
                                   "structures": r.structures}),
            );
            if let serde_json::Value::Object(t) = tab {
                t.insert(snr_key(r.setting.snr_db), serde_json::Value::Object(params));
            }
        }
        root.insert("targets".into(), serde_json::json!(checks));
        root.insert(
            "config".into(),
            serde_json::json!({"runs": config.runs, "seed": config.seed,
                "method": method.name(), "strategy": config.strategy, "seconds": elapsed}),
        );
        outln!(
            "{}",
            serde_json::to_string_pretty(&serde_json::Value::Object(root))?
        )?;
        return Ok(());
    }
    outln!(
        "Example 1 (paper Section 4.1): {} runs per setting, seed {}, {}, {} — {elapsed:.1} s",
        config.runs,
        config.seed,
        method.name(),
        match config.strategy {
            Strategy::Best => "loop + refinement, Table 2 structure decided by BIC",
            Strategy::PaperLoop => "the paper's loop alone",
        }
    )?;
    for r in &results {
        print_setting(r, r.setting.snr_db.and_then(crlb).as_ref(), &crlb_def)?;
    }
    let missed: Vec<_> = checks.iter().filter(|c| !c.met).collect();
    outln!(
        "\nTargets: {} of {} met.",
        checks.len() - missed.len(),
        checks.len()
    )?;
    for c in missed {
        outln!(
            "  MISSED table {} {:>4} {:<3} {:?}: {}",
            c.table,
            snr_key(c.snr_db),
            c.param,
            c.kind,
            c.detail
        )?;
    }
    Ok(())
}

fn print_setting(
    r: &SettingResult,
    bound: Option<&Crlb>,
    crlb_def: &dyn Fn(f64, SnrDefinition) -> Option<Crlb>,
) -> super::CliResult {
    let table = r.setting.table.number();
    let snr = match r.setting.snr_db {
        None => "noise-free".to_string(),
        Some(s) => format!("SNR {s} dB"),
    };
    outln!(
        "\nTable {table}, {snr}: {} runs ok, {} failed{}",
        r.successes,
        r.failures.len(),
        if table == 2 {
            format!(
                "; structures {}",
                r.structures
                    .iter()
                    .map(|(l, n)| format!("{{{l}}}×{n}"))
                    .collect::<Vec<_>>()
                    .join(" ")
            )
        } else {
            String::new()
        }
    )?;
    if let Some((seed, msg)) = r.failures.first() {
        outln!("  first failure (seed {seed}): {msg}")?;
    }
    let amp = r
        .setting
        .snr_db
        .and_then(|s| crlb_def(s, SnrDefinition::Amplitude));
    outln!(
        "  {:<4}{:>8}  {:>19}  {:>19}  {:>8} {:>6}  {:>9}",
        "",
        "true",
        "ours mean ± std",
        "paper mean ± std",
        "CRLB",
        "ratio",
        "CRLB(amp)"
    )?;
    for p in &r.params {
        let paper = paper_value(table, r.setting.snr_db, &p.name)
            .map(|(m, s)| format!("{m:>9.4} ± {s:<7.4}"))
            .unwrap_or_else(|| format!("{:>19}", "—"));
        let c = bound.and_then(|b| b.get(&p.name));
        let ca = amp.as_ref().and_then(|b| b.get(&p.name));
        outln!(
            "  {:<4}{:>8.4}  {:>9.4} ± {:<7.4}  {paper}  {:>8} {:>6}  {:>9}",
            p.name,
            p.truth,
            p.mean,
            p.std,
            c.map(|c| format!("{c:.4}")).unwrap_or_else(|| "—".into()),
            c.map(|c| format!("{:.2}", p.std / c))
                .unwrap_or_else(|| "".into()),
            ca.map(|c| format!("{c:.4}")).unwrap_or_else(|| "—".into()),
        )?;
    }
    Ok(())
}
