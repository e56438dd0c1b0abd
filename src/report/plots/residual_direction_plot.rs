//! Plot: the residual against the input, split by the input's direction of motion — the picture
//! that shows a missing hysteresis (the two directions separate).

use crate::error::Result;
use crate::regressors::directions;
use crate::report::input::ReportInput;
use crate::report::plot::Plot;
use crate::report::style::*;
use plotters::prelude::*;

/// Mean residual per input bin for one direction: (bin centre, mean) of bins with enough samples.
fn binned_means(u: &[f64], e: &[f64], s: &[f64], dir: f64, edges: &[f64]) -> Vec<(f64, f64)> {
    let nb = edges.len() - 1;
    let mut sum = vec![0.0; nb];
    let mut cnt = vec![0usize; nb];
    for k in 0..u.len() {
        if s[k] != dir {
            continue;
        }
        let b = edges[1..nb].partition_point(|&x| x <= u[k]);
        sum[b] += e[k];
        cnt[b] += 1;
    }
    (0..nb)
        .filter(|&b| cnt[b] >= 5)
        .map(|b| (0.5 * (edges[b] + edges[b + 1]), sum[b] / cnt[b] as f64))
        .collect()
}

/// Residual vs input, rising and falling samples in two colours, with binned means.
pub fn residual_direction_plot(input: &ReportInput) -> Result<Plot> {
    let err = plot_err("residual vs input");
    let u = &input.train.u;
    let referred = input.referred_residual.is_some();
    let e = input
        .referred_residual
        .clone()
        .unwrap_or_else(|| input.train.residual());
    let s = directions(u);
    let (ulo, uhi) = range_of([u.as_slice()], 0.04);
    // robust range: the central 98 % of the cloud and all bin means
    let mut abs: Vec<f64> = e.iter().map(|x| x.abs()).collect();
    abs.sort_by(|a, b| a.total_cmp(b));
    let cloud = abs[(abs.len() * 98 / 100).min(abs.len() - 1)];
    // quantile bins of the input, so every bin holds data
    let mut sorted = u.clone();
    sorted.sort_by(|a, b| a.total_cmp(b));
    let nb = 12;
    let mut edges: Vec<f64> = (0..=nb)
        .map(|i| sorted[(i * (sorted.len() - 1)) / nb])
        .collect();
    edges.dedup();
    let means = |dir| {
        if edges.len() >= 2 {
            binned_means(u, &e, &s, dir, &edges)
        } else {
            Vec::new()
        }
    };
    let (m_up, m_down) = (means(1.0), means(-1.0));
    let mmax = m_up
        .iter()
        .chain(&m_down)
        .fold(cloud, |m, p| m.max(p.1.abs()));
    let (elo, ehi) = symmetric_range(&[mmax], 0.1);
    let idx = stride_indices(u.len(), 4000);
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (WIDTH, 420)).into_drawing_area();
        root.fill(&WHITE).map_err(&err)?;
        let mut chart = ChartBuilder::on(&root)
            .margin(12)
            .x_label_area_size(42)
            .y_label_area_size(70)
            .build_cartesian_2d(ulo..uhi, elo..ehi)
            .map_err(&err)?;
        mesh_style(&mut chart.configure_mesh(), 16)
            .x_desc(with_unit("input u", &input.units.input))
            .y_desc(if referred {
                "residual referred to the input (units of v)".to_string()
            } else {
                with_unit("residual y − ŷ", &input.units.output)
            })
            .draw()
            .map_err(&err)?;
        chart
            .draw_series(LineSeries::new([(ulo, 0.0), (uhi, 0.0)], BLACK.mix(0.5)))
            .map_err(&err)?;
        for (dir, colour) in [(-1.0, FALLING), (1.0, RISING)] {
            chart
                .draw_series(
                    idx.iter()
                        .filter(|&&k| s[k] == dir && e[k] > elo && e[k] < ehi)
                        .map(|&k| Circle::new((u[k], e[k]), 2, colour.mix(0.35).filled())),
                )
                .map_err(&err)?;
        }
        for (m, colour, name) in [
            (&m_up, RISING, "rising input (u increasing): bin means"),
            (&m_down, FALLING, "falling input (u decreasing): bin means"),
        ] {
            chart
                .draw_series(LineSeries::new(m.iter().copied(), colour.stroke_width(3)))
                .map_err(&err)?
                .label(name)
                .legend(move |(x, y)| {
                    PathElement::new([(x, y), (x + 20, y)], colour.stroke_width(3))
                });
            chart
                .draw_series(m.iter().map(|&p| Circle::new(p, 4, colour.filled())))
                .map_err(&err)?;
        }
        draw_legend(
            &mut chart,
            SeriesLabelPosition::UpperLeft,
            "residual vs input",
        )?;
        root.present().map_err(&err)?;
    }
    Ok(Plot {
        id: "residual-direction".into(),
        title: "Residual against input, by direction of motion".into(),
        svg,
        caption: format!(
            "{}Each dot is one training sample: orange while the input rises, blue while it \
                  falls; the thick lines are the mean residual in input bins. If the two colours \
                  separate (orange above blue, or the reverse), the output depends on where the \
                  input comes from: the model misses hysteresis. If both lines bend together at the \
                  ends, it misses saturation; a step at u = 0 points to a dead-zone or preload. Two \
                  flat lines on zero: nothing static is missing.",
            if referred {
                "The residual is referred to the input: filtered through the inverse of the \
                 model's linear block and aligned with the input sample that caused it, so it \
                 estimates the part of v the model misses. "
            } else {
                ""
            }
        ),
    })
}
