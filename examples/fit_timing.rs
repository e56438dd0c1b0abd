//! Times the single-input fits of `benches/fit.rs` (issue 10) in one process, for CPU-time and
//! instruction counts beside the bench's wall time, and prints the fitted numbers so that a
//! change meant to be bit-identical can be checked:
//! `perf stat -e instructions,task-clock target/release/examples/fit_timing default 20`
//! (modes: `default`, `fixed`, `loop` on the record at 10 dB; `clean`: the fixed-order fit of
//! the noise-free record, `fit_udn_2000_clean`).

#[path = "../benches/common/example1_record.rs"]
mod example1_record;

use example1_record::example1;
use hammerstein::regressors::EffectSet;
use hammerstein::{Hammerstein, Order};
use std::time::Instant;

fn main() -> Result<(), hammerstein::Error> {
    let mut args = std::env::args().skip(1);
    let mode = args.next().unwrap_or_else(|| "default".into());
    let reps: usize = args.next().and_then(|a| a.parse().ok()).unwrap_or(20);
    let data = example1(if mode == "clean" { 0.0 } else { 0.87 });
    let default = Hammerstein::<f64>::udn(EffectSet::all());
    let settings = match mode.as_str() {
        "fixed" | "clean" => default.order(Order::Fixed(2)).with_d(false),
        "loop" => default.order(Order::Fixed(2)).with_d(false).refine(false),
        _ => default,
    };
    let t = Instant::now();
    let mut last = None;
    for _ in 0..reps {
        last = Some(settings.fit(&data)?);
    }
    let wall = t.elapsed().as_secs_f64() * 1e3 / reps.max(1) as f64;
    if let Some(m) = last {
        println!(
            "{mode}: {reps} fits, {wall:.2} ms wall each; order {}, train MSE {:.12e}, params {:?}",
            m.linear().order(),
            m.report().train_mse,
            m.parameters()
        );
    }
    Ok(())
}
