//! Checks of output paths before any work starts: the directory exists and is writable, the
//! target is not a directory, and no output overwrites an input file.

use crate::cli::Failure;
use std::path::{Path, PathBuf};

/// The directory a file path lives in ("." for a bare name).
fn parent_dir(path: &Path) -> PathBuf {
    match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    }
}

/// True when `a` and `b` name the same existing file (through symbolic links, `..`, hard links).
pub fn same_file(a: &Path, b: &Path) -> bool {
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        if let (Ok(ma), Ok(mb)) = (std::fs::metadata(a), std::fs::metadata(b)) {
            return ma.dev() == mb.dev() && ma.ino() == mb.ino();
        }
    }
    match (a.canonicalize(), b.canonicalize()) {
        (Ok(x), Ok(y)) => x == y,
        _ => false,
    }
}

/// Creates and removes a probe file in `dir`: the only reliable test that files can be
/// created there (permissions, read-only file systems, ACLs).
fn probe_writable(dir: &Path, what: &str) -> Result<(), Failure> {
    let nanos = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.subsec_nanos());
    let probe = dir.join(format!(".hammerstein-probe-{}-{nanos}", std::process::id()));
    match std::fs::OpenOptions::new()
        .write(true)
        .create_new(true)
        .open(&probe)
    {
        Ok(_) => {
            let _ = std::fs::remove_file(&probe);
            Ok(())
        }
        Err(e) => Err(format!(
            "cannot write {what}: directory {} is not writable ({e})",
            dir.display()
        )
        .into()),
    }
}

/// Checks that the file `path` (option `option`) can be written and is none of `inputs`.
pub fn check_output_file(path: &Path, option: &str, inputs: &[&Path]) -> Result<(), Failure> {
    let what = format!("{option} {}", path.display());
    if path.is_dir() {
        return Err(format!("cannot write {what}: it is a directory").into());
    }
    if let Some(input) = inputs.iter().find(|i| same_file(path, i)) {
        return Err(format!(
            "refusing to write {what}: it is the input file {} (choose another output path)",
            input.display()
        )
        .into());
    }
    // a link, device or FIFO is written in place (`atomic::in_place`): its directory need not
    // take new files, and the write itself reports what fails (`/dev/full`)
    if hammerstein::atomic::in_place(path) {
        return Ok(());
    }
    let dir = parent_dir(path);
    if !dir.is_dir() {
        return Err(format!(
            "cannot write {what}: directory {} does not exist",
            dir.display()
        )
        .into());
    }
    probe_writable(&dir, &what)
}

/// Checks that a report can be written into directory `dir` (created if missing) without
/// replacing any of `inputs` (the report writes `index.html` and `*.svg`).
pub fn check_output_dir(dir: &Path, option: &str, inputs: &[&Path]) -> Result<(), Failure> {
    let what = format!("{option} {}", dir.display());
    if dir.exists() && !dir.is_dir() {
        return Err(format!("cannot write {what}: it is a file, not a directory").into());
    }
    for input in inputs {
        let ext = input.extension().and_then(|e| e.to_str()).unwrap_or("");
        let inside = input
            .file_name()
            .is_some_and(|n| same_file(&dir.join(n), input));
        if inside && (ext == "svg" || ext == "html") {
            return Err(format!(
                "refusing to write {what}: the report's files would replace the input {}",
                input.display()
            )
            .into());
        }
    }
    // the nearest existing ancestor must accept new entries (the report creates the rest)
    let mut existing = dir.to_path_buf();
    while !existing.exists() {
        existing = match existing.parent() {
            Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
            _ => PathBuf::from("."),
        };
    }
    if !existing.is_dir() {
        return Err(format!(
            "cannot write {what}: {} is a file, not a directory",
            existing.display()
        )
        .into());
    }
    probe_writable(&existing, &what)
}
