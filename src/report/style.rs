//! Shared look of the plots: size, colours (Okabe–Ito, colour-blind safe), fonts, axis ranges,
//! thinning of long series, and the conversion of plotting errors.

use crate::error::Error;
use plotters::chart::MeshStyle;
use plotters::coord::ranged1d::Ranged;
use plotters::prelude::*;

/// Width of every plot in pixels.
pub const WIDTH: u32 = 960;
/// Height of a standard plot in pixels.
pub const HEIGHT: u32 = 360;

/// Measured data.
pub const MEASURED: RGBColor = RGBColor(60, 60, 60);
/// Model output.
pub const MODEL: RGBColor = RGBColor(0, 114, 178);
/// Rising input (direction +1).
pub const RISING: RGBColor = RGBColor(213, 94, 0);
/// Falling input (direction −1).
pub const FALLING: RGBColor = RGBColor(0, 114, 178);
/// Confidence bounds and reference lines.
pub const BOUND: RGBColor = RGBColor(204, 121, 167);
/// Highlight (chosen order, noise floor).
pub const ACCENT: RGBColor = RGBColor(0, 158, 115);
/// Background shade of the validation part.
pub const SHADE: RGBColor = RGBColor(236, 236, 236);

/// Font family of all text.
pub const FONT: &str = "sans-serif";

/// Converts a plotting error into the crate's error.
pub fn plot_err<E: std::fmt::Debug>(what: &str) -> impl Fn(E) -> Error + '_ {
    move |e| {
        Error::io(
            format!("<{what} plot>"),
            std::io::Error::other(format!("{e:?}")),
        )
    }
}

/// A padded range covering all values of the given series (never empty).
pub fn range_of<'a>(series: impl IntoIterator<Item = &'a [f64]>, pad: f64) -> (f64, f64) {
    let mut lo = f64::INFINITY;
    let mut hi = f64::NEG_INFINITY;
    for s in series {
        for &x in s {
            if x.is_finite() {
                lo = lo.min(x);
                hi = hi.max(x);
            }
        }
    }
    if !lo.is_finite() {
        return (-1.0, 1.0);
    }
    let span = hi - lo;
    let span = if span > 0.0 {
        span
    } else {
        lo.abs().max(1.0) * 0.1
    };
    (lo - pad * span, hi + pad * span)
}

/// Symmetric padded range around zero.
pub fn symmetric_range(xs: &[f64], pad: f64) -> (f64, f64) {
    let m = xs
        .iter()
        .filter(|x| x.is_finite())
        .fold(0.0f64, |m, x| m.max(x.abs()));
    let m = if m > 0.0 { m * (1.0 + pad) } else { 1.0 };
    (-m, m)
}

/// Thins a series for plotting: keeps the minimum and maximum of each of `buckets` consecutive
/// chunks (in time order), so peaks survive. Returns (index, value) pairs.
pub fn thin(xs: &[f64], offset: usize, buckets: usize) -> Vec<(f64, f64)> {
    if xs.len() <= 2 * buckets {
        return xs
            .iter()
            .enumerate()
            .map(|(i, &v)| ((i + offset) as f64, v))
            .collect();
    }
    let chunk = xs.len().div_ceil(buckets);
    let mut out = Vec::with_capacity(2 * buckets);
    for (c, part) in xs.chunks(chunk).enumerate() {
        let base = c * chunk + offset;
        let (mut imin, mut imax) = (0, 0);
        for (i, &v) in part.iter().enumerate() {
            if v < part[imin] {
                imin = i;
            }
            if v > part[imax] {
                imax = i;
            }
        }
        let (a, b) = if imin <= imax {
            (imin, imax)
        } else {
            (imax, imin)
        };
        out.push(((base + a) as f64, part[a]));
        if b != a {
            out.push(((base + b) as f64, part[b]));
        }
    }
    out
}

/// Indices of at most `max` evenly spread samples out of `n`.
pub fn stride_indices(n: usize, max: usize) -> Vec<usize> {
    if n <= max || max == 0 {
        return (0..n).collect();
    }
    (0..max).map(|i| i * n / max).collect()
}

/// Axis label with its unit in brackets ("output y [V]"), or bare when the unit is unknown.
pub fn with_unit(label: &str, unit: &str) -> String {
    if unit.is_empty() {
        label.to_string()
    } else {
        format!("{label} [{unit}]")
    }
}

/// Time-axis label and scale factor (seconds per sample, or 1 for the sample index).
pub fn time_axis(sample_time: Option<f64>) -> (String, f64) {
    match sample_time {
        Some(ts) if ts > 0.0 && ts.is_finite() => ("time [s]".to_string(), ts),
        _ => ("sample k".to_string(), 1.0),
    }
}

/// Standard caption font.
pub fn label_font(size: u32) -> TextStyle<'static> {
    TextStyle::from((FONT, size).into_font()).color(&BLACK)
}

/// Legend sample of a series: a short horizontal line in `style`.
pub fn legend_line(style: ShapeStyle) -> impl Fn((i32, i32)) -> PathElement<(i32, i32)> {
    move |(x, y)| PathElement::new([(x, y), (x + 20, y)], style)
}

/// Draws the legend of `chart` at `position` in the shared style (translucent white box, thin
/// border, the label font).
pub fn draw_legend<'a, DB, CT>(
    chart: &mut ChartContext<'a, DB, CT>,
    position: SeriesLabelPosition,
    what: &str,
) -> crate::error::Result<()>
where
    DB: DrawingBackend + 'a,
    CT: CoordTranslate,
{
    chart
        .configure_series_labels()
        .position(position)
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK.mix(0.3))
        .label_font(label_font(16))
        .draw()
        .map_err(plot_err(what))
}

/// The shared grid look: no minor lines, faint major lines, tick labels at `size` and axis
/// descriptions one point larger.
pub fn mesh_style<'a, 'b, 'c, X: Ranged, Y: Ranged, DB: DrawingBackend>(
    mesh: &'c mut MeshStyle<'a, 'b, X, Y, DB>,
    size: u32,
) -> &'c mut MeshStyle<'a, 'b, X, Y, DB> {
    mesh.light_line_style(WHITE.mix(0.0))
        .bold_line_style(BLACK.mix(0.08))
        .label_style(label_font(size))
        .axis_desc_style(label_font(size + 1))
}
