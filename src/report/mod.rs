//! Reports: SVG plots and one self-contained HTML page.
