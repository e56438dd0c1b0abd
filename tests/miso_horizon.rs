//! Several inputs: each branch's report states the horizon it finished with, and that the
//! default was raised (`horizon_raised_from`) exactly when it stands raised for the branch's
//! order — also after a refit from a fitted model (what `diagnose --follow` does after each
//! step), whose branch settings carry the raised horizon as a chosen one.

mod common;

use common::{InputKind, Udn, add_noise, input, paper_block};
use hammerstein::IoData;
use hammerstein::fit::{DEFAULT_HORIZON, Hammerstein};
use hammerstein::miso::{MisoHammerstein, MisoModel};
use hammerstein::subspace::{Order, max_order};

/// u1 through the paper's block, plus half of u2, with white noise (600 samples).
fn record() -> IoData<f64> {
    let n = 600;
    let u1 = input(InputKind::Uniform, n, 3.0, 1);
    let u2 = input(InputKind::Uniform, n, 1.0, 7);
    let y1 = paper_block()
        .simulate_siso(&Udn::linear(2.0).eval(&u1), None)
        .unwrap();
    let y: Vec<f64> = add_noise(&y1, 0.01, 1)
        .iter()
        .zip(&u2)
        .map(|(a, b)| a + 0.5 * b)
        .collect();
    IoData::with_names(
        hammerstein::faer::Mat::from_fn(n, 2, |k, j| if j == 0 { u1[k] } else { u2[k] }),
        hammerstein::faer::Mat::from_fn(n, 1, |k, _| y[k]),
        vec!["u1".into(), "u2".into()],
        vec!["y".into()],
    )
    .unwrap()
}

/// Every branch of `m`: the horizon its settings hold is above the default and the default
/// cannot hold its order, and its report says the default was raised.
fn says_raised(m: &MisoModel<f64>, what: &str) {
    for (i, b) in m.branches().iter().enumerate() {
        let h = b.settings().options().horizon;
        let n = b.linear().order();
        assert!(
            h > DEFAULT_HORIZON && max_order(DEFAULT_HORIZON, 1) < n && max_order(h, 1) >= n,
            "{what}, branch {i}: horizon {h} for order {n}"
        );
        assert_eq!(
            b.report().horizon_raised_from,
            Some(DEFAULT_HORIZON),
            "{what}, branch {i}: finished at horizon {h} (order {n})"
        );
    }
}

#[test]
fn a_raised_horizon_is_stated_after_fit_and_refit() {
    let data = record();
    let settings = MisoHammerstein::new(vec![
        Hammerstein::linear().order(Order::Fixed(9)),
        Hammerstein::linear().order(Order::Fixed(9)),
    ]);
    let model = settings.fit(&data).unwrap();
    says_raised(&model, "fit");
    // a refit from the model with its own settings (as `diagnose --follow` does): the branch
    // settings now hold the raised horizon, but it is still the default raised
    let again = MisoHammerstein::new(
        model
            .branches()
            .iter()
            .map(|b| b.settings().clone())
            .collect(),
    );
    let refit = again.refit_from(&data, &model).unwrap();
    says_raised(&refit, "refit_from");
    let warm = again.fit_from(&data, &model).unwrap();
    says_raised(&warm, "fit_from");
    // a horizon chosen by the user is never reported as raised: not in a fresh fit, not in a
    // refit from a model whose branches stood raised at another horizon (the refit copied the
    // base's "raised from 8" while it ran at the chosen 12)
    let chosen_settings = MisoHammerstein::new(vec![
        Hammerstein::linear().order(Order::Fixed(9)).horizon(12),
        Hammerstein::linear().order(Order::Fixed(9)).horizon(12),
    ]);
    let chosen = chosen_settings.fit(&data).unwrap();
    let from_raised = chosen_settings.fit_from(&data, &model).unwrap();
    for (what, m) in [("fit", &chosen), ("fit_from", &from_raised)] {
        for (i, b) in m.branches().iter().enumerate() {
            assert_eq!(b.settings().options().horizon, 12, "{what}, branch {i}");
            assert_eq!(
                b.report().horizon_raised_from,
                None,
                "{what} at the chosen horizon 12, branch {i}"
            );
        }
    }
    // default settings from a base fitted at a chosen horizon: the default is raised for the
    // base's order 9 (to 10), and the report says so (it copied the base's silence)
    let defaults = MisoHammerstein::new(vec![Hammerstein::linear(), Hammerstein::linear()]);
    let raised = defaults.fit_from(&data, &chosen).unwrap();
    says_raised(&raised, "fit_from with the default horizon");
}
