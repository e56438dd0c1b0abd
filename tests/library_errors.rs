//! Library calls that returned Ok where an error is due (issue 40, item 7): each now returns a
//! typed error that says what is wrong.

use hammerstein::diagnosis::{compare, diagnose};
use hammerstein::regressors::{Udn, play};
use hammerstein::subspace::{Order, SubspaceOptions, identify, select_order};
use hammerstein::{Error, Faer, Hammerstein, IoData, Moesp};

/// A first-order record driven by a deterministic pseudo-random input.
fn record(n: usize, seed: u64) -> IoData<f64> {
    let mut s = seed.wrapping_mul(2654435761).wrapping_add(1);
    let u: Vec<f64> = (0..n)
        .map(|_| {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (s >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
        })
        .collect();
    let mut y = vec![0.0; n];
    for k in 1..n {
        y[k] = 0.7 * y[k - 1] + u[k - 1] + 0.01 * (((k * 31) % 7) as f64 - 3.0);
    }
    IoData::siso(&u, &y).unwrap()
}

#[test]
fn compare_on_too_few_samples_is_an_error() {
    let model = Hammerstein::<f64>::linear()
        .order(Order::Fixed(2))
        .fit(&record(400, 1))
        .unwrap();
    let short = record(3, 2);
    let e = compare(&model, &short);
    assert!(
        matches!(e, Err(Error::TooFewSamples { got: 3, .. })),
        "{:?}",
        e.map(|c| c.metrics)
    );
    // enough samples: Ok
    assert!(compare(&model, &record(50, 3)).is_ok());
}

#[test]
fn a_four_sample_validation_part_is_refused_by_the_diagnosis() {
    let train = record(600, 4);
    let model = Hammerstein::<f64>::linear()
        .order(Order::Fixed(1))
        .fit(&train)
        .unwrap();
    let e = diagnose(&model, &train, &record(4, 5));
    assert!(
        matches!(e, Err(Error::TooFewSamples { got: 4, .. })),
        "{:?}",
        e.map(|d| d.adequate)
    );
}

#[test]
fn an_empty_nonlinearity_name_is_refused() {
    for name in ["", "  "] {
        let e = Udn::<f64>::by_name(name);
        assert!(
            matches!(e, Err(Error::InvalidParameter(_))),
            "{name:?}: {e:?}"
        );
    }
    assert!(Udn::<f64>::by_name("sh").is_ok());
}

#[test]
fn moesp_on_fewer_samples_than_its_horizon_needs_is_refused() {
    let d = record(10, 6);
    let e = identify(
        &Moesp::new(2),
        &Faer::default(),
        &[d.view()],
        &SubspaceOptions::default(),
    );
    assert!(
        matches!(e, Err(Error::TooFewSamples { got: 10, .. })),
        "{:?}",
        e.map(|i| i.model.order())
    );
}

#[test]
fn order_selection_needs_two_singular_values() {
    for sv in [&[][..], &[1.0][..]] {
        for rule in [Order::Auto, Order::Gap, Order::Fixed(1)] {
            let e = select_order(sv, &rule, 5);
            assert!(
                matches!(e, Err(Error::Identification(_))),
                "{sv:?} {rule:?}: {e:?}"
            );
        }
    }
    assert_eq!(select_order(&[10.0, 0.1], &Order::Auto, 5).unwrap(), 1);
}

#[test]
fn the_play_operator_refuses_a_nan_or_negative_threshold() {
    let u = [0.0, 1.0, 2.0, 1.0, 0.0];
    for r in [f64::NAN, -1.0, f64::NEG_INFINITY] {
        let e = play(&u, r, 0.0);
        assert!(
            matches!(e, Err(Error::InvalidParameter(_))),
            "r = {r}: {e:?}"
        );
    }
    assert!(matches!(
        play(&u, 0.5, f64::NAN),
        Err(Error::InvalidParameter(_))
    ));
    // threshold 0: the identity
    assert_eq!(play(&u, 0.0, 0.0).unwrap(), u.to_vec());
}

#[test]
fn decimating_by_the_largest_factor_is_a_typed_error() {
    let d = record(2000, 7);
    let e = d.decimate(usize::MAX).unwrap_err();
    assert!(matches!(e, Error::InvalidParameter(_)), "{e:?}");
    let msg = e.to_string();
    assert!(msg.contains("18446744073709551615"), "{msg}");
    assert!(!msg.contains("0 needed"), "{msg}");
    // a factor beyond the record but below the overflow: the samples needed, exact
    let e = d.decimate(5000).unwrap_err();
    assert!(
        matches!(
            e,
            Error::TooFewSamples {
                needed: 5001,
                got: 2000,
                ..
            }
        ),
        "{e:?}"
    );
}
