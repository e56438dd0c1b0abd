//! Plot: residual autocorrelation and residual–input cross-correlation with confidence bounds.

use crate::error::Result;
use crate::report::input::{Correlation, ReportInput};
use crate::report::plot::Plot;
use crate::report::style::*;
use plotters::coord::Shift;
use plotters::prelude::*;

fn panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    c: &Correlation,
    title: &str,
    x_desc: &str,
) -> std::result::Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    let lmin = c.lags.iter().copied().min().unwrap_or(0) as f64 - 0.5;
    let lmax = c.lags.iter().copied().max().unwrap_or(1) as f64 + 0.5;
    let m = c
        .values
        .iter()
        .fold(c.bound, |m, v| m.max(v.abs()))
        .max(1e-12)
        * 1.1;
    let mut chart = ChartBuilder::on(area)
        .margin(12)
        .caption(title, label_font(18))
        .x_label_area_size(42)
        .y_label_area_size(60)
        .build_cartesian_2d(lmin..lmax, -m..m)?;
    mesh_style(&mut chart.configure_mesh(), 15)
        .x_desc(x_desc)
        .y_desc("normalised correlation")
        .draw()?;
    chart.draw_series(LineSeries::new([(lmin, 0.0), (lmax, 0.0)], BLACK.mix(0.5)))?;
    for b in [c.bound, -c.bound] {
        chart.draw_series(DashedLineSeries::new(
            [(lmin, b), (lmax, b)],
            6,
            4,
            BOUND.stroke_width(2),
        ))?;
    }
    for (&l, &v) in c.lags.iter().zip(&c.values) {
        let colour = if v.abs() > c.bound { RISING } else { MODEL };
        chart.draw_series(LineSeries::new(
            [(l as f64, 0.0), (l as f64, v)],
            colour.stroke_width(2),
        ))?;
        chart.draw_series(std::iter::once(Circle::new(
            (l as f64, v),
            3,
            colour.filled(),
        )))?;
    }
    Ok(())
}

/// Autocorrelation (left) and cross-correlation with the input (right), outside-bound lags in orange.
pub fn correlation_plot(
    ac: Option<&Correlation>,
    xc: Option<&Correlation>,
    _input: &ReportInput,
) -> Result<Plot> {
    let err = plot_err("correlation");
    let mut svg = String::new();
    let level = ac.or(xc).map_or(0.99, |c| c.level);
    {
        let root = SVGBackend::with_string(&mut svg, (WIDTH, 340)).into_drawing_area();
        root.fill(&WHITE).map_err(&err)?;
        let (left, right) = root.split_horizontally(WIDTH / 2);
        if let Some(c) = ac {
            panel(&left, c, "residual autocorrelation", "lag τ [samples]").map_err(&err)?;
        }
        if let Some(c) = xc {
            panel(
                &right,
                c,
                "cross-correlation residual ↔ input",
                "lag τ [samples] (τ > 0: input leads)",
            )
            .map_err(&err)?;
        }
        root.present().map_err(&err)?;
    }
    Ok(Plot {
        id: "correlation".into(),
        title: "Residual correlation tests".into(),
        svg,
        caption: format!(
            "Dashed: the {:.0} % confidence band for white residuals independent of the input; \
             orange stems leave it. Autocorrelation outside the band at small lags means the \
             residual has structure (missing dynamics, or a missing nonlinearity seen through the \
             dynamics). Cross-correlation outside the band at positive lags means part of the \
             output is still a (linear or nonlinear) function of past inputs: the model is \
             incomplete; at negative lags it suggests feedback. Lag 0 of the autocorrelation is 1 \
             by definition and is not shown.",
            100.0 * level
        ),
    })
}
