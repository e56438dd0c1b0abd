//! Plot: the estimated static nonlinearity v = N(u) with its rising and falling branches, over the
//! data.

use crate::error::Result;
use crate::report::input::{NonlinearityCurve, ReportInput};
use crate::report::plot::Plot;
use crate::report::style::*;
use plotters::prelude::*;

/// The two branches of the estimated nonlinearity with the data's (u, v) points behind them.
pub fn nonlinearity_plot(input: &ReportInput, nl: &NonlinearityCurve) -> Result<Plot> {
    let err = plot_err("nonlinearity");
    let (ulo, uhi) = range_of([nl.u_grid.as_slice(), nl.data_u.as_slice()], 0.03);
    let (vlo, vhi) = range_of(
        [
            nl.v_rising.as_slice(),
            nl.v_falling.as_slice(),
            nl.data_v.as_slice(),
        ],
        0.06,
    );
    let idx = stride_indices(nl.data_u.len(), 3000);
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (WIDTH, 440)).into_drawing_area();
        root.fill(&WHITE).map_err(&err)?;
        let mut chart = ChartBuilder::on(&root)
            .margin(12)
            .x_label_area_size(42)
            .y_label_area_size(70)
            .build_cartesian_2d(ulo..uhi, vlo..vhi)
            .map_err(&err)?;
        mesh_style(&mut chart.configure_mesh(), 16)
            .x_desc(with_unit("input u", &input.units.input))
            .y_desc("nonlinearity output v (drives the linear block)")
            .draw()
            .map_err(&err)?;
        for (dir, colour) in [(-1.0, FALLING), (1.0, RISING)] {
            chart
                .draw_series(
                    idx.iter()
                        .filter(|&&k| nl.data_direction[k] == dir)
                        .map(|&k| {
                            Circle::new((nl.data_u[k], nl.data_v[k]), 2, colour.mix(0.18).filled())
                        }),
                )
                .map_err(&err)?;
        }
        let pairs = |v: &[f64]| {
            nl.u_grid
                .iter()
                .copied()
                .zip(v.iter().copied())
                .collect::<Vec<_>>()
        };
        chart
            .draw_series(LineSeries::new(
                pairs(&nl.v_falling),
                FALLING.stroke_width(3),
            ))
            .map_err(&err)?
            .label("falling branch (u decreasing)")
            .legend(legend_line(FALLING.stroke_width(3)));
        chart
            .draw_series(DashedLineSeries::new(
                pairs(&nl.v_rising),
                8,
                5,
                RISING.stroke_width(3),
            ))
            .map_err(&err)?
            .label("rising branch (u increasing)")
            .legend(legend_line(RISING.stroke_width(3)));
        draw_legend(&mut chart, SeriesLabelPosition::UpperLeft, "nonlinearity")?;
        root.present().map_err(&err)?;
    }
    let data = if nl.data_note.is_empty() {
        String::new()
    } else {
        format!(" Dots: {}", nl.data_note)
    };
    Ok(Plot {
        id: "nonlinearity".into(),
        title: format!("Estimated nonlinearity: {}", nl.name),
        svg,
        caption: format!(
            "The static actuator characteristic the model uses (its scale is fixed by the linear \
             block's normalisation). Orange dashed: the branch followed while the input rises; blue: \
             while it falls. Where the two branches part, the model has hysteresis (their horizontal \
             distance is 2a); flat ends are saturation, a flat middle a dead-zone, a jump at the \
             dead band a preload. Check that the data cover the region where the curve bends: a \
             threshold outside the data is a guess.{data}"
        ),
    })
}
