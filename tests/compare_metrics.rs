//! The metrics-only simulation (`compare_metrics`, `order_selection::training_mse`), which never
//! holds both starts of the hysteresis, gives the numbers of the full simulation (`compare`,
//! `simulate_on`) bit for bit, whichever start wins.

#[path = "common/paper.rs"]
mod paper;

use hammerstein::diagnosis::{compare, compare_metrics};
use hammerstein::fit::order_selection::training_mse;
use hammerstein::regressors::{Effect, EffectSet, StaticNonlinearity, Udn};
use hammerstein::subspace::Order;
use hammerstein::{Hammerstein, IoData};
use rand::{RngExt, SeedableRng, rngs::StdRng};
use rand_distr::{Distribution, Normal};

fn record(seed: u64, n: usize) -> IoData<f64> {
    let set = EffectSet::of(&[Effect::Hysteresis, Effect::Saturation]);
    let truth = Udn::<f64>::with_params(set, &[2.0, 0.5, 1.5, -1.0]).unwrap();
    let mut rng = StdRng::seed_from_u64(seed);
    let u: Vec<f64> = (0..n).map(|_| rng.random_range(-3.0..3.0)).collect();
    let g = paper::paper_block();
    let noise = Normal::new(0.0, 0.2).unwrap();
    let y: Vec<f64> = g
        .simulate_siso(&truth.eval(&u), None)
        .unwrap()
        .into_iter()
        .map(|y| y + noise.sample(&mut rng))
        .collect();
    IoData::siso(&u, &y).unwrap()
}

#[test]
fn metrics_alone_match_the_full_simulation_bit_for_bit() {
    let set = EffectSet::of(&[Effect::Hysteresis, Effect::Saturation]);
    let settings = Hammerstein::<f64>::udn(set)
        .order(Order::Fixed(2))
        .with_d(false);
    let model = settings.fit(&record(1, 800)).unwrap();
    let mut starts_differ = 0;
    for seed in 2..8 {
        let data = record(seed, 500);
        assert_matches_full(&model, &data, &format!("seed {seed}"));
        // the two starts of the hysteresis give different simulations on these records (else
        // the test would not reach the comparison of the two starts)
        let falling_first = {
            let mut u = data.input(0);
            u.insert(0, u[0] + u[0].abs().max(1.0));
            let mut v = model.nonlinearity().eval(&u);
            v.remove(0);
            v
        };
        if falling_first != model.nonlinearity().eval(&data.input(0)) {
            starts_differ += 1;
        }
    }
    assert!(starts_differ > 0);
}

/// The metrics of `compare_metrics` and the training MSE equal those of the full simulation
/// (`compare`, `simulate_on`) bit for bit on `data`.
fn assert_matches_full(model: &hammerstein::HammersteinModel<f64>, data: &IoData<f64>, what: &str) {
    let full = compare(model, data).unwrap();
    let alone = compare_metrics(model, data).unwrap();
    assert_eq!(full.metrics, alone, "{what}");
    let sim = model.simulate_on(data).unwrap();
    assert_eq!(sim.y_hat, full.y_hat, "{what}");
    let y = data.output(0);
    let mse = y
        .iter()
        .zip(&sim.y_hat)
        .map(|(a, b)| (a - b) * (a - b))
        .sum::<f64>()
        / y.len() as f64;
    assert_eq!(
        training_mse(model, data).to_bits(),
        mse.min(model.report().train_mse).to_bits(),
        "{what}"
    );
}

/// The same for the other memories: a memoryless saturation (one start simulated), the
/// Prandtl–Ishlinskii operator (its memory histories simulated one after the other) and a
/// model with an output map (its initial state through the map).
#[test]
fn metrics_alone_match_the_full_simulation_for_every_memory() {
    use hammerstein::regressors::output_map_from_name;
    let train = record(1, 800);
    let fits = [
        (
            "saturation",
            Hammerstein::<f64>::udn(EffectSet::of(&[Effect::Saturation])),
        ),
        (
            "prandtl-ishlinskii",
            Hammerstein::<f64>::udn(EffectSet::of(&[Effect::PrandtlIshlinskii])),
        ),
        (
            "saturation + poly3 output map",
            Hammerstein::<f64>::udn(EffectSet::of(&[Effect::Saturation]))
                .output_nonlinearity(Some(output_map_from_name("poly3").unwrap())),
        ),
    ];
    for (what, settings) in fits {
        let model = settings
            .order(Order::Fixed(2))
            .with_d(false)
            .fit(&train)
            .unwrap();
        for seed in 2..5 {
            assert_matches_full(&model, &record(seed, 500), what);
        }
    }
}
