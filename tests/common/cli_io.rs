//! Temporary directories, CSV records and runs of the `hammerstein` binary: the command-line
//! tests' file helpers, with no dependency beyond std (a test that cannot load `common` whole,
//! `tests/screening.rs`, includes this file alone).

/// Writes a CSV with the given columns.
pub fn write_csv(path: &std::path::Path, names: &[&str], cols: &[&[f64]]) {
    let mut s = names.join(",");
    s.push('\n');
    for k in 0..cols[0].len() {
        let row: Vec<String> = cols.iter().map(|c| format!("{}", c[k])).collect();
        s.push_str(&row.join(","));
        s.push('\n');
    }
    std::fs::write(path, s).unwrap();
}

/// Writes a training and a validation record (columns u, y) as `train.csv` and `val.csv` in
/// `dir`; their paths.
pub fn write_train_val(
    dir: &std::path::Path,
    (u, y): (&[f64], &[f64]),
    (uv, yv): (&[f64], &[f64]),
) -> (std::path::PathBuf, std::path::PathBuf) {
    let train = dir.join("train.csv");
    let val = dir.join("val.csv");
    write_csv(&train, &["u", "y"], &[u, y]);
    write_csv(&val, &["u", "y"], &[uv, yv]);
    (train, val)
}

/// A fresh temporary directory under the target dir.
pub fn temp_dir(tag: &str) -> std::path::PathBuf {
    let d = std::env::temp_dir().join(format!(
        "hammerstein-{tag}-{}-{}",
        std::process::id(),
        std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .unwrap()
            .as_nanos()
    ));
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// The `hammerstein` binary's standard output for `args`; panics with its standard error when
/// it fails.
#[cfg(feature = "cli")]
pub fn run_cli(args: &[&str]) -> String {
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_hammerstein"))
        .args(args)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout).unwrap()
}

/// The `hammerstein` binary's (success, standard output, standard error) for `args`: for the
/// tests that check a failure's message or what it says on standard error.
#[cfg(feature = "cli")]
pub fn run_cli_outcome(args: &[&str]) -> (bool, String, String) {
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_hammerstein"))
        .args(args)
        .output()
        .unwrap();
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// A directory's entries, sorted (to see that no temporary file stays behind).
pub fn entries(d: &std::path::Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(d)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}
