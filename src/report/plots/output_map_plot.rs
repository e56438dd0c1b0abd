//! Plot: the estimated output map y = g(x) of a Hammerstein–Wiener model (the linear block's
//! output x against the measured output), over the data.

use crate::error::Result;
use crate::report::input::{OutputMapCurve, ReportInput};
use crate::report::plot::Plot;
use crate::report::style::*;
use plotters::prelude::*;

/// The output map as a curve with the training record's (x, y) points behind it.
pub fn output_map_plot(input: &ReportInput, g: &OutputMapCurve) -> Result<Plot> {
    let err = plot_err("output map");
    let (xlo, xhi) = range_of([g.x_grid.as_slice(), g.data_x.as_slice()], 0.03);
    let (ylo, yhi) = range_of([g.y_grid.as_slice(), g.data_y.as_slice()], 0.06);
    let idx = stride_indices(g.data_x.len(), 3000);
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (WIDTH, 440)).into_drawing_area();
        root.fill(&WHITE).map_err(&err)?;
        let mut chart = ChartBuilder::on(&root)
            .margin(12)
            .x_label_area_size(42)
            .y_label_area_size(70)
            .build_cartesian_2d(xlo..xhi, ylo..yhi)
            .map_err(&err)?;
        mesh_style(&mut chart.configure_mesh(), 16)
            .x_desc(with_unit("linear block output x", &input.units.output))
            .y_desc(with_unit("output y", &input.units.output))
            .draw()
            .map_err(&err)?;
        chart
            .draw_series(
                idx.iter().map(|&k| {
                    Circle::new((g.data_x[k], g.data_y[k]), 2, RISING.mix(0.18).filled())
                }),
            )
            .map_err(&err)?;
        let pairs: Vec<(f64, f64)> = g
            .x_grid
            .iter()
            .copied()
            .zip(g.y_grid.iter().copied())
            .collect();
        chart
            .draw_series(LineSeries::new(pairs, FALLING.stroke_width(3)))
            .map_err(&err)?
            .label(format!("g(x) + offset ({})", g.name))
            .legend(legend_line(FALLING.stroke_width(3)));
        draw_legend(&mut chart, SeriesLabelPosition::UpperLeft, "output map")?;
        root.present().map_err(&err)?;
    }
    Ok(Plot {
        id: "output-map".into(),
        title: format!("Estimated output map: {}", g.name),
        svg,
        caption: "The static map after the linear block (Hammerstein–Wiener): the linear block's \
                  output x (offset removed) against the output y. The map has unit slope and zero \
                  value at x = 0, so the small-signal gain sits in the nonlinearity and the linear \
                  block; the curve shows how the output departs from it. Dots: the measured output \
                  against the model's x along the training record; their spread around the curve \
                  is noise and dynamics the model misses."
            .into(),
    })
}
