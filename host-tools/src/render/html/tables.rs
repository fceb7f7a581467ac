//! The report's tables: the verdict with the candidate table, each model's figures, and the
//! segments of the shown run. Every figure is written by [`num`] with its unit, every change by
//! [`num::pct`] (negative when the residual fell), so the tables read like the plots' axes.

use super::ReportInput;
use super::plot::esc;
use crate::render::num;
use std::fmt::Write as _;
use tcomp_discover::segments::{self, SegmentRow};
use tcomp_discover::{Analysis, Verdict};
use tcomp_train::metrics;

/// The verdict, the criterion and the candidate table of the first model's diagnosis.
pub(super) fn verdict(h: &mut String, a: &Analysis, unit: &str, noise_floor: Option<f64>) {
    let d = &a.diagnosis;
    let _ = write!(
        h,
        "<h2>Verdict</h2>\n<p class=\"verdict\" id=\"verdict\" data-verdict=\"{}\">{}</p>\n<p><small>Criterion: {}. Held-out: {}; noise floor estimate {}{}.</small></p>\n",
        match d.verdict {
            Verdict::MissingEffect => "missing_effect",
            Verdict::CannotTell => "cannot_tell",
            Verdict::None => "none",
        },
        esc(&d.verdict_text),
        esc(&d.criterion),
        esc(&d.base.heldout),
        esc(&num::num(d.base.noise_floor_estimate, unit)),
        noise_floor
            .map(|f| format!(" (true noise floor {})", esc(&num::num(f, unit))))
            .unwrap_or_default(),
    );
    let _ = write!(
        h,
        "<h2>Candidates</h2>\n<div class=\"scroll\"><table><tr><th>effect</th><th>expression</th><th>Δ log evidence</th><th>held-out before</th><th>held-out after</th><th>change</th><th title=\"Δ log evidence under AR(1) noise against the best placebo (its columns shifted in time)\">vs placebos</th><th>passes</th></tr>\n"
    );
    for c in d.candidates.iter().take(12) {
        let _ = writeln!(
            h,
            "<tr><td>{}</td><td><code>{}</code></td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td></tr>",
            esc(&c.effect),
            esc(&c.expressions.join(" ; ")),
            num::signed(c.delta_log_evidence, 1),
            esc(&num::num(c.residual_std_before, unit)),
            esc(&num::num(c.residual_std_after, unit)),
            num::pct(num::change_pct(c.residual_std_before, c.residual_std_after)),
            esc(&crate::render::candidates::placebo(c)),
            if c.passes { "yes" } else { "no" }
        );
    }
    h.push_str("</table></div>\n");
}

/// Each model's figures on the shown run: raw and residual std, the same on 100 s bins, and the
/// change from raw to residual.
pub(super) fn figures(h: &mut String, input: &ReportInput<'_>, unit: &str) {
    h.push_str("<h2>Figures</h2>\n<div class=\"scroll\"><table><tr><th>model</th><th>raw std</th><th>residual std</th><th>100 s bins: raw std</th><th>100 s bins: residual std</th><th>change (100 s bins)</th></tr>\n");
    for m in &input.models {
        let r = metrics::report(&m.run, 100.0);
        let binned = |v: f64| {
            if r.binned.bins > 1 {
                num::num(v, unit)
            } else {
                "no bins".into()
            }
        };
        let _ = writeln!(
            h,
            "<tr><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td></tr>",
            esc(&m.name),
            esc(&num::num(r.raw_std, unit)),
            esc(&num::num(r.residual_std, unit)),
            esc(&binned(r.binned.raw_std)),
            esc(&binned(r.binned.residual_std)),
            if r.binned.bins > 1 {
                num::pct(num::change_pct(r.binned.raw_std, r.binned.residual_std))
            } else {
                "n/a".into()
            }
        );
    }
    h.push_str("</table></div>\n");
}

/// When a segment is: minutes from–to for a span of time; a band spreads over the run.
fn span(s: &SegmentRow) -> String {
    if s.kind == "band" {
        "(spread over the run)".into()
    } else {
        format!(
            "{}–{} min",
            num::plain(s.start_s / 60.0, 3),
            num::plain(s.end_s / 60.0, 3)
        )
    }
}

/// Each segment of the first model's run: when, at what temperature, raw error and every
/// model's residual std.
pub(super) fn segments(
    h: &mut String,
    input: &ReportInput<'_>,
    segs: &[SegmentRow],
    unit: &str,
    temp_unit: &str,
) {
    h.push_str("<h2>Segments</h2>\n<div class=\"scroll\"><table><tr><th>segment</th><th>when</th><th>mean temperature</th><th>raw std</th>");
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
            "<tr><td>{}</td><td>{}</td><td>{}</td><td>{}</td>",
            esc(&s.label),
            esc(&span(s)),
            esc(&num::with_unit(
                num::plain(s.mean_temperature, 3),
                temp_unit
            )),
            esc(&num::num(s.raw_std, unit))
        );
        for pm in &per_model {
            let v = pm
                .get(k)
                .map_or_else(|| "n/a".into(), |r| num::num(r.residual_std, unit));
            let _ = write!(h, "<td>{}</td>", esc(&v));
        }
        h.push_str("</tr>\n");
    }
    h.push_str("</table></div>\n");
}
