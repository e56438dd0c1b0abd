//! Observers: callbacks the loop notifies after every iteration and at the end (progress bars,
//! logging, convergence plots). They only watch; they cannot change the fit.

use super::fit_report::{FitReport, IterationRecord};
use std::io::Write;

/// Watches a fit. Both methods default to doing nothing.
pub trait Observer: Send + Sync {
    /// Called after iteration `index` (0-based) with its record.
    fn observe_iteration(&self, _index: usize, _record: &IterationRecord) {}
    /// Called once with the final report (before the model is returned).
    fn observe_final(&self, _report: &FitReport) {}
    /// Called as a long task advances: `stage` (what runs now), `done` of `total` steps.
    fn progress(&self, _stage: &str, _done: usize, _total: usize) {}
}

/// An observer from a closure over (iteration index, record).
pub struct FnObserver<F: Fn(usize, &IterationRecord) + Send + Sync>(pub F);

impl<F: Fn(usize, &IterationRecord) + Send + Sync> Observer for FnObserver<F> {
    fn observe_iteration(&self, index: usize, record: &IterationRecord) {
        (self.0)(index, record)
    }
}

/// Prints one line per iteration to standard error.
#[derive(Debug, Clone, Copy, Default)]
pub struct StderrObserver;

impl Observer for StderrObserver {
    // writeln! rather than eprintln!: a closed standard error must not panic the fit
    fn observe_iteration(&self, index: usize, record: &IterationRecord) {
        let _ = writeln!(
            std::io::stderr(),
            "iteration {index:3}: mse {:.6e}  params {:?}",
            record.mse,
            record.params
        );
    }
    fn observe_final(&self, report: &FitReport) {
        let _ = writeln!(
            std::io::stderr(),
            "finished: {:?} after {} iteration(s), best {} (mse {:.6e})",
            report.termination,
            report.iterations.len(),
            report.best_iteration,
            report.train_mse
        );
    }
}
