//! A one-sided saturation (v = min(u, z1): the diode of the Wiener–Hammerstein 2009 benchmark)
//! fitted with the UDN's saturation, which has two finite limits: the upper limit is found, the
//! lower one ends where no training sample reaches it (at or below the input's minimum), so it
//! changes nothing on the training record — the behaviour docs/case-studies.md describes for
//! that benchmark. Random held levels, a random stable second-order block, SNR 30 dB, a few
//! seeds. The guided loop's final check says that limit (`final_check::unmeasured_limits`).

mod common;

use hammerstein::regressors::{Effect, EffectSet};
use hammerstein::subspace::Order;
use hammerstein::{Hammerstein, IoData, StateSpace};
use rand::{RngExt, SeedableRng, rngs::StdRng};

/// Upper limit of the truth.
const Z1: f64 = 0.8;

fn record(seed: u64) -> (Vec<f64>, Vec<f64>) {
    let mut rng = StdRng::seed_from_u64(seed);
    let n = 2000;
    let mut u: Vec<f64> = Vec::with_capacity(n);
    while u.len() < n {
        let level: f64 = rng.random_range(-2.0..2.0);
        let hold = rng.random_range(5..30usize);
        u.extend(std::iter::repeat_n(level, hold));
    }
    u.truncate(n);
    let (r, th) = (rng.random_range(0.5..0.9), rng.random_range(0.1..0.8));
    let g = StateSpace::from_rows(
        &[&[2.0 * r * f64::cos(th), 1.0], &[-r * r, 0.0]],
        &[&[1.0], &[0.3]],
        &[&[1.0, 0.0]],
        &[&[0.0]],
    )
    .unwrap();
    let v: Vec<f64> = u.iter().map(|&x| x.min(Z1)).collect();
    let (y, _) = common::output(&g, &v, 30.0, seed);
    (u, y)
}

#[test]
fn a_one_sided_saturation_keeps_its_lower_limit_out_of_the_training_input() {
    for seed in 1..=4u64 {
        let (u, y) = record(seed);
        let data = IoData::siso(&u, &y).unwrap();
        let model = Hammerstein::<f64>::udn(EffectSet::of(&[Effect::Saturation]))
            .order(Order::Fixed(2))
            .seed(seed)
            .fit(&data)
            .unwrap();
        let p: std::collections::HashMap<String, f64> = model.parameters().into_iter().collect();
        let (z1, z2) = (p["z1"], p["z2"]);
        let below = u.iter().filter(|&&x| x < z2).count();
        let min = u.iter().copied().fold(f64::INFINITY, f64::min);
        println!("seed {seed}: z1 {z1:.4}, z2 {z2:.4} (min u {min:.4}), {below} samples below z2");
        assert!(
            (z1 - Z1).abs() < 0.05,
            "seed {seed}: upper limit {z1} (truth {Z1})"
        );
        // the lower limit acts on no more than 1 % of the training samples
        assert!(
            below * 100 <= u.len(),
            "seed {seed}: the lower limit {z2} clips {below} training samples (min u {min})"
        );
    }
}

#[test]
fn the_final_check_says_the_limit_the_record_does_not_measure() {
    let (u, y) = record(2);
    let data = IoData::siso(&u, &y).unwrap();
    let (train, val) = data.split_validation(0.3).unwrap();
    let start = Hammerstein::<f64>::udn(EffectSet::of(&[Effect::Saturation])).seed(2);
    let followed = hammerstein::diagnosis::Diagnoser::new()
        .follow(&start, &train, &val, 3)
        .unwrap();
    println!("final check: {:?}", followed.final_check);
    let said: Vec<&String> = followed
        .final_check
        .iter()
        .filter(|n| n.contains("does not measure it"))
        .collect();
    assert_eq!(said.len(), 1, "{:?}", followed.final_check);
    assert!(
        said[0].contains("lower limit z2") && said[0].contains("minimum"),
        "{}",
        said[0]
    );
}

#[test]
fn a_two_sided_saturation_is_not_said_unmeasured() {
    // the truth clipped on both sides (at 0.8 and −0.8): both limits measured
    let (u, _) = record(3);
    let g = StateSpace::from_rows(
        &[&[1.2, 1.0], &[-0.5, 0.0]],
        &[&[0.3], &[0.12]],
        &[&[1.0, 0.0]],
        &[&[0.0]],
    )
    .unwrap();
    let v: Vec<f64> = u.iter().map(|&x| x.clamp(-Z1, Z1)).collect();
    let (y, _) = common::output(&g, &v, 30.0, 3);
    let data = IoData::siso(&u, &y).unwrap();
    let (train, val) = data.split_validation(0.3).unwrap();
    let start = Hammerstein::<f64>::udn(EffectSet::of(&[Effect::Saturation])).seed(3);
    let followed = hammerstein::diagnosis::Diagnoser::new()
        .follow(&start, &train, &val, 3)
        .unwrap();
    assert!(
        !followed
            .final_check
            .iter()
            .any(|n| n.contains("does not measure it")),
        "{:?}",
        followed.final_check
    );
}
