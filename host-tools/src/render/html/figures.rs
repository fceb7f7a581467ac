//! The report's figures, each one SVG plot of the run the report shows (the held-out run when
//! there is one, where the base model fails): error and models over time, residual against
//! temperature for each model side by side (heating and cooling told apart), residual of each
//! model against the leading candidates, and residual per segment for each model.
//!
//! Everything is binned first ([`plot_bins`]): a 1 Hz residual is mostly noise, and a bursty
//! record (a few seconds of samples every few minutes) has no 60 s bin with enough samples, so
//! the bin adapts until the run gives enough bins. Axes carry units: the model's unit, else the
//! one the target column's name carries; the temperature's from its column name.

use super::ReportInput;
use super::bars::{BarSeries, bars};
use super::plot::{COLORS, Plot, range};
use super::{ModelRun, View};
use tcomp_discover::segments::SegmentRow;
use tcomp_discover::{Analysis, score};
use tcomp_train::binning::{adaptive_bin, bin_mean, bins};
use tcomp_train::features::FeatureSpec;
use tcomp_train::metrics::{self, Run};

/// Bins a plot aims for over a run.
const PLOT_BINS: f64 = 600.0;
/// Fewest bins a plot accepts before it shortens its bin.
const MIN_PLOT_BINS: usize = 20;
/// Width of a plot shown beside another (px).
const HALF_W: u32 = 430;

/// The bins of a plot over `time`: about [`PLOT_BINS`] bins of at least 60 s, shortened until a
/// bursty record still gives [`MIN_PLOT_BINS`].
pub(super) fn plot_bins(time: &[f64]) -> Vec<(usize, usize)> {
    let span = time.last().copied().unwrap_or(0.0) - time.first().copied().unwrap_or(0.0);
    let wanted = (span / PLOT_BINS).max(60.0);
    bins(time, adaptive_bin(time, wanted, MIN_PLOT_BINS))
}

/// Binned time in minutes, error, residual and temperature of a run.
fn binned(run: &Run) -> (Vec<f64>, Vec<f64>, Vec<f64>, Vec<f64>) {
    let b = plot_bins(&run.time);
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

fn model_color(k: usize) -> &'static str {
    COLORS.get(k % COLORS.len()).copied().unwrap_or("#d62728")
}

/// `label (unit)`, or the label alone when the unit is unknown.
fn axis(label: &str, unit: &str) -> String {
    if unit.is_empty() {
        label.to_string()
    } else {
        format!("{label} ({unit})")
    }
}

/// The measured error and each model over time (the page's first plot), with the defaults of
/// [`View`].
#[allow(
    dead_code,
    reason = "the figure API other report pages (calibrate) call"
)]
pub(super) fn time_plot(input: &ReportInput<'_>) -> Option<String> {
    time_plot_in(input, &View::default())
}

/// The measured error and each model over time, temperature on the right axis.
pub(super) fn time_plot_in(input: &ReportInput<'_>, view: &View<'_>) -> Option<String> {
    let first = input.models.first()?;
    let unit = view.unit(input);
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
        &format!(
            "{}: measured error and model over time",
            view.subject(input)
        ),
        "time (min)",
        &axis("error − mean", &unit),
        range(&t),
        range(&all),
    );
    p.right_axis(&axis("temperature", &view.temperature_unit()), range(&temp));
    p.line(&t, &ec, "#000000", "measured error", false, false);
    for (k, (name, f)) in curves.iter().enumerate() {
        p.line(&t, f, model_color(k), &format!("model {name}"), false, true);
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

/// One model's residual against temperature, in `unit`, full width.
#[allow(
    dead_code,
    reason = "the figure API other report pages (calibrate) call"
)]
pub(super) fn temp_plot(m: &ModelRun, unit: &str) -> String {
    let (_, _, r, _) = binned(&m.run);
    temp_plot_sized(m, unit, "°C", range(&r), None)
}

fn temp_plot_sized(
    m: &ModelRun,
    unit: &str,
    temp_unit: &str,
    y: (f64, f64),
    width: Option<u32>,
) -> String {
    let (t, _, r, temp) = binned(&m.run);
    let colors = rate_colors(&t, &temp);
    let mut p = Plot::new(
        &format!("Residual against temperature — {}", m.name),
        &axis("temperature", temp_unit),
        &axis("residual", unit),
        range(&temp),
        y,
    );
    if let Some(w) = width {
        p = p.width(w);
    }
    p.dots(&temp, &r, &colors);
    p.legend.push(("heating".into(), "#d62728".into()));
    p.legend.push(("cooling".into(), "#1f77b4".into()));
    p.legend.push(("hold".into(), "#7f7f7f".into()));
    p.finish()
}

/// Each model's residual against temperature, side by side on one residual scale.
pub(super) fn temp_plots_in(input: &ReportInput<'_>, view: &View<'_>) -> Vec<String> {
    let unit = view.unit(input);
    let all: Vec<f64> = input.models.iter().flat_map(|m| binned(&m.run).2).collect();
    let width = (input.models.len() > 1).then_some(HALF_W);
    input
        .models
        .iter()
        .map(|m| temp_plot_sized(m, &unit, &view.temperature_unit(), range(&all), width))
        .collect()
}

/// Residual against the leading candidates, on the training run's binned scoring state (what
/// `render` shows without a [`View`] of the shown run).
pub(super) fn candidate_plots(a: &Analysis, unit: &str) -> Vec<String> {
    let res = score::base_residual(&a.prepared);
    a.diagnosis
        .candidates
        .iter()
        .take(3)
        .filter_map(|c| {
            let x = score::binned_feature(&a.prepared, &c.expression).ok()?;
            let mut p = Plot::new(
                &format!("Residual against candidate: {} (training run)", c.effect),
                &c.expression,
                &axis("residual of the model's features", unit),
                range(&x),
                range(&res),
            );
            p.dots(&x, &res, &["#ff7f0e"]);
            Some(p.finish())
        })
        .collect()
}

/// Each model's residual on the shown run against the leading candidates' values on the same
/// run (binned alike): where the base model fails, its residual follows the missing effect; the
/// model that has it is flat. Falls back to [`candidate_plots`] without the shown run's data.
pub(super) fn candidate_plots_in(
    a: &Analysis,
    input: &ReportInput<'_>,
    view: &View<'_>,
) -> Vec<String> {
    let unit = view.unit(input);
    let (Some(data), Some(time_col), Some(first)) =
        (view.data, view.time.as_deref(), input.models.first())
    else {
        return candidate_plots(a, &unit);
    };
    let Ok(time) = data.time(time_col) else {
        return candidate_plots(a, &unit);
    };
    if time.len() != first.run.time.len() {
        return candidate_plots(a, &unit);
    }
    let b = plot_bins(time);
    let starts = tcomp_train::dataset::stretch_starts(time, view.gap_s);
    let residuals: Vec<(String, Vec<f64>)> = input
        .models
        .iter()
        .filter(|m| m.run.residual.len() == time.len())
        .map(|m| (m.name.clone(), bin_mean(&m.run.residual, &b)))
        .collect();
    let all: Vec<f64> = residuals
        .iter()
        .flat_map(|(_, r)| r.iter().copied())
        .collect();
    a.diagnosis
        .candidates
        .iter()
        .take(3)
        .filter_map(|c| {
            let spec = FeatureSpec {
                signals: a.diagnosis.model.signals.clone(),
                features: vec![c.expression.clone()],
            };
            let program = spec.program().ok()?;
            let rows = tcomp_train::features::compute(&program, data, time, &starts).ok()?;
            let col: Vec<f64> = rows
                .iter()
                .map(|r| r.first().copied().map_or(f64::NAN, f64::from))
                .collect();
            let x = bin_mean(&col, &b);
            let mut p = Plot::new(
                &format!(
                    "Residual against candidate: {} — {}",
                    c.effect,
                    view.run_label()
                ),
                &c.expression,
                &axis("residual", &unit),
                range(&x),
                range(&all),
            );
            for (k, (name, r)) in residuals.iter().enumerate() {
                let color = if k == 0 { "#ff7f0e" } else { model_color(k) };
                p.dots(&x, r, &[color]);
                p.legend.push((name.clone(), color.into()));
            }
            Some(p.finish())
        })
        .collect()
}

/// The profile of each leading candidate's estimated parameter: the training criterion (the log
/// evidence of the trainer's refit, on the training run alone) against the parameter on a log
/// scale, with the estimate and the interval of values the run cannot tell apart
/// ([`tcomp_discover::param`]) — how sharply the run pins τ, a window or a threshold down.
pub(super) fn profile_plots(a: &Analysis) -> Vec<String> {
    a.diagnosis
        .candidates
        .iter()
        .take(3)
        .filter_map(|c| {
            let e = c.estimate.as_ref()?;
            let pts: Vec<[f64; 2]> = e
                .profile
                .iter()
                .copied()
                .filter(|p| p[0] > 0.0 && p[1].is_finite())
                .collect();
            if pts.len() < 2 {
                return None;
            }
            let xs: Vec<f64> = pts.iter().map(|p| p[0].log10()).collect();
            let ys: Vec<f64> = pts.iter().map(|p| p[1]).collect();
            let what = match e.kind {
                tcomp_discover::families::ParamKind::TimeConstant => "τ (s)",
                tcomp_discover::families::ParamKind::Window => "window (s)",
                tcomp_discover::families::ParamKind::Threshold => "threshold",
            };
            let (lo, hi) = range(&ys);
            let mut p = Plot::new(
                &format!(
                    "Profile of {}: {} = {} ({} … {} cannot be told apart{})",
                    c.effect,
                    what,
                    tcomp_train::num::plain(e.value, 2),
                    tcomp_train::num::plain(e.interval[0], 2),
                    tcomp_train::num::plain(e.interval[1], 2),
                    if e.bounded {
                        ""
                    } else {
                        "; not bounded by the run"
                    }
                ),
                &format!("log10 {what}"),
                "log evidence of the refit (training run)",
                range(&xs),
                (lo, hi),
            );
            p.line(&xs, &ys, "#1f77b4", "profile", false, false);
            p.dots(&xs, &ys, &["#1f77b4"]);
            let v = e.value.log10();
            p.line(&[v, v], &[lo, hi], "#d62728", "estimate", false, false);
            for (k, b) in e.interval.iter().enumerate() {
                if *b > 0.0 {
                    let x = b.log10();
                    let name = if k == 0 { "interval" } else { "" };
                    p.line(&[x, x], &[lo, hi], "#7f7f7f", name, false, true);
                }
            }
            p.legend.retain(|(n, _)| !n.is_empty());
            Some(p.finish())
        })
        .collect()
}

/// The placebo test of each leading candidate that was tested: its placebos' statistics, sorted,
/// as dots; the candidate's own and the acceptance threshold as lines — what the acceptance was
/// judged against ([`tcomp_discover::placebo`]). A candidate judged in the second stage shows its
/// held-out improvement against its refitted placebos'.
pub(super) fn placebo_plots(a: &Analysis) -> Vec<String> {
    a.diagnosis
        .candidates
        .iter()
        .take(3)
        .filter_map(|c| {
            let pl = c.placebo.as_ref()?;
            let (values, own, threshold, label) = match &pl.refit {
                Some(r) => (
                    r.placebos_pct.clone(),
                    r.improvement_pct,
                    r.threshold_pct,
                    "held-out improvement of the trainer's refit (%)",
                ),
                None => (
                    pl.placebos.clone(),
                    pl.statistic,
                    pl.threshold,
                    "Δ log evidence under AR(1) noise",
                ),
            };
            let mut sorted: Vec<f64> = values.into_iter().filter(|v| v.is_finite()).collect();
            sorted.sort_by(f64::total_cmp);
            if sorted.is_empty() {
                return None;
            }
            let xs: Vec<f64> = (1..=sorted.len()).map(|i| i as f64).collect();
            let mut all = sorted.clone();
            all.extend([own, threshold].iter().filter(|v| v.is_finite()));
            let mut p = Plot::new(
                &format!(
                    "Placebos of {}: {} (its columns shifted in time; it {} them)",
                    c.effect,
                    label,
                    if pl.passes() {
                        "beats"
                    } else {
                        "does not beat"
                    }
                ),
                "placebo, sorted",
                label,
                (0.0, sorted.len() as f64 + 1.0),
                range(&all),
            );
            p.dots(&xs, &sorted, &["#7f7f7f"]);
            p.legend.push(("placebos".into(), "#7f7f7f".into()));
            let ends = [0.0, sorted.len() as f64 + 1.0];
            p.line(&ends, &[own, own], "#d62728", "the candidate", false, false);
            if threshold.is_finite() {
                p.line(
                    &ends,
                    &[threshold, threshold],
                    "#1f77b4",
                    "threshold",
                    false,
                    true,
                );
            }
            Some(p.finish())
        })
        .collect()
}

/// Row range of segment `s` in `run`.
fn rows_of(run: &Run, s: &SegmentRow) -> (usize, usize) {
    let a = run.time.partition_point(|&x| x < s.start_s);
    let b = run.time.partition_point(|&x| x <= s.end_s);
    (a, b)
}

/// Raw error std and each model's residual std per segment (bands left out: they are not spans
/// of time), as horizontal bars labelled by segment.
#[allow(
    dead_code,
    reason = "the figure API other report pages (calibrate) call"
)]
pub(super) fn segment_bars(input: &ReportInput<'_>, segs: &[SegmentRow]) -> Option<String> {
    segment_bars_in(input, segs, &View::default())
}

/// [`segment_bars`] with the units of `view`.
pub(super) fn segment_bars_in(
    input: &ReportInput<'_>,
    segs: &[SegmentRow],
    view: &View<'_>,
) -> Option<String> {
    let first = input.models.first()?;
    let rows: Vec<&SegmentRow> = segs.iter().filter(|s| s.kind != "band").collect();
    if rows.is_empty() {
        return None;
    }
    let std_of = |v: &[f64], run: &Run, s: &SegmentRow| {
        let (a, b) = rows_of(run, s);
        let part = v.get(a..b).unwrap_or(&[]);
        if part.is_empty() {
            f64::NAN
        } else {
            metrics::std(part)
        }
    };
    let mut series = vec![BarSeries {
        name: "raw error".into(),
        color: "#bbbbbb".into(),
        values: rows
            .iter()
            .map(|s| std_of(&first.run.error, &first.run, s))
            .collect(),
    }];
    for (j, m) in input.models.iter().enumerate() {
        series.push(BarSeries {
            name: m.name.clone(),
            color: model_color(j).into(),
            values: rows
                .iter()
                .map(|s| std_of(&m.run.residual, &m.run, s))
                .collect(),
        });
    }
    let categories: Vec<String> = rows.iter().map(|s| s.label.clone()).collect();
    Some(bars(
        &format!("{}: residual std per segment", view.subject(input)),
        &axis("std", &view.unit(input)),
        &categories,
        &series,
    ))
}
