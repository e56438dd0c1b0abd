//! Plot: validation error before and after each added effect, with the noise floor when known.

use crate::error::Result;
use crate::report::input::{ReportInput, Step};
use crate::report::plot::Plot;
use crate::report::style::*;
use plotters::prelude::*;

/// One bar per step (validation MSE), fit % written on each, noise floor dashed.
pub fn steps_plot(steps: &[Step], input: &ReportInput) -> Result<Plot> {
    let err = plot_err("steps");
    let n = steps.len();
    // log scale: the later steps are often orders of magnitude below the linear model
    let values = || {
        steps
            .iter()
            .map(|s| s.validation_mse)
            .chain(input.noise_floor)
            .filter(|v| *v > 0.0)
    };
    let top = values().fold(f64::MIN_POSITIVE, f64::max) * 4.0;
    let bottom = values().fold(top, f64::min) / 3.0;
    let labels: Vec<String> = steps.iter().map(|s| s.label.clone()).collect();
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (WIDTH, 340)).into_drawing_area();
        root.fill(&WHITE).map_err(&err)?;
        let mut chart = ChartBuilder::on(&root)
            .margin(12)
            .x_label_area_size(48)
            .y_label_area_size(80)
            .build_cartesian_2d(
                (0..n as i32 - 1).into_segmented(),
                (bottom..top).log_scale(),
            )
            .map_err(&err)?;
        mesh_style(&mut chart.configure_mesh(), 16)
            .disable_x_mesh()
            .x_desc("model (each step adds the effect the diagnosis named)")
            .y_desc(with_unit(
                "validation MSE (log scale)",
                &if input.units.output.is_empty() {
                    String::new()
                } else {
                    format!("{}²", input.units.output)
                },
            ))
            .x_labels(n.max(1))
            .x_label_formatter(&|v| match v {
                SegmentValue::CenterOf(i) => labels.get(*i as usize).cloned().unwrap_or_default(),
                _ => String::new(),
            })
            .y_label_formatter(&|y| format!("{y:.0e}"))
            .draw()
            .map_err(&err)?;
        chart
            .draw_series(steps.iter().enumerate().map(|(i, s)| {
                let i = i as i32;
                let mut bar = Rectangle::new(
                    [
                        (SegmentValue::Exact(i), bottom),
                        (SegmentValue::Exact(i + 1), s.validation_mse.max(bottom)),
                    ],
                    MODEL.mix(0.75).filled(),
                );
                bar.set_margin(0, 0, 40, 40);
                bar
            }))
            .map_err(&err)?;
        chart
            .draw_series(steps.iter().enumerate().map(|(i, s)| {
                Text::new(
                    format!("MSE {:.3e}, fit {:.1} %", s.validation_mse, s.fit_percent),
                    (
                        SegmentValue::CenterOf(i as i32),
                        s.validation_mse.max(bottom) * 1.25,
                    ),
                    label_font(16).pos(plotters::style::text_anchor::Pos::new(
                        plotters::style::text_anchor::HPos::Center,
                        plotters::style::text_anchor::VPos::Bottom,
                    )),
                )
            }))
            .map_err(&err)?;
        if let Some(f) = input.noise_floor {
            chart
                .draw_series(DashedLineSeries::new(
                    [(SegmentValue::Exact(0), f), (SegmentValue::Last, f)],
                    8,
                    5,
                    ACCENT.stroke_width(2),
                ))
                .map_err(&err)?
                .label(format!("noise floor (noise variance {f:.3e})"))
                .legend(legend_line(ACCENT.stroke_width(2)));
            draw_legend(&mut chart, SeriesLabelPosition::UpperRight, "steps")?;
        }
        root.present().map_err(&err)?;
    }
    Ok(Plot {
        id: "steps".into(),
        title: "Validation error as effects are added".into(),
        svg,
        caption: "Each bar is one model, left to right in the order the effects were added; the \
                  error is measured on validation data (log scale: one grid step is a factor of \
                  ten). A named effect that is really present \
                  makes the bar drop clearly; once the bars reach the noise floor (dashed, when \
                  known) there is nothing left to explain and further effects only add parameters."
            .into(),
    })
}
