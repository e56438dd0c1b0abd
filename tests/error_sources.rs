//! I/O failures keep their cause: `Error::Io` carries the `std::io::Error`, reachable through
//! `Error::io_error` and through the `source()` chain, with the message unchanged.

use hammerstein::Error;
use hammerstein::fit::HammersteinModel;
use std::error::Error as _;
use std::io::ErrorKind;
use std::path::PathBuf;

fn missing(name: &str) -> PathBuf {
    let p = std::env::temp_dir().join(format!("hammerstein_missing_{}_{name}", std::process::id()));
    assert!(!p.exists());
    p
}

/// The first `std::io::Error` in the source chain, as a generic error reporter would find it.
fn io_in_chain(e: &Error) -> Option<&std::io::Error> {
    let mut next = e.source();
    while let Some(s) = next {
        if let Some(io) = s.downcast_ref::<std::io::Error>() {
            return Some(io);
        }
        next = s.source();
    }
    None
}

fn check_not_found(e: &Error, path: &std::path::Path) {
    assert!(matches!(e, Error::Io { .. }), "{e:?}");
    assert_eq!(e.io_error().map(|io| io.kind()), Some(ErrorKind::NotFound));
    assert_eq!(
        io_in_chain(e).map(|io| io.kind()),
        Some(ErrorKind::NotFound)
    );
    let text = e.to_string();
    let os = e.io_error().unwrap().to_string();
    assert_eq!(text, format!("cannot access {}: {os}", path.display()));
    // still Clone and PartialEq
    assert_eq!(e.clone(), *e);
    assert_ne!(*e, Error::io(path.display(), std::io::Error::other("else")));
}

#[cfg(feature = "csv")]
#[test]
fn missing_csv_is_io_not_found_with_its_cause() {
    let p = missing("record.csv");
    let e = hammerstein::IoData::<f64>::from_csv(&p, &["u"], &["y"]).unwrap_err();
    check_not_found(&e, &p);
    let e = hammerstein::CsvTable::read(&p).unwrap_err();
    check_not_found(&e, &p);
}

#[cfg(all(feature = "csv", unix))]
#[test]
fn a_directory_read_as_csv_is_an_io_error_not_a_malformed_csv() {
    let dir = std::env::temp_dir();
    let e = hammerstein::CsvTable::read(&dir).unwrap_err();
    assert!(matches!(e, Error::Io { .. }), "{e:?}");
    assert_eq!(
        e.io_error().map(|io| io.kind()),
        Some(ErrorKind::IsADirectory)
    );
}

#[test]
fn missing_model_file_is_io_not_found_with_its_cause() {
    let p = missing("model.json");
    let e = HammersteinModel::load(&p).unwrap_err();
    check_not_found(&e, &p);
}

#[test]
fn other_errors_have_no_io_cause() {
    let e = Error::InvalidParameter("x".into());
    assert!(e.io_error().is_none() && e.source().is_none());
}
