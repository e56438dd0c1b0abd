//! The Rust side of `python/bench/fit_overhead.py`: the same fit as the Python call, timed in
//! Rust (same release profile, same library features).
//!
//! `cargo run --release --example fit_time -- RECORD.csv EFFECTS REPEATS` (RECORD.csv: columns
//! u,y; EFFECTS: comma-separated, as `--effects`) prints each fit's wall time in seconds, one
//! and CPU time (all threads of the process) in seconds, one fit per line, after one untimed
//! warm-up fit; then the training MSE.

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
        let (t0, c0) = (Instant::now(), cpu_seconds());
        // the record is built inside the timing, as the Python call builds it from its arrays
        let data = IoData::siso(&u, &y)?;
        let model = settings.fit(&data)?;
        println!("{} {}", t0.elapsed().as_secs_f64(), cpu_seconds() - c0);
        mse = model.report().train_mse;
    }
    println!("train_mse {mse:e}");
    Ok(())
}

/// CPU time of the whole process (every thread), in seconds: what the fit costs on a machine
/// whose other work stretches the wall-clock time.
fn cpu_seconds() -> f64 {
    let mut ts = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: `ts` is a valid, writable timespec; the clock id is a constant Linux knows.
    unsafe { libc::clock_gettime(libc::CLOCK_PROCESS_CPUTIME_ID, &mut ts) };
    ts.tv_sec as f64 + ts.tv_nsec as f64 * 1e-9
}
