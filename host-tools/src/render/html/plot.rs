//! The SVG plot area of the report: axes with ticks, an optional right axis, lines, dots and a
//! legend, written as SVG text.
//!
//! Why hand-written: the plots are simple (lines, dots, bars), the file must open anywhere without
//! fonts or scripts fetched, and a few hundred lines of SVG text are easier to check in a headless
//! browser than a plotting stack (`plotters` returns with the rewrite of the report's plots).

use std::fmt::Write as _;

pub(super) const COLORS: [&str; 4] = ["#d62728", "#2ca02c", "#9467bd", "#8c564b"];
pub(super) const W: f64 = 860.0;
pub(super) const H: f64 = 300.0;
pub(super) const ML: f64 = 70.0;
pub(super) const MR: f64 = 70.0;
pub(super) const MT: f64 = 30.0;
pub(super) const MB: f64 = 45.0;

pub(super) fn esc(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

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
        return (lo - 1.0, hi + 1.0);
    }
    let pad = 0.05 * (hi - lo);
    (lo - pad, hi + pad)
}

fn ticks(lo: f64, hi: f64) -> Vec<f64> {
    let span = hi - lo;
    let raw = span / 5.0;
    let mag = 10f64.powf(raw.log10().floor());
    let step = [1.0, 2.0, 5.0, 10.0]
        .iter()
        .map(|m| m * mag)
        .find(|s| span / s <= 6.0)
        .unwrap_or(10.0 * mag);
    let mut t = (lo / step).ceil() * step;
    let mut out = Vec::new();
    while t <= hi + 1e-9 * step && out.len() < 12 {
        out.push(if t.abs() < 1e-12 * step { 0.0 } else { t });
        t += step;
    }
    out
}

fn fmt_tick(v: f64) -> String {
    let a = v.abs();
    if a == 0.0 {
        "0".into()
    } else if !(1e-3..1e5).contains(&a) {
        format!("{v:.1e}")
    } else {
        let s = format!("{v:.4}");
        let s = s.trim_end_matches('0').trim_end_matches('.');
        s.to_string()
    }
}

/// A plot area with a left axis, an optional right axis, and marks.
pub(super) struct Plot {
    pub(super) svg: String,
    x: (f64, f64),
    y: (f64, f64),
    y2: Option<(f64, f64)>,
    pub(super) legend: Vec<(String, String)>,
}

impl Plot {
    pub(super) fn new(title: &str, xl: &str, yl: &str, x: (f64, f64), y: (f64, f64)) -> Self {
        let mut svg = format!(
            "<svg class=\"plot\" xmlns=\"http://www.w3.org/2000/svg\" width=\"{W}\" height=\"{H}\" viewBox=\"0 0 {W} {H}\" role=\"img\" aria-label=\"{t}\">\n<text x=\"{cx}\" y=\"18\" text-anchor=\"middle\" font-size=\"14\" font-weight=\"bold\">{t}</text>\n",
            t = esc(title),
            cx = W / 2.0
        );
        let _ = writeln!(
            svg,
            "<rect x=\"{ML}\" y=\"{MT}\" width=\"{}\" height=\"{}\" fill=\"none\" stroke=\"#888\"/>",
            W - ML - MR,
            H - MT - MB
        );
        let mut p = Self {
            svg,
            x,
            y,
            y2: None,
            legend: Vec::new(),
        };
        for t in ticks(x.0, x.1) {
            let px = p.px(t);
            let _ = writeln!(
                p.svg,
                "<line x1=\"{px:.1}\" y1=\"{}\" x2=\"{px:.1}\" y2=\"{}\" stroke=\"#eee\"/><text x=\"{px:.1}\" y=\"{}\" text-anchor=\"middle\" font-size=\"11\">{}</text>",
                MT,
                H - MB,
                H - MB + 15.0,
                fmt_tick(t)
            );
        }
        for t in ticks(y.0, y.1) {
            let py = p.py(t);
            let _ = writeln!(
                p.svg,
                "<line x1=\"{ML}\" y1=\"{py:.1}\" x2=\"{}\" y2=\"{py:.1}\" stroke=\"#eee\"/><text x=\"{}\" y=\"{:.1}\" text-anchor=\"end\" font-size=\"11\">{}</text>",
                W - MR,
                ML - 5.0,
                py + 4.0,
                fmt_tick(t)
            );
        }
        let _ = writeln!(
            p.svg,
            "<text x=\"{}\" y=\"{}\" text-anchor=\"middle\" font-size=\"12\">{}</text><text transform=\"translate(16,{}) rotate(-90)\" text-anchor=\"middle\" font-size=\"12\">{}</text>",
            ML + (W - ML - MR) / 2.0,
            H - 8.0,
            esc(xl),
            MT + (H - MT - MB) / 2.0,
            esc(yl)
        );
        p
    }

    pub(super) fn px(&self, v: f64) -> f64 {
        ML + (v - self.x.0) / (self.x.1 - self.x.0) * (W - ML - MR)
    }
    fn py_in(r: (f64, f64), v: f64) -> f64 {
        H - MB - (v - r.0) / (r.1 - r.0) * (H - MT - MB)
    }
    pub(super) fn py(&self, v: f64) -> f64 {
        Self::py_in(self.y, v)
    }

    pub(super) fn right_axis(&mut self, label: &str, r: (f64, f64)) {
        self.y2 = Some(r);
        for t in ticks(r.0, r.1) {
            let py = Self::py_in(r, t);
            let _ = writeln!(
                self.svg,
                "<text x=\"{}\" y=\"{:.1}\" font-size=\"11\" fill=\"#1f77b4\">{}</text>",
                W - MR + 5.0,
                py + 4.0,
                fmt_tick(t)
            );
        }
        let _ = writeln!(
            self.svg,
            "<text transform=\"translate({},{}) rotate(90)\" text-anchor=\"middle\" font-size=\"12\" fill=\"#1f77b4\">{}</text>",
            W - 14.0,
            MT + (H - MT - MB) / 2.0,
            esc(label)
        );
    }

    pub(super) fn line(
        &mut self,
        xs: &[f64],
        ys: &[f64],
        color: &str,
        name: &str,
        right: bool,
        dash: bool,
    ) {
        let r = if right {
            self.y2.unwrap_or(self.y)
        } else {
            self.y
        };
        let pts: Vec<String> = xs
            .iter()
            .zip(ys)
            .filter(|(x, y)| x.is_finite() && y.is_finite())
            .map(|(x, y)| format!("{:.1},{:.1}", self.px(*x), Self::py_in(r, *y)))
            .collect();
        let _ = writeln!(
            self.svg,
            "<polyline fill=\"none\" stroke=\"{color}\" stroke-width=\"1.5\"{} points=\"{}\"/>",
            if dash {
                " stroke-dasharray=\"5,3\""
            } else {
                ""
            },
            pts.join(" ")
        );
        self.legend.push((name.to_string(), color.to_string()));
    }

    pub(super) fn dots(&mut self, xs: &[f64], ys: &[f64], colors: &[&str]) {
        for (i, (x, y)) in xs.iter().zip(ys).enumerate() {
            if !(x.is_finite() && y.is_finite()) {
                continue;
            }
            let c = colors.get(i).or(colors.first()).copied().unwrap_or("#000");
            let _ = writeln!(
                self.svg,
                "<circle cx=\"{:.1}\" cy=\"{:.1}\" r=\"2.2\" fill=\"{c}\" fill-opacity=\"0.7\"/>",
                self.px(*x),
                self.py(*y)
            );
        }
    }

    pub(super) fn finish(mut self) -> String {
        for (k, (name, color)) in self.legend.iter().enumerate() {
            let y = MT + 14.0 + 16.0 * k as f64;
            let _ = writeln!(
                self.svg,
                "<rect x=\"{}\" y=\"{}\" width=\"12\" height=\"3\" fill=\"{color}\"/><text x=\"{}\" y=\"{}\" font-size=\"11\">{}</text>",
                ML + 8.0,
                y - 4.0,
                ML + 24.0,
                y,
                esc(name)
            );
        }
        self.svg.push_str("</svg>\n");
        self.svg
    }
}
