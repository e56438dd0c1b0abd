//! The joint refinement of a two-input record longer than the refinement's `DIRECT_ROWS`
//! (65 536 samples): its Jacobian's rows stream in blocks (`STREAM_ROWS`) through a TSQR, the
//! branches' blocks side by side. Checked against the same refinement with all rows in one
//! QR (`fit::refine_jointly_whole`, test builds only): the two must end at the same total
//! training MSE after the same iterations.

use super::model::mse_of_sum;
use super::partial::partial_record;
use super::settings::MisoHammerstein;
use crate::data::IoData;
use crate::fit::{Hammerstein, refine_jointly, refine_jointly_whole};
use crate::regressors::{Effect, EffectSet};
use crate::subspace::Order;
use rand::{RngExt, SeedableRng, rngs::StdRng};

/// Samples of the record: above `DIRECT_ROWS` = 65 536, five row blocks of 16 384.
const N: usize = 70_000;

/// u1 through a saturation at ±0.8 into a second-order block, u2 through a gain into a
/// first-order one, summed, offset 0.3, uniform noise of variance 1e-4 (`N` samples).
fn record() -> IoData<f64> {
    let mut rng = StdRng::seed_from_u64(7);
    let mut uni = |a: f64| a * (2.0 * rng.random::<f64>() - 1.0);
    let u1: Vec<f64> = (0..N).map(|_| uni(1.5)).collect();
    let u2: Vec<f64> = (0..N).map(|_| uni(1.0)).collect();
    let noise: Vec<f64> = (0..N).map(|_| uni(1e-2 * 3f64.sqrt())).collect();
    let (mut y1, mut y2) = (vec![0.0; N], vec![0.0; N]);
    for k in 1..N {
        let prev2 = if k >= 2 { y1[k - 2] } else { 0.0 };
        y1[k] = 1.2 * y1[k - 1] - 0.5 * prev2 + 0.3 * u1[k - 1].clamp(-0.8, 0.8);
        y2[k] = 0.7 * y2[k - 1] + 0.6 * u2[k - 1];
    }
    let y: Vec<f64> = (0..N).map(|k| y1[k] + y2[k] + 0.3 + noise[k]).collect();
    IoData::with_names(
        faer::Mat::from_fn(N, 2, |k, j| if j == 0 { u1[k] } else { u2[k] }),
        faer::Mat::from_fn(N, 1, |k, _| y[k]),
        vec!["u1".into(), "u2".into()],
        vec!["y".into()],
    )
    .unwrap()
}

#[test]
fn the_streamed_joint_refinement_ends_where_the_whole_one_does() {
    let data = record();
    // the start: the branches fitted on the first 1000 samples, so that the whole record
    // leaves the joint refinement something to do
    let settings = MisoHammerstein::new(vec![
        Hammerstein::udn(EffectSet::empty().with(Effect::Saturation)).order(Order::Fixed(2)),
        Hammerstein::linear().order(Order::Fixed(1)),
    ])
    .joint_refinement(false);
    let start = settings.fit(&data.slice(0, 1000).unwrap()).unwrap();
    let sim = start.simulate_on(&data).unwrap();
    let recs: Vec<IoData<f64>> = (0..2)
        .map(|i| partial_record(&data, i, &sim.contributions).unwrap())
        .collect();
    let y = data.output_slice(0);
    let before = mse_of_sum(y, &sim.contributions);
    let branches = start.branches();
    let (streamed, it_streamed) = refine_jointly(branches, &recs, y, before, 0.0).unwrap();
    let (whole, it_whole) = refine_jointly_whole(branches, &recs, y, before, 0.0).unwrap();
    let (streamed, whole) = (streamed.unwrap(), whole.unwrap());
    assert!(
        streamed.mse < before,
        "the streamed refinement did not lower the MSE: {before:e} -> {:e}",
        streamed.mse
    );
    assert_eq!(it_streamed, it_whole, "iterations streamed vs whole");
    let rel = (streamed.mse - whole.mse).abs() / whole.mse;
    assert!(
        rel <= 1e-9,
        "training MSE streamed {:e}, whole {:e} (relative difference {rel:e})",
        streamed.mse,
        whole.mse
    );
    // and the refinement reaches the record's noise floor (variance 1e-4)
    assert!(
        streamed.mse < 1.02e-4,
        "training MSE {:e} after the joint refinement, noise 1e-4 (start {before:e})",
        streamed.mse
    );
}
