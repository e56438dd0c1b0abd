//! Subcommands of the command line, one file each, and the output helpers they share.
//!
//! Nothing here prints with `println!` (which panics when standard output is closed early, as in
//! `hammerstein simulate … | head -1`, or full, as `> /dev/full`): text goes through [`out`],
//! whose failures come back as [`Failure::Output`]; `main` ends quietly with status 141 on a
//! broken pipe and with a one-line error on any other write failure.

/// Writes formatted text to standard output: `outp!(...)?` (the counterpart of `print!`).
macro_rules! outp {
    ($($arg:tt)*) => {
        $crate::cli::out(&format!($($arg)*))
    };
}

/// Writes a formatted line to standard output: `outln!(...)?` (the counterpart of `println!`).
macro_rules! outln {
    () => {
        $crate::cli::out("\n")
    };
    ($($arg:tt)*) => {
        $crate::cli::out(&format!("{}\n", format_args!($($arg)*)))
    };
}

use std::io::Write;

/// Why a subcommand failed: kept typed until `main` prints it as one line.
#[derive(Debug, thiserror::Error)]
pub enum Failure {
    /// The library refused (bad data, a failed fit, an unreadable file…).
    #[error(transparent)]
    Library(#[from] hammerstein::Error),
    /// A JSON value could not be built.
    #[error(transparent)]
    Json(#[from] serde_json::Error),
    /// A one-line message of the command line's own (bad options, unwritable paths…).
    #[error("{0}")]
    Message(String),
    /// Writing to standard output failed (a closed pipe, a full disk).
    #[error("cannot write to standard output: {0}")]
    Output(#[source] std::io::Error),
}

impl From<String> for Failure {
    fn from(msg: String) -> Self {
        Failure::Message(msg)
    }
}

impl From<&str> for Failure {
    fn from(msg: &str) -> Self {
        Failure::Message(msg.to_string())
    }
}

/// The result of a subcommand.
pub type CliResult = Result<(), Failure>;

/// Writes `text` to standard output and flushes it; failures (a closed pipe included) are
/// returned, never a panic.
pub fn out(text: &str) -> CliResult {
    let mut o = std::io::stdout().lock();
    o.write_all(text.as_bytes())
        .and_then(|()| o.flush())
        .map_err(Failure::Output)
}

/// Writes a line to standard error, ignoring failures (a closed standard error has no one to
/// tell; the exit status still reports the outcome).
pub fn note(text: &str) {
    let _ = writeln!(std::io::stderr().lock(), "{text}");
}

pub mod common;
pub mod compare;
pub mod demo;
pub mod diagnose;
pub mod experiment;
pub mod feedback;
pub mod fit;
pub mod miso;
pub mod paper;
pub mod paths;
pub mod saved;
pub mod simulate;
pub mod stability;
pub mod subspace;

pub use experiment::{bla, design, structure};

/// Writes the HTML report of a model and its diagnosis into `dir` (the `--report` option).
pub fn write_model_report<T: hammerstein::Real>(
    dir: &std::path::Path,
    data: &std::path::Path,
    model: &hammerstein::fit::HammersteinModel<T>,
    diagnosis: &hammerstein::diagnosis::Diagnosis<T>,
    train: &hammerstein::IoData<T>,
) -> Result<(), Failure> {
    use hammerstein::report::{Context, Step, report_input, write_report};
    let ctx = Context {
        title: format!("Hammerstein model of {}", data.display()),
        dataset: data.display().to_string(),
        units: common::units_of(train),
        steps: vec![Step {
            label: model.nonlinearity().name(),
            validation_mse: diagnosis.validation.metrics.mse,
            fit_percent: diagnosis.validation.metrics.fit_percent,
        }],
        ..Default::default()
    };
    let input = report_input(model, diagnosis, ctx)?;
    let path = write_report(dir, &input)?;
    note(&format!("report written to {}", path.display()));
    Ok(())
}

/// A spinner on stderr for work that may take more than a second (hidden when stderr is not a
/// terminal, so `--json` into a pipe stays quiet); finish it with `finish_and_clear`.
pub fn spinner(message: &str) -> indicatif::ProgressBar {
    let pb =
        indicatif::ProgressBar::with_draw_target(None, indicatif::ProgressDrawTarget::stderr());
    if let Ok(style) = indicatif::ProgressStyle::with_template("{spinner} {msg}  {elapsed}") {
        pb.set_style(style);
    }
    pb.set_message(message.to_string());
    pb.enable_steady_tick(std::time::Duration::from_millis(120));
    pb
}

/// The process's resident memory now and at its peak (Linux `/proc/self/status`), for the
/// stage log; empty elsewhere.
pub fn memory_note() -> String {
    let Ok(status) = std::fs::read_to_string("/proc/self/status") else {
        return String::new();
    };
    let mb = |key: &str| {
        status
            .lines()
            .find(|l| l.starts_with(key))
            .and_then(|l| l.split_whitespace().nth(1))
            .and_then(|kb| kb.parse::<f64>().ok())
            .map_or(f64::NAN, |kb| kb / 1024.0)
    };
    format!(
        "  [RSS {:.0} MB, peak {:.0} MB]",
        mb("VmRSS:"),
        mb("VmHWM:")
    )
}

/// An observer that shows a long task's stages on a spinner from [`spinner`] (stage and step
/// count in its message; nothing is drawn when stderr is not a terminal).
pub struct ProgressObserver {
    bar: indicatif::ProgressBar,
    prefix: String,
    /// With the environment variable `HAMMERSTEIN_STAGES` set: every stage is also logged to
    /// stderr with the seconds since the start and the resident memory, now and at its peak
    /// (profiling long runs).
    log: Option<std::time::Instant>,
}

impl ProgressObserver {
    /// Reports on `bar`, each stage's message after `prefix`.
    pub fn new(bar: &indicatif::ProgressBar, prefix: &str) -> std::sync::Arc<Self> {
        std::sync::Arc::new(Self {
            bar: bar.clone(),
            prefix: prefix.to_string(),
            log: std::env::var_os("HAMMERSTEIN_STAGES").map(|_| std::time::Instant::now()),
        })
    }
}

/// Makes every thread allocate from glibc's main arena (`mallopt(M_ARENA_MAX, 1)`; nothing
/// elsewhere). By default each worker thread of the parallel candidate refits gets its own
/// arena, which keeps the freed memory of its fits beside the others': at 1e6 samples `diagnose`
/// peaks at 77–79 MiB with them and 60–65 MiB with one arena, with the same output and the
/// same CPU time (the threads' allocations are small against their arithmetic). Called once,
/// before any thread starts.
pub fn single_allocator_arena() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    {
        /// glibc's `M_ARENA_MAX` (malloc.h).
        const M_ARENA_MAX: std::os::raw::c_int = -8;
        unsafe extern "C" {
            fn mallopt(
                param: std::os::raw::c_int,
                value: std::os::raw::c_int,
            ) -> std::os::raw::c_int;
        }
        // SAFETY: mallopt sets a tuning parameter of glibc's allocator; called before any
        // other thread exists, it races with no allocation
        unsafe {
            mallopt(M_ARENA_MAX, 1);
        }
    }
}

/// Hands the allocator's free memory back to the system (glibc's `malloc_trim`; nothing
/// elsewhere). Called between the stages of a long task: the worker threads' allocator arenas
/// keep what the leading window's fits freed (up to twice the largest signal freed so far each,
/// glibc's dynamic trim threshold), which the whole-record stages on the main thread cannot
/// reuse — at 1e6 samples 8–10 MB of the `diagnose` command's peak.
pub fn release_free_memory() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    {
        unsafe extern "C" {
            fn malloc_trim(pad: usize) -> std::os::raw::c_int;
        }
        // SAFETY: malloc_trim only returns free pages of glibc's own arenas to the system; it
        // takes the arenas' locks and touches no live allocation
        unsafe {
            malloc_trim(0);
        }
    }
}

impl hammerstein::fit::Observer for ProgressObserver {
    fn progress(&self, stage: &str, done: usize, total: usize) {
        release_free_memory();
        if let Some(t0) = self.log {
            let _ = writeln!(
                std::io::stderr(),
                "[{:8.3} s] {stage} ({done}/{total}){}",
                t0.elapsed().as_secs_f64(),
                memory_note()
            );
        }
        self.bar
            .set_message(format!("{}: {stage} ({done}/{total})", self.prefix));
    }
}

/// Ignores SIGXFSZ, so that a write beyond the file-size limit (`ulimit -f`) fails with EFBIG —
/// reported as an error, the temporary file removed — instead of killing the process silently
/// and leaving the temporary behind. Unix only; the signal's number is 25 on Linux (all but
/// MIPS), macOS and the BSDs, 31 on MIPS Linux.
pub fn ignore_file_size_signal() {
    #[cfg(unix)]
    {
        #[cfg(any(target_arch = "mips", target_arch = "mips64"))]
        const SIGXFSZ: std::os::raw::c_int = 31;
        #[cfg(not(any(target_arch = "mips", target_arch = "mips64")))]
        const SIGXFSZ: std::os::raw::c_int = 25;
        /// `SIG_IGN` of `<signal.h>`: the handler value 1.
        const SIG_IGN: usize = 1;
        unsafe extern "C" {
            fn signal(signum: std::os::raw::c_int, handler: usize) -> usize;
        }
        // SAFETY: `signal` with SIG_IGN installs no handler code; it only changes the
        // disposition of one signal, before any thread is started
        unsafe {
            signal(SIGXFSZ, SIG_IGN);
        }
    }
}
