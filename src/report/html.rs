//! The HTML page: one self-contained file (inline CSS, inline SVG, no external resources).

use super::input::ReportInput;
use super::plot::Plot;

/// Escapes text for HTML.
pub fn escape(s: &str) -> String {
    let mut o = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => o.push_str("&amp;"),
            '<' => o.push_str("&lt;"),
            '>' => o.push_str("&gt;"),
            '"' => o.push_str("&quot;"),
            '\'' => o.push_str("&#39;"),
            c => o.push(c),
        }
    }
    o
}

/// Strips the XML declaration, if any, so the SVG can be inlined.
fn inline_svg(svg: &str) -> &str {
    match svg.find("<svg") {
        Some(i) => &svg[i..],
        None => svg,
    }
}

const CSS: &str = "
body{font-family:system-ui,-apple-system,'Segoe UI',Roboto,sans-serif;max-width:1000px;margin:0 auto;
padding:24px;color:#222;line-height:1.45;background:#fff}
h1{font-size:1.6em;margin-bottom:0.2em}
h2{font-size:1.2em;margin-top:1.8em;border-bottom:1px solid #ddd;padding-bottom:4px}
.sub{color:#666;margin-top:0}
figure{margin:0.6em 0 1.4em 0}
figure svg{max-width:100%;height:auto;display:block;border:1px solid #eee}
figcaption{color:#444;font-size:0.93em;margin-top:6px;padding-left:10px;border-left:3px solid #0072B2}
table{border-collapse:collapse;margin:0.6em 0;font-size:0.93em}
th,td{border-bottom:1px solid #e4e4e4;padding:4px 10px;text-align:left;vertical-align:top}
th{background:#f6f6f6}
td.num{text-align:right;font-variant-numeric:tabular-nums;white-space:nowrap}
.summary{font-size:1.08em;background:#f3f8fc;border:1px solid #cfe3f2;padding:10px 14px;border-radius:4px}
.sig{color:#b34700;font-weight:600}
nav a{margin-right:12px}
";

fn num(x: f64) -> String {
    if !x.is_finite() {
        "–".into()
    } else if x != 0.0 && (x.abs() < 1e-3 || x.abs() >= 1e5) {
        format!("{x:.4e}")
    } else {
        format!("{x:.4}")
    }
}

/// Renders the page.
pub fn page(input: &ReportInput, plots: &[Plot]) -> String {
    let mut h = String::new();
    h.push_str("<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n");
    h.push_str("<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n");
    h.push_str(&format!("<title>{}</title>\n", escape(&input.title)));
    h.push_str(&format!("<style>{CSS}</style>\n</head>\n<body>\n"));
    h.push_str(&format!("<h1>{}</h1>\n", escape(&input.title)));
    let mut sub = format!("Data: {}", escape(&input.dataset));
    sub.push_str(&format!(" — {} training samples", input.train.len()));
    if let Some(v) = &input.validation {
        sub.push_str(&format!(", {} validation samples", v.len()));
    }
    if let Some(ts) = input.units.sample_time {
        sub.push_str(&format!(", sampling time {ts} s"));
    }
    h.push_str(&format!("<p class=\"sub\">{sub}</p>\n"));
    if !input.diagnosis_summary.is_empty() {
        h.push_str(&format!(
            "<p class=\"summary\"><b>Diagnosis:</b> {}</p>\n",
            escape(&input.diagnosis_summary)
        ));
    }
    h.push_str("<nav>");
    for p in plots {
        h.push_str(&format!("<a href=\"#{}\">{}</a>", p.id, escape(&p.title)));
    }
    h.push_str("<a href=\"#tables\">Tables</a></nav>\n");
    for n in &input.notes {
        h.push_str(&format!("<p>{}</p>\n", escape(n)));
    }
    for p in plots {
        h.push_str(&format!(
            "<section id=\"{}\">\n<h2>{}</h2>\n<figure>\n{}\n<figcaption>{}</figcaption>\n</figure>\n</section>\n",
            p.id,
            escape(&p.title),
            inline_svg(&p.svg),
            escape(&p.caption)
        ));
    }
    h.push_str("<section id=\"tables\">\n");
    if !input.steps.is_empty() {
        h.push_str("<h2>Steps</h2>\n<table><tr><th>step</th><th>model</th><th>validation MSE</th><th>validation fit %</th></tr>\n");
        for (i, s) in input.steps.iter().enumerate() {
            h.push_str(&format!(
                "<tr><td class=\"num\">{}</td><td>{}</td><td class=\"num\">{}</td><td class=\"num\">{:.2}</td></tr>\n",
                i,
                escape(&s.label),
                num(s.validation_mse),
                s.fit_percent
            ));
        }
        h.push_str("</table>\n");
    }
    h.push_str("<h2>Diagnosis of the final model</h2>\n");
    if input.diagnosis.is_empty() {
        h.push_str("<p>No missing effect suggested.</p>\n");
    } else {
        h.push_str("<table><tr><th>rank</th><th>effect</th><th>score</th><th>evidence</th><th>estimate</th><th>validation MSE after</th></tr>\n");
        for (i, d) in input.diagnosis.iter().enumerate() {
            h.push_str(&format!(
                "<tr><td class=\"num\">{}</td><td>{}</td><td class=\"num\">{:.3}</td><td>{}</td><td>{}</td><td class=\"num\">{}</td></tr>\n",
                i + 1,
                escape(&d.effect),
                d.score,
                escape(&d.evidence),
                escape(&d.estimate),
                num(d.validation_mse_after)
            ));
        }
        h.push_str("</table>\n");
    }
    if !input.tests.is_empty() {
        h.push_str("<h2>Residual tests</h2>\n<table><tr><th>test</th><th>what it checks</th><th>adjusted p-value</th><th></th></tr>\n");
        for t in &input.tests {
            h.push_str(&format!(
                "<tr><td>{}</td><td>{}</td><td class=\"num\">{:.3e}</td><td>{}</td></tr>\n",
                escape(&t.name),
                escape(&t.description),
                t.p_adjusted,
                if t.significant {
                    "<span class=\"sig\">significant</span>"
                } else {
                    ""
                }
            ));
        }
        h.push_str("</table>\n");
    }
    if !input.parameters.is_empty() {
        h.push_str(
            "<h2>Parameters</h2>\n<table><tr><th>parameter</th><th>value</th><th>note</th></tr>\n",
        );
        for p in &input.parameters {
            h.push_str(&format!(
                "<tr><td>{}</td><td class=\"num\">{}</td><td>{}</td></tr>\n",
                escape(&p.name),
                num(p.value),
                escape(&p.note)
            ));
        }
        h.push_str("</table>\n");
    }
    h.push_str("</section>\n<p class=\"sub\">Generated by hammerstein ");
    h.push_str(env!("CARGO_PKG_VERSION"));
    h.push_str(".</p>\n</body>\n</html>\n");
    h
}
