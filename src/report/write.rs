//! Writing a report: one SVG file per plot and one self-contained `index.html`.

use super::correlation_plot::correlation_plot;
use super::html::page;
use super::input::ReportInput;
use super::nonlinearity_plot::nonlinearity_plot;
use super::order_plot::{order_criterion_plot, order_plot};
use super::output_plot::output_plot;
use super::plot::Plot;
use super::residual_direction_plot::residual_direction_plot;
use super::residual_time_plot::residual_time_plot;
use super::steps_plot::steps_plot;
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

fn write(path: &Path, text: &str) -> Result<()> {
    std::fs::write(path, text).map_err(|e| Error::io(path.display(), e))
}

/// Writes `<id>.svg` for every plot and `index.html` into `dir` (created if needed); returns the
/// path of `index.html`. Validates the input first: non-finite numbers are an error.
pub fn write_report(dir: &Path, input: &ReportInput) -> Result<PathBuf> {
    let plots = render_plots(input)?;
    std::fs::create_dir_all(dir).map_err(|e| Error::io(dir.display(), e))?;
    for p in &plots {
        write(&dir.join(format!("{}.svg", p.id)), &p.svg)?;
    }
    let index = dir.join("index.html");
    write(&index, &page(input, &plots))?;
    Ok(index)
}
