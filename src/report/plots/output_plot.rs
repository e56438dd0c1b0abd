//! Plot: measured against simulated output over time, training and validation parts marked.

use crate::error::Result;
use crate::report::input::ReportInput;
use crate::report::plot::Plot;
use crate::report::style::*;
use plotters::coord::Shift;
use plotters::prelude::*;

/// Length of the zoomed window.
const ZOOM: usize = 300;

fn zoom_panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    y: &[f64],
    y_hat: &[f64],
    start: usize,
    end: usize,
    ts: f64,
    t_label: &str,
    unit: &str,
) -> std::result::Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    let (lo, hi) = range_of([&y[start..end], &y_hat[start..end]], 0.08);
    let mut chart = ChartBuilder::on(area)
        .margin(12)
        .caption(format!("zoom: samples {start}–{}", end - 1), label_font(17))
        .x_label_area_size(42)
        .y_label_area_size(70)
        .build_cartesian_2d(start as f64 * ts..(end - 1) as f64 * ts, lo..hi)?;
    mesh_style(&mut chart.configure_mesh(), 16)
        .x_desc(t_label)
        .y_desc(with_unit("output y", unit))
        .draw()?;
    chart.draw_series(LineSeries::new(
        (start..end).map(|k| (k as f64 * ts, y_hat[k])),
        MODEL.stroke_width(2),
    ))?;
    chart.draw_series(LineSeries::new(
        (start..end).map(|k| (k as f64 * ts, y[k])),
        MEASURED.stroke_width(1),
    ))?;
    chart.draw_series(
        (start..end).map(|k| Circle::new((k as f64 * ts, y[k]), 2, MEASURED.filled())),
    )?;
    Ok(())
}

/// Measured vs simulated output, validation part shaded.
pub fn output_plot(input: &ReportInput) -> Result<Plot> {
    let err = plot_err("output");
    let (t_label, ts) = time_axis(input.units.sample_time);
    let n_train = input.train.len();
    let n_val = input.validation.as_ref().map_or(0, |v| v.len());
    let n = n_train + n_val;
    let mut y_all = input.train.y.clone();
    let mut yh_all = input.train.y_hat.clone();
    if let Some(v) = &input.validation {
        y_all.extend_from_slice(&v.y);
        yh_all.extend_from_slice(&v.y_hat);
    }
    let (lo, hi) = range_of([y_all.as_slice(), yh_all.as_slice()], 0.08);
    let mut svg = String::new();
    {
        let zoom = n > 2 * ZOOM;
        let height = if zoom { HEIGHT + 300 } else { HEIGHT };
        let full = SVGBackend::with_string(&mut svg, (WIDTH, height)).into_drawing_area();
        full.fill(&WHITE).map_err(&err)?;
        let (root, lower) = full.split_vertically(HEIGHT);
        if zoom {
            // a window of the validation part (or the end of training), where detail is visible
            let start = if n_val > 0 { n_train } else { n - ZOOM };
            let end = (start + ZOOM).min(n);
            zoom_panel(
                &lower,
                &y_all,
                &yh_all,
                start,
                end,
                ts,
                &t_label,
                &input.units.output,
            )
            .map_err(&err)?;
        }
        let mut chart = ChartBuilder::on(&root)
            .margin(12)
            .x_label_area_size(42)
            .y_label_area_size(70)
            .build_cartesian_2d(0.0..(n.max(2) - 1) as f64 * ts, lo..hi)
            .map_err(&err)?;
        mesh_style(&mut chart.configure_mesh(), 16)
            .x_desc(t_label.clone())
            .y_desc(with_unit("output y", &input.units.output))
            .draw()
            .map_err(&err)?;
        if n_val > 0 {
            let x0 = (n_train as f64 - 0.5) * ts;
            chart
                .draw_series(std::iter::once(Rectangle::new(
                    [(x0, lo), ((n - 1) as f64 * ts, hi)],
                    SHADE.filled(),
                )))
                .map_err(&err)?;
            let font = label_font(16);
            chart
                .draw_series([
                    Text::new("training", (0.01 * n as f64 * ts, hi), font.clone()),
                    Text::new(
                        "validation (not used for fitting)",
                        (x0 + 0.01 * n as f64 * ts, hi),
                        font,
                    ),
                ])
                .map_err(&err)?;
        }
        let buckets = 1500;
        chart
            .draw_series(LineSeries::new(
                thin(&y_all, 0, buckets)
                    .into_iter()
                    .map(|(k, v)| (k * ts, v)),
                MEASURED.stroke_width(1),
            ))
            .map_err(&err)?
            .label("measured y")
            .legend(legend_line(MEASURED.stroke_width(2)));
        chart
            .draw_series(LineSeries::new(
                thin(&yh_all, 0, buckets)
                    .into_iter()
                    .map(|(k, v)| (k * ts, v)),
                MODEL.stroke_width(2),
            ))
            .map_err(&err)?
            .label("simulated ŷ (free run)")
            .legend(legend_line(MODEL.stroke_width(2)));
        draw_legend(&mut chart, SeriesLabelPosition::LowerRight, "output")?;
        full.present().map_err(&err)?;
    }
    Ok(Plot {
        id: "output".into(),
        title: "Measured and simulated output".into(),
        svg,
        caption: "Grey: measured output; blue: the model simulated from the input alone (free run, \
                  initial state estimated). The shaded part is validation data the model never saw; on long records the lower \
                  panel zooms into its first samples (measured as dots). \
                  Look for systematic misses: clipped peaks or plateaus the model overshoots point to \
                  saturation, a lag that depends on the direction of motion to hysteresis, a constant \
                  shift to an offset."
            .into(),
    })
}
