//! Direct feed-through (issue "Right by default", item 3): a block with D ≠ 0 (force →
//! acceleration) is found by the automatic decision, a strictly proper one keeps D = 0, and the
//! order selection's table records both candidates.

mod common;

use common::{InputKind, Udn, add_noise, input};
use hammerstein::diagnosis::compare;
use hammerstein::fit::{Feedthrough, Hammerstein};
use hammerstein::regressors::{Effect, EffectSet};
use hammerstein::{IoData, StateSpace};

fn block(d: f64) -> StateSpace<f64> {
    StateSpace::from_rows(
        &[&[1.1, 1.0], &[-0.4, 0.0]],
        &[&[0.6], &[-0.2]],
        &[&[1.0, 0.0]],
        &[&[d]],
    )
    .unwrap()
}

fn record(d: f64, seed: u64) -> (IoData<f64>, IoData<f64>, f64) {
    let mut t = Udn::linear(1.5);
    t.z1 = 1.0;
    t.z2 = -0.8;
    let u = input(InputKind::Uniform, 2500, 2.0, seed);
    let y0 = block(d).simulate_siso(&t.eval(&u), None).unwrap();
    let nv = 1e-3;
    let y = add_noise(&y0, nv, seed);
    let data = IoData::siso(&u, &y).unwrap();
    let (a, b) = data.split_validation(0.3).unwrap();
    (a, b, nv)
}

fn sat() -> Hammerstein<f64> {
    Hammerstein::udn(EffectSet::of(&[Effect::Saturation]))
}

#[test]
fn feedthrough_is_decided_by_the_criterion() {
    for seed in [1u64, 2, 3] {
        let (train, valid, nv) = record(0.8, seed);
        let m = sat().fit(&train).unwrap();
        let d = m.linear().d[(0, 0)];
        assert!(d.abs() > 0.1, "seed {seed}: D = {d} not found");
        let rows = &m.report().order_selection;
        assert!(rows.iter().any(|r| r.feedthrough) && rows.iter().any(|r| !r.feedthrough));
        let ratio = compare(&m, &valid).unwrap().metrics.mse / nv;
        assert!(ratio < 1.2, "seed {seed}: validation MSE {ratio}× noise");
        // the decision survives saving and loading, and refits built from the model keep it
        let path = std::env::temp_dir().join(format!(
            "hammerstein-feedthrough-{}-{seed}.json",
            std::process::id()
        ));
        m.save(&path).unwrap();
        let loaded = hammerstein::HammersteinModel::<f64>::load(&path).unwrap();
        std::fs::remove_file(&path).ok();
        assert_eq!(loaded.linear().d[(0, 0)], d);
        assert!(loaded.settings().options().with_d);
        assert!(m.has_feedthrough());
        // forcing D = 0 on the same record misses the floor
        let off = sat().feedthrough(Feedthrough::Absent).fit(&train).unwrap();
        assert_eq!(off.linear().d[(0, 0)], 0.0);
        let off_ratio = compare(&off, &valid).unwrap().metrics.mse / nv;
        assert!(
            off_ratio > ratio,
            "seed {seed}: D = 0 {off_ratio} vs auto {ratio}"
        );

        let (train, valid, nv) = record(0.0, seed);
        let m = sat().fit(&train).unwrap();
        assert_eq!(m.linear().d[(0, 0)], 0.0, "seed {seed}: spurious D");
        let ratio = compare(&m, &valid).unwrap().metrics.mse / nv;
        assert!(ratio < 1.2, "seed {seed}: strictly proper, {ratio}× noise");
    }
}
