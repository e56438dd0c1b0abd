//! Bench binary: the whole Example 1 study (50 runs × 7 settings) for each strategy, timed once
//! (a single study takes seconds, too long for criterion's repeated sampling).
//! Target: under 10 s on 2 cores (best strategy). `cargo bench --bench study`.

use hammerstein::study::{Strategy, StudyConfig, run_study};
use std::time::Instant;

fn main() {
    for strategy in [Strategy::PaperLoop, Strategy::Best] {
        let config = StudyConfig {
            strategy,
            ..StudyConfig::default()
        };
        let t = Instant::now();
        let res = run_study::<f64>(&config, &|| {}).expect("study");
        let secs = t.elapsed().as_secs_f64();
        let failed: usize = res.iter().map(|r| r.failures.len()).sum();
        println!(
            "study {:?}: {} runs × {} settings in {secs:.2} s ({} threads, {failed} failed runs)",
            strategy,
            config.runs,
            config.settings.len(),
            rayon::current_num_threads()
        );
    }
}
