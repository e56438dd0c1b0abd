//! Atomic file writes: the new content goes to a temporary file in the target's directory and is
//! renamed over the target only once it is complete, so a failed write (full disk, file size
//! limit, interruption) leaves the previous file untouched and never a truncated one.
//!
//! Only a regular file (or a path that does not exist yet) is replaced that way. A target that
//! is a symbolic link, a device, a FIFO or a socket is written in place, through the path as it
//! is ([`in_place`]): a rename would replace the link, `/dev/null`, `/dev/stdout` or the pipe a
//! reader waits on with a regular file. A failed write there (`/dev/full`: no space) is an
//! error like any other.

use crate::error::{Error, Result};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

fn io_err(path: &Path, e: std::io::Error) -> Error {
    Error::io(path.display(), e)
}

/// A fresh temporary path next to `path` (same directory, so the rename stays atomic).
fn temp_path(path: &Path) -> PathBuf {
    static COUNTER: AtomicU64 = AtomicU64::new(0);
    let n = COUNTER.fetch_add(1, Ordering::Relaxed);
    let name = path
        .file_name()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "output".into());
    let tmp = format!(".{name}.tmp-{}-{n}", std::process::id());
    match path.parent() {
        Some(dir) if !dir.as_os_str().is_empty() => dir.join(tmp),
        _ => PathBuf::from(tmp),
    }
}

/// Writes `bytes` to a new temporary file beside `path` (synced to disk, with the permissions of
/// the file it replaces); returns the temporary path. Removes it again on failure.
fn stage(path: &Path, bytes: &[u8]) -> Result<PathBuf> {
    let tmp = temp_path(path);
    let res = (|| {
        let mut f = std::fs::OpenOptions::new()
            .write(true)
            .create_new(true)
            .open(&tmp)?;
        f.write_all(bytes)?;
        f.sync_all()?;
        if let Ok(meta) = std::fs::metadata(path) {
            std::fs::set_permissions(&tmp, meta.permissions())?;
        }
        Ok(())
    })();
    match res {
        Ok(()) => Ok(tmp),
        Err(e) => {
            let _ = std::fs::remove_file(&tmp);
            Err(io_err(path, e))
        }
    }
}

/// True when `path` is written in place rather than replaced: it exists and is a symbolic link
/// or not a regular file (a device, a FIFO, a socket). A directory is not (writing it fails).
pub fn in_place(path: &Path) -> bool {
    match std::fs::symlink_metadata(path) {
        Ok(m) => m.file_type().is_symlink() || !(m.is_file() || m.is_dir()),
        Err(_) => false,
    }
}

/// Writes `bytes` through `path` as it is (opened for writing, truncated when it is a file;
/// created at the end of a dangling link), synced when it leads to a regular file.
fn write_in_place(path: &Path, bytes: &[u8]) -> Result<()> {
    let res = (|| {
        let mut f = std::fs::OpenOptions::new()
            .write(true)
            .create(true)
            .truncate(true)
            .open(path)?;
        f.write_all(bytes)?;
        f.flush()?;
        if f.metadata()?.is_file() {
            f.sync_all()?;
        }
        Ok(())
    })();
    res.map_err(|e| io_err(path, e))
}

/// Writes `bytes` to `path` atomically: temporary file in the same directory, then rename.
/// On failure the previous content of `path` (if any) is unchanged and no temporary file is
/// left behind. A symbolic link, device or FIFO is written in place instead ([`in_place`]).
pub fn write_atomic(path: impl AsRef<Path>, bytes: &[u8]) -> Result<()> {
    write_all_atomic(&[(path.as_ref().to_path_buf(), bytes.to_vec())])
}

/// Writes several files, each atomically, all or nothing as far as the data go: every file is
/// first written in full to a temporary beside its target, and only when all are written are
/// they renamed into place, in the order given (put an index file last). A failure while
/// writing leaves every target as it was; only a failing rename (rare: the data are already on
/// disk) can leave the earlier targets new and the later ones old. Targets written in place
/// ([`in_place`]) are written after the others are staged, before the renames.
pub fn write_all_atomic(files: &[(PathBuf, Vec<u8>)]) -> Result<()> {
    let mut staged: Vec<(PathBuf, &Path)> = Vec::with_capacity(files.len());
    let (special, regular): (Vec<_>, Vec<_>) = files.iter().partition(|(p, _)| in_place(p));
    for (path, bytes) in regular {
        match stage(path, bytes) {
            Ok(tmp) => staged.push((tmp, path)),
            Err(e) => {
                for (tmp, _) in &staged {
                    let _ = std::fs::remove_file(tmp);
                }
                return Err(e);
            }
        }
    }
    let mut result = Ok(());
    for (path, bytes) in special {
        if result.is_ok() {
            result = write_in_place(path, bytes);
        }
    }
    for (tmp, path) in &staged {
        if result.is_ok() {
            if let Err(e) = std::fs::rename(tmp, path) {
                result = Err(io_err(path, e));
                let _ = std::fs::remove_file(tmp);
            }
        } else {
            let _ = std::fs::remove_file(tmp);
        }
    }
    result
}

#[cfg(test)]
mod tests {
    use super::*;

    fn dir(tag: &str) -> PathBuf {
        let d =
            std::env::temp_dir().join(format!("hammerstein_atomic_{}_{tag}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    fn entries(d: &Path) -> Vec<String> {
        let mut v: Vec<String> = std::fs::read_dir(d)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        v.sort();
        v
    }

    #[test]
    fn replaces_the_file_and_leaves_no_temporary() {
        let d = dir("replace");
        let p = d.join("a.txt");
        write_atomic(&p, b"one").unwrap();
        write_atomic(&p, b"two").unwrap();
        assert_eq!(std::fs::read(&p).unwrap(), b"two");
        assert_eq!(entries(&d), vec!["a.txt"]);
    }

    #[test]
    fn a_failed_batch_changes_nothing() {
        let d = dir("batch");
        let a = d.join("a.txt");
        write_atomic(&a, b"old").unwrap();
        // the second target's directory does not exist: nothing is renamed, no temporary stays
        let files = vec![
            (a.clone(), b"new".to_vec()),
            (d.join("missing").join("b.txt"), b"b".to_vec()),
        ];
        assert!(matches!(write_all_atomic(&files), Err(Error::Io { .. })));
        assert_eq!(std::fs::read(&a).unwrap(), b"old");
        assert_eq!(entries(&d), vec!["a.txt"]);
    }

    #[cfg(unix)]
    #[test]
    fn a_link_is_written_through_and_kept() {
        let d = dir("link");
        let target = d.join("real.txt");
        write_atomic(&target, b"old").unwrap();
        let link = d.join("link.txt");
        std::os::unix::fs::symlink(&target, &link).unwrap();
        assert!(in_place(&link) && !in_place(&target) && !in_place(&d.join("new.txt")));
        write_atomic(&link, b"new").unwrap();
        assert!(
            std::fs::symlink_metadata(&link)
                .unwrap()
                .file_type()
                .is_symlink()
        );
        assert_eq!(std::fs::read(&target).unwrap(), b"new");
        assert_eq!(entries(&d), vec!["link.txt", "real.txt"]);
    }

    #[cfg(unix)]
    #[test]
    fn a_full_device_is_an_error() {
        let full = Path::new("/dev/full");
        if !full.exists() {
            return;
        }
        assert!(in_place(full));
        let e = write_atomic(full, b"x").unwrap_err();
        assert_eq!(
            e.io_error().map(|e| e.raw_os_error()),
            Some(Some(28)),
            "{e:?}"
        );
    }

    #[test]
    fn a_directory_target_is_an_error() {
        let d = dir("isdir");
        std::fs::create_dir(d.join("sub")).unwrap();
        assert!(write_atomic(d.join("sub"), b"x").is_err());
        assert_eq!(entries(&d), vec!["sub"]);
    }
}
