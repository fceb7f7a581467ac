//! The report's figures, each one SVG plot: error and model over time, residual against
//! temperature (heating and cooling told apart), residual against the leading candidates, and
//! residual per segment for each model.

use super::ModelRun;
use super::ReportInput;
use super::plot::{COLORS, H, MB, ML, MR, Plot, W, esc, range};
use std::fmt::Write as _;
use tcomp_discover::segments::SegmentRow;
use tcomp_discover::{Analysis, score};
use tcomp_train::features::{bin_mean, bins};
use tcomp_train::metrics::{self, Run};

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

pub(super) fn time_plot(input: &ReportInput<'_>) -> Option<String> {
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

pub(super) fn temp_plot(m: &ModelRun, unit: &str) -> String {
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

pub(super) fn candidate_plots(a: &Analysis, unit: &str) -> Vec<String> {
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

pub(super) fn segment_bars(input: &ReportInput<'_>, segs: &[SegmentRow]) -> Option<String> {
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
