//! `tcomp calibrate SPEC --units DIR`: every unit of a folder with the same spec, in parallel, one
//! folder of results (blobs, image, `summary.json`) per unit, and a fleet page naming the units
//! that stand apart.
//!
//! A unit is a subfolder of `DIR` (the spec's `[data]` file names are looked up in it) or a log
//! file (`.csv`, `.csv.gz`, split at the spec's `split-s`). Its serial is the number its name ends
//! in (`unit-0042` → 42), else its position. The per-unit HTML page is not written here (a
//! thousand 1 MB pages help nobody); `tcomp calibrate` on one unit writes it.
//!
//! The outlier rule, fixed before any fleet was looked at: per channel and per statistic (the
//! held-out residual RMS of what ships, and each coefficient of the poly3 baseline — the cubic's
//! coefficients mean the same thing in every unit, unlike an RBF's placed Gaussians), a unit is an
//! outlier when its robust z-score `|x − median| / (1.4826·MAD)` exceeds [`Z_OUTLIER`] = 5. Why
//! median/MAD: a planted outlier must not widen the yardstick it is measured with (a mean and
//! standard deviation are dragged by the outliers themselves). Why 5 and not the textbook 3.5: a
//! production line of 1,000 units × 4 statistics per channel makes thousands of comparisons, and
//! for a normal spread |z| > 3.5 happens 4.7·10⁻⁴ of the time — about two false alarms per
//! channel — while |z| > 5 happens 5.7·10⁻⁷ of the time, about one false alarm in 400 channels.

use super::channel::Settings;
use super::spec::{CalSpec, ChannelPlan, DataSource};
use super::unit::{self, UnitData};
use crate::output::files::Staging;
use anyhow::{Context, bail};
use rayon::prelude::*;
use serde::Serialize;
use std::path::{Path, PathBuf};
use tcomp_board_description::Board;

/// The robust z-score above which a unit is named an outlier (see the module doc for why 5).
pub const Z_OUTLIER: f64 = 5.0;

/// One unit to calibrate.
#[derive(Clone, Debug)]
pub struct UnitEntry {
    /// Folder or file name.
    pub name: String,
    /// Serial.
    pub serial: u64,
    /// Its data.
    pub source: DataSource,
}

/// One channel of one unit, as the fleet page needs it.
#[derive(Clone, Debug, Serialize)]
pub struct UnitChannel {
    /// Held-out RMS of what ships.
    pub residual_rms: Option<f64>,
    /// Held-out RMS of raw.
    pub raw_rms: Option<f64>,
    /// What ships.
    pub shipped: &'static str,
    /// Flags raised.
    pub flags: usize,
    /// The poly3 baseline's coefficients (normalised linear weights of T, T², T³).
    pub coefficients: Vec<f64>,
}

/// One unit's row.
#[derive(Clone, Debug, Serialize)]
pub struct UnitRow {
    /// Name.
    pub unit: String,
    /// Serial.
    pub serial: u64,
    /// Per channel, in the spec's order.
    pub channels: Vec<UnitChannel>,
}

/// The spread of one statistic over the fleet.
#[derive(Clone, Debug, Serialize)]
pub struct Spread {
    /// What.
    pub statistic: String,
    /// Median.
    pub median: f64,
    /// 1.4826·MAD (a standard deviation for a normal spread).
    pub robust_sigma: f64,
    /// Smallest.
    pub min: f64,
    /// Largest.
    pub max: f64,
    /// Units with a value.
    pub units: usize,
}

/// One channel's spreads.
#[derive(Clone, Debug, Serialize)]
pub struct ChannelSpread {
    /// Channel name.
    pub name: String,
    /// Unit of the residual.
    pub unit: String,
    /// Each statistic's spread.
    pub spreads: Vec<Spread>,
}

/// A unit named an outlier.
#[derive(Clone, Debug, Serialize)]
pub struct Outlier {
    /// Unit.
    pub unit: String,
    /// Channel.
    pub channel: String,
    /// Statistic.
    pub statistic: String,
    /// Its value.
    pub value: f64,
    /// Robust z-score.
    pub z: f64,
}

/// The fleet's JSON body.
#[derive(Serialize)]
pub struct Fleet {
    /// Units calibrated.
    pub units: usize,
    /// The rule.
    pub rule: String,
    /// Threshold on |z|.
    pub z_threshold: f64,
    /// Per channel, the spread of each statistic.
    pub channels: Vec<ChannelSpread>,
    /// Outliers, one per (unit, channel, statistic).
    pub outliers: Vec<Outlier>,
    /// The units named, once each.
    pub outlier_units: Vec<String>,
    /// Every unit's figures.
    pub rows: Vec<UnitRow>,
}

/// The units of `dir`, sorted by name.
pub fn units_in(spec: &CalSpec, dir: &Path) -> anyhow::Result<Vec<UnitEntry>> {
    let mut entries: Vec<PathBuf> = std::fs::read_dir(dir)
        .with_context(|| format!("--units {}", dir.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .collect();
    entries.sort();
    let mut units = Vec::new();
    for p in entries {
        if let Some(e) = entry(spec, &p, units.len() as u64 + 1)? {
            units.push(e);
        }
    }
    if units.is_empty() {
        bail!(
            "--units {}: no unit folders or log files in it",
            dir.display()
        );
    }
    Ok(units)
}

/// The unit at `path` (a folder holding the spec's `[data]` files, or a log file split at the
/// spec's `split-s`); `None` for anything else (a hidden file, `fleet-truth.json`). Its serial is
/// the number its name ends in, else `fallback`.
pub fn entry(spec: &CalSpec, path: &Path, fallback: u64) -> anyhow::Result<Option<UnitEntry>> {
    let Some(file_name) = path.file_name().map(|n| n.to_string_lossy().into_owned()) else {
        return Ok(None);
    };
    if file_name.starts_with('.') {
        return Ok(None);
    }
    let name = file_name
        .trim_end_matches(".gz")
        .trim_end_matches(".csv")
        .to_string();
    let source = if path.is_dir() {
        spec.source_in(path)?
    } else if file_name.ends_with(".csv") || file_name.ends_with(".csv.gz") {
        let Some(split_s) = spec.data.split_s else {
            bail!(
                "{} is a log file, and {} has no split-s to split it at",
                path.display(),
                spec.path.display()
            );
        };
        DataSource::Split {
            log: path.to_path_buf(),
            split_s,
        }
    } else {
        return Ok(None);
    };
    let digits: String = name
        .chars()
        .rev()
        .take_while(char::is_ascii_digit)
        .collect::<Vec<_>>()
        .into_iter()
        .rev()
        .collect();
    let serial = digits.parse().unwrap_or(fallback);
    Ok(Some(UnitEntry {
        name,
        serial,
        source,
    }))
}

/// Median of `v` (sorted in place); `None` when empty.
fn median(v: &mut [f64]) -> Option<f64> {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n == 0 {
        return None;
    }
    let hi = *v.get(n / 2)?;
    if n % 2 == 1 {
        return Some(hi);
    }
    Some((*v.get(n / 2 - 1)? + hi) / 2.0)
}

/// The spread of `(unit, value)` pairs and the units past the threshold.
pub fn spread_and_outliers(
    channel: &str,
    statistic: &str,
    values: &[(String, f64)],
) -> Option<(Spread, Vec<Outlier>)> {
    let mut v: Vec<f64> = values
        .iter()
        .map(|(_, x)| *x)
        .filter(|x| x.is_finite())
        .collect();
    let med = median(&mut v)?;
    let (min, max) = (*v.first()?, *v.last()?);
    let mut dev: Vec<f64> = v.iter().map(|x| (x - med).abs()).collect();
    let sigma = 1.4826 * median(&mut dev)?;
    let outliers = if sigma > 0.0 {
        values
            .iter()
            .filter(|(_, x)| x.is_finite())
            .map(|(u, x)| (u, *x, (x - med) / sigma))
            .filter(|(_, _, z)| z.abs() > Z_OUTLIER)
            .map(|(u, x, z)| Outlier {
                unit: u.clone(),
                channel: channel.to_string(),
                statistic: statistic.to_string(),
                value: x,
                z,
            })
            .collect()
    } else {
        Vec::new()
    };
    let spread = Spread {
        statistic: statistic.to_string(),
        median: med,
        robust_sigma: sigma,
        min,
        max,
        units: v.len(),
    };
    Some((spread, outliers))
}

/// The fleet's spreads and outliers from its rows.
pub fn analyse(plans: &[ChannelPlan], rows: Vec<UnitRow>) -> Fleet {
    let mut channels = Vec::new();
    let mut outliers = Vec::new();
    for (ci, p) in plans.iter().enumerate() {
        let ch = |r: &UnitRow| r.channels.get(ci).cloned();
        let mut stats: Vec<(String, Vec<(String, f64)>)> = vec![(
            "held-out residual rms".into(),
            rows.iter()
                .filter_map(|r| Some((r.unit.clone(), ch(r)?.residual_rms?)))
                .collect(),
        )];
        let n_coef = rows
            .iter()
            .filter_map(|r| ch(r).map(|c| c.coefficients.len()))
            .max()
            .unwrap_or(0);
        for k in 0..n_coef {
            stats.push((
                format!("poly3 coefficient of T^{}", k + 1),
                rows.iter()
                    .filter_map(|r| Some((r.unit.clone(), *ch(r)?.coefficients.get(k)?)))
                    .collect(),
            ));
        }
        let mut spreads = Vec::new();
        for (stat, values) in &stats {
            if let Some((s, o)) = spread_and_outliers(&p.name, stat, values) {
                spreads.push(s);
                outliers.extend(o);
            }
        }
        channels.push(ChannelSpread {
            name: p.name.clone(),
            unit: super::channel::options(p, None)
                .map(|o| o.unit)
                .unwrap_or_default(),
            spreads,
        });
    }
    let mut outlier_units: Vec<String> = outliers.iter().map(|o| o.unit.clone()).collect();
    outlier_units.sort();
    outlier_units.dedup();
    Fleet {
        units: rows.len(),
        rule: format!(
            "robust z = |x − median| / (1.4826·MAD) > {Z_OUTLIER}, per channel and statistic"
        ),
        z_threshold: Z_OUTLIER,
        channels,
        outliers,
        outlier_units,
        rows,
    }
}

/// Calibrates one unit into `dir/NAME/` and returns its row.
fn one(
    e: &UnitEntry,
    plans: &[ChannelPlan],
    board: Option<&Board>,
    settings: Settings,
    dir: &Path,
) -> anyhow::Result<UnitRow> {
    let data = UnitData::load(&e.source, plans)?;
    let u = unit::run(plans, data, e.serial, board, settings, &|| {})
        .with_context(|| format!("unit {}", e.name))?;
    let udir = dir.join(&e.name);
    std::fs::create_dir(&udir).with_context(|| format!("creating {}", udir.display()))?;
    unit::write_blobs(&u, &udir)?;
    let board_name = board.map(|b| b.path.display().to_string());
    let json = super::summary::to_json(&u, board_name.as_deref(), None)?;
    std::fs::write(udir.join("summary.json"), json)
        .with_context(|| format!("writing {}", udir.display()))?;
    Ok(UnitRow {
        unit: e.name.clone(),
        serial: e.serial,
        channels: u
            .channels
            .iter()
            .map(|c| UnitChannel {
                residual_rms: c.choice.residual_rms,
                raw_rms: c.model.figures.raw_rms,
                shipped: c.choice.shipped.name(),
                flags: c.choice.flags.len(),
                coefficients: c.poly3.summary.linear.clone(),
            })
            .collect(),
    })
}

/// How a fleet is run: what [`run`] takes of `tcomp calibrate`'s arguments.
#[derive(Clone, Copy, Debug)]
pub struct FleetOptions<'a> {
    /// The output folder: one folder per unit, the fleet page and `fleet.json`.
    pub out: &'a Path,
    /// How each unit's channels are run.
    pub settings: Settings,
    /// No progress display.
    pub quiet: bool,
}

/// Runs every unit of `dir` and writes the fleet page and `fleet.json`; returns the fleet and
/// the JSON.
pub fn run(
    options: &FleetOptions<'_>,
    spec: &CalSpec,
    plans: &[ChannelPlan],
    board: Option<&Board>,
    dir: &Path,
) -> anyhow::Result<(Fleet, String)> {
    let units = units_in(spec, dir)?;
    if let Some(e) = units.iter().find(|e| options.out.join(&e.name).exists()) {
        bail!(
            "--out {} already holds {}: choose a fresh output folder",
            options.out.display(),
            e.name
        );
    }
    let settings = options.settings;
    let staging = Staging::new("--out", options.out)?;
    let bar =
        crate::output::progress::counter(options.quiet, "calibrating", units.len() as u64, "units");
    let rows = units
        .par_iter()
        .map(|e| {
            let r = one(e, plans, board, settings, staging.path());
            bar.inc(1);
            r
        })
        .collect::<anyhow::Result<Vec<_>>>()?;
    bar.finish_and_clear();
    let (fleet, json) = write_fleet(plans, rows, spec, dir, staging.path())?;
    staging.commit()?;
    Ok((fleet, json))
}

/// Analyses the rows and writes `fleet.html` and `fleet.json` into `into`.
pub fn write_fleet(
    plans: &[ChannelPlan],
    rows: Vec<UnitRow>,
    spec: &CalSpec,
    units: &Path,
    into: &Path,
) -> anyhow::Result<(Fleet, String)> {
    let fleet = analyse(plans, rows);
    let html = crate::render::html::fleet::page(&fleet, spec);
    std::fs::write(into.join("fleet.html"), html).context("writing fleet.html")?;
    let subject = crate::output::json::Subject {
        data: Some(units.display().to_string()),
        ..Default::default()
    };
    let json = serde_json::to_string_pretty(&crate::output::json::Output {
        command: "calibrate",
        subject: &subject,
        body: &serde_json::json!({ "fleet": &fleet }),
    })?;
    std::fs::write(into.join("fleet.json"), &json).context("writing fleet.json")?;
    Ok((fleet, json))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn median_and_mad_name_a_far_unit_and_not_its_neighbours() {
        // 19 units spread ±1 around 10 and one at 30: the mean/std rule would be dragged by it.
        let mut values: Vec<(String, f64)> = (0..19)
            .map(|i| (format!("u{i}"), 10.0 + (f64::from(i) - 9.0) / 9.0))
            .collect();
        values.push(("far".into(), 30.0));
        let (s, o) = spread_and_outliers("c", "rms", &values).unwrap_or_else(|| {
            (
                Spread {
                    statistic: String::new(),
                    median: 0.0,
                    robust_sigma: 0.0,
                    min: 0.0,
                    max: 0.0,
                    units: 0,
                },
                Vec::new(),
            )
        });
        assert_eq!(s.units, 20);
        assert!((s.median - 10.0556).abs() < 1e-3, "{}", s.median);
        let named: Vec<&str> = o.iter().map(|o| o.unit.as_str()).collect();
        assert_eq!(named, ["far"]);
        // A unit at 5 robust σ exactly is not named: the rule is strictly greater.
        let edge = s.median + Z_OUTLIER * s.robust_sigma;
        values.push(("edge".into(), edge));
        let (_, o) = spread_and_outliers("c", "rms", &values).unwrap_or((s, Vec::new()));
        assert!(o.iter().all(|o| o.unit != "edge"));
    }
}
