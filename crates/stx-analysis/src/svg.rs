//! Small SVG line and scatter plots: the eigenvalue map and step responses.
//!
//! Written by hand rather than with a plotting crate: the figures need axes, ticks, a grid,
//! lines, markers and a legend, which is a page of code, and SVG text renders the same in a
//! browser, an image viewer or `rsvg-convert` without fonts or a backend to install. Text is
//! escaped by `quick_xml::escape::escape`, the XML escaper of every XML stx writes.

use std::fmt::Write;

use quick_xml::escape::escape;

/// How a series is drawn.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Style {
    /// A solid line.
    Line,
    /// A dashed line.
    Dashed,
    /// Circles at the points.
    Circles,
    /// Crosses at the points.
    Crosses,
}

/// One data series.
#[derive(Debug, Clone)]
pub struct Series {
    /// Legend text.
    pub label: String,
    /// Points `(x, y)`.
    pub points: Vec<(f64, f64)>,
    /// Colour (any SVG colour).
    pub color: &'static str,
    /// How it is drawn.
    pub style: Style,
}

/// One plot panel.
#[derive(Debug, Clone, Default)]
pub struct Panel {
    /// Title above the panel.
    pub title: String,
    /// X axis label.
    pub x_label: String,
    /// Y axis label.
    pub y_label: String,
    /// The data.
    pub series: Vec<Series>,
    /// X range; from the data when None.
    pub x_range: Option<(f64, f64)>,
    /// Y range; from the data when None.
    pub y_range: Option<(f64, f64)>,
    /// Horizontal reference lines (e.g. a target), dashed grey.
    pub h_lines: Vec<f64>,
    /// Where the legend goes (pick the corner the data leave empty).
    pub legend: Corner,
}

/// A corner of a panel.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum Corner {
    /// Top right.
    #[default]
    TopRight,
    /// Top left.
    TopLeft,
    /// Bottom right.
    BottomRight,
}

/// Colours that stay distinct for people with the common colour-vision deficiencies
/// (Okabe–Ito).
pub const COLORS: [&str; 6] = [
    "#0072B2", "#D55E00", "#009E73", "#CC79A7", "#E69F00", "#56B4E9",
];

/// "Nice" tick positions covering `lo..hi` (steps of 1, 2 or 5 × 10^k).
pub fn ticks(lo: f64, hi: f64, target: usize) -> Vec<f64> {
    if !(lo.is_finite() && hi.is_finite()) || hi <= lo {
        return vec![lo];
    }
    let raw = (hi - lo) / target.max(1) as f64;
    let magnitude = 10f64.powf(raw.log10().floor());
    let step = [1.0, 2.0, 5.0, 10.0]
        .iter()
        .map(|m| m * magnitude)
        .find(|s| *s >= raw)
        .unwrap_or(10.0 * magnitude);
    let first = (lo / step).ceil() as i64;
    let last = (hi / step).floor() as i64;
    (first..=last).map(|k| k as f64 * step).collect()
}

fn data_range(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let (lo, hi) = values
        .filter(|v| v.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
            (a.min(v), b.max(v))
        });
    if !lo.is_finite() {
        return (0.0, 1.0);
    }
    if (hi - lo).abs() < 1e-12 {
        return (lo - 1.0, hi + 1.0);
    }
    let pad = 0.05 * (hi - lo);
    (lo - pad, hi + pad)
}

fn fmt_tick(v: f64) -> String {
    let s = format!("{v:.4}");
    let s = s.trim_end_matches('0').trim_end_matches('.').to_string();
    if s == "-0" { "0".into() } else { s }
}

/// Renders panels in a grid of `columns` columns, each panel `panel_w × panel_h` pixels.
pub fn render(title: &str, panels: &[Panel], columns: usize, panel_w: f64, panel_h: f64) -> String {
    let columns = columns.max(1);
    let rows = panels.len().div_ceil(columns);
    let (width, height) = (panel_w * columns as f64, 40.0 + panel_h * rows as f64);
    let mut out = String::new();
    let _ = writeln!(
        out,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{width}" height="{height}" viewBox="0 0 {width} {height}" font-family="sans-serif" font-size="12">"#
    );
    let _ = writeln!(out, r#"<rect width="100%" height="100%" fill="white"/>"#);
    let _ = writeln!(
        out,
        r#"<text x="{}" y="24" text-anchor="middle" font-size="16" font-weight="bold">{}</text>"#,
        width / 2.0,
        escape(title)
    );
    for (k, panel) in panels.iter().enumerate() {
        let ox = panel_w * (k % columns) as f64;
        let oy = 40.0 + panel_h * (k / columns) as f64;
        draw_panel(&mut out, panel, ox, oy, panel_w, panel_h);
    }
    out.push_str("</svg>\n");
    out
}

fn draw_panel(out: &mut String, p: &Panel, ox: f64, oy: f64, w: f64, h: f64) {
    let (left, right, top, bottom) = (70.0, 20.0, 28.0, 50.0);
    let (pw, ph) = (w - left - right, h - top - bottom);
    let (x0, x1) = p
        .x_range
        .unwrap_or_else(|| data_range(p.series.iter().flat_map(|s| s.points.iter().map(|q| q.0))));
    let (y0, y1) = p.y_range.unwrap_or_else(|| {
        data_range(
            p.series
                .iter()
                .flat_map(|s| s.points.iter().map(|q| q.1))
                .chain(p.h_lines.iter().copied()),
        )
    });
    let sx = |x: f64| ox + left + (x - x0) / (x1 - x0) * pw;
    let sy = |y: f64| oy + top + (1.0 - (y - y0) / (y1 - y0)) * ph;
    let _ = writeln!(
        out,
        r#"<text x="{}" y="{}" text-anchor="middle" font-size="13">{}</text>"#,
        ox + left + pw / 2.0,
        oy + 16.0,
        escape(&p.title)
    );
    let _ = writeln!(
        out,
        r##"<rect x="{}" y="{}" width="{pw}" height="{ph}" fill="none" stroke="#333"/>"##,
        ox + left,
        oy + top
    );
    for t in ticks(x0, x1, 6) {
        let x = sx(t);
        let _ = writeln!(
            out,
            r##"<line x1="{x:.1}" y1="{:.1}" x2="{x:.1}" y2="{:.1}" stroke="#ddd"/><text x="{x:.1}" y="{:.1}" text-anchor="middle">{}</text>"##,
            oy + top,
            oy + top + ph,
            oy + top + ph + 16.0,
            fmt_tick(t)
        );
    }
    for t in ticks(y0, y1, 5) {
        let y = sy(t);
        let _ = writeln!(
            out,
            r##"<line x1="{:.1}" y1="{y:.1}" x2="{:.1}" y2="{y:.1}" stroke="#ddd"/><text x="{:.1}" y="{:.1}" text-anchor="end">{}</text>"##,
            ox + left,
            ox + left + pw,
            ox + left - 6.0,
            y + 4.0,
            fmt_tick(t)
        );
    }
    let _ = writeln!(
        out,
        r#"<text x="{}" y="{}" text-anchor="middle">{}</text>"#,
        ox + left + pw / 2.0,
        oy + h - 14.0,
        escape(&p.x_label)
    );
    let (lx, ly) = (ox + 16.0, oy + top + ph / 2.0);
    let _ = writeln!(
        out,
        r#"<text x="{lx}" y="{ly}" text-anchor="middle" transform="rotate(-90 {lx} {ly})">{}</text>"#,
        escape(&p.y_label)
    );
    let _ = writeln!(
        out,
        r#"<clipPath id="clip{}_{}"><rect x="{}" y="{}" width="{pw}" height="{ph}"/></clipPath>"#,
        ox as i64,
        oy as i64,
        ox + left,
        oy + top
    );
    let clip = format!("clip{}_{}", ox as i64, oy as i64);
    for &y in &p.h_lines {
        if y >= y0 && y <= y1 {
            let _ = writeln!(
                out,
                r##"<line x1="{:.1}" y1="{:.1}" x2="{:.1}" y2="{:.1}" stroke="#888" stroke-dasharray="2,3"/>"##,
                ox + left,
                sy(y),
                ox + left + pw,
                sy(y)
            );
        }
    }
    for s in &p.series {
        let finite: Vec<(f64, f64)> = s
            .points
            .iter()
            .copied()
            .filter(|q| q.0.is_finite() && q.1.is_finite())
            .collect();
        match s.style {
            Style::Line | Style::Dashed => {
                let path: Vec<String> = finite
                    .iter()
                    .map(|&(x, y)| format!("{:.1},{:.1}", sx(x), sy(y)))
                    .collect();
                let dash = if s.style == Style::Dashed {
                    r#" stroke-dasharray="6,4""#
                } else {
                    ""
                };
                let _ = writeln!(
                    out,
                    r#"<polyline clip-path="url(#{clip})" fill="none" stroke="{}" stroke-width="1.8"{dash} points="{}"/>"#,
                    s.color,
                    path.join(" ")
                );
            }
            Style::Circles => {
                for &(x, y) in &finite {
                    let _ = writeln!(
                        out,
                        r#"<circle clip-path="url(#{clip})" cx="{:.1}" cy="{:.1}" r="4" fill="none" stroke="{}" stroke-width="1.6"/>"#,
                        sx(x),
                        sy(y),
                        s.color
                    );
                }
            }
            Style::Crosses => {
                for &(x, y) in &finite {
                    let (cx, cy) = (sx(x), sy(y));
                    let _ = writeln!(
                        out,
                        r#"<path clip-path="url(#{clip})" d="M{:.1},{:.1}L{:.1},{:.1}M{:.1},{:.1}L{:.1},{:.1}" stroke="{}" stroke-width="1.6"/>"#,
                        cx - 4.0,
                        cy - 4.0,
                        cx + 4.0,
                        cy + 4.0,
                        cx - 4.0,
                        cy + 4.0,
                        cx + 4.0,
                        cy - 4.0,
                        s.color
                    );
                }
            }
        }
    }
    // Legend inside the panel, in the corner asked for.
    let rows = p.series.len() as f64;
    let mut y = match p.legend {
        Corner::TopRight | Corner::TopLeft => oy + top + 18.0,
        Corner::BottomRight => oy + top + ph - 16.0 * rows + 8.0,
    };
    // Wide enough for the longest label (about 7 px a character at 12 px), no wider, so the
    // box hides as little data as it can.
    let box_w = 40.0
        + 7.0
            * p.series
                .iter()
                .map(|s| s.label.chars().count())
                .max()
                .unwrap_or(0) as f64;
    for s in &p.series {
        let x = match p.legend {
            Corner::TopLeft => ox + left + 10.0,
            _ => ox + left + pw - box_w - 10.0,
        };
        let sample = match s.style {
            Style::Line => format!(
                r#"<line x1="{x}" y1="{}" x2="{}" y2="{}" stroke="{}" stroke-width="2"/>"#,
                y - 4.0,
                x + 22.0,
                y - 4.0,
                s.color
            ),
            Style::Dashed => format!(
                r#"<line x1="{x}" y1="{}" x2="{}" y2="{}" stroke="{}" stroke-width="2" stroke-dasharray="6,4"/>"#,
                y - 4.0,
                x + 22.0,
                y - 4.0,
                s.color
            ),
            Style::Circles => format!(
                r#"<circle cx="{}" cy="{}" r="4" fill="none" stroke="{}" stroke-width="1.6"/>"#,
                x + 11.0,
                y - 4.0,
                s.color
            ),
            Style::Crosses => format!(
                r#"<path d="M{},{}L{},{}M{},{}L{},{}" stroke="{}" stroke-width="1.6"/>"#,
                x + 7.0,
                y - 8.0,
                x + 15.0,
                y,
                x + 7.0,
                y,
                x + 15.0,
                y - 8.0,
                s.color
            ),
        };
        let _ = writeln!(
            out,
            r#"<rect x="{}" y="{}" width="{box_w}" height="16" fill="white" fill-opacity="0.8"/>{sample}<text x="{}" y="{y}">{}</text>"#,
            x - 4.0,
            y - 13.0,
            x + 28.0,
            escape(&s.label)
        );
        y += 16.0;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ticks_are_round_numbers_inside_the_range() {
        assert_eq!(ticks(0.0, 10.0, 5), vec![0.0, 2.0, 4.0, 6.0, 8.0, 10.0]);
        let t = ticks(-0.33, 1.7, 8);
        assert_eq!(t, vec![0.0, 0.5, 1.0, 1.5]);
        assert_eq!(ticks(3.0, 3.0, 5), vec![3.0]);
    }

    #[test]
    fn a_plot_is_well_formed_svg_with_every_series_and_escaped_text() {
        let panel = Panel {
            title: "a < b & c".into(),
            x_label: "t, s".into(),
            y_label: "y".into(),
            series: vec![
                Series {
                    label: "line".into(),
                    points: vec![(0.0, 0.0), (1.0, 1.0), (2.0, f64::NAN)],
                    color: COLORS[0],
                    style: Style::Line,
                },
                Series {
                    label: "dots".into(),
                    points: vec![(0.5, 0.2)],
                    color: COLORS[1],
                    style: Style::Circles,
                },
            ],
            h_lines: vec![0.5],
            ..Default::default()
        };
        let svg = render("test", &[panel.clone(), panel], 2, 400.0, 300.0);
        assert!(svg.starts_with("<svg") && svg.trim_end().ends_with("</svg>"));
        assert!(svg.contains("a &lt; b &amp; c"));
        // Quotes too (they were left as written): text is safe in an attribute as well.
        let quoted = render("say \"hi\" & 'bye'", &[], 1, 100.0, 100.0);
        assert!(
            quoted.contains("say &quot;hi&quot; &amp; &apos;bye&apos;"),
            "{quoted}"
        );
        assert_eq!(svg.matches("<polyline").count(), 2);
        assert!(!svg.contains("NaN"), "non-finite points are skipped");
        // Every opened element is closed or self-closed.
        assert_eq!(svg.matches("<svg").count(), svg.matches("</svg>").count());
    }
}
