//! Autopilot logs as tables: each message (a PX4 topic instance, an ArduPilot message instance)
//! is a table with its own timestamps; a command's rows are those of the message its first column
//! (the target) belongs to.
//!
//! Why: a log is not one table. Topics are logged at their own rates, and an IMU with three
//! instances logs three interleaved streams under one name. Mixing instances into one column (as
//! plotting tools that key by name alone do) would fit a model to three sensors at once, so each
//! instance is its own message: `IMU.GyrX` when the log has one IMU, `IMU[0].GyrX`, `IMU[1].GyrX`,
//! … when it has several. A column is named `message.field` (`sensor_gyro.x`, `IMU.T`,
//! `sensor_combined.gyro_rad[0]`), names the feature language can spell. Time is the log's own:
//! `time_s` is the message's timestamp (PX4's `timestamp`, ArduPilot's `TimeUS`) in seconds.
//! A column of another message is interpolated linearly onto the rows' timestamps (empty outside
//! its span, which the missing-cell policy then handles). For messages in errors, a row's "line"
//! is its record number within its message, and the file is named `FILE#message`.

use super::{DataError, Dataset, LoadOptions, clip, closest};
use std::path::Path;

/// The kinds of log read.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    /// PX4 ULog.
    ULog,
    /// ArduPilot DataFlash (binary).
    DataFlash,
}

/// The ULog file magic.
pub(super) const ULOG_MAGIC: &[u8] = b"ULog\x01\x12\x35";
/// A DataFlash record header followed by the FMT type (the first record of every log).
pub(super) const DATAFLASH_MAGIC: &[u8] = &[0xA3, 0x95, 0x80];

impl Kind {
    /// The kind of log at `path` from its first bytes, or from its name (`.ulg`, `.bin`) when the
    /// bytes are wrong, so that the reader can say what is wrong; `None` for a CSV file.
    pub fn of(path: &Path, head: &[u8]) -> Option<Self> {
        if head.starts_with(ULOG_MAGIC) {
            return Some(Self::ULog);
        }
        if head.starts_with(DATAFLASH_MAGIC) {
            return Some(Self::DataFlash);
        }
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase);
        match ext.as_deref() {
            Some("ulg") => Some(Self::ULog),
            Some("bin") => Some(Self::DataFlash),
            _ => None,
        }
    }
}

/// Reads the autopilot log at `path` (its kind from its first bytes or name); `None` for a CSV.
pub fn read(path: &Path) -> Result<Option<(Kind, Tables)>, DataError> {
    let file = path.display().to_string();
    let bytes = std::fs::read(path).map_err(|source| DataError::Io {
        file: file.clone(),
        source,
    })?;
    let Some(kind) = Kind::of(path, bytes.get(..8).unwrap_or(&bytes)) else {
        return Ok(None);
    };
    let tables = match kind {
        Kind::ULog => super::ulog::read(&file, &bytes)?,
        Kind::DataFlash => super::dataflash::read(&file, &bytes)?,
    };
    Ok(Some((kind, tables)))
}

/// One message of a log: its timestamps (µs), record numbers and numeric fields.
#[derive(Clone, Debug, Default)]
pub struct Message {
    /// The message's name (`sensor_gyro`, `IMU`).
    pub name: String,
    /// Its instance (PX4's multi id, ArduPilot's `I` field).
    pub instance: u8,
    /// Timestamp of each record (µs since boot).
    pub time_us: Vec<u64>,
    /// The 1-based number of each record within its message.
    pub records: Vec<u64>,
    /// Field names and values, one value per record.
    pub fields: Vec<(String, Vec<f64>)>,
}

impl Message {
    /// Appends one record: its timestamp and its fields' values (in the message's field order).
    pub fn push(&mut self, time_us: u64, values: impl Iterator<Item = (String, f64)>) {
        self.time_us.push(time_us);
        self.records.push(self.time_us.len() as u64);
        let n = self.time_us.len();
        for (name, v) in values {
            match self.fields.iter_mut().find(|(f, _)| *f == name) {
                Some((_, col)) => col.push(v),
                None => {
                    let mut col = vec![f64::NAN; n - 1];
                    col.push(v);
                    self.fields.push((name, col));
                }
            }
        }
        // A field this record lacked stays aligned with the records.
        for (_, col) in &mut self.fields {
            col.resize(n, f64::NAN);
        }
    }
}

/// The messages of a log.
#[derive(Clone, Debug, Default)]
pub struct Tables {
    /// The messages, instances apart.
    pub messages: Vec<Message>,
    /// The log's parameter records in file order (ArduPilot's `PARM`: name and value), for the
    /// autopilot's own calibration tool, which reads the calibration the log flew with from them.
    pub params: Vec<(String, f64)>,
    /// What the reader did to the log that a user should know (a partial last record dropped).
    pub notes: Vec<String>,
}

impl Tables {
    /// The name of a message as columns spell it: `IMU` when it has one instance, `IMU[k]` when
    /// it has several.
    pub fn label(&self, m: &Message) -> String {
        let several = self
            .messages
            .iter()
            .filter(|o| o.name == m.name)
            .take(2)
            .count()
            > 1;
        if several {
            format!("{}[{}]", m.name, m.instance)
        } else {
            m.name.clone()
        }
    }

    /// Every column name of the log, message by message.
    pub fn column_names(&self) -> Vec<String> {
        let mut out = Vec::new();
        for m in &self.messages {
            let label = self.label(m);
            out.extend(m.fields.iter().map(|(f, _)| format!("{label}.{f}")));
        }
        out
    }

    /// The message `name` instance `instance`, if the log has it.
    pub fn message(&self, name: &str, instance: u8) -> Option<&Message> {
        self.messages
            .iter()
            .find(|m| m.name == name && m.instance == instance)
    }

    /// The message and field index of a column.
    fn find(&self, column: &str) -> Option<(usize, usize)> {
        self.messages.iter().enumerate().find_map(|(i, m)| {
            let label = self.label(m);
            let field = column.strip_prefix(label.as_str())?.strip_prefix('.')?;
            let k = m.fields.iter().position(|(f, _)| f == field)?;
            Some((i, k))
        })
    }

    /// The error for a column the log does not have: the closest name, or the instances of a
    /// message named without its instance.
    fn unknown(&self, file: &str, column: &str) -> DataError {
        let names = self.column_names();
        let (msg, field) = column.split_once('.').unwrap_or((column, ""));
        let instances: Vec<String> = self
            .messages
            .iter()
            .filter(|m| m.name == msg && m.fields.iter().any(|(f, _)| f == field))
            .map(|m| format!("{}[{}].{field}", m.name, m.instance))
            .collect();
        let what = if instances.len() > 1 {
            format!(
                "no column `{}`: the log has {} instances of {}, kept apart: {}",
                clip(column),
                instances.len(),
                clip(msg),
                instances.join(", ")
            )
        } else {
            let mut labels: Vec<String> = self.messages.iter().map(|m| self.label(m)).collect();
            labels.dedup();
            format!(
                "no column `{}`{}; columns are `message.field`, and the log's messages are: {}",
                clip(column),
                closest(column, &names)
                    .map(|c| format!(" (did you mean `{}`?)", clip(&c)))
                    .unwrap_or_default(),
                labels.join(", ")
            )
        };
        DataError::LogColumn {
            file: file.to_string(),
            what,
        }
    }

    /// The table of the message of the first column of `opts` (of the message with the most
    /// records when no column is named), with the other columns named in `opts` interpolated
    /// onto its timestamps.
    pub fn dataset(&self, file: &str, opts: &LoadOptions) -> Result<Dataset, DataError> {
        let named: Vec<&str> = opts
            .columns
            .iter()
            .map(String::as_str)
            .filter(|c| *c != opts.time() && *c != "time_s")
            .collect();
        let base = match named.first() {
            Some(first) => match self.find(first) {
                Some((i, _)) => i,
                None => return Err(self.unknown(file, first)),
            },
            None => (0..self.messages.len())
                .max_by_key(|&i| self.messages.get(i).map_or(0, |m| m.time_us.len()))
                .ok_or_else(|| DataError::Empty {
                    file: file.to_string(),
                    what: "no data records in the log",
                })?,
        };
        let Some(m) = self.messages.get(base) else {
            return Err(self.unknown(file, named.first().copied().unwrap_or("")));
        };
        let label = self.label(m);
        let mut names = vec!["time_s".to_string()];
        let mut cols = vec![
            m.time_us
                .iter()
                .map(|&t| t as f64 * 1e-6)
                .collect::<Vec<f64>>(),
        ];
        for (f, v) in &m.fields {
            names.push(format!("{label}.{f}"));
            cols.push(v.clone());
        }
        for c in named.iter().skip(1) {
            if names.iter().any(|n| n == c) {
                continue;
            }
            let Some((i, k)) = self.find(c) else {
                return Err(self.unknown(file, c));
            };
            let Some(other) = self.messages.get(i) else {
                continue;
            };
            let Some((_, values)) = other.fields.get(k) else {
                continue;
            };
            names.push((*c).to_string());
            cols.push(interpolate(&other.time_us, values, &m.time_us));
        }
        let mut d = Dataset::from_parts(&format!("{file}#{label}"), names, cols, m.records.clone());
        d.notes.extend(self.notes.iter().cloned());
        d.notes.push(format!(
            "{file}: rows are the {} records of {label} (time_s from its timestamps){}",
            m.records.len(),
            if named.len() > 1 {
                "; columns of other messages interpolated onto them"
            } else {
                ""
            }
        ));
        Ok(d)
    }
}

/// `values` at times `t` (µs), given at times `at` (µs, non-decreasing): linear interpolation
/// between the neighbours, NaN outside `at`'s span.
fn interpolate(at: &[u64], values: &[f64], t: &[u64]) -> Vec<f64> {
    let mut out = Vec::with_capacity(t.len());
    let mut j = 0usize;
    for &x in t {
        while at.get(j + 1).is_some_and(|&a| a <= x) {
            j += 1;
        }
        let v = match (at.get(j), at.get(j + 1), values.get(j), values.get(j + 1)) {
            (Some(&a0), _, Some(&v0), _) if a0 == x => v0,
            (Some(&a0), Some(&a1), Some(&v0), Some(&v1)) if a0 <= x && x <= a1 && a1 > a0 => {
                v0 + (v1 - v0) * ((x - a0) as f64 / (a1 - a0) as f64)
            }
            _ => f64::NAN,
        };
        out.push(v);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn interpolation_is_linear_inside_and_nan_outside() {
        let v = interpolate(&[10, 20, 30], &[1.0, 3.0, 5.0], &[5, 10, 15, 30, 31]);
        assert!(v[0].is_nan() && v[4].is_nan());
        assert_eq!(&v[1..4], &[1.0, 2.0, 5.0]);
    }
}
