//! Residual tests with the true linear block: size under a correct model, power against each
//! missing effect, and the size estimates.

mod common;

use common::{InputKind, Udn, add_noise, input, paper_block};
use hammerstein::diagnosis::{AnalysisOptions, ResidualAnalysis};

fn analyse(
    truth: &Udn,
    model: &Udn,
    kind: InputKind,
    snr_ratio: f64,
    seed: u64,
) -> ResidualAnalysis {
    let g = paper_block();
    let u = input(kind, 3000, 3.0, seed);
    let v = truth.eval(&u);
    let vh = model.eval(&u);
    let y0 = g.simulate_siso(&v, None).unwrap();
    let yh = g.simulate_siso(&vh, None).unwrap();
    // noise variance relative to the variance of the clean output
    let m = y0.iter().sum::<f64>() / y0.len() as f64;
    let var = y0.iter().map(|y| (y - m).powi(2)).sum::<f64>() / y0.len() as f64;
    let y = add_noise(&y0, var * snr_ratio, seed);
    ResidualAnalysis::new(&u, &y, &yh, &vh, &g, AnalysisOptions::default()).unwrap()
}

fn sh() -> Udn {
    Udn {
        p: 2.0,
        a: 0.0,
        b: 0.0,
        z1: 1.5,
        z2: -1.0,
        e1: 0.0,
        e2: 0.0,
    }
}

#[test]
fn correct_model_is_rarely_flagged() {
    // family-wise level 1 %: over 30 records (3 input kinds) expect about 0.3 alarms
    let truth = sh();
    let mut alarms = Vec::new();
    let mut p_small = 0;
    let mut n_tests = 0;
    for seed in 0..10 {
        for kind in [InputKind::Uniform, InputKind::Smooth, InputKind::Multisine] {
            let a = analyse(&truth, &truth, kind, 0.05, seed);
            for t in &a.tests {
                n_tests += 1;
                if t.p_value < 0.05 {
                    p_small += 1;
                }
            }
            if a.any_significant() {
                alarms.push(format!(
                    "{kind:?}/{seed}: {:?}",
                    a.tests
                        .iter()
                        .filter(|t| t.significant)
                        .map(|t| (&t.name, t.p_value))
                        .collect::<Vec<_>>()
                ));
            }
        }
    }
    let rate = p_small as f64 / n_tests as f64;
    println!("per-test rate of p < 0.05 under H0: {rate:.3}; family alarms: {alarms:?}");
    assert!(alarms.len() <= 2, "{alarms:?}");
    assert!(rate < 0.10, "per-test false-alarm rate {rate}");
}

#[test]
fn each_missing_effect_lights_its_own_test() {
    let cases: Vec<(&str, Udn, &str)> = vec![
        ("saturation", Udn::linear(2.0), "input-extremes"),
        (
            "hysteresis",
            Udn {
                a: 0.3,
                ..Udn::linear(2.0)
            },
            "input-direction",
        ),
        (
            "dead-zone",
            Udn {
                b: 0.5,
                ..Udn::linear(2.0)
            },
            "input-near-zero",
        ),
        (
            "preload",
            Udn {
                e1: 0.4,
                e2: -0.4,
                ..Udn::linear(2.0)
            },
            "input-zero-step",
        ),
    ];
    for (name, mut truth, test) in cases {
        if name == "saturation" {
            truth.z1 = 1.5;
            truth.z2 = -1.0;
        }
        for kind in [InputKind::Uniform, InputKind::Smooth] {
            let a = analyse(&truth, &Udn::linear(2.0), kind, 0.02, 3);
            let t = a.test(test).unwrap();
            assert!(t.significant, "{name} {kind:?}: {t:?}");
            println!("{name} {kind:?}: {}", t.detail);
            match name {
                "hysteresis" => {
                    let w = a.hysteresis_half_width().unwrap();
                    assert!((w - 0.3).abs() < 0.06, "half-width {w}");
                }
                "dead-zone" => {
                    let w = a.dead_zone_width().unwrap();
                    assert!((w - 0.5).abs() < 0.2, "dead-zone {w}");
                }
                "preload" => {
                    let e = a.preload_step().unwrap();
                    assert!((e - 0.4).abs() < 0.1, "preload {e}");
                }
                "saturation" => {
                    let (hi, lo) = a.saturation_levels();
                    let (hi, lo) = (hi.unwrap(), lo.unwrap());
                    println!("sat {hi} {lo}");
                    assert!(
                        (hi - 1.5).abs() < 0.3 && (lo + 1.0).abs() < 0.3,
                        "{hi} {lo}"
                    );
                }
                _ => {}
            }
        }
    }
}
