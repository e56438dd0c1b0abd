//! A model that extends another fits the training record at least as well: an effect added at
//! its null value, an output map added (at the identity), the order raised (states with zero
//! input weight) — each nested fit starts from the simpler model's optimum, and the refinement
//! only takes steps that lower the training MSE. A randomised property over blocks, effect
//! subsets, inputs, SNRs and seeds (`NESTED_SEEDS`, default 20; `NESTED_FIRST` the first seed;
//! `NESTED_DEBUG` prints each comparison).

mod common;

use common::random_system::{Ranges, random_record};
use hammerstein::diagnosis::compare;
use hammerstein::diagnosis::final_check::TRAINING_SLACK;
use hammerstein::fit::order_selection::training_mse;
use hammerstein::regressors::{Effect, EffectSet, OutputMap, PolynomialMap, SaturationMap};
use hammerstein::subspace::Order;
use hammerstein::{Hammerstein, HammersteinModel, IoData};

/// θ of `settings`' nonlinearity: `base`'s parameters by name, the others at their null value
/// (half-widths and steps 0, saturation limits beyond every input value).
fn null_theta(settings: &Hammerstein<f64>, base: &HammersteinModel<f64>, u: &[f64]) -> Vec<f64> {
    let far = 2.0 * u.iter().fold(0.0f64, |m, x| m.max(x.abs())) + 1.0;
    let have = base.parameters();
    settings
        .build_nonlinearity()
        .unwrap()
        .param_names()
        .iter()
        .map(|n| match have.iter().find(|(k, _)| k == n) {
            Some((_, v)) => *v,
            None if n == "z1" => far,
            None if n == "z2" => -far,
            None => 0.0,
        })
        .collect()
}

fn no_worse(
    what: &str,
    seed: u64,
    ext: &HammersteinModel<f64>,
    base: &HammersteinModel<f64>,
    data: &IoData<f64>,
) {
    let (after, before) = (training_mse(ext, data), training_mse(base, data));
    if std::env::var("NESTED_DEBUG").is_ok() {
        eprintln!(
            "seed {seed} {what}: ext own {:e} compare {:e}; base own {:e} compare {:e}; refinement {:?}",
            ext.report().train_mse,
            compare(ext, data).unwrap().metrics.mse,
            base.report().train_mse,
            compare(base, data).unwrap().metrics.mse,
            ext.report().refinement
        );
    }
    assert!(
        after <= before * (1.0 + TRAINING_SLACK),
        "seed {seed}, {what}: training MSE {after:e} above the simpler model's {before:e}"
    );
}

#[test]
fn extensions_never_fit_the_training_record_worse() {
    let seeds = common::env_count("NESTED_SEEDS", 20);
    let ranges = Ranges {
        orders: (1, 3),
        snr_db: (10.0, 40.0),
        n: (300, 600),
        effect_prob: 0.4,
    };
    let mut checked = 0;
    let first = common::env_count("NESTED_FIRST", 0);
    for seed in first..first + seeds {
        let rec = random_record(1000 + seed, &ranges);
        let data = IoData::siso(&rec.u, &rec.y).unwrap();
        // the simpler model: a random effect subset (of the truth's or not) at a random order
        let pick = |k: u64| Effect::ALL[((seed.wrapping_mul(7) + k) % 4) as usize];
        let mut effects = EffectSet::empty();
        if seed % 3 != 0 {
            effects = effects.with(pick(1));
        }
        let n = 1 + (seed as usize % 3);
        let settings = Hammerstein::<f64>::udn(effects)
            .order(Order::Fixed(n))
            .with_d(false);
        let Ok(base) = settings.fit(&data) else {
            continue;
        };
        checked += 1;
        // an effect added at its null value
        let added = pick(2 + seed % 2);
        if !effects.contains(added) {
            let ext = settings.with_effect(added).unwrap().at_structure_of(&base);
            let theta = null_theta(&ext, &base, &rec.u);
            let m = ext.fit_from(&data, &base, &theta).unwrap();
            no_worse(&format!("+ {added}"), seed, &m, &base, &data);
        }
        // the order raised by one
        let up = settings.clone().order(Order::Fixed(n + 1));
        let theta = null_theta(&up, &base, &rec.u);
        let m = up.fit_from(&data, &base, &theta).unwrap();
        no_worse("order + 1", seed, &m, &base, &data);
        // an output map added (the whole fit: its Hammerstein stage is the simpler model's)
        let map: Box<dyn OutputMap<f64>> = if seed % 2 == 0 {
            Box::new(PolynomialMap::new(3).unwrap())
        } else {
            Box::new(SaturationMap::unbounded())
        };
        let with_map = settings
            .clone()
            .output_nonlinearity(Some(map))
            .fit(&data)
            .unwrap();
        no_worse("output map", seed, &with_map, &base, &data);
        // and what `compare` reports on the training record is the fit's own criterion or lower
        let shown = compare(&with_map, &data).unwrap().metrics.mse;
        let own = with_map.report().train_mse;
        assert!(
            shown <= own * (1.0 + TRAINING_SLACK),
            "seed {seed}: compare's training MSE {shown:e} above the fit's {own:e}"
        );
    }
    // the property was checked on most records (a fit may fail on a record too short for it)
    assert!(
        checked * 10 >= seeds * 8,
        "{checked} of {seeds} records fitted"
    );
}
