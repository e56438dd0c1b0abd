//! Bad input gets a typed error, never a panic.

#[cfg(feature = "csv")]
use hammerstein::data::CsvTable;
use hammerstein::subspace::{MethodKind, Order, SubspaceOptions, estimate_bd_x0, identify};
use hammerstein::{Error, Faer, IoData, IoView};

#[cfg(feature = "csv")]
fn tmp_csv(name: &str, text: &str) -> std::path::PathBuf {
    let p = std::env::temp_dir().join(format!(
        "hammerstein_subspace_{}_{name}.csv",
        std::process::id()
    ));
    std::fs::write(&p, text).unwrap();
    p
}

fn record(n: usize) -> IoData<f64> {
    let u: Vec<f64> = (0..n).map(|k| ((k * 7919) % 13) as f64 - 6.0).collect();
    let mut y = vec![0.0; n];
    for k in 1..n {
        y[k] = 0.5 * y[k - 1] + u[k - 1] + 0.01 * (((k * 31) % 7) as f64 - 3.0);
    }
    IoData::siso(&u, &y).unwrap()
}

#[test]
fn nan_is_rejected() {
    let u = vec![1.0, f64::NAN, 0.5, 2.0];
    let y = vec![0.0; 4];
    assert!(matches!(IoData::siso(&u, &y), Err(Error::NonFinite { .. })));
    // also at the method level, on an unvalidated view
    let um = faer::Mat::from_fn(100, 1, |i, _| if i == 50 { f64::NAN } else { i as f64 });
    let ym = faer::Mat::from_fn(100, 1, |i, _| (i as f64).sin());
    let v = IoView::new(um.as_ref(), ym.as_ref()).unwrap();
    let m = MethodKind::Moesp.build::<f64>(5).unwrap();
    let e = identify(
        m.as_ref(),
        &Faer::default(),
        &[v],
        &SubspaceOptions::default(),
    );
    assert!(
        matches!(e, Err(Error::NonFinite { index: 50, .. })),
        "{e:?}"
    );
}

#[test]
fn mismatched_lengths_are_rejected() {
    assert!(matches!(
        IoData::siso(&[1.0, 2.0, 3.0], &[1.0, 2.0]),
        Err(Error::LengthMismatch { .. })
    ));
    let um = faer::Mat::<f64>::zeros(10, 1);
    let ym = faer::Mat::<f64>::zeros(9, 1);
    assert!(matches!(
        IoView::new(um.as_ref(), ym.as_ref()),
        Err(Error::LengthMismatch { .. })
    ));
}

#[test]
fn too_few_samples_for_the_horizon() {
    let d = record(30);
    assert!(matches!(
        d.check_horizon(10),
        Err(Error::TooFewSamples { .. })
    ));
    for kind in [MethodKind::Moesp, MethodKind::N4sid] {
        let m = kind.build::<f64>(20).unwrap();
        let e = identify(
            m.as_ref(),
            &Faer::default(),
            &[d.view()],
            &SubspaceOptions::default(),
        );
        assert!(matches!(e, Err(Error::TooFewSamples { .. })), "{e:?}");
    }
}

#[test]
fn constant_input_is_rejected() {
    let u = vec![2.0; 100];
    let y: Vec<f64> = (0..100).map(|k| k as f64).collect();
    assert!(matches!(
        IoData::siso(&u, &y),
        Err(Error::ConstantInput { .. })
    ));
}

#[cfg(feature = "csv")]
#[test]
fn unknown_column_and_malformed_csv() {
    let p = tmp_csv("ok", "u,y\n1,2\n3,4\n5,7\n");
    let t = CsvTable::read(&p).unwrap();
    assert!(matches!(
        t.io_data::<f64>(&["u"], &["z"]),
        Err(Error::UnknownColumn { .. })
    ));
    let bad = tmp_csv("bad", "u,y\n1,2\n3,abc\n");
    assert!(matches!(CsvTable::read(&bad), Err(Error::Csv { .. })));
    let ragged = tmp_csv("ragged", "u,y\n1,2\n3\n");
    assert!(matches!(CsvTable::read(&ragged), Err(Error::Csv { .. })));
    let _ = std::fs::remove_file(p);
    let _ = std::fs::remove_file(bad);
    let _ = std::fs::remove_file(ragged);
}

#[test]
fn order_larger_than_possible() {
    let d = record(500);
    for kind in [MethodKind::Moesp, MethodKind::N4sid] {
        let m = kind.build::<f64>(5).unwrap();
        let e = identify(
            m.as_ref(),
            &Faer::default(),
            &[d.view()],
            &SubspaceOptions {
                order: Order::Fixed(9),
                ..Default::default()
            },
        );
        assert!(
            matches!(
                e,
                Err(Error::OrderTooLarge {
                    requested: 9,
                    max: 4
                })
            ),
            "{e:?}"
        );
    }
}

#[test]
fn horizon_zero_or_one_is_rejected() {
    for h in [0, 1] {
        assert!(matches!(
            MethodKind::Moesp.build::<f64>(h),
            Err(Error::HorizonTooSmall { min: 2, .. })
        ));
    }
    // the method structs themselves refuse horizon 0 at decomposition
    let d = record(100);
    assert!(matches!(
        d.check_horizon(0),
        Err(Error::HorizonTooSmall { horizon: 0, min: 2 })
    ));
    assert_eq!(hammerstein::data::min_samples_for_horizon(0, 1, 1), 0);
    let e = identify(
        &hammerstein::Moesp::new(0),
        &Faer::default(),
        &[d.view()],
        &SubspaceOptions::default(),
    );
    assert!(matches!(e, Err(Error::HorizonTooSmall { .. })), "{e:?}");
}

#[test]
fn bd_with_wrong_shapes_is_an_error() {
    let d = record(100);
    let a = faer::Mat::<f64>::identity(2, 2);
    let c = faer::Mat::<f64>::zeros(1, 3);
    assert!(matches!(
        estimate_bd_x0(
            &Faer::default(),
            a.as_ref(),
            c.as_ref(),
            &[d.view()],
            true,
            true
        ),
        Err(Error::Dimension(_))
    ));
}
