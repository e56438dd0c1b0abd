//! Several inputs (issue 12, item 2): one Hammerstein branch per input fitted by backfitting.

mod common;

use common::random_miso::{io_data, random_miso};
use hammerstein::diagnosis::compare_miso;
use hammerstein::fit::Hammerstein;
use hammerstein::miso::{MisoHammerstein, MisoModel};
use hammerstein::regressors::EffectSet;
use hammerstein::{Error, IoData};

/// The record of inputs `u1`, `u2` (named so) and output `y`.
fn two_inputs(u1: &[f64], u2: &[f64], y: &[f64]) -> IoData<f64> {
    IoData::with_names(
        hammerstein::faer::Mat::from_fn(y.len(), 2, |k, j| if j == 0 { u1[k] } else { u2[k] }),
        hammerstein::faer::Mat::from_fn(y.len(), 1, |k, _| y[k]),
        vec!["u1".into(), "u2".into()],
        vec!["y".into()],
    )
    .unwrap()
}

/// The settings with each branch's true effects.
fn true_settings(r: &common::random_miso::RandomMiso, seed: u64) -> MisoHammerstein<f64> {
    MisoHammerstein::new(
        r.branches
            .iter()
            .map(|b| Hammerstein::udn(b.effects).seed(seed))
            .collect(),
    )
}

/// With every branch's true effects the fit reaches the noise floor on held-out data.
#[test]
fn true_effects_reach_the_floor() {
    let mut at_floor = 0;
    let seeds = 1..=4u64;
    for seed in seeds.clone() {
        let r = random_miso(seed, (20.0, 35.0));
        let data = io_data(&r);
        let (train, valid) = data.split_validation(0.3).unwrap();
        let model = true_settings(&r, seed).fit(&train).unwrap();
        let ratio = compare_miso(&model, &valid).unwrap().metrics.mse / r.noise_var;
        println!(
            "seed {seed}: orders {:?}, effects {:?}, sweeps {}, val MSE/noise {ratio:.3}",
            model
                .branches()
                .iter()
                .map(|b| b.linear().order())
                .collect::<Vec<_>>(),
            r.branches
                .iter()
                .map(|b| b.effects.label())
                .collect::<Vec<_>>(),
            model.report().sweeps.len()
        );

        if ratio <= 1.5 {
            at_floor += 1;
        }
    }
    // seed 3 (a slow block behind a narrow saturation band with dead-zone and preload) stays at
    // 13× noise: the single-input fit of that branch stalls as in docs/battery.md; the rates
    // over many records are `tests/miso_battery.rs`
    assert!(at_floor >= 3, "{at_floor}/4 at the floor");
}

/// A branch's parameters are recovered: the second input's saturation limits.
#[test]
fn second_input_parameters_recovered() {
    use common::{InputKind, Udn, input};
    let n = 3000;
    let u1 = input(InputKind::Uniform, n, 2.0, 3);
    let u2 = input(InputKind::Multisine, n, 1.5, 4);
    let g1 =
        hammerstein::StateSpace::from_rows(&[&[0.7]], &[&[1.0]], &[&[0.5]], &[&[0.0]]).unwrap();
    let g2 = common::slow_block();
    let t2 = Udn {
        z1: 0.8,
        z2: -1.0,
        ..Udn::linear(1.0)
    };
    let y1 = g1.simulate_siso(&Udn::linear(1.0).eval(&u1), None).unwrap();
    let y2 = g2.simulate_siso(&t2.eval(&u2), None).unwrap();
    let y: Vec<f64> = y1.iter().zip(&y2).map(|(a, b)| a + b + 0.3).collect();
    let data = two_inputs(&u1, &u2, &y);
    let settings = MisoHammerstein::new(vec![
        Hammerstein::linear(),
        Hammerstein::udn(EffectSet::parse("saturation").unwrap()),
    ]);
    let model = settings.fit(&data).unwrap();
    let m = y.iter().sum::<f64>() / n as f64;
    let var = y.iter().map(|v| (v - m).powi(2)).sum::<f64>() / n as f64;
    let rel = model.report().train_mse / var;
    assert!(rel < 1e-8, "noise-free record: relative MSE {rel:e}");
    // the saturation's limits, in input units (the gain's scale does not enter them)
    let p = model.branch("u2").unwrap().parameters();
    let get = |name: &str| p.iter().find(|(n, _)| n == name).unwrap().1;
    assert!(
        (get("z1") - 0.8).abs() < 1e-3 && (get("z2") + 1.0).abs() < 1e-3,
        "{p:?}"
    );
    // the parallel block: order 1 + 2, two inputs
    let lin = model.linear().unwrap();
    assert_eq!((lin.order(), lin.n_inputs()), (model.order(), 2));
}

#[test]
fn wrong_shapes_are_typed_errors() {
    let r = random_miso(7, (30.0, 31.0));
    let data = io_data(&r);
    let one = MisoHammerstein::new(vec![Hammerstein::<f64>::linear()]);
    assert!(matches!(one.fit(&data), Err(Error::Dimension(_))));
    let none = MisoHammerstein::<f64>::new(vec![]);
    assert!(matches!(none.fit(&data), Err(Error::InvalidParameter(_))));
    let map = hammerstein::regressors::output_map_from_name::<f64>("poly3").unwrap();
    let with_map = MisoHammerstein::new(vec![
        Hammerstein::linear().output_nonlinearity(Some(map)),
        Hammerstein::linear(),
    ]);
    assert!(matches!(
        with_map.fit(&data),
        Err(Error::InvalidParameter(_))
    ));
}

#[test]
fn model_file_round_trip() {
    let r = random_miso(5, (25.0, 30.0));
    let data = io_data(&r);
    let model = true_settings(&r, 5).max_sweeps(2).fit(&data).unwrap();
    let dir = common::temp_dir("miso-file");
    let path = dir.join("m.json");
    model.save(&path).unwrap();
    let back = MisoModel::load(&path).unwrap();
    assert_eq!(back.input_names(), model.input_names());
    let a = model.simulate(data.u()).unwrap();
    let b = back.simulate(data.u()).unwrap();
    let d = a
        .iter()
        .zip(&b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max);
    assert!(d < 1e-9, "simulation differs after a round trip by {d:e}");
}

/// An input the output does not depend on: the fit succeeds (no "constant output" from an
/// exactly explained partial residual) and that input's contribution is negligible.
#[test]
fn an_input_without_effect_gets_a_negligible_branch() {
    use common::{InputKind, input};
    let n = 1500;
    let u1 = input(InputKind::Uniform, n, 1.0, 21);
    let u2 = input(InputKind::Uniform, n, 1.0, 22);
    let g = hammerstein::StateSpace::from_rows(&[&[0.6]], &[&[1.0]], &[&[1.0]], &[&[0.0]]).unwrap();
    let y = g.simulate_siso(&u1, None).unwrap();
    let data = two_inputs(&u1, &u2, &y);
    let model = MisoHammerstein::new(vec![Hammerstein::linear(), Hammerstein::linear()])
        .fit(&data)
        .unwrap();
    let sim = model.simulate_on(&data).unwrap();
    let c2 = &sim.contributions[1];
    let rms2 = (c2.iter().map(|v| v * v).sum::<f64>() / n as f64).sqrt();
    assert!(rms2 < 1e-6, "u2's branch contributes {rms2:e} RMS");
}

/// Coupled branches (the second input mostly the first, the two blocks' outputs largely
/// cancelling): backfitting crawls — with two sweeps it stops well above the noise — while the
/// joint refinement of both branches after the sweeps reaches the noise floor on the training
/// record (the several-input fit's step 5, docs/algorithm.md).
#[test]
fn joint_refinement_reaches_the_floor_where_backfitting_crawls() {
    use common::{InputKind, add_noise, input};
    use hammerstein::subspace::Order;
    let n = 2000;
    let u1 = input(InputKind::Uniform, n, 1.0, 31);
    let w = input(InputKind::Uniform, n, 1.0, 32);
    let u2: Vec<f64> = u1.iter().zip(&w).map(|(a, b)| 0.9 * a + 0.2 * b).collect();
    let g1 =
        hammerstein::StateSpace::from_rows(&[&[0.9]], &[&[1.0]], &[&[0.3]], &[&[0.0]]).unwrap();
    let g2 =
        hammerstein::StateSpace::from_rows(&[&[0.6]], &[&[1.0]], &[&[-0.6]], &[&[0.0]]).unwrap();
    let sat = common::Udn {
        z1: 0.6,
        z2: -0.6,
        ..common::Udn::linear(1.0)
    };
    let y1 = g1.simulate_siso(&u1, None).unwrap();
    let y2 = g2.simulate_siso(&sat.eval(&u2), None).unwrap();
    let y0: Vec<f64> = y1.iter().zip(&y2).map(|(a, b)| a + b).collect();
    let nv = 1e-4;
    let y = add_noise(&y0, nv, 33);
    let data = two_inputs(&u1, &u2, &y);
    let settings = MisoHammerstein::new(vec![
        Hammerstein::linear().order(Order::Fixed(1)),
        Hammerstein::udn(EffectSet::parse("saturation").unwrap()).order(Order::Fixed(1)),
    ])
    .max_sweeps(2);
    let sweeps_only = settings.clone().joint_refinement(false).fit(&data).unwrap();
    let joint = settings.fit(&data).unwrap();
    let (before, after) = (
        sweeps_only.report().train_mse / nv,
        joint.report().train_mse / nv,
    );
    println!("train MSE/noise: sweeps only {before:.3}, with the joint refinement {after:.3}");
    assert!(sweeps_only.report().joint_refinement.is_none());
    let rep = joint.report().joint_refinement.as_ref().unwrap();
    assert!(rep.accepted && rep.mse_after < rep.mse_before, "{rep:?}");
    assert!(
        before > 1.5,
        "the sweeps alone already at {before:.3}× noise"
    );
    assert!(
        after < 1.05,
        "the joint refinement ends at {after:.3}× noise"
    );
    // the reported MSE is the model's: simulated on the record (its initial states re-estimated
    // by `simulate_on`'s passes, which stop within a small fraction of the joint optimum)
    let sim = joint.simulate_on(&data).unwrap();
    let e = y
        .iter()
        .zip(&sim.y_hat)
        .map(|(a, b)| (a - b).powi(2))
        .sum::<f64>()
        / n as f64;
    assert!(e <= joint.report().train_mse * 1.01, "{e:e}");
}

/// An input on a large offset (u1 = 10⁶ + a signal): its branch is fitted with the offset taken
/// out and given back (`fit/scaling.rs`), and the joint refinement of the two branches, which
/// runs on the record as it is, leaves the fit where the centred record's is: the same training
/// MSE to 1e-4 relative, the saturation limits moved by the offset.
#[test]
fn an_input_on_a_large_offset_fits_as_the_centred_record() {
    let n = 2000;
    let mut s = 5u64;
    let mut next = || {
        s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((s >> 11) as f64 / (1u64 << 53) as f64) - 0.5
    };
    let u1: Vec<f64> = (0..n).map(|_| 4.0 * next()).collect();
    let u2: Vec<f64> = (0..n).map(|_| 2.0 * next()).collect();
    let (mut x1, mut x2) = (0.0, 0.0);
    let y: Vec<f64> = (0..n)
        .map(|k| {
            let y = x1 + x2 + 0.04 * next();
            x1 = 0.7 * x1 + u1[k].clamp(-1.2, 1.5);
            x2 = 0.5 * x2 + 0.8 * u2[k];
            y
        })
        .collect();
    let settings = MisoHammerstein::new(vec![
        Hammerstein::udn(EffectSet::of(&[
            hammerstein::regressors::Effect::Saturation,
        ]))
        .order(hammerstein::subspace::Order::Fixed(1)),
        Hammerstein::linear().order(hammerstein::subspace::Order::Fixed(1)),
    ]);
    let centred = settings.fit(&two_inputs(&u1, &u2, &y)).unwrap();
    let m = 1e6;
    let far: Vec<f64> = u1.iter().map(|&u| u + m).collect();
    let offset = settings.fit(&two_inputs(&far, &u2, &y)).unwrap();
    let (a, b) = (centred.report().train_mse, offset.report().train_mse);
    assert!(
        (b / a - 1.0).abs() < 1e-4,
        "training MSE {a} centred, {b} at 1e6"
    );
    let limits = |model: &MisoModel<f64>| {
        let p = model.branches()[0].nonlinearity().params();
        (p[1], p[2])
    };
    let ((z1c, z2c), (z1o, z2o)) = (limits(&centred), limits(&offset));
    assert!((z1o - m - z1c).abs() < 1e-3 && (z2o - m - z2c).abs() < 1e-3);
    assert!(
        (z1c - 1.5).abs() < 0.05 && (z2c + 1.2).abs() < 0.05,
        "{z1c} {z2c}"
    );
}
