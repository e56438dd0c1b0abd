//! The classic BLA plot: |BLA|, its noise level and its distortion level (standard deviations,
//! dB) against frequency, one colour per level.

use crate::error::Result;
use crate::report::style::*;
use crate::structure::Bla;
use plotters::prelude::*;

const LEVEL_COLOURS: [RGBColor; 6] = [
    RGBColor(0, 114, 178),
    RGBColor(213, 94, 0),
    RGBColor(0, 158, 115),
    RGBColor(204, 121, 167),
    RGBColor(230, 159, 0),
    RGBColor(86, 180, 233),
];

fn db(v: f64) -> f64 {
    10.0 * v.max(1e-300).log10()
}

/// The SVG of the BLA plot; frequencies in Hz when `ts` is given, else in fractions of the
/// sampling frequency.
pub fn bla_svg(bla: &Bla, ts: Option<f64>) -> Result<String> {
    let err = plot_err("BLA plot");
    let scale = ts.map_or(1.0, |t| 1.0 / t);
    let mut series: Vec<(Vec<(f64, f64)>, Vec<(f64, f64)>, Vec<(f64, f64)>)> = Vec::new();
    for l in &bla.levels {
        let g = l
            .lines
            .iter()
            .map(|x| (x.freq * scale, db(x.value().norm_sqr())))
            .collect();
        let n = l
            .lines
            .iter()
            .filter_map(|x| {
                x.var_noise
                    .filter(|v| v.is_finite() && *v > 0.0)
                    .map(|v| (x.freq * scale, db(v)))
            })
            .collect();
        let d = l
            .lines
            .iter()
            .filter_map(|x| {
                x.var_distortion
                    .filter(|v| v.is_finite() && *v > 0.0)
                    .map(|v| (x.freq * scale, db(v)))
            })
            .collect();
        series.push((g, n, d));
    }
    let all: Vec<f64> = series
        .iter()
        .flat_map(|(g, n, d)| g.iter().chain(n).chain(d).map(|p| p.1))
        .collect();
    let ymax = all.iter().fold(f64::MIN, |m, v| m.max(*v)) + 5.0;
    let ymin = all
        .iter()
        .fold(f64::MAX, |m, v| m.min(*v))
        .max(ymax - 120.0)
        - 5.0;
    let f0 = bla.excited[0] as f64 / bla.period as f64 * scale;
    let f1 = *bla.excited.last().unwrap_or(&1) as f64 / bla.period as f64 * scale;
    let pad = 0.02 * (f1 - f0).max(1e-12);
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (WIDTH, 420)).into_drawing_area();
        root.fill(&WHITE).map_err(&err)?;
        let mut chart = ChartBuilder::on(&root)
            .margin(12)
            .x_label_area_size(42)
            .y_label_area_size(64)
            .build_cartesian_2d(f0 - pad..f1 + pad, ymin..ymax)
            .map_err(&err)?;
        mesh_style(&mut chart.configure_mesh(), 16)
            .x_desc(if ts.is_some() {
                "frequency (Hz)"
            } else {
                "frequency (fraction of fs)"
            })
            .y_desc("dB")
            .draw()
            .map_err(&err)?;
        for (i, (g, n, d)) in series.iter().enumerate() {
            let c = LEVEL_COLOURS[i % LEVEL_COLOURS.len()];
            let rms = bla.levels[i].rms;
            chart
                .draw_series(LineSeries::new(g.iter().copied(), c.stroke_width(2)))
                .map_err(&err)?
                .label(format!("|BLA|², level {i} (RMS {rms:.3})"))
                .legend(legend_line(c.stroke_width(2)));
            chart
                .draw_series(n.iter().map(|&p| Circle::new(p, 2, c.mix(0.6).filled())))
                .map_err(&err)?
                .label("noise variance (dots)")
                .legend(move |(x, y)| Circle::new((x + 10, y), 3, c.mix(0.6).filled()));
            chart
                .draw_series(d.iter().map(|&p| TriangleMarker::new(p, 4, c.mix(0.8))))
                .map_err(&err)?
                .label("distortion variance (triangles)")
                .legend(move |(x, y)| TriangleMarker::new((x + 10, y), 4, c.mix(0.8)));
        }
        draw_legend(&mut chart, SeriesLabelPosition::LowerLeft, "BLA plot")?;
        root.present().map_err(&err)?;
    }
    Ok(svg)
}
