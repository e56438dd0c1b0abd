//! A candidate refitted at the model's order gets a horizon that admits that order: an order
//! chosen automatically may exceed what the settings' horizon allows (the order selection raises
//! the horizon for it), and the candidates used to keep the settings' horizon, so every refit
//! failed with "order n is larger than possible" (seen on the Bouc–Wen benchmark: order 8 at the
//! default horizon 8, which admits 7).

mod common;

use hammerstein::diagnosis::diagnose;
use hammerstein::regressors::{Effect, EffectSet, StaticNonlinearity, Udn};
use hammerstein::{Hammerstein, IoData, Order, StateSpace};

#[test]
fn candidates_at_an_order_above_the_settings_horizon_refit() {
    // third-order block, saturation at the input; the settings' horizon 3 admits order 2 only
    let g = StateSpace::from_rows(
        &[&[1.1, 1.0, 0.0], &[-0.5, 0.0, 1.0], &[0.08, 0.0, 0.0]],
        &[&[1.0], &[0.4], &[0.1]],
        &[&[1.0, 0.0, 0.0]],
        &[&[0.0]],
    )
    .unwrap();
    let sat = Udn::with_params(EffectSet::of(&[Effect::Saturation]), &[1.0, 1.2, -1.2]).unwrap();
    let u = common::input(common::InputKind::Uniform, 3000, 2.0, 7);
    let (y, _) = common::output(&g, &sat.eval(&u), 30.0, 8);
    let data = IoData::siso(&u, &y).unwrap();
    let (train, val) = data.split_validation(0.3).unwrap();
    assert!(hammerstein::subspace::max_order(3, 1) < 3);
    // order chosen automatically: the selection raises the horizon for order 3, the model's
    // settings keep the user's horizon 3
    let model = Hammerstein::<f64>::linear()
        .horizon(3)
        .order(Order::Auto)
        .fit(&train)
        .unwrap();
    assert_eq!(model.linear().order(), 3, "the test needs order 3 chosen");
    assert_eq!(model.settings().options().horizon, 3);
    for m in [&model] {
        let d = diagnose(m, &train, &val).unwrap();
        for c in &d.candidates {
            if let Some(e) = &c.refit_error {
                assert!(
                    !e.contains("larger than possible"),
                    "{}: {e} (order {}, horizon {})",
                    c.effect,
                    m.linear().order(),
                    m.settings().options().horizon
                );
            }
        }
    }
}
