//! One rendered plot: its SVG text, title and the caption telling the reader what to look for.

/// A plot ready to be written and inlined.
#[derive(Debug, Clone)]
pub struct Plot {
    /// File stem and HTML anchor ("output", "residual-direction", …).
    pub id: String,
    /// Heading shown above the plot.
    pub title: String,
    /// The SVG document.
    pub svg: String,
    /// What to look for, shown under the plot.
    pub caption: String,
}
