//! The page of `tcomp calibrate`: an overview table of every channel (held-out RMS of raw, poly3
//! and the model, what ships and why, flags in red), the note on the shipping gate, then one
//! section per channel composed from the report's own parts ([`super::body`]: verdict, figures,
//! plots on the held-out run, segments) with the model, the poly3 baseline and, after `--accept`,
//! the model before it.

use super::{ModelRun, ReportInput, View, body, esc, head, tail};
use crate::calibrate::channel::ChannelResult;
use crate::calibrate::spec::CalSpec;
use crate::calibrate::summary::GATE_NOTE;
use crate::calibrate::unit::UnitResult;
use crate::output::json;
use crate::render::num;
use std::fmt::Write as _;

/// An anchor-safe id for a channel.
fn anchor(name: &str) -> String {
    name.chars()
        .map(|c| if c.is_ascii_alphanumeric() { c } else { '-' })
        .collect()
}

/// The overview table.
fn overview(h: &mut String, u: &UnitResult) {
    h.push_str("<h2>Overview (held-out run, RMS against the reference)</h2>\n<div class=\"scroll\"><table><tr><th>channel</th><th>raw</th><th>poly3 baseline</th><th>model</th><th>model change</th><th>ships</th><th>residual</th><th>change</th><th>status</th></tr>\n");
    for c in &u.channels {
        let unit = &c.unit;
        let n = |v: Option<f64>| v.map_or_else(|| "no data".into(), |v| num::num(v, unit));
        let f = &c.model.figures;
        let status = if c.choice.flags.is_empty() {
            "ok".to_string()
        } else {
            let worse: Vec<&str> = ["RAW", "POLY3"]
                .into_iter()
                .filter(|w| {
                    c.choice
                        .flags
                        .iter()
                        .any(|f| f.contains(&format!("THAN {w}")))
                })
                .collect();
            let all = esc(&c.choice.flags.join("; "));
            let short = if worse.is_empty() {
                all.clone()
            } else {
                format!("model worse than {}", worse.join(" and ").to_lowercase())
            };
            format!(
                "<span style=\"color:#b71c1c;font-weight:bold\" title=\"{all}\">FLAGGED: {short}</span>"
            )
        };
        let _ = writeln!(
            h,
            "<tr><td><a href=\"#{a}\">{name}</a></td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td><b>{}</b></td><td>{}</td><td>{}</td><td>{status}</td></tr>",
            esc(&n(f.raw_rms)),
            esc(&n(c.poly3.figures.residual_rms)),
            esc(&n(f.residual_rms)),
            num::pct(json::change(f.raw_rms, f.residual_rms)),
            c.choice.shipped.name(),
            esc(&n(c.choice.residual_rms)),
            num::pct(json::change(f.raw_rms, c.choice.residual_rms)),
            a = anchor(&c.plan.name),
            name = esc(&c.plan.name),
        );
    }
    h.push_str("</table></div>\n");
    let _ = writeln!(h, "<p><i>{}</i></p>", esc(GATE_NOTE));
    h.push_str("<p>A channel that ships <b>raw</b> has no model in the image: the firmware passes its raw value through with status \"no model\".</p>\n");
}

/// One channel's section.
fn section(h: &mut String, u: &UnitResult, c: &ChannelResult) {
    let _ = writeln!(
        h,
        "<h2 id=\"{}\">{}</h2>",
        anchor(&c.plan.name),
        esc(&c.plan.name)
    );
    for f in &c.choice.flags {
        let _ = writeln!(h, "<div class=\"flag\">{}</div>", esc(f));
    }
    let _ = writeln!(
        h,
        "<p>Ships: <b>{}</b> — {}.</p>",
        c.choice.shipped.name(),
        esc(&c.choice.reason)
    );
    if let Some(a) = &c.accepted {
        let n = |v: Option<f64>| v.map_or_else(|| "no data".into(), |v| num::num(v, &c.unit));
        let _ = writeln!(
            h,
            "<p>--accept: {} (chosen on the training run). Held-out model RMS before {}, after {} ({}).</p>",
            esc(&a.instruction),
            esc(&n(a.before.figures.residual_rms)),
            esc(&n(c.model.figures.residual_rms)),
            num::pct(json::change(
                a.before.figures.residual_rms,
                c.model.figures.residual_rms
            ))
        );
    }
    if c.analysis.is_some() {
        h.push_str("<p>The diagnosis below ran on the training run only (contiguous blocks held out in turn); the plots show the held-out run.</p>\n");
    }
    let mut models = vec![ModelRun {
        name: c.model.summary.method.to_string(),
        run: c.model.run.clone(),
    }];
    models.push(ModelRun {
        name: "poly3 baseline".into(),
        run: c.poly3.run.clone(),
    });
    if let Some(a) = &c.accepted {
        models.push(ModelRun {
            name: "before --accept".into(),
            run: a.before.run.clone(),
        });
    }
    let verify = u.data.windows(&c.opts.time).ok();
    let data_name = match &u.data.verify_file {
        Some(v) => format!(
            "{} (held out: {})",
            u.data.train_file.display(),
            v.display()
        ),
        None => format!(
            "{} (held out: time ≥ {} s)",
            u.data.train_file.display(),
            u.data
                .split_s
                .map_or_else(String::new, |s| num::plain(s, 6))
        ),
    };
    let input = ReportInput {
        title: c.plan.name.clone(),
        data_name,
        unit: c.unit.clone(),
        models,
        analysis: c.analysis.as_ref(),
        noise_floor: None,
    };
    let view = View {
        channel: Some(c.opts.target.clone()),
        temperature: c.temperature.clone(),
        data: verify.as_ref().map(|w| &w.verify),
        time: Some(c.opts.time.clone()),
        gap_s: c.plan.spec.run.gap,
        run: Some("held-out run".into()),
    };
    body(h, &input, &view);
}

/// The whole page.
pub fn page(u: &UnitResult, spec: &CalSpec) -> String {
    let title = format!("tcomp calibrate: unit {}", u.serial);
    let mut h = String::new();
    head(&mut h, &title);
    let _ = writeln!(
        h,
        "<h1>{}</h1>\n<p>Spec: {}. {} channel(s), {} flagged.</p>",
        esc(&title),
        esc(&spec.path.display().to_string()),
        u.channels.len(),
        u.channels
            .iter()
            .filter(|c| !c.choice.flags.is_empty())
            .count()
    );
    overview(&mut h, u);
    for c in &u.channels {
        section(&mut h, u, c);
    }
    tail(&mut h);
    h
}
