//! Reports: SVG plots and one self-contained HTML page.
//!
//! A report is drawn from plain data ([`ReportInput`]: series, curves, tables), so it does not
//! depend on how the model was fitted; [`write_report`] writes one SVG per plot and `index.html`
//! with the SVGs inlined. Plots: measured vs simulated output, residual over time, residual against
//! input by direction of motion, the estimated nonlinearity's branches, residual correlations,
//! singular values for the order, and the validation error as effects are added.

mod from_fit;
mod from_miso;
mod html;
mod input;
mod plot;
mod plots;
mod style;
mod write;

pub use from_fit::{Context, autocorrelation, cross_correlation, report_input};
pub use from_miso::miso_report_input;
pub use html::escape;
pub use input::{
    Correlation, DiagnosisRow, FeedbackCurve, NonlinearityCurve, OrderChoice, OutputMapCurve,
    Parameter, Record, ReportInput, Step, TestRow, Units,
};
pub use plot::Plot;
pub use plots::bla_plot;
pub use write::{render_plots, write_report};
