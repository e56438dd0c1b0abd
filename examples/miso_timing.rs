//! Times the two-input default fit of `benches/fit_miso.rs` (issue 12) in one process, for a
//! CPU-time figure beside the bench's wall time: `/usr/bin/time cargo run --release --example
//! miso_timing -- 20` (the fits run one after another; the branch work inside may use 2 threads).

#[path = "../benches/common/miso_record.rs"]
mod miso_record;

use miso_record::{default_settings, record};
use std::time::Instant;

fn main() -> Result<(), hammerstein::Error> {
    let reps: usize = std::env::args()
        .nth(1)
        .and_then(|a| a.parse().ok())
        .unwrap_or(20);
    let data = record();
    let settings = default_settings();
    let t = Instant::now();
    let mut last = None;
    for _ in 0..reps {
        last = Some(settings.fit(&data)?);
    }
    let wall = t.elapsed().as_secs_f64() * 1e3 / reps.max(1) as f64;
    if let Some(m) = last {
        let orders: Vec<usize> = m.branches().iter().map(|b| b.linear().order()).collect();
        let joint = m.report().joint_refinement.as_ref().map_or_else(
            || "no joint refinement".to_string(),
            |j| {
                format!(
                    "joint refinement {} iterations, {:.4e} -> {:.4e}",
                    j.iterations, j.mse_before, j.mse_after
                )
            },
        );
        println!(
            "{reps} fits, {wall:.1} ms wall each; orders {orders:?}, sweeps {}, train MSE {:.4e}; {joint}",
            m.report().sweeps.len(),
            m.report().train_mse
        );
    }
    Ok(())
}
