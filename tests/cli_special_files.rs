//! Outputs that are not regular files (issue 40, item 7): a device, a FIFO or a symbolic link
//! is written in place, never replaced by a regular file; a full device is an error with a
//! non-zero exit; a write beyond the file-size limit is reported and leaves no temporary file.

mod common;

use common::{
    InputKind, Udn, add_noise, entries, input, paper_block, run_cli_outcome, temp_dir, write_csv,
};
use std::path::{Path, PathBuf};

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// A 400-sample linear record and a model fitted to it (saved), in a fresh directory.
fn setup(tag: &str) -> (PathBuf, PathBuf, PathBuf) {
    let dir = temp_dir(tag);
    let u = input(InputKind::Uniform, 400, 3.0, 1);
    let v = Udn::linear(2.0).eval(&u);
    let y0 = paper_block().simulate_siso(&v, None).unwrap();
    let y = add_noise(&y0, 0.01, 1);
    let data = dir.join("data.csv");
    write_csv(&data, &["u", "y"], &[&u, &y]);
    let model = dir.join("model.json");
    let (ok, _, err) = run_cli_outcome(&["fit", s(&data), "--order", "2", "--save", s(&model)]);
    assert!(ok, "{err}");
    (dir, data, model)
}

#[cfg(unix)]
fn is_char_device(p: &Path) -> bool {
    use std::os::unix::fs::FileTypeExt;
    std::fs::metadata(p).is_ok_and(|m| m.file_type().is_char_device())
}

#[cfg(unix)]
#[test]
fn a_full_device_is_an_error_and_stays_a_device() {
    let full = Path::new("/dev/full");
    if !is_char_device(full) {
        eprintln!("skipped: no /dev/full");
        return;
    }
    let (_dir, data, model) = setup("special-full");
    for args in [
        vec!["fit", s(&data), "--order", "2", "--save", "/dev/full"],
        vec!["simulate", s(&model), s(&data), "--out", "/dev/full"],
    ] {
        let (ok, _, err) = run_cli_outcome(&args);
        assert!(!ok, "{args:?} exited 0: {err}");
        assert!(err.contains("No space left"), "{args:?}: {err}");
        assert!(!err.contains("panicked"), "{err}");
        assert!(is_char_device(full), "/dev/full was replaced");
    }
}

#[cfg(unix)]
#[test]
fn a_fifo_is_written_in_place() {
    let (dir, data, model) = setup("special-fifo");
    let fifo = dir.join("out.fifo");
    let made = std::process::Command::new("mkfifo")
        .arg(&fifo)
        .status()
        .is_ok_and(|s| s.success());
    if !made {
        eprintln!("skipped: mkfifo failed");
        return;
    }
    // the reader: opens the FIFO and keeps what comes through
    let reader = {
        let fifo = fifo.clone();
        std::thread::spawn(move || std::fs::read_to_string(fifo).unwrap())
    };
    let (ok, _, err) = run_cli_outcome(&["simulate", s(&model), s(&data), "--out", s(&fifo)]);
    assert!(ok, "{err}");
    let text = reader.join().unwrap();
    assert_eq!(
        text.lines().count(),
        401,
        "{}",
        &text[..text.len().min(200)]
    );
    assert!(text.starts_with("u,y_hat\n"), "{}", &text[..40]);
    use std::os::unix::fs::FileTypeExt;
    let m = std::fs::symlink_metadata(&fifo).unwrap();
    assert!(m.file_type().is_fifo(), "the FIFO was replaced");
    assert_eq!(
        entries(&dir),
        vec!["data.csv", "model.json", "out.fifo"],
        "a temporary stayed"
    );
}

#[cfg(unix)]
#[test]
fn a_symlink_to_standard_output_prints_and_stays_a_link() {
    let (dir, data, model) = setup("special-link");
    let link = dir.join("stdout-link");
    std::os::unix::fs::symlink("/proc/self/fd/1", &link).unwrap();
    if !Path::new("/proc/self/fd/1").exists() {
        eprintln!("skipped: no /proc/self/fd");
        return;
    }
    for target in [s(&link), "/dev/stdout"] {
        let (ok, out, err) = run_cli_outcome(&["simulate", s(&model), s(&data), "--out", target]);
        assert!(ok, "{target}: {err}");
        assert_eq!(out.lines().count(), 401, "{target}: nothing printed");
        assert!(out.starts_with("u,y_hat\n"), "{target}");
    }
    let m = std::fs::symlink_metadata(&link).unwrap();
    assert!(m.file_type().is_symlink(), "the link was replaced");
    assert_eq!(
        std::fs::read_link(&link).unwrap(),
        PathBuf::from("/proc/self/fd/1")
    );
}

#[cfg(unix)]
#[test]
fn a_symlink_to_a_regular_file_is_written_through_and_kept() {
    let (dir, data, model) = setup("special-link-file");
    let target = dir.join("real.json");
    std::fs::write(&target, "old").unwrap();
    let link = dir.join("m.json");
    std::os::unix::fs::symlink(&target, &link).unwrap();
    let (ok, _, err) = run_cli_outcome(&["fit", s(&data), "--order", "2", "--save", s(&link)]);
    assert!(ok, "{err}");
    assert!(
        std::fs::symlink_metadata(&link)
            .unwrap()
            .file_type()
            .is_symlink()
    );
    let saved = std::fs::read_to_string(&target).unwrap();
    assert!(saved.contains("\"linear\""), "{saved}");
    // and the saved model reads back through the link
    let (ok, out, err) = run_cli_outcome(&["compare", s(&link), s(&data)]);
    assert!(ok && out.contains("fit"), "{err}");
    let _ = model;
}

#[test]
fn a_regular_file_is_still_replaced_atomically() {
    let (dir, data, _model) = setup("special-regular");
    let out = dir.join("sim.csv");
    std::fs::write(&out, "old").unwrap();
    let model = dir.join("model.json");
    let (ok, _, err) = run_cli_outcome(&["simulate", s(&model), s(&data), "--out", s(&out)]);
    assert!(ok, "{err}");
    assert_eq!(std::fs::read_to_string(&out).unwrap().lines().count(), 401);
    assert_eq!(entries(&dir), vec!["data.csv", "model.json", "sim.csv"]);
}

/// `ulimit -f 2` (2 KiB) and a model file larger than that: EFBIG reported, exit 1, the
/// temporary removed (SIGXFSZ is ignored), the previous file untouched.
#[cfg(unix)]
#[test]
fn a_file_size_limit_is_reported_and_leaves_no_temporary() {
    let (dir, data, model) = setup("special-ulimit");
    let size = std::fs::metadata(&model).unwrap().len();
    assert!(
        size > 2048,
        "the model file ({size} bytes) fits under the limit"
    );
    let target = dir.join("limited.json");
    std::fs::write(&target, "previous").unwrap();
    let script = format!(
        "ulimit -f 2 || exit 77; exec \"$0\" fit '{}' --order 2 --save '{}'",
        s(&data),
        s(&target)
    );
    let out = std::process::Command::new("sh")
        .arg("-c")
        .arg(&script)
        .arg(env!("CARGO_BIN_EXE_hammerstein"))
        .output();
    let Ok(out) = out else {
        eprintln!("skipped: no sh");
        return;
    };
    if out.status.code() == Some(77) {
        eprintln!("skipped: ulimit -f not available");
        return;
    }
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(
        out.status.code(),
        Some(1),
        "killed or exit 0: {:?} {err}",
        out.status
    );
    assert!(err.contains("File too large"), "{err}");
    assert_eq!(std::fs::read_to_string(&target).unwrap(), "previous");
    assert_eq!(
        entries(&dir),
        vec!["data.csv", "limited.json", "model.json"],
        "a temporary stayed"
    );
}
