//! Battery of hidden effects: data from a Hammerstein system with a known UDN, a model that lacks
//! one effect (or lacks nothing), and the diagnosis' verdict.
//!
//! Targets: the top suggestion names the hidden effect in ≥ 90 % of the cases; no
//! effect is suggested where nothing is missing; adding the named effect brings the validation MSE
//! within 1.5× the noise variance and removes at least half of its excess over the noise variance.
//! The table printed (`cargo test --test diagnosis_battery -- --nocapture`) gives the measured rates.

mod common;

use common::{InputKind, Udn, add_noise, input, paper_block, slow_block};
use hammerstein::IoData;
use hammerstein::StateSpace;
use hammerstein::diagnosis::diagnose;
use hammerstein::fit::Hammerstein;
use hammerstein::regressors::{Effect, EffectSet};

const N: usize = 3000;

#[derive(Debug, Clone)]
struct Case {
    name: String,
    truth: Udn,
    model: EffectSet,
    hidden: Option<Effect>,
    kind: InputKind,
    block: fn() -> StateSpace<f64>,
    /// Noise: SNR in dB, or (when `weak` is set) the ratio by which the hidden effect raises the
    /// residual variance of a model without it.
    snr_db: f64,
    weak: Option<f64>,
    seed: u64,
}

fn udn(effects: &[Effect]) -> Udn {
    let mut t = Udn::linear(2.0);
    for e in effects {
        match e {
            Effect::Hysteresis => t.a = 0.3,
            Effect::DeadZone => t.b = 0.4,
            Effect::Saturation => {
                t.z1 = 1.5;
                t.z2 = -1.2;
            }
            Effect::Preload => {
                t.e1 = 0.5;
                t.e2 = -0.5;
            }
            // not a UDN effect (its battery is tests/pi_battery.rs)
            Effect::PrandtlIshlinskii => {}
        }
    }
    t
}

#[derive(Debug)]
struct Outcome {
    case: String,
    expected: String,
    top: String,
    correct: bool,
    excess_before: f64,
    after_ratio: f64,
    halves_excess: bool,
    within_1_5: bool,
}

fn settings(set: EffectSet, seed: u64) -> Hammerstein<f64> {
    let s = if set.is_empty() {
        Hammerstein::linear()
    } else {
        Hammerstein::udn(set)
    };
    s.seed(seed)
}

fn run_case(c: &Case) -> Outcome {
    let g = (c.block)();
    let u = input(c.kind, N, 3.0, c.seed);
    let v = c.truth.eval(&u);
    let y0 = g.simulate_siso(&v, None).unwrap();
    let mean = y0.iter().sum::<f64>() / N as f64;
    let var = y0.iter().map(|y| (y - mean).powi(2)).sum::<f64>() / N as f64;
    let noise_var = match (c.weak, c.hidden) {
        (Some(ratio), Some(_)) => {
            // the error a model without the effect cannot avoid, measured on noise-free data
            let clean = IoData::siso(&u, &y0).unwrap();
            let (tr, va) = clean.split_validation(0.3).unwrap();
            let m = settings(c.model, c.seed).fit(&tr).unwrap();
            let e = hammerstein::diagnosis::compare(&m, &va)
                .unwrap()
                .metrics
                .mse;
            e / (ratio - 1.0)
        }
        _ => var / 10f64.powf(c.snr_db / 10.0),
    };
    let y = add_noise(&y0, noise_var, c.seed);
    let data = IoData::siso(&u, &y).unwrap();
    let (train, val) = data.split_validation(0.3).unwrap();
    let model = settings(c.model, c.seed).fit(&train).unwrap();
    let d = diagnose(&model, &train, &val).unwrap();
    let before = d.validation.metrics.mse;
    let expected = c
        .hidden
        .map_or("none".to_string(), |e| e.name().to_string());
    let top = d
        .suggestions
        .first()
        .map_or("none".to_string(), |s| s.effect.to_string());
    let after = d
        .suggestions
        .first()
        .map_or(before, |s| s.validation_mse_after);
    let correct = top == expected;
    if !correct {
        for c in &d.candidates {
            println!(
                "    [applicable {}] {}: improvement {:?} refit {:?} error {:?} evidence p {:?}",
                c.applicable,
                c.effect,
                c.improvement,
                c.refit
                    .as_ref()
                    .map(|r| (r.validation_mse / noise_var, r.change.clone())),
                c.refit_error,
                c.evidence.as_ref().map(|e| e.p_adjusted)
            );
        }
    }
    let excess = before - noise_var;
    Outcome {
        case: c.name.clone(),
        expected,
        top,
        correct,
        excess_before: before / noise_var,
        after_ratio: after / noise_var,
        halves_excess: c.hidden.is_none() || (before - after) >= 0.5 * excess,
        within_1_5: c.hidden.is_none() || after <= 1.5 * noise_var,
    }
}

fn cases(seeds: &[u64]) -> Vec<Case> {
    use Effect::*;
    let mut v = Vec::new();
    for &seed in seeds {
        // each effect alone, the model linear, three input kinds
        for kind in [InputKind::Uniform, InputKind::Smooth, InputKind::Multisine] {
            for e in Effect::ALL {
                v.push(Case {
                    name: format!("{} alone/{}/s{seed}", e.name(), kind.name()),
                    truth: udn(&[e]),
                    model: EffectSet::empty(),
                    hidden: Some(e),
                    kind,
                    block: if kind == InputKind::Smooth {
                        slow_block
                    } else {
                        paper_block
                    },
                    snr_db: 25.0,
                    weak: None,
                    seed,
                });
            }
        }
        // one effect missing, others already modelled
        for (truth, model, hidden) in [
            (vec![Saturation, Hysteresis], vec![Saturation], Hysteresis),
            (vec![Saturation, Hysteresis], vec![Hysteresis], Saturation),
            (vec![Saturation, DeadZone], vec![Saturation], DeadZone),
            (vec![Saturation, Preload], vec![Saturation], Preload),
            (vec![Hysteresis, DeadZone], vec![Hysteresis], DeadZone),
        ] {
            v.push(Case {
                name: format!(
                    "{} given {}/uniform/s{seed}",
                    hidden.name(),
                    EffectSet::of(&model).label()
                ),
                truth: udn(&truth),
                model: EffectSet::of(&model),
                hidden: Some(hidden),
                kind: InputKind::Uniform,
                block: paper_block,
                snr_db: 22.0,
                weak: None,
                seed,
            });
        }
        // weak effects: +30 % residual variance
        for e in Effect::ALL {
            v.push(Case {
                name: format!("{} weak (+30 %)/uniform/s{seed}", e.name()),
                truth: udn(&[e]),
                model: EffectSet::empty(),
                hidden: Some(e),
                kind: InputKind::Uniform,
                block: paper_block,
                snr_db: 0.0,
                weak: Some(1.3),
                seed,
            });
        }
        // nothing missing
        for (effects, kind) in [
            (vec![], InputKind::Uniform),
            (vec![Saturation], InputKind::Uniform),
            (vec![Saturation, Hysteresis], InputKind::Uniform),
            (vec![DeadZone], InputKind::Smooth),
            (vec![Hysteresis], InputKind::Multisine),
            (vec![Preload, Saturation], InputKind::Uniform),
        ] {
            v.push(Case {
                name: format!(
                    "nothing missing ({})/{}/s{seed}",
                    EffectSet::of(&effects).label(),
                    kind.name()
                ),
                truth: udn(&effects),
                model: EffectSet::of(&effects),
                hidden: None,
                kind,
                block: if kind == InputKind::Smooth {
                    slow_block
                } else {
                    paper_block
                },
                snr_db: 25.0,
                weak: None,
                seed,
            });
        }
    }
    v
}

fn run_battery(seeds: &[u64]) {
    let cs = cases(seeds);
    let outcomes: Vec<Outcome> = cs.iter().map(run_case).collect();
    println!(
        "\n{:<44} {:<12} {:<20} {:>9} {:>9} {:>5}",
        "case", "hidden", "top suggestion", "before/σ²", "after/σ²", "ok"
    );
    for o in &outcomes {
        println!(
            "{:<44} {:<12} {:<20} {:>9.3} {:>9.3} {:>5}",
            o.case,
            o.expected,
            o.top,
            o.excess_before,
            o.after_ratio,
            if o.correct && o.halves_excess && o.within_1_5 {
                "yes"
            } else {
                "NO"
            }
        );
    }
    let hidden: Vec<&Outcome> = outcomes.iter().filter(|o| o.expected != "none").collect();
    let clean: Vec<&Outcome> = outcomes.iter().filter(|o| o.expected == "none").collect();
    let named = hidden.iter().filter(|o| o.correct).count();
    let false_alarms = clean.iter().filter(|o| !o.correct).count();
    let fixed: Vec<&&Outcome> = hidden.iter().filter(|o| o.correct).collect();
    let within = fixed.iter().filter(|o| o.within_1_5).count();
    let halves = fixed.iter().filter(|o| o.halves_excess).count();
    println!(
        "\nnamed the hidden effect: {named}/{} ({:.0} %); false alarms: {false_alarms}/{}; \
         after the named effect: within 1.5σ² {within}/{}, half the excess removed {halves}/{}",
        hidden.len(),
        100.0 * named as f64 / hidden.len() as f64,
        clean.len(),
        fixed.len(),
        fixed.len()
    );
    // a Hammerstein record never has the feedback nonlinearity named first
    let feedback = outcomes
        .iter()
        .filter(|o| o.top == "feedback-nonlinearity")
        .count();
    println!(
        "feedback-nonlinearity named first: {feedback}/{}",
        outcomes.len()
    );
    assert_eq!(
        feedback, 0,
        "a feedback nonlinearity named on Hammerstein records"
    );
    assert!(
        named as f64 >= 0.9 * hidden.len() as f64,
        "top suggestion right in only {named}/{}",
        hidden.len()
    );
    assert_eq!(
        false_alarms, 0,
        "effects suggested where nothing is missing"
    );
    assert_eq!(
        within,
        fixed.len(),
        "validation MSE not within 1.5σ² after the fix"
    );
    assert_eq!(halves, fixed.len(), "less than half of the excess removed");
}

#[test]
fn battery_of_hidden_effects() {
    run_battery(&[1]);
}

#[test]
#[ignore = "bigger battery (3 seeds); run with --ignored in release"]
fn battery_of_hidden_effects_three_seeds() {
    run_battery(&[11, 12, 13]);
}
