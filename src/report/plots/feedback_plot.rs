//! Plot: the nonlinearity in feedback w = f(z) over the range z visits, with its uncertainty
//! band, and the distribution of z along the training record beneath it.

use crate::error::Result;
use crate::report::input::{FeedbackCurve, ReportInput};
use crate::report::plot::Plot;
use crate::report::style::*;
use plotters::prelude::*;

/// f(z) with a ±2 standard-error band; ticks along the bottom mark the visited z.
pub fn feedback_plot(input: &ReportInput, f: &FeedbackCurve) -> Result<Plot> {
    let err = plot_err("feedback nonlinearity");
    let upper: Vec<f64> = f.w.iter().zip(&f.se).map(|(w, s)| w + 2.0 * s).collect();
    let lower: Vec<f64> = f.w.iter().zip(&f.se).map(|(w, s)| w - 2.0 * s).collect();
    let (zlo, zhi) = range_of([f.z_grid.as_slice()], 0.03);
    let (wlo, whi) = range_of([upper.as_slice(), lower.as_slice(), f.w.as_slice()], 0.08);
    let idx = stride_indices(f.data_z.len(), 3000);
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (WIDTH, 440)).into_drawing_area();
        root.fill(&WHITE).map_err(&err)?;
        let mut chart = ChartBuilder::on(&root)
            .margin(12)
            .x_label_area_size(42)
            .y_label_area_size(70)
            .build_cartesian_2d(zlo..zhi, wlo..whi)
            .map_err(&err)?;
        mesh_style(&mut chart.configure_mesh(), 16)
            .x_desc(with_unit("feedback variable z", &input.units.output))
            .y_desc(with_unit(
                "w = f(z), as an equivalent input",
                &input.units.input,
            ))
            .draw()
            .map_err(&err)?;
        let mut band: Vec<(f64, f64)> = f.z_grid.iter().copied().zip(upper).collect();
        band.extend(f.z_grid.iter().copied().zip(lower).rev());
        chart
            .draw_series(std::iter::once(Polygon::new(
                band,
                BOUND.mix(0.25).filled(),
            )))
            .map_err(&err)?
            .label("± 2 standard errors")
            .legend(|(x, y)| {
                Rectangle::new([(x, y - 5), (x + 20, y + 5)], BOUND.mix(0.25).filled())
            });
        // the visited z: a rug along the bottom
        let tick = (whi - wlo) * 0.03;
        chart
            .draw_series(idx.iter().map(|&k| {
                PathElement::new(
                    vec![(f.data_z[k], wlo), (f.data_z[k], wlo + tick)],
                    MEASURED.mix(0.15).stroke_width(1),
                )
            }))
            .map_err(&err)?;
        let pairs: Vec<(f64, f64)> = f.z_grid.iter().copied().zip(f.w.iter().copied()).collect();
        chart
            .draw_series(LineSeries::new(pairs, MODEL.stroke_width(3)))
            .map_err(&err)?
            .label(format!("f(z): {}", f.name))
            .legend(legend_line(MODEL.stroke_width(3)));
        draw_legend(
            &mut chart,
            SeriesLabelPosition::UpperRight,
            "feedback nonlinearity",
        )?;
        root.present().map_err(&err)?;
    }
    Ok(Plot {
        id: "feedback-nonlinearity".into(),
        title: format!("Nonlinearity in feedback: {}", f.name),
        svg,
        caption: format!(
            "The static nonlinearity the model feeds back, w = f(z), drawn over the range z \
             visits on the training record (ticks along the bottom: the model's z along the \
             record); w is in input units, the input that would act on the linear block the same \
             way. The shaded band is ± 2 standard errors of f(z). {} A band that includes zero \
             everywhere means the data do not show the nonlinearity; outside the ticks the curve \
             is an extrapolation.",
            f.method
        ),
    })
}
