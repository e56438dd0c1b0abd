//! The Rust side of `python/bench/fit_overhead.py`: the same fit as the Python call, timed in
//! Rust (same release profile, same library features).
//!
//! `cargo run --release --example fit_time -- RECORD.csv EFFECTS REPEATS` (RECORD.csv: columns
//! u,y; EFFECTS: comma-separated, as `--effects`) prints each fit's wall time in seconds, one
//! per line, after one untimed warm-up fit, then the training MSE.

use hammerstein::regressors::EffectSet;
use hammerstein::{Hammerstein, IoData};
use std::time::Instant;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let [_, path, effects, repeats] = args.as_slice() else {
        return Err("usage: fit_time RECORD.csv EFFECTS REPEATS".into());
    };
    let text = std::fs::read_to_string(path)?;
    let (mut u, mut y) = (Vec::new(), Vec::new());
    for line in text.lines().skip(1) {
        let mut it = line.split(',');
        u.push(it.next().ok_or("short line")?.trim().parse::<f64>()?);
        y.push(it.next().ok_or("short line")?.trim().parse::<f64>()?);
    }
    let settings = Hammerstein::<f64>::udn(EffectSet::parse(effects)?);
    // warm-up, untimed: the thread pool started and the pages touched, as in the Python
    // process whose first call is not timed either
    settings.fit(&IoData::siso(&u, &y)?)?;
    let mut mse = 0.0;
    for _ in 0..repeats.parse::<usize>()? {
        let t0 = Instant::now();
        // the record is built inside the timing, as the Python call builds it from its arrays
        let data = IoData::siso(&u, &y)?;
        let model = settings.fit(&data)?;
        println!("{}", t0.elapsed().as_secs_f64());
        mse = model.report().train_mse;
    }
    println!("train_mse {mse:e}");
    Ok(())
}
