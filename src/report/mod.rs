//! Reports: SVG plots and one self-contained HTML page.
//!
//! A report is drawn from plain data ([`ReportInput`]: series, curves, tables), so it does not
//! depend on how the model was fitted; [`write_report`] writes one SVG per plot and `index.html`
//! with the SVGs inlined. Plots: measured vs simulated output, residual over time, residual against
//! input by direction of motion, the estimated nonlinearity's branches, residual correlations,
//! singular values for the order, and the validation error as effects are added.

pub mod bla_plot;
mod correlation_plot;
mod from_fit;
mod html;
mod input;
mod nonlinearity_plot;
mod order_plot;
mod output_map_plot;
mod output_plot;
mod plot;
mod residual_direction_plot;
mod residual_time_plot;
mod steps_plot;
mod style;
mod write;

pub use from_fit::{Context, autocorrelation, cross_correlation, report_input};
pub use html::escape;
pub use input::{
    Correlation, DiagnosisRow, NonlinearityCurve, OrderChoice, OutputMapCurve, Parameter, Record,
    ReportInput, Step, TestRow, Units,
};
pub use plot::Plot;
pub use write::{render_plots, write_report};
