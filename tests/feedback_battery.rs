//! A randomised battery of feedback fits: random second- and third-order blocks with a cubic
//! stiffness on the output, Coulomb plus viscous friction on the velocity, or a clearance
//! (dead-zone) on the output; random filtered-noise inputs, seeds and signal-to-noise ratios
//! (20–40 dB). Each record is fitted with the matching `--feedback-nonlinearity` (the order
//! chosen by the singular-value gap) and validated on a second record of the same system, its
//! initial state estimated: the rate of validation MSEs within 1.5× the noise variance is the
//! battery's result. The default test draws a few cases; the `#[ignore]`d one draws more
//! (`cargo test --release --test feedback_battery -- --ignored --nocapture`), seeds 100..160
//! unless `FEEDBACK_BATTERY_SEEDS=a..b` names another range (a held-out range checks that a
//! change to the fit is not tuned on the default seeds).

use hammerstein::IoData;
use hammerstein::feedback::{self, FeedbackKind, FeedbackOn, FeedbackSettings};
use rand::{RngExt, SeedableRng, rngs::StdRng};

mod feedback_common;
use feedback_common::{Truth, denominator, gauss, input, rms, simulate};

struct Case {
    truth: Truth,
    order: usize,
    snr_db: f64,
    ratio: f64,
    fitted_order: usize,
}

/// One record fitted and validated; `None` when the drawn true loop itself blows up at the
/// drawn input's amplitude (its output beyond 100× the linear block's RMS: no record to fit).
fn run_case(seed: u64, n: usize) -> Option<Case> {
    let mut rng = StdRng::seed_from_u64(seed);
    let truth = [Truth::Stiffness, Truth::Friction, Truth::Clearance][(seed % 3) as usize];
    let order = 2 + (rng.random_range(0..2) as usize);
    let a = denominator(&mut rng, order);
    let bnum: Vec<f64> = (0..order)
        .map(|i| {
            if i == 0 {
                1.0
            } else {
                rng.random_range(-0.5..0.5)
            }
        })
        .collect();
    let u = input(&mut rng, 2 * n);
    let velocity = matches!(truth, Truth::Friction);
    // the scale of z on the linear block, then the nonlinearity sized against the input
    let ylin = simulate(&a, &bnum, &u, &|_| 0.0, velocity);
    let zlin: Vec<f64> = if velocity {
        (1..ylin.len()).map(|k| ylin[k] - ylin[k - 1]).collect()
    } else {
        ylin.clone()
    };
    let (sz, su) = (rms(&zlin), rms(&u));
    let strength = rng.random_range(0.3..0.8);
    let f: Box<dyn Fn(f64) -> f64> = match truth {
        Truth::Stiffness => Box::new(move |z: f64| -0.15 * strength * su * (z / sz).powi(3)),
        Truth::Friction => {
            let fv = rng.random_range(0.0..0.3) * su / sz;
            if std::env::var("FB_DEBUG").is_ok() {
                let zt: Vec<f64> = Vec::new();
                let _ = zt;
                eprintln!(
                    "DBG truth strength {strength:.3} su {su:.3} sz {sz:.3e} fv {fv:.3e} slope {:.2}",
                    strength * su / (0.05 * sz)
                );
            }
            // Coulomb's sign with a pre-sliding transition 5 % of the velocity's RMS wide: a
            // sharp sign chatters at the sample rate in discrete time, which no smooth model
            // (nor a physical friction) follows
            Box::new(move |v: f64| -strength * su * (v / (0.05 * sz)).tanh() - fv * v)
        }
        Truth::Clearance => {
            let b = rng.random_range(0.3..0.8) * sz;
            Box::new(move |z: f64| -strength * su / sz * z.signum() * (z.abs() - b).max(0.0))
        }
    };
    let y0 = simulate(&a, &bnum, &u, &*f, velocity);
    // a true loop unstable at the drawn amplitude (a restoring force that pushes on a block of
    // negative gain) grows without bound: the stable draws peak below 5× the linear block's
    // RMS on both seed ranges, the unstable ones above 10⁵× or overflow
    let peak = y0.iter().fold(0.0f64, |a, b| a.max(b.abs()));
    if y0.iter().any(|v| !v.is_finite()) || peak > 100.0 * rms(&ylin) {
        eprintln!("seed {seed}: the drawn true loop diverges on its input; not a record");
        return None;
    }
    let snr_db = rng.random_range(20.0..40.0);
    let sd = rms(&y0) / 10f64.powf(snr_db / 20.0);
    let y: Vec<f64> = y0.iter().map(|v| v + sd * gauss(&mut rng)).collect();
    let train = IoData::siso(&u[..n], &y[..n]).unwrap();
    let val = IoData::siso(&u[n..], &y[n..]).unwrap();
    let (kind, on) = match truth {
        Truth::Stiffness => (FeedbackKind::Poly3, FeedbackOn::Output),
        Truth::Friction => (FeedbackKind::Coulomb, FeedbackOn::Velocity),
        Truth::Clearance => (FeedbackKind::DeadZone, FeedbackOn::Output),
    };
    let s = FeedbackSettings::new(kind, on);
    if std::env::var("FB_DEBUG").is_ok() {
        eprintln!("DBG seed {seed} noise var {:.4e}", sd * sd);
    }
    let (ratio, fitted_order) = match feedback::fit(&s, &train) {
        Ok(fit) => match fit.model.compare(&val) {
            Ok(c) => (c.rms.powi(2) / (sd * sd), fit.model.order()),
            Err(e) => {
                eprintln!("seed {seed}: validation failed: {e}");
                (f64::INFINITY, fit.model.order())
            }
        },
        Err(e) => {
            eprintln!("seed {seed}: fit failed: {e}");
            (f64::INFINITY, 0)
        }
    };
    Some(Case {
        truth,
        order,
        snr_db,
        ratio,
        fitted_order,
    })
}

fn battery(seeds: std::ops::Range<u64>, n: usize) -> f64 {
    battery_by_truth(seeds, n).0
}

/// The overall rate and the rates of stiffness, friction and clearance records.
fn battery_by_truth(seeds: std::ops::Range<u64>, n: usize) -> (f64, [f64; 3]) {
    let cases: Vec<(u64, Case)> = seeds
        .filter_map(|s| run_case(s, n).map(|c| (s, c)))
        .collect();
    for (s, c) in &cases {
        eprintln!(
            "seed {s:3} {:9} order {} (fitted {}) SNR {:4.1} dB: validation MSE / noise = {:.3}",
            format!("{:?}", c.truth),
            c.order,
            c.fitted_order,
            c.snr_db,
            c.ratio
        );
    }
    let cases: Vec<Case> = cases.into_iter().map(|(_, c)| c).collect();
    let ok = cases.iter().filter(|c| c.ratio <= 1.5).count();
    let rate = ok as f64 / cases.len() as f64;
    eprintln!(
        "{ok} of {} within 1.5× the noise ({:.0} %)",
        cases.len(),
        100.0 * rate
    );
    let by = |t: fn(&Truth) -> bool| {
        let of: Vec<&Case> = cases.iter().filter(|c| t(&c.truth)).collect();
        let ok = of.iter().filter(|c| c.ratio <= 1.5).count();
        eprintln!("  {:?}: {ok} of {}", of.first().map(|c| c.truth), of.len());
        ok as f64 / of.len().max(1) as f64
    };
    let rates = [
        by(|t| matches!(t, Truth::Stiffness)),
        by(|t| matches!(t, Truth::Friction)),
        by(|t| matches!(t, Truth::Clearance)),
    ];
    (rate, rates)
}

#[test]
fn feedback_fits_reach_the_noise_on_random_records() {
    let rate = battery(0..6, 1500);
    assert!(rate >= 5.0 / 6.0, "rate {rate}");
}

/// The large battery's seeds: `FEEDBACK_BATTERY_SEEDS=a..b`, or 100..160.
fn large_seeds() -> std::ops::Range<u64> {
    let Ok(v) = std::env::var("FEEDBACK_BATTERY_SEEDS") else {
        return 100..160;
    };
    let parsed = v
        .split_once("..")
        .and_then(|(a, b)| Some(a.trim().parse::<u64>().ok()?..b.trim().parse::<u64>().ok()?));
    match parsed {
        Some(r) if r.start < r.end => r,
        _ => panic!("FEEDBACK_BATTERY_SEEDS takes a range a..b with a < b, got '{v}'"),
    }
}

#[test]
#[ignore = "the larger battery whose rates the docs quote (minutes in release)"]
fn feedback_fits_reach_the_noise_on_random_records_large() {
    // stiffness and clearance reach the target, and all records together; friction on the
    // velocity alone does not (its rate is printed and quoted in docs/feedback.md: 16 of 20
    // on the default seeds, 18 of 20 on 1000..1060; 0.75 held here)
    let (all, [stiffness, friction, clearance]) = battery_by_truth(large_seeds(), 3000);
    eprintln!("stiffness {stiffness:.2}, friction {friction:.2}, clearance {clearance:.2}");
    assert!(
        all >= 0.9 && stiffness >= 0.9 && clearance >= 0.9 && friction >= 0.75,
        "{all} {stiffness} {friction} {clearance}"
    );
}
