//! `tcomp calibrate SPEC --collect DIR`: the fleet's rows read back from the `summary.json` each
//! per-unit batch job wrote (`--unit UNIT --out DIR/UNIT`, e.g. as a Slurm array task), so the
//! fleet page of a line calibrated on many machines is the same as that of `--units` on one.

use super::fleet::{UnitChannel, UnitRow};
use super::spec::ChannelPlan;
use anyhow::{Context, bail};
use std::path::{Path, PathBuf};

/// The fleet's rows from the `summary.json` of each unit folder in `dir` (the outputs of
/// per-unit batch jobs: `tcomp calibrate SPEC --unit UNIT --out DIR/UNIT`).
pub fn collect(plans: &[ChannelPlan], dir: &Path) -> anyhow::Result<Vec<UnitRow>> {
    let mut dirs: Vec<PathBuf> = std::fs::read_dir(dir)
        .with_context(|| format!("--collect {}", dir.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.join("summary.json").is_file())
        .collect();
    dirs.sort();
    if dirs.is_empty() {
        bail!(
            "--collect {}: no unit folder with a summary.json in it",
            dir.display()
        );
    }
    dirs.iter().map(|d| row_of_summary(plans, d)).collect()
}

/// One unit's row from its `summary.json`.
fn row_of_summary(plans: &[ChannelPlan], d: &Path) -> anyhow::Result<UnitRow> {
    let p = d.join("summary.json");
    let v: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(&p).with_context(|| format!("reading {}", p.display()))?,
    )
    .with_context(|| format!("{}", p.display()))?;
    let unit = d
        .file_name()
        .map_or_else(String::new, |n| n.to_string_lossy().into_owned());
    let chans = v["channels"].as_array().cloned().unwrap_or_default();
    let channels = plans
        .iter()
        .map(|plan| {
            let c = chans
                .iter()
                .find(|c| c["name"] == plan.name.as_str())
                .with_context(|| format!("{}: no channel `{}`", p.display(), plan.name))?;
            Ok(UnitChannel {
                residual_rms: c["heldout"]["residual_rms"].as_f64(),
                raw_rms: c["heldout"]["raw_rms"].as_f64(),
                shipped: match c["shipped"].as_str() {
                    Some("poly3") => "poly3",
                    Some("raw") => "raw",
                    _ => "model",
                },
                flags: c["flags"].as_array().map_or(0, Vec::len),
                coefficients: c["poly3_coefficients"]
                    .as_array()
                    .map(|a| a.iter().filter_map(serde_json::Value::as_f64).collect())
                    .unwrap_or_default(),
            })
        })
        .collect::<anyhow::Result<Vec<_>>>()?;
    Ok(UnitRow {
        unit,
        serial: v["serial"].as_u64().unwrap_or(0),
        channels,
    })
}
