//! Writing a report: one SVG file per plot and one self-contained `index.html`.

use super::html::page;
use super::input::ReportInput;
use super::plot::Plot;
use super::plots::correlation_plot::correlation_plot;
use super::plots::feedback_plot::feedback_plot;
use super::plots::nonlinearity_plot::nonlinearity_plot;
use super::plots::order_plot::{order_criterion_plot, order_plot};
use super::plots::output_map_plot::output_map_plot;
use super::plots::output_plot::output_plot;
use super::plots::residual_direction_plot::residual_direction_plot;
use super::plots::residual_time_plot::residual_time_plot;
use super::plots::steps_plot::steps_plot;
use crate::error::{Error, Result};
use std::path::{Path, PathBuf};

/// Draws every plot the input has data for, in reading order.
pub fn render_plots(input: &ReportInput) -> Result<Vec<Plot>> {
    input.validate()?;
    let mut plots = vec![
        output_plot(input)?,
        residual_time_plot(input)?,
        residual_direction_plot(input)?,
    ];
    if let Some(nl) = &input.nonlinearity {
        plots.push(nonlinearity_plot(input, nl)?);
    }
    for (k, (name, unit, nl)) in input.other_inputs.iter().enumerate() {
        // the same plot with the other input's unit on its axis
        let mut view = input.clone();
        view.units.input = unit.clone();
        let mut p = nonlinearity_plot(&view, nl)?;
        p.id = format!("nonlinearity-input-{}", k + 2);
        p.title = format!("{} (input {name})", p.title);
        plots.push(p);
    }
    if let Some(g) = &input.output_map {
        plots.push(output_map_plot(input, g)?);
    }
    if let Some(f) = &input.feedback {
        plots.push(feedback_plot(input, f)?);
    }
    if input.autocorrelation.is_some() || input.cross_correlation.is_some() {
        plots.push(correlation_plot(
            input.autocorrelation.as_ref(),
            input.cross_correlation.as_ref(),
            input,
        )?);
    }
    if let Some(o) = &input.order {
        plots.push(order_plot(o, input)?);
        if !o.criterion.is_empty() {
            plots.push(order_criterion_plot(o, input)?);
        }
    }
    if !input.steps.is_empty() {
        plots.push(steps_plot(&input.steps, input)?);
    }
    Ok(plots)
}

/// Writes `<id>.svg` for every plot and `index.html` into `dir` (created if needed); returns the
/// path of `index.html`. Validates the input first: non-finite numbers are an error.
///
/// Every page and plot is rendered in memory first; then each file is written to a temporary
/// beside its target and, once all are complete, renamed into place with `index.html` last
/// ([`write_all_atomic`](crate::atomic::write_all_atomic)): a failed write (full disk, file
/// size limit) leaves a previous report in `dir` as it was, never half new.
pub fn write_report(dir: &Path, input: &ReportInput) -> Result<PathBuf> {
    let plots = render_plots(input)?;
    let index = dir.join("index.html");
    let html = page(input, &plots);
    std::fs::create_dir_all(dir).map_err(|e| Error::io(dir.display(), e))?;
    let mut files: Vec<(PathBuf, Vec<u8>)> = plots
        .iter()
        .map(|p| {
            (
                dir.join(format!("{}.svg", p.id)),
                p.svg.clone().into_bytes(),
            )
        })
        .collect();
    files.push((index.clone(), html.into_bytes()));
    crate::atomic::write_all_atomic(&files)?;
    Ok(index)
}
