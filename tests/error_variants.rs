//! A caller can match on specific error variants instead of parsing the catch-all's text: an
//! unknown CSV column, too few samples for the horizon, an unknown effect name, a bad sample
//! range, and a malformed CSV that keeps the reader's error.

use hammerstein::regressors::Effect;
use hammerstein::{Error, IoData};

#[cfg(feature = "csv")]
#[test]
fn unknown_column_is_typed() {
    let t = hammerstein::CsvTable::parse(b"u,y\n1,2\n3,4\n", "table").unwrap();
    match t.io_data::<f64>(&["x"], &["y"]) {
        Err(Error::UnknownColumn { name, available }) => {
            assert_eq!(name, "x");
            assert_eq!(available, "u, y");
        }
        other => panic!("{other:?}"),
    }
}

#[cfg(feature = "csv")]
#[test]
fn malformed_csv_keeps_the_readers_error() {
    let e = hammerstein::CsvTable::parse(b"u,y\n1,2\n3\n", "ragged").unwrap_err();
    assert!(matches!(e, Error::Csv { .. }), "{e:?}");
    let e = hammerstein::CsvTable::parse(b"u,y\n1,\xff\n", "utf8").unwrap_err();
    match &e {
        Error::Csv { .. } => {
            let cause = e.csv_error().expect("the csv::Error behind it");
            assert!(
                matches!(cause.kind(), csv::ErrorKind::Utf8 { .. }),
                "{cause:?}"
            );
            assert!(std::error::Error::source(&e).is_some());
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn too_few_samples_for_the_horizon_is_typed() {
    let u: Vec<f64> = (0..12).map(|k| (k as f64).sin()).collect();
    let y: Vec<f64> = u.iter().map(|x| 2.0 * x).collect();
    let data = IoData::siso(&u, &y).unwrap();
    match data.check_horizon(10) {
        Err(Error::TooFewSamples { needed, got, .. }) => {
            assert_eq!(got, 12);
            assert!(needed > got);
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn unknown_effect_name_is_typed() {
    match "friction".parse::<Effect>() {
        Err(e @ Error::UnknownName { .. }) => {
            let Error::UnknownName { kind, name, .. } = &e else {
                unreachable!()
            };
            assert_eq!(*kind, hammerstein::error::NameKind::Effect);
            assert_eq!(name, "friction");
            // the text is the one the catch-all printed
            assert!(
                e.to_string()
                    .starts_with("invalid parameter: unknown effect 'friction' (hysteresis"),
                "{e}"
            );
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn sample_range_is_typed() {
    let u: Vec<f64> = (0..20).map(|k| (k as f64).sin()).collect();
    let data = IoData::siso(&u, &u).unwrap();
    assert!(matches!(
        data.slice(5, 30),
        Err(Error::SampleRange {
            start: 5,
            end: 30,
            len: 20
        })
    ));
}

/// Asking UDN effects of a user basis, or an unknown feed-through name, gives specific variants.
#[test]
fn not_udn_and_unknown_feedthrough_are_specific() {
    use hammerstein::error::NameKind;
    use hammerstein::fit::Feedthrough;
    use hammerstein::regressors::Polynomial;
    let poly = hammerstein::Hammerstein::<f64>::new(Box::new(Polynomial::<f64>::new(3).unwrap()));
    match poly.with_effect(Effect::Hysteresis) {
        Err(Error::NotUdn { name, .. }) => assert!(name.contains("poly"), "{name}"),
        other => panic!("expected NotUdn, got {other:?}"),
    }
    match "sometimes".parse::<Feedthrough>() {
        Err(Error::UnknownName {
            kind: NameKind::Feedthrough,
            name,
            ..
        }) => assert_eq!(name, "sometimes"),
        other => panic!("expected UnknownName(feed-through), got {other:?}"),
    }
}
