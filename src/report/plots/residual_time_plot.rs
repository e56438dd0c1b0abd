//! Plot: the residual y − ŷ over time, training and validation parts marked.

use crate::error::Result;
use crate::report::input::ReportInput;
use crate::report::plot::Plot;
use crate::report::style::*;
use plotters::prelude::*;

/// Residual over time with ±2 standard deviations of the training residual.
pub fn residual_time_plot(input: &ReportInput) -> Result<Plot> {
    let err = plot_err("residual time");
    let (t_label, ts) = time_axis(input.units.sample_time);
    let e_train = input.train.residual();
    let e_val = input
        .validation
        .as_ref()
        .map(|v| v.residual())
        .unwrap_or_default();
    let n_train = e_train.len();
    let n = n_train + e_val.len();
    let sd = (e_train.iter().map(|e| e * e).sum::<f64>() / n_train as f64).sqrt();
    let (lo, hi) = range_of([e_train.as_slice(), e_val.as_slice()], 0.08);
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (WIDTH, 300)).into_drawing_area();
        root.fill(&WHITE).map_err(&err)?;
        let mut chart = ChartBuilder::on(&root)
            .margin(12)
            .x_label_area_size(42)
            .y_label_area_size(70)
            .build_cartesian_2d(0.0..(n.max(2) - 1) as f64 * ts, lo..hi)
            .map_err(&err)?;
        mesh_style(&mut chart.configure_mesh(), 16)
            .x_desc(t_label)
            .y_desc(with_unit("residual y − ŷ", &input.units.output))
            .draw()
            .map_err(&err)?;
        if !e_val.is_empty() {
            let x0 = (n_train as f64 - 0.5) * ts;
            chart
                .draw_series(std::iter::once(Rectangle::new(
                    [(x0, lo), ((n - 1) as f64 * ts, hi)],
                    SHADE.filled(),
                )))
                .map_err(&err)?;
            chart
                .draw_series([
                    Text::new("training", (0.01 * n as f64 * ts, hi), label_font(16)),
                    Text::new(
                        "validation",
                        (x0 + 0.01 * n as f64 * ts, hi),
                        label_font(16),
                    ),
                ])
                .map_err(&err)?;
        }
        let x_end = (n.max(2) - 1) as f64 * ts;
        for (level, dashed) in [(0.0, false), (2.0 * sd, true), (-2.0 * sd, true)] {
            if dashed {
                chart
                    .draw_series(DashedLineSeries::new(
                        [(0.0, level), (x_end, level)],
                        6,
                        4,
                        BOUND.stroke_width(2),
                    ))
                    .map_err(&err)?;
            } else {
                chart
                    .draw_series(LineSeries::new(
                        [(0.0, level), (x_end, level)],
                        BLACK.mix(0.5),
                    ))
                    .map_err(&err)?;
            }
        }
        let mut all = e_train.clone();
        all.extend_from_slice(&e_val);
        chart
            .draw_series(LineSeries::new(
                thin(&all, 0, 1500).into_iter().map(|(k, v)| (k * ts, v)),
                MEASURED.stroke_width(1),
            ))
            .map_err(&err)?
            .label("residual")
            .legend(legend_line(MEASURED.stroke_width(2)));
        chart
            .draw_series(std::iter::once(PathElement::new(
                Vec::<(f64, f64)>::new(),
                BOUND.stroke_width(2),
            )))
            .map_err(&err)?
            .label("±2 std of the training residual")
            .legend(legend_line(BOUND.stroke_width(2)));
        draw_legend(&mut chart, SeriesLabelPosition::LowerRight, "residual time")?;
        root.present().map_err(&err)?;
    }
    Ok(Plot {
        id: "residual-time".into(),
        title: "Residual over time".into(),
        svg,
        caption: "What the model leaves unexplained. If the model is complete this looks like noise: \
                  no trend, no bursts at particular moments, the same spread in training and \
                  validation. Spikes where the input turns round point to hysteresis; bursts at the \
                  input's extremes to saturation; a slow wander to drift or a missing slow pole."
            .into(),
    })
}
