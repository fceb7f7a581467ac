//! One unit: load its data once, run every channel in parallel (rayon), build its image through
//! `tcomp image`'s checks, and write the blobs, the image, the report and `summary.json` into a
//! directory.
//!
//! Why the board is applied to the plans first: a channel's sensor kind, axis and unit must match
//! the board row for the image to accept its model, so they default to the row's (the spec then
//! names only the target and the channel id).

use super::channel::{self, ChannelResult, Settings, Windows};
use super::ship::Shipped;
use super::spec::{CalSpec, ChannelPlan, DataSource};
use crate::image::{self, ChannelBlob};
use anyhow::{Context, bail};
use rayon::prelude::*;
use std::path::{Path, PathBuf};
use tcomp_board_description::Board;
use tcomp_train::Dataset;

/// The data of one unit.
pub struct UnitData {
    /// The log (split) or the training log.
    pub train_file: PathBuf,
    /// The verification log, when separate.
    pub verify_file: Option<PathBuf>,
    /// The split time, when one log is split.
    pub split_s: Option<f64>,
    main: Dataset,
    verify: Option<Dataset>,
}

impl UnitData {
    /// Loads the data of `source` for the channels of `plans`: the columns they use (the first
    /// channel's target first, so that in an autopilot log its message gives the rows) and the
    /// first channel's policies for messy rows.
    pub fn load(source: &DataSource, plans: &[super::spec::ChannelPlan]) -> anyhow::Result<Self> {
        let mut opts = tcomp_train::dataset::LoadOptions::default();
        for (k, plan) in plans.iter().enumerate() {
            let Ok(fit) = tcomp_train::FitOptions::from_spec(&plan.spec) else {
                continue;
            };
            let lo = fit.load_options();
            if k == 0 {
                opts = lo;
            } else {
                opts.columns.extend(lo.columns);
            }
        }
        let load =
            |p: &std::path::Path| Dataset::load_with(p, &opts, &tcomp_train::progress::Silent);
        Ok(match source {
            DataSource::Split { log, split_s } => Self {
                train_file: log.clone(),
                verify_file: None,
                split_s: Some(*split_s),
                main: load(log)?,
                verify: None,
            },
            DataSource::Pair { train, verify } => Self {
                train_file: train.clone(),
                verify_file: Some(verify.clone()),
                split_s: None,
                main: load(train)?,
                verify: Some(load(verify)?),
            },
        })
    }

    /// The training and held-out rows of a channel whose time column is `time`.
    pub fn windows(&self, time: &str) -> anyhow::Result<Windows<'_>> {
        let w = match (&self.verify, self.split_s) {
            (Some(v), _) => Windows {
                fit_data: &self.main,
                until: None,
                train: self.main.clone(),
                verify: v.clone(),
            },
            (None, Some(s)) => Windows {
                fit_data: &self.main,
                until: Some(s),
                train: self.main.select_time(time, f64::NEG_INFINITY, s)?,
                verify: self.main.select_time(time, s, f64::INFINITY)?,
            },
            (None, None) => bail!("no held-out data"),
        };
        for (what, d) in [("training", &w.train), ("held-out", &w.verify)] {
            if d.len() < 2 {
                bail!(
                    "{}: the {what} part has {} row(s) (split-s {:?}); at least 2 are needed",
                    self.train_file.display(),
                    d.len(),
                    self.split_s
                );
            }
        }
        Ok(w)
    }
}

/// The plans with the board row's sensor, axis and unit filled in where the spec left them.
pub fn apply_board(spec: &CalSpec, board: Option<&Board>) -> anyhow::Result<Vec<ChannelPlan>> {
    let Some(board) = board else {
        return Ok(spec.channels.clone());
    };
    let rows = board.channel_rows();
    spec.channels
        .iter()
        .map(|p| {
            let Some(id) = p.id else {
                bail!(
                    "{}: channel `{}` has no `id`: with a board, each channel names its row of {}",
                    spec.path.display(),
                    p.name,
                    board.path.display()
                );
            };
            let Some(row) = rows.iter().find(|r| r.id == id) else {
                let ids: Vec<String> = rows.iter().map(|r| r.id.to_string()).collect();
                bail!(
                    "{}: channel `{}`: id {id} is not in {} (its channels: {})",
                    spec.path.display(),
                    p.name,
                    board.path.display(),
                    ids.join(", ")
                );
            };
            let mut p = p.clone();
            let c = &mut p.spec.channel;
            c.sensor
                .get_or_insert_with(|| row.sensor.name().to_string());
            c.axis.get_or_insert_with(|| row.axis.to_string());
            c.unit.get_or_insert_with(|| row.unit.to_string());
            Ok(p)
        })
        .collect()
}

/// A calibrated unit.
pub struct UnitResult {
    /// Serial.
    pub serial: u64,
    /// Its data.
    pub data: UnitData,
    /// Its channels, in the spec's order.
    pub channels: Vec<ChannelResult>,
    /// The image, when there is a board.
    pub image: Option<Vec<u8>>,
}

/// File name of a channel's blob (`which`: "" for the model, "poly3", "before").
pub fn blob_name(channel: &str, which: &str) -> String {
    let safe: String = channel
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' || c == '_' {
                c
            } else {
                '_'
            }
        })
        .collect();
    if which.is_empty() {
        format!("{safe}.tcm")
    } else {
        format!("{safe}.{which}.tcm")
    }
}

/// Runs every channel of one unit (in parallel), ticking `tick` after each, and builds its image.
pub fn run(
    plans: &[ChannelPlan],
    data: UnitData,
    serial: u64,
    board: Option<&Board>,
    settings: Settings,
    tick: &(dyn Fn() + Sync),
) -> anyhow::Result<UnitResult> {
    let channels = plans
        .par_iter()
        .map(|p| {
            let time = channel::options(p, None)?.time;
            let w = data.windows(&time)?;
            let r = channel::run(p, &w, settings);
            tick();
            r
        })
        .collect::<anyhow::Result<Vec<_>>>()?;
    let image = match board {
        Some(b) => {
            let blobs: Vec<ChannelBlob> = channels
                .iter()
                .filter_map(|c| {
                    let bytes = match c.choice.shipped {
                        Shipped::Model => c.model.bytes.clone(),
                        Shipped::Poly3 => c.poly3.bytes.clone(),
                        Shipped::Raw => return None,
                    };
                    let which = if c.choice.shipped == Shipped::Poly3 {
                        "poly3"
                    } else {
                        ""
                    };
                    Some(ChannelBlob {
                        id: c.plan.id?,
                        path: PathBuf::from(blob_name(&c.plan.name, which)),
                        label: format!("channel `{}`", c.plan.name),
                        bytes,
                    })
                })
                .collect();
            Some(image::build(b, serial, image::created_now()?, &blobs)?)
        }
        None => None,
    };
    Ok(UnitResult {
        serial,
        data,
        channels,
        image,
    })
}

/// Writes a unit's blobs and image into `dir`.
pub fn write_blobs(u: &UnitResult, dir: &Path) -> anyhow::Result<()> {
    let write = |name: String, bytes: &[u8]| {
        let p = dir.join(&name);
        std::fs::write(&p, bytes).with_context(|| format!("writing {}", p.display()))
    };
    for c in &u.channels {
        write(blob_name(&c.plan.name, ""), &c.model.bytes)?;
        write(blob_name(&c.plan.name, "poly3"), &c.poly3.bytes)?;
        if let Some(a) = &c.accepted {
            write(blob_name(&c.plan.name, "before"), &a.before.bytes)?;
        }
    }
    if let Some(img) = &u.image {
        write("image.bin".into(), img)?;
    }
    Ok(())
}
