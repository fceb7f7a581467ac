//! The report: one self-contained HTML file (no network, no scripts from elsewhere) with inline SVG
//! plots — measured error and model over time with temperature on a second axis, residual against
//! temperature with heating and cooling told apart, residual against the top candidates, residual
//! per segment for each model (before/after bars), and the verdict and figures as text.
//!
//! Layout: this module writes the page and its tables, [`figures`] the plots, [`plot`] the SVG
//! plot area they share (and why it is hand-written SVG). A short inline script only checks that
//! every plot has laid out (non-empty bounding box) and records the count on `<body data-plots=…>`,
//! which the headless-Chromium test (`host-tools/tests/report_chromium.rs`) reads back.

mod figures;
mod plot;

use figures::{candidate_plots, segment_bars, temp_plot, time_plot};
use plot::esc;
use std::fmt::Write as _;
use tcomp_discover::segments::{self, SegmentRow};
use tcomp_discover::{Analysis, Verdict};
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

/// Renders the report: the page, its tables, and the plots of [`figures`].
pub fn render(input: &ReportInput<'_>) -> String {
    let mut h = String::new();
    let _ = write!(
        h,
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>{t}</title>\n<style>body{{font-family:sans-serif;max-width:900px;margin:1em auto;color:#222}}table{{border-collapse:collapse;font-size:12px}}td,th{{border:1px solid #ccc;padding:2px 6px;text-align:right}}td:first-child,th:first-child{{text-align:left}}.verdict{{font-size:16px;padding:8px;background:#f4f4e8;border-left:4px solid #c90}}svg{{display:block;margin:10px 0}}</style></head>\n<body>\n<h1>{t}</h1>\n<p>Data: {d}</p>\n",
        t = esc(&input.title),
        d = esc(&input.data_name)
    );
    let segs = input
        .models
        .first()
        .map(|m| segments::table(&m.run))
        .unwrap_or_default();
    if let Some(a) = input.analysis {
        verdict(&mut h, input, a);
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
    segment_table(&mut h, input, &segs);
    h.push_str("<script>(function(){var s=document.querySelectorAll('svg.plot'),ok=0;for(var i=0;i<s.length;i++){var b=s[i].getBBox();if(b.width>0&&b.height>0&&s[i].querySelectorAll('polyline,circle,rect').length>1)ok++;}document.body.setAttribute('data-plots',String(s.length));document.body.setAttribute('data-plots-ok',String(ok));})();</script>\n</body></html>\n");
    h
}

/// The verdict, the criterion and the candidate table of the first model's diagnosis.
fn verdict(h: &mut String, input: &ReportInput<'_>, a: &Analysis) {
    let d = &a.diagnosis;
    let _ = write!(
        h,
        "<h2>Verdict</h2>\n<p class=\"verdict\" id=\"verdict\" data-verdict=\"{}\">{}</p>\n<p><small>Criterion: {}. Held-out: {}; noise floor estimate {:.4e} {u}{}.</small></p>\n",
        match d.verdict {
            Verdict::MissingEffect => "missing_effect",
            Verdict::None => "none",
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

/// Each segment of the first model's run: raw error and every model's residual std.
fn segment_table(h: &mut String, input: &ReportInput<'_>, segs: &[SegmentRow]) {
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
}
