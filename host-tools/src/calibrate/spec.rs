//! The calibration spec: one TOML file naming the unit, the data and the channels.
//!
//! ```toml
//! [unit]
//! serial = 1
//! board = "../../firmware/descriptions/mems6.toml"   # relative to this file
//! [data]
//! log = "mems_thermal_cycle.csv"                     # or train = … and verify = …
//! split-s = 3130                                     # train on t < 3130 s, verify on the rest
//! [defaults]
//! feature = ["temp_imu_C"]                           # any key of `tcomp fit --spec`
//! [[channel]]
//! target = "gyro_x_rad_s"
//! id = 0                                             # the board description's channel
//! ```
//! `[defaults]` and each `[[channel]]` take the keys of `tcomp fit --spec` (the trainer's
//! [`Spec`] structs, read the same way), a channel's keys laid over the defaults; a channel adds
//! `name` (default: its target) and `id`. With a board, a channel's sensor, axis and unit default
//! to the board row's, so that the image's checks pass without repeating them.
//!
//! Why the key check walks toml's spanned tables: serde's `flatten` (four option structs in one
//! table) cannot refuse unknown keys, and a typo must be refused with its file, line and column.
//! `from`/`until` are refused too: the `[data]` section alone says what is trained on and what is
//! held out, so no channel can quietly train on its verification rows.

use anyhow::{Context, bail};
use serde::Deserialize;
use std::path::{Path, PathBuf};
use tcomp_train::layer::Layer;
use tcomp_train::{ChannelOptions, FeatureOptions, MethodOptions, RunOptions, Spec};
use toml::de::{DeTable, DeValue};

/// `[unit]`.
#[derive(Clone, Debug, Default, Deserialize)]
#[serde(deny_unknown_fields, rename_all = "kebab-case")]
pub struct UnitSection {
    /// Serial number of the unit (its image is refused by another unit).
    pub serial: Option<u64>,
    /// Board description (relative to the spec file): with it, an image is written.
    pub board: Option<PathBuf>,
}

/// `[data]`: one log and a split time, or a training and a verification log.
#[derive(Clone, Debug, Default, Deserialize)]
#[serde(deny_unknown_fields, rename_all = "kebab-case")]
pub struct DataSection {
    /// One log, split at `split-s`.
    pub log: Option<PathBuf>,
    /// Training log.
    pub train: Option<PathBuf>,
    /// Verification log.
    pub verify: Option<PathBuf>,
    /// Rows with time < this train; the rest verify (s).
    pub split_s: Option<f64>,
}

/// `[defaults]` or a `[[channel]]`: the fit spec's keys (and, for a channel, `name` and `id`).
#[derive(Clone, Debug, Default, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub struct Section {
    /// Channel name (default: the target column).
    pub name: Option<String>,
    /// Channel id in the board description.
    pub id: Option<u16>,
    /// Reference, gaps.
    #[serde(flatten)]
    pub run: RunOptions,
    /// Columns.
    #[serde(flatten)]
    pub channel: ChannelOptions,
    /// Signals and features.
    #[serde(flatten)]
    pub features: FeatureOptions,
    /// Method.
    #[serde(flatten)]
    pub method: MethodOptions,
}

impl Section {
    fn spec(&self) -> Spec {
        Spec {
            run: self.run.clone(),
            channel: self.channel.clone(),
            features: self.features.clone(),
            method: self.method.clone(),
        }
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Raw {
    #[serde(default)]
    unit: UnitSection,
    data: DataSection,
    #[serde(default)]
    defaults: Section,
    channel: Vec<Section>,
}

/// Where the data come from, resolved against the spec's directory.
#[derive(Clone, Debug, PartialEq)]
pub enum DataSource {
    /// One log split at a time.
    Split {
        /// The log.
        log: PathBuf,
        /// Split time (s).
        split_s: f64,
    },
    /// Separate logs.
    Pair {
        /// Training log.
        train: PathBuf,
        /// Verification log.
        verify: PathBuf,
    },
}

/// One channel to calibrate: its name, board id and its merged fit spec.
#[derive(Clone, Debug)]
pub struct ChannelPlan {
    /// Name (file names, tables).
    pub name: String,
    /// Board channel id.
    pub id: Option<u16>,
    /// The fit spec: defaults with the channel's keys over them.
    pub spec: Spec,
}

/// A parsed calibration spec.
#[derive(Clone, Debug)]
pub struct CalSpec {
    /// The spec file.
    pub path: PathBuf,
    /// Unit serial (default 0).
    pub serial: u64,
    /// Board description, resolved.
    pub board: Option<PathBuf>,
    /// The data as written (relative paths resolved against `base`).
    pub data: DataSection,
    /// The spec's directory.
    pub base: PathBuf,
    /// The channels.
    pub channels: Vec<ChannelPlan>,
}

impl CalSpec {
    /// Reads and checks a spec file.
    pub fn load(path: &Path) -> anyhow::Result<Self> {
        let text =
            std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
        Self::parse(path, &text)
    }

    /// Parses the text of a spec; `path` names it and its directory resolves relative paths.
    pub fn parse(path: &Path, text: &str) -> anyhow::Result<Self> {
        let file = path.display();
        check_keys(&file.to_string(), text)?;
        let raw: Raw = toml::from_str(text).map_err(|e| anyhow::anyhow!("{file}: {e}"))?;
        let base = path
            .parent()
            .filter(|p| !p.as_os_str().is_empty())
            .unwrap_or(Path::new("."))
            .to_path_buf();
        if raw.channel.is_empty() {
            bail!("{file}: no [[channel]]: name at least one target to calibrate");
        }
        let mut channels: Vec<ChannelPlan> = Vec::new();
        for (i, c) in raw.channel.iter().enumerate() {
            let spec = raw.defaults.spec().merged(c.spec());
            let Some(target) = spec.channel.target.clone() else {
                bail!("{file}: channel {} has no `target` column", i + 1);
            };
            let name = c.name.clone().unwrap_or(target);
            if channels.iter().any(|p| p.name == name) {
                bail!("{file}: two channels are named `{name}` (give one a `name`)");
            }
            tcomp_train::FitOptions::from_spec(&spec)
                .map_err(|e| anyhow::anyhow!("{file}: channel `{name}`: {e}"))?;
            channels.push(ChannelPlan {
                name,
                id: c.id.or(raw.defaults.id),
                spec,
            });
        }
        let spec = Self {
            path: path.to_path_buf(),
            serial: raw.unit.serial.unwrap_or(0),
            board: raw.unit.board.map(|b| base.join(b)),
            data: raw.data,
            base,
            channels,
        };
        spec.source_in(&spec.base)?;
        Ok(spec)
    }

    /// The data source with relative paths resolved against `dir` (the spec's directory, or a
    /// unit's folder in a fleet run).
    pub fn source_in(&self, dir: &Path) -> anyhow::Result<DataSource> {
        let d = &self.data;
        let file = self.path.display();
        match (&d.log, &d.train, &d.verify, d.split_s) {
            (Some(log), None, None, Some(split_s)) => Ok(DataSource::Split {
                log: dir.join(log),
                split_s,
            }),
            (None, Some(train), Some(verify), None) => Ok(DataSource::Pair {
                train: dir.join(train),
                verify: dir.join(verify),
            }),
            (Some(_), None, None, None) => bail!(
                "{file}: [data] log needs split-s (rows before it train, the rest verify), or give \
                 train and verify logs instead"
            ),
            _ => bail!("{file}: [data] takes either `log` and `split-s`, or `train` and `verify`"),
        }
    }
}

/// The keys a `[defaults]` or `[[channel]]` table takes.
fn section_keys() -> Vec<String> {
    let mut keys = vec!["name".to_string(), "id".to_string()];
    Spec::keys(&mut keys);
    keys.retain(|k| k != "from" && k != "until");
    keys
}

/// 1-based line and column of byte `offset` in `text`.
fn line_col(text: &str, offset: usize) -> (usize, usize) {
    let before = text.get(..offset).unwrap_or(text);
    let line = before.matches('\n').count() + 1;
    let col = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
    (line, col)
}

/// Refuses an unknown key of `[defaults]` or a `[[channel]]`, naming its line and column.
fn check_keys(file: &str, text: &str) -> anyhow::Result<()> {
    let Ok(root) = DeTable::parse(text) else {
        return Ok(()); // a syntax error: toml's own message, with its position, follows
    };
    let known = section_keys();
    let mut tables: Vec<(&str, &DeTable<'_>)> = Vec::new();
    for (k, v) in root.get_ref() {
        match (k.get_ref().as_ref(), v.get_ref()) {
            ("defaults", DeValue::Table(t)) => tables.push(("[defaults]", t)),
            ("channel", DeValue::Array(a)) => {
                for item in a {
                    if let DeValue::Table(t) = item.get_ref() {
                        tables.push(("[[channel]]", t));
                    }
                }
            }
            _ => {}
        }
    }
    for (section, t) in tables {
        for k in t.keys() {
            let key = k.get_ref().as_ref();
            if !known.iter().any(|n| n == key) {
                let (line, col) = line_col(text, k.span().start);
                let hint = if key == "from" || key == "until" {
                    " (the [data] section sets what trains and what is held out)".to_string()
                } else {
                    format!(" (known: {})", known.join(", "))
                };
                bail!("{file}: line {line}, column {col}: unknown key `{key}` in {section}{hint}");
            }
        }
    }
    Ok(())
}

#[cfg(test)]
#[allow(clippy::panic, clippy::indexing_slicing)]
mod tests {
    use super::*;

    const MEMS: &str = "channel = [ { target = \"gyro_x_rad_s\", id = 0 },\n\
        { target = \"acc_z_m_s2\", id = 5, average = 60 } ]\n\
        [unit]\nserial = 7\n[data]\nlog = \"d.csv\"\nsplit-s = 3130\n\
        [defaults]\nfeature = [\"temp_imu_C\"]\n";

    #[test]
    fn defaults_lie_under_each_channel() {
        let s = CalSpec::parse(Path::new("dir/s.toml"), MEMS);
        let s = s.map_err(|e| e.to_string());
        let Ok(s) = s else {
            panic!("{s:?}");
        };
        assert_eq!(s.serial, 7);
        assert_eq!(s.channels.len(), 2);
        assert_eq!(s.channels[1].name, "acc_z_m_s2");
        assert_eq!(s.channels[1].id, Some(5));
        assert_eq!(s.channels[1].spec.features.feature, ["temp_imu_C"]);
        assert_eq!(s.channels[1].spec.method.average, Some(60.0));
        assert_eq!(s.channels[0].spec.method.average, None);
        assert_eq!(
            s.source_in(&s.base).ok(),
            Some(DataSource::Split {
                log: PathBuf::from("dir/d.csv"),
                split_s: 3130.0
            })
        );
    }

    #[test]
    fn an_unknown_key_is_named_with_line_and_column() {
        let text = MEMS.replace("id = 5,", "id = 5, avrage = 3,");
        let e = CalSpec::parse(Path::new("s.toml"), &text)
            .err()
            .map(|e| e.to_string())
            .unwrap_or_default();
        assert!(
            e.contains("s.toml: line 2, column 34") && e.contains("`avrage`"),
            "{e}"
        );
        let e = CalSpec::parse(Path::new("s.toml"), "[data]\nlog = \"d\"\nsplit = 3\n")
            .err()
            .map(|e| e.to_string())
            .unwrap_or_default();
        assert!(e.contains("s.toml") && e.contains("line 3"), "{e}");
        let e = CalSpec::parse(
            Path::new("s.toml"),
            &MEMS.replace("[defaults]", "[defaults]\nuntil = 3"),
        )
        .err()
        .map(|e| e.to_string())
        .unwrap_or_default();
        assert!(e.contains("`until`") && e.contains("[data]"), "{e}");
    }
}
