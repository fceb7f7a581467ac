//! The report's plot areas, drawn with `plotters`' SVG backend: a [`Plot`] (numeric axes, an
//! optional right axis, lines and dots, a legend); [`super::bars`] draws the categorical one.
//!
//! Why plotters: the hand-written SVG this replaces put numeric ticks on categories, cut long
//! labels and had its own tick formatting. plotters lays out axes, ticks and legends; its SVG
//! backend writes text as `<text>` elements, so no font file is read and the page opens anywhere
//! (the default features — bitmap backends, system fonts — are off). Tick labels go through the
//! report's one number formatter ([`crate::render::num`]).
//!
//! Every plot's `<svg>` carries `class="plot"` and `data-points` (the marks drawn from data): the
//! page's inline check and the headless-Chromium test count plots that are laid out *and* hold
//! data, so an empty plot fails the test instead of passing as an empty frame.

use crate::render::num;
use plotters::prelude::*;
use std::fmt::Write as _;

/// Series colours, in order.
pub(super) const COLORS: [&str; 4] = ["#d62728", "#2ca02c", "#9467bd", "#8c564b"];
/// Width of a full-width plot (px).
pub(super) const W: f64 = 860.0;
/// Height of a plot (px).
pub(super) const H: f64 = 300.0;

/// `s` escaped for HTML text and attributes.
pub(super) fn esc(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// The finite range of `vs` with 5 % padding; (0, 1) when there is none.
pub(super) fn range(vs: &[f64]) -> (f64, f64) {
    let (lo, hi) = vs
        .iter()
        .filter(|v| v.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), v| {
            (l.min(*v), h.max(*v))
        });
    if !lo.is_finite() {
        return (0.0, 1.0);
    }
    if hi - lo < 1e-300 {
        let d = if lo.abs() > 0.0 { 0.05 * lo.abs() } else { 1.0 };
        return (lo - d, hi + d);
    }
    let pad = 0.05 * (hi - lo);
    (lo - pad, hi + pad)
}

/// `#rrggbb` as a colour (black when malformed).
pub(super) fn color(hex: &str) -> RGBColor {
    let h = hex.trim_start_matches('#');
    let byte = |i: usize| {
        h.get(i..i + 2)
            .and_then(|s| u8::from_str_radix(s, 16).ok())
            .unwrap_or(0)
    };
    RGBColor(byte(0), byte(2), byte(4))
}

/// A drawn mark.
enum Mark {
    Line {
        pts: Vec<(f64, f64)>,
        color: String,
        right: bool,
        dash: bool,
    },
    Dots {
        pts: Vec<(f64, f64, String)>,
    },
}

/// What drawing a plot gives: plotters' errors boxed (a plot that fails says so in its place).
pub(super) type DrawResult = Result<(), Box<dyn std::error::Error>>;

/// A plot with numeric axes, recorded mark by mark and drawn by [`Plot::finish`].
pub(super) struct Plot {
    /// Extra SVG elements placed inside the plot (in its pixels).
    pub(super) svg: String,
    title: String,
    xl: String,
    yl: String,
    x: (f64, f64),
    y: (f64, f64),
    y2: Option<(String, (f64, f64))>,
    marks: Vec<Mark>,
    /// Legend entries: name and colour.
    pub(super) legend: Vec<(String, String)>,
    size: (u32, u32),
}

impl Plot {
    /// A plot titled `title` with axis labels `xl`, `yl` over the ranges `x`, `y`.
    pub(super) fn new(title: &str, xl: &str, yl: &str, x: (f64, f64), y: (f64, f64)) -> Self {
        Self {
            svg: String::new(),
            title: title.into(),
            xl: xl.into(),
            yl: yl.into(),
            x,
            y,
            y2: None,
            marks: Vec::new(),
            legend: Vec::new(),
            size: (W as u32, H as u32),
        }
    }

    /// The same plot `width` pixels wide (two side by side).
    pub(super) fn width(mut self, width: u32) -> Self {
        self.size.0 = width;
        self
    }

    /// Adds a right axis labelled `label` over `r`.
    pub(super) fn right_axis(&mut self, label: &str, r: (f64, f64)) {
        self.y2 = Some((label.into(), r));
    }

    /// Adds a line (on the right axis if `right`, dashed if `dash`) and its legend entry.
    pub(super) fn line(
        &mut self,
        xs: &[f64],
        ys: &[f64],
        color: &str,
        name: &str,
        right: bool,
        dash: bool,
    ) {
        let pts = xs
            .iter()
            .zip(ys)
            .filter(|(x, y)| x.is_finite() && y.is_finite())
            .map(|(x, y)| (*x, *y))
            .collect();
        self.marks.push(Mark::Line {
            pts,
            color: color.into(),
            right,
            dash,
        });
        self.legend.push((name.into(), color.into()));
    }

    /// Adds dots, the i-th in `colors[i]` (or the first colour).
    pub(super) fn dots(&mut self, xs: &[f64], ys: &[f64], colors: &[&str]) {
        let pts = xs
            .iter()
            .zip(ys)
            .enumerate()
            .filter(|(_, (x, y))| x.is_finite() && y.is_finite())
            .map(|(i, (x, y))| {
                let c = colors.get(i).or(colors.first()).copied().unwrap_or("#000");
                (*x, *y, c.to_string())
            })
            .collect();
        self.marks.push(Mark::Dots { pts });
    }

    /// Marks drawn from data.
    fn points(&self) -> usize {
        self.marks
            .iter()
            .map(|m| match m {
                Mark::Line { pts, .. } => pts.len(),
                Mark::Dots { pts } => pts.len(),
            })
            .sum()
    }

    /// The plot as an `<svg class="plot">` element.
    pub(super) fn finish(self) -> String {
        let mut buf = String::new();
        let drawn = self.draw(&mut buf);
        wrap(buf, drawn, &self.title, self.points(), &self.svg)
    }

    fn draw(&self, buf: &mut String) -> DrawResult {
        let root = SVGBackend::with_string(buf, self.size).into_drawing_area();
        root.fill(&WHITE)?;
        let mut chart = ChartBuilder::on(&root)
            .caption(&self.title, ("sans-serif", 15))
            .margin(8)
            .x_label_area_size(40)
            .y_label_area_size(72)
            .right_y_label_area_size(if self.y2.is_some() { 60 } else { 8 })
            .build_cartesian_2d(self.x.0..self.x.1, self.y.0..self.y.1)?
            .set_secondary_coord(
                self.x.0..self.x.1,
                self.y2.as_ref().map_or(self.y, |(_, r)| *r).0
                    ..self.y2.as_ref().map_or(self.y, |(_, r)| *r).1,
            );
        let (xs, ys) = ((self.x.1 - self.x.0) / 20.0, (self.y.1 - self.y.0) / 20.0);
        let fx = |v: &f64| num::tick(*v, xs);
        let fy = |v: &f64| num::tick(*v, ys);
        chart
            .configure_mesh()
            .x_desc(self.xl.as_str())
            .y_desc(self.yl.as_str())
            .x_label_formatter(&fx)
            .y_label_formatter(&fy)
            .light_line_style(RGBColor(245, 245, 245))
            .label_style(("sans-serif", 11))
            .axis_desc_style(("sans-serif", 12))
            .draw()?;
        if let Some((label, r)) = &self.y2 {
            let s2 = (r.1 - r.0) / 20.0;
            let f2 = |v: &f64| num::tick(*v, s2);
            chart
                .configure_secondary_axes()
                .y_desc(label.as_str())
                .y_label_formatter(&f2)
                .label_style(("sans-serif", 11).into_font().color(&color("#1f77b4")))
                .axis_desc_style(("sans-serif", 12))
                .draw()?;
        }
        for m in &self.marks {
            match m {
                Mark::Line {
                    pts,
                    color: c,
                    right,
                    dash,
                } => {
                    let style = color(c).stroke_width(2);
                    match (right, dash) {
                        (false, false) => {
                            chart.draw_series(LineSeries::new(pts.iter().copied(), style))?;
                        }
                        (false, true) => {
                            chart.draw_series(DashedLineSeries::new(
                                pts.iter().copied(),
                                6,
                                4,
                                style,
                            ))?;
                        }
                        (true, _) => {
                            chart.draw_secondary_series(LineSeries::new(
                                pts.iter().copied(),
                                style,
                            ))?;
                        }
                    }
                }
                Mark::Dots { pts } => {
                    chart
                        .draw_series(pts.iter().map(|(x, y, c)| {
                            Circle::new((*x, *y), 3, color(c).mix(0.75).filled())
                        }))?;
                }
            }
        }
        for (name, c) in &self.legend {
            let col = color(c);
            chart
                .draw_series(std::iter::empty::<Circle<(f64, f64), i32>>())?
                .label(name.as_str())
                .legend(move |(x, y)| Rectangle::new([(x, y - 2), (x + 14, y + 2)], col.filled()));
        }
        if !self.legend.is_empty() {
            chart
                .configure_series_labels()
                .position(SeriesLabelPosition::UpperLeft)
                .background_style(WHITE.mix(0.85))
                .border_style(RGBColor(200, 200, 200))
                .label_font(("sans-serif", 11))
                .draw()?;
        }
        root.present()?;
        Ok(())
    }
}

/// plotters' `<svg>` with the report's class, title, data count and extra elements; a message in
/// place of the plot when drawing failed.
pub(super) fn wrap(
    svg: String,
    drawn: DrawResult,
    title: &str,
    points: usize,
    extra: &str,
) -> String {
    let attrs = format!(
        "<svg class=\"plot\" role=\"img\" aria-label=\"{}\" data-points=\"{points}\" ",
        esc(title)
    );
    match drawn {
        Ok(()) => {
            let mut s = svg.replacen("<svg ", &attrs, 1);
            if !extra.is_empty()
                && let Some(end) = s.rfind("</svg>")
            {
                s.insert_str(end, extra);
            }
            if !s.ends_with('\n') {
                s.push('\n');
            }
            s
        }
        Err(e) => {
            let mut s =
                format!("{attrs}xmlns=\"http://www.w3.org/2000/svg\" width=\"{W}\" height=\"40\">");
            let _ = writeln!(
                s,
                "<text x=\"10\" y=\"24\" font-size=\"12\">{}: not drawn ({})</text></svg>",
                esc(title),
                esc(&e.to_string())
            );
            s
        }
    }
}
