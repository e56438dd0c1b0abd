//! Plots: singular values of the subspace step on a log scale, with the chosen order marked;
//! the automatic order selection's criterion per candidate.

use crate::error::Result;
use crate::report::input::{OrderChoice, ReportInput};
use crate::report::plot::Plot;
use crate::report::style::*;
use plotters::prelude::*;

/// Singular values (log scale), the kept ones highlighted, a line between order n and n+1.
pub fn order_plot(o: &OrderChoice, _input: &ReportInput) -> Result<Plot> {
    let err = plot_err("singular values");
    let sv: Vec<(f64, f64)> = o
        .singular_values
        .iter()
        .enumerate()
        .filter(|(_, s)| **s > 0.0)
        .map(|(i, &s)| ((i + 1) as f64, s))
        .collect();
    let smax = sv.iter().fold(f64::MIN_POSITIVE, |m, p| m.max(p.1));
    let smin = sv.iter().fold(smax, |m, p| m.min(p.1)).max(smax * 1e-12);
    let n = o.singular_values.len().max(1) as f64;
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (WIDTH, 320)).into_drawing_area();
        root.fill(&WHITE).map_err(&err)?;
        let mut chart = ChartBuilder::on(&root)
            .margin(12)
            .x_label_area_size(42)
            .y_label_area_size(80)
            .build_cartesian_2d(0.5..n + 0.5, (smin / 2.0..smax * 2.0).log_scale())
            .map_err(&err)?;
        mesh_style(&mut chart.configure_mesh(), 16)
            .x_desc("index i")
            .y_desc("singular value σᵢ (log)")
            .x_labels(o.singular_values.len().clamp(2, 30))
            .x_label_formatter(&|x| format!("{x:.0}"))
            .y_label_formatter(&|y| format!("{y:.0e}"))
            .draw()
            .map_err(&err)?;
        chart
            .draw_series(LineSeries::new(sv.iter().copied(), MEASURED.mix(0.6)))
            .map_err(&err)?;
        chart
            .draw_series(sv.iter().map(|&(i, s)| {
                if (i as usize) <= o.chosen {
                    Circle::new((i, s), 5, ACCENT.filled())
                } else {
                    Circle::new((i, s), 4, MEASURED.mix(0.6).filled())
                }
            }))
            .map_err(&err)?;
        let x = o.chosen as f64 + 0.5;
        chart
            .draw_series(DashedLineSeries::new(
                [(x, smin / 2.0), (x, smax * 2.0)],
                6,
                4,
                ACCENT.stroke_width(2),
            ))
            .map_err(&err)?;
        chart
            .draw_series(std::iter::once(Text::new(
                format!("chosen order n = {}", o.chosen),
                (x + 0.1, smax * 1.2),
                label_font(17),
            )))
            .map_err(&err)?;
        root.present().map_err(&err)?;
    }
    Ok(Plot {
        id: "order".into(),
        title: "Singular values and the model order".into(),
        svg,
        caption: "Singular values of the subspace step (log scale); green dots are the kept ones. \
                  A clear gap right after the dashed line means the order is well defined; a smooth \
                  decay means the data do not pin it down and neighbouring orders deserve a try. \
                  Values that stay high far beyond the chosen order can be noise, or dynamics the \
                  static nonlinearity does not explain."
            .into(),
    })
}

/// The information criterion of every candidate order (and feed-through) of the automatic
/// selection, the chosen one marked.
pub fn order_criterion_plot(o: &OrderChoice, _input: &ReportInput) -> Result<Plot> {
    let err = plot_err("order selection");
    let pts = |d: bool| -> Vec<(f64, f64)> {
        o.criterion
            .iter()
            .filter(|c| c.1 == d && c.2.is_finite())
            .map(|c| (c.0 as f64, c.2))
            .collect()
    };
    let (without, with) = (pts(false), pts(true));
    let all: Vec<(f64, f64)> = without.iter().chain(&with).copied().collect();
    let best = all
        .iter()
        .copied()
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .unwrap_or((1.0, 0.0));
    let (lo, hi) = all
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), p| {
            (l.min(p.1), h.max(p.1))
        });
    let pad = ((hi - lo) * 0.1).max(1.0);
    let nmax = all.iter().fold(1.0f64, |m, p| m.max(p.0));
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (WIDTH, 300)).into_drawing_area();
        root.fill(&WHITE).map_err(&err)?;
        let mut chart = ChartBuilder::on(&root)
            .margin(12)
            .x_label_area_size(42)
            .y_label_area_size(80)
            .build_cartesian_2d(0.5..nmax + 0.5, lo - pad..hi + pad)
            .map_err(&err)?;
        mesh_style(&mut chart.configure_mesh(), 16)
            .x_desc("model order n")
            .y_desc("BIC (training part)")
            .x_labels((nmax as usize).clamp(2, 12))
            .x_label_formatter(&|x| format!("{x:.0}"))
            .y_label_formatter(&|y| format!("{y:.0}"))
            .draw()
            .map_err(&err)?;
        chart
            .draw_series(LineSeries::new(without.iter().copied(), MEASURED.mix(0.7)))
            .map_err(&err)?;
        chart
            .draw_series(
                without
                    .iter()
                    .map(|&p| Circle::new(p, 4, MEASURED.filled())),
            )
            .map_err(&err)?;
        chart
            .draw_series(
                with.iter()
                    .map(|&p| TriangleMarker::new(p, 6, MODEL.filled())),
            )
            .map_err(&err)?;
        chart
            .draw_series(std::iter::once(Circle::new(
                best,
                8,
                ACCENT.stroke_width(3),
            )))
            .map_err(&err)?;
        chart
            .draw_series(std::iter::once(Text::new(
                format!("chosen: order {}", best.0),
                (best.0 + 0.1, best.1 + pad * 0.5),
                label_font(17),
            )))
            .map_err(&err)?;
        root.present().map_err(&err)?;
    }
    Ok(Plot {
        id: "order-selection".into(),
        title: "Order selection".into(),
        svg,
        caption:
            "Every candidate order was fitted completely (loop and refinement) on the training \
                  part and scored by BIC = N·ln(MSE) + (k − n)·ln(N) + 2n, the n initial states \
                  charged 2 each (dots: D = 0; triangles: with a \
                  direct feed-through D). The circled candidate, the lowest, is the model. A flat \
                  bottom means neighbouring orders explain the data almost equally well."
                .into(),
    })
}
