//! The report: one self-contained HTML file (no network, no scripts from elsewhere) with inline SVG
//! plots — measured error and model over time with temperature on a second axis, residual against
//! temperature with heating and cooling told apart, residual against the top candidates, residual
//! per segment for each model (before/after bars), and the verdict and figures as text.
//!
//! Why hand-written SVG: the plots are simple (lines, dots, bars), the file must open anywhere
//! without fonts or scripts fetched, and a few hundred lines of SVG text are easier to check in a
//! headless browser than a plotting stack. A short inline script only checks that every plot has
//! laid out (non-empty bounding box) and records the count on `<body data-plots=…>`, which the
//! headless-Chromium test reads back.

use crate::error::Result;
use crate::segments::{self, SegmentRow};
use crate::{Analysis, score};
use std::fmt::Write as _;
use tcomp_train::features::{bin_mean, bins};
use tcomp_train::metrics::{self, Run};

/// One model's run over the report's data.
#[derive(Clone, Debug)]
pub struct ModelRun {
    /// Legend name.
    pub name: String,
    /// The run.
    pub run: Run,
}

/// What the report shows.
pub struct ReportInput<'a> {
    /// Title.
    pub title: String,
    /// Name of the data file.
    pub data_name: String,
    /// Output unit.
    pub unit: String,
    /// Models (the first defines the segments).
    pub models: Vec<ModelRun>,
    /// A diagnosis of the first model, when available.
    pub analysis: Option<&'a Analysis>,
    /// Known noise floor (100 s bins), when available.
    pub noise_floor: Option<f64>,
}

const COLORS: [&str; 4] = ["#d62728", "#2ca02c", "#9467bd", "#8c564b"];
const W: f64 = 860.0;
const H: f64 = 300.0;
const ML: f64 = 70.0;
const MR: f64 = 70.0;
const MT: f64 = 30.0;
const MB: f64 = 45.0;

fn esc(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

fn range(vs: &[f64]) -> (f64, f64) {
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
struct Plot {
    svg: String,
    x: (f64, f64),
    y: (f64, f64),
    y2: Option<(f64, f64)>,
    legend: Vec<(String, String)>,
}

impl Plot {
    fn new(title: &str, xl: &str, yl: &str, x: (f64, f64), y: (f64, f64)) -> Self {
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

    fn px(&self, v: f64) -> f64 {
        ML + (v - self.x.0) / (self.x.1 - self.x.0) * (W - ML - MR)
    }
    fn py_in(r: (f64, f64), v: f64) -> f64 {
        H - MB - (v - r.0) / (r.1 - r.0) * (H - MT - MB)
    }
    fn py(&self, v: f64) -> f64 {
        Self::py_in(self.y, v)
    }

    fn right_axis(&mut self, label: &str, r: (f64, f64)) {
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

    fn line(&mut self, xs: &[f64], ys: &[f64], color: &str, name: &str, right: bool, dash: bool) {
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

    fn dots(&mut self, xs: &[f64], ys: &[f64], colors: &[&str]) {
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

    fn finish(mut self) -> String {
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

/// Binned (60 s) time in minutes, error, residual and temperature of a run.
fn binned(run: &Run) -> (Vec<f64>, Vec<f64>, Vec<f64>, Vec<f64>) {
    let span = run.time.last().copied().unwrap_or(0.0) - run.time.first().copied().unwrap_or(0.0);
    let b = bins(&run.time, (span / 600.0).max(60.0));
    let t: Vec<f64> = bin_mean(&run.time, &b).iter().map(|v| v / 60.0).collect();
    (
        t,
        bin_mean(&run.error, &b),
        bin_mean(&run.residual, &b),
        bin_mean(&run.temperature, &b),
    )
}

fn mean(v: &[f64]) -> f64 {
    v.iter().sum::<f64>() / v.len().max(1) as f64
}

fn time_plot(input: &ReportInput<'_>) -> Option<String> {
    let first = input.models.first()?;
    let (t, e, _, temp) = binned(&first.run);
    let em = mean(&e);
    let ec: Vec<f64> = e.iter().map(|v| v - em).collect();
    let mut all = ec.clone();
    let mut curves = Vec::new();
    for m in &input.models {
        let (_, e2, r2, _) = binned(&m.run);
        let f: Vec<f64> = e2.iter().zip(&r2).map(|(a, b)| a - b - em).collect();
        all.extend_from_slice(&f);
        curves.push((m.name.clone(), f));
    }
    let mut p = Plot::new(
        "Measured error and model over time",
        "time (min)",
        &format!("error − mean ({})", input.unit),
        range(&t),
        range(&all),
    );
    p.right_axis("temperature (°C)", range(&temp));
    p.line(&t, &ec, "#000", "measured error", false, false);
    for (k, (name, f)) in curves.iter().enumerate() {
        p.line(
            &t,
            f,
            COLORS.get(k % COLORS.len()).copied().unwrap_or("#d62728"),
            &format!("model {name}"),
            false,
            true,
        );
    }
    p.line(
        &t,
        &temp,
        "#1f77b4",
        "temperature (right axis)",
        true,
        false,
    );
    Some(p.finish())
}

fn rate_colors(t_min: &[f64], temp: &[f64]) -> Vec<&'static str> {
    let n = temp.len();
    (0..n)
        .map(|i| {
            let (a, c) = (i.saturating_sub(1), (i + 1).min(n.saturating_sub(1)));
            let dt = t_min.get(c).copied().unwrap_or(0.0) - t_min.get(a).copied().unwrap_or(0.0);
            let r = if dt > 0.0 {
                (temp.get(c).copied().unwrap_or(0.0) - temp.get(a).copied().unwrap_or(0.0)) / dt
            } else {
                0.0
            };
            if r > metrics::HOLD_RATE_PER_MIN {
                "#d62728"
            } else if r < -metrics::HOLD_RATE_PER_MIN {
                "#1f77b4"
            } else {
                "#7f7f7f"
            }
        })
        .collect()
}

fn temp_plot(m: &ModelRun, unit: &str) -> String {
    let (t, _, r, temp) = binned(&m.run);
    let colors = rate_colors(&t, &temp);
    let mut p = Plot::new(
        &format!("Residual against temperature — {}", m.name),
        "temperature (°C)",
        &format!("residual ({unit})"),
        range(&temp),
        range(&r),
    );
    p.dots(&temp, &r, &colors);
    p.legend.push(("heating".into(), "#d62728".into()));
    p.legend.push(("cooling".into(), "#1f77b4".into()));
    p.legend.push(("hold".into(), "#7f7f7f".into()));
    p.finish()
}

fn candidate_plots(a: &Analysis, unit: &str) -> Vec<String> {
    let res = score::base_residual(&a.prepared);
    a.diagnosis
        .candidates
        .iter()
        .take(3)
        .filter_map(|c| {
            let x = score::binned_feature(&a.prepared, &c.expression).ok()?;
            let mut p = Plot::new(
                &format!("Residual against candidate: {}", c.effect),
                &c.expression,
                &format!("residual of the model's features ({unit})"),
                range(&x),
                range(&res),
            );
            p.dots(&x, &res, &["#ff7f0e"]);
            Some(p.finish())
        })
        .collect()
}

fn segment_bars(input: &ReportInput<'_>, segs: &[SegmentRow]) -> Option<String> {
    let first = input.models.first()?;
    let rows: Vec<&SegmentRow> = segs.iter().filter(|s| s.kind != "band").collect();
    if rows.is_empty() {
        return None;
    }
    let idx = |run: &Run, s: &SegmentRow| {
        let a = run.time.partition_point(|&x| x < s.start_s);
        let b = run.time.partition_point(|&x| x <= s.end_s);
        (a, b)
    };
    let vals: Vec<Vec<f64>> = input
        .models
        .iter()
        .map(|m| {
            rows.iter()
                .map(|s| {
                    let (a, b) = idx(&m.run, s);
                    metrics::std(m.run.residual.get(a..b).unwrap_or(&[]))
                })
                .collect()
        })
        .collect();
    let raw: Vec<f64> = rows
        .iter()
        .map(|s| {
            let (a, b) = idx(&first.run, s);
            metrics::std(first.run.error.get(a..b).unwrap_or(&[]))
        })
        .collect();
    let top = vals
        .iter()
        .flatten()
        .chain(raw.iter())
        .fold(0.0f64, |m, v| m.max(*v))
        .max(1e-300)
        * 1.1;
    let mut p = Plot::new(
        "Residual std per segment (raw error in grey)",
        "segment",
        &format!("std ({})", input.unit),
        (0.0, rows.len() as f64),
        (0.0, top),
    );
    let nb = vals.len() + 1;
    let slot = (W - ML - MR) / rows.len() as f64;
    let bw = 0.8 * slot / nb as f64;
    for (k, s) in rows.iter().enumerate() {
        let x0 = ML + slot * k as f64 + 0.1 * slot;
        let series = std::iter::once((raw.get(k).copied().unwrap_or(0.0), "#bbbbbb")).chain(
            vals.iter().enumerate().map(|(j, v)| {
                (
                    v.get(k).copied().unwrap_or(0.0),
                    COLORS.get(j % COLORS.len()).copied().unwrap_or("#d62728"),
                )
            }),
        );
        for (j, (v, c)) in series.enumerate() {
            let y = p.py(v);
            let _ = writeln!(
                p.svg,
                "<rect x=\"{:.1}\" y=\"{y:.1}\" width=\"{bw:.1}\" height=\"{:.1}\" fill=\"{c}\"><title>{}: {v:.4e}</title></rect>",
                x0 + bw * j as f64,
                (H - MB - y).max(0.0),
                esc(&s.label)
            );
        }
        let _ = writeln!(
            p.svg,
            "<text x=\"{:.1}\" y=\"{}\" text-anchor=\"middle\" font-size=\"9\">{}</text>",
            x0 + 0.4 * slot,
            H - MB + 28.0,
            esc(&s.label.chars().take(18).collect::<String>())
        );
    }
    p.legend.push(("raw error".into(), "#bbbbbb".into()));
    for (j, m) in input.models.iter().enumerate() {
        p.legend.push((
            m.name.clone(),
            COLORS
                .get(j % COLORS.len())
                .copied()
                .unwrap_or("#d62728")
                .into(),
        ));
    }
    Some(p.finish())
}

/// Renders the report.
pub fn render(input: &ReportInput<'_>) -> Result<String> {
    let mut h = String::new();
    let _ = write!(
        h,
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>{t}</title>\n<style>body{{font-family:sans-serif;max-width:900px;margin:1em auto;color:#222}}table{{border-collapse:collapse;font-size:12px}}td,th{{border:1px solid #ccc;padding:2px 6px;text-align:right}}td:first-child,th:first-child{{text-align:left}}.verdict{{font-size:16px;padding:8px;background:#f4f4e8;border-left:4px solid #c90}}svg{{display:block;margin:10px 0}}</style></head>\n<body>\n<h1>{t}</h1>\n<p>Data: {d}</p>\n",
        t = esc(&input.title),
        d = esc(&input.data_name)
    );
    let mut segs = Vec::new();
    if let Some(m) = input.models.first() {
        segs = segments::table(&m.run);
    }
    if let Some(a) = input.analysis {
        let d = &a.diagnosis;
        let _ = write!(
            h,
            "<h2>Verdict</h2>\n<p class=\"verdict\" id=\"verdict\" data-verdict=\"{}\">{}</p>\n<p><small>Criterion: {}. Held-out: {}; noise floor estimate {:.4e} {u}{}.</small></p>\n",
            match d.verdict {
                crate::Verdict::MissingEffect => "missing_effect",
                crate::Verdict::None => "none",
            },
            esc(&d.verdict_text),
            esc(&d.criterion),
            esc(&d.base.heldout),
            d.base.noise_floor_estimate,
            input
                .noise_floor
                .map(|f| format!(" (true noise floor {f:.4e})"))
                .unwrap_or_default(),
            u = esc(&input.unit)
        );
        h.push_str("<h2>Candidates</h2>\n<table><tr><th>effect</th><th>expression</th><th>Δ log evidence</th><th>held-out after</th><th>improvement %</th><th>passes</th></tr>\n");
        for c in d.candidates.iter().take(12) {
            let _ = writeln!(
                h,
                "<tr><td>{}</td><td><code>{}</code></td><td>{:+.1}</td><td>{:.4e}</td><td>{:.1}</td><td>{}</td></tr>",
                esc(&c.effect),
                esc(&c.expressions.join(" ; ")),
                c.delta_log_evidence,
                c.residual_std_after,
                c.improvement_pct,
                if c.passes { "yes" } else { "no" }
            );
        }
        h.push_str("</table>\n");
    }
    h.push_str("<h2>Figures</h2>\n<table><tr><th>model</th><th>raw std</th><th>residual std</th><th>100 s bins: residual std</th><th>improvement %</th></tr>\n");
    for m in &input.models {
        let r = metrics::report(&m.run, 100.0);
        let _ = writeln!(
            h,
            "<tr><td>{}</td><td>{:.4e}</td><td>{:.4e}</td><td>{:.4e}</td><td>{:.1}</td></tr>",
            esc(&m.name),
            r.raw_std,
            r.residual_std,
            r.binned.residual_std,
            r.binned.improvement_pct
        );
    }
    h.push_str("</table>\n<h2>Plots</h2>\n");
    if let Some(s) = time_plot(input) {
        h.push_str(&s);
    }
    for m in &input.models {
        h.push_str(&temp_plot(m, &input.unit));
    }
    if let Some(a) = input.analysis {
        for s in candidate_plots(a, &input.unit) {
            h.push_str(&s);
        }
    }
    if let Some(s) = segment_bars(input, &segs) {
        h.push_str(&s);
    }
    h.push_str("<h2>Segments</h2>\n<table><tr><th>segment</th><th>start s</th><th>end s</th><th>raw std</th>");
    for m in &input.models {
        let _ = write!(h, "<th>{}</th>", esc(&m.name));
    }
    h.push_str("</tr>\n");
    let per_model: Vec<Vec<SegmentRow>> = input
        .models
        .iter()
        .map(|m| segments::table(&m.run))
        .collect();
    for (k, s) in segs.iter().enumerate() {
        let _ = write!(
            h,
            "<tr><td>{}</td><td>{:.0}</td><td>{:.0}</td><td>{:.4e}</td>",
            esc(&s.label),
            s.start_s,
            s.end_s,
            s.raw_std
        );
        for pm in &per_model {
            let v = pm.get(k).map_or(f64::NAN, |r| r.residual_std);
            let _ = write!(h, "<td>{v:.4e}</td>");
        }
        h.push_str("</tr>\n");
    }
    h.push_str("</table>\n");
    h.push_str("<script>(function(){var s=document.querySelectorAll('svg.plot'),ok=0;for(var i=0;i<s.length;i++){var b=s[i].getBBox();if(b.width>0&&b.height>0&&s[i].querySelectorAll('polyline,circle,rect').length>1)ok++;}document.body.setAttribute('data-plots',String(s.length));document.body.setAttribute('data-plots-ok',String(ok));})();</script>\n</body></html>\n");
    Ok(h)
}
