//! A UDN fitted with the automatic order is no worse than the linear model it contains
//! (`fit/selection/linear_nested.rs`): on the committed F-16 excerpt (`tests/data/f16_gvt/`, force →
//! wing acceleration, 2000 samples) the full UDN's own fit ended at 66.96 % training fit against
//! 82.72 % for the linear model, and dead-zone with preload lost as much on longer windows.

use hammerstein::IoData;
use hammerstein::diagnosis::compare;
use hammerstein::fit::Hammerstein;
use hammerstein::fit::order_selection::training_mse;
use hammerstein::regressors::{Effect, EffectSet};

fn excerpt() -> IoData<f64> {
    IoData::from_csv(
        concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/tests/data/f16_gvt/level3_excerpt_2000.csv"
        ),
        &["force_N"],
        &["acc2"],
    )
    .unwrap()
}

#[test]
fn a_full_udn_is_no_worse_than_the_linear_model_it_contains() {
    let data = excerpt();
    let linear = Hammerstein::<f64>::linear().fit(&data).unwrap();
    let fit = |m: &hammerstein::fit::HammersteinModel<f64>| {
        compare(m, &data).unwrap().metrics.fit_percent
    };
    for effects in [
        EffectSet::all(),
        EffectSet::of(&[Effect::DeadZone, Effect::Preload]),
    ] {
        let udn = Hammerstein::<f64>::udn(effects).fit(&data).unwrap();
        // the UDN holds the linear model (effects at their null values, the saturation limits
        // at the input's extremes): its training error is not above the linear model's
        let (m_udn, m_lin) = (training_mse(&udn, &data), training_mse(&linear, &data));
        assert!(
            m_udn <= 1.001 * m_lin,
            "{}: training MSE {m_udn} against the linear model's {m_lin} (fit {:.2} against \
             {:.2} %, {:?})",
            effects.label(),
            fit(&udn),
            fit(&linear),
            udn.parameters()
        );
    }
}
