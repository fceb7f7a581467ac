//! ArduPilot DataFlash logs (`.bin`) through the `ardupilot-binlog` crate: every message instance
//! (the `I` field of `IMU`, `BARO`, …) a message, every numeric field a column, `TimeUS` the time.
//!
//! Why a structural pass first: the crate skips a record it cannot decode and, after 256 in a
//! row, ends the stream as if the file had ended — right for a plotting tool, wrong for a
//! calibration, which must not be fitted on a silently shortened or thinned log. So the records
//! are walked once by their lengths (each record `A3 95 type`, its length given by the type's
//! FMT record): a record of a type with no FMT or bytes that are not a record header are refused
//! with their byte offset. Only a log that walks cleanly is decoded. A file that ends partway
//! through its last record is how a real log ends when the logger stops or power goes while a
//! record is being written (ArduPilot writes in blocks): that partial record is dropped, with a
//! note naming its byte offset; every record before it is whole. Damage before the end is
//! refused, so a log is never silently thinned.

use super::DataError;
use super::log::{Message, Tables};
use ardupilot_binlog::Reader;
use std::collections::HashMap;

/// The FMT record's type and length (fixed by the format).
const FMT_TYPE: u8 = 0x80;
const FMT_LEN: u8 = 89;

/// What the walk found: the number of whole records, and where a partial last record starts.
struct Walk {
    records: usize,
    partial_at: Option<usize>,
}

/// Walks the records by their lengths; the first damage found, as an error.
fn walk(file: &str, bytes: &[u8]) -> Result<Walk, DataError> {
    let err = |offset: usize, what: String| DataError::Log {
        file: file.to_string(),
        offset: offset as u64,
        what,
    };
    let mut lens: [Option<u8>; 256] = [None; 256];
    if let Some(l) = lens.get_mut(usize::from(FMT_TYPE)) {
        *l = Some(FMT_LEN);
    }
    let mut off = 0usize;
    let mut records = 0usize;
    while off < bytes.len() {
        match bytes.get(off..off + 3) {
            Some([0xA3, 0x95, _]) => {}
            Some(_) => {
                return Err(err(
                    off,
                    if off == 0 {
                        "not a DataFlash log: it does not start with an FMT record (A3 95 80)"
                            .into()
                    } else {
                        "no record header (A3 95) where a record should start: the log is damaged"
                            .into()
                    },
                ));
            }
            None if off > 0
                && bytes
                    .get(off..)
                    .is_some_and(|t| [0xA3, 0x95].starts_with(t)) =>
            {
                return Ok(Walk {
                    records,
                    partial_at: Some(off),
                });
            }
            None => {
                return Err(err(
                    off,
                    "the log ends partway through a record header: the file is truncated".into(),
                ));
            }
        }
        let t = bytes.get(off + 2).copied().unwrap_or(0);
        let Some(len) = lens.get(usize::from(t)).copied().flatten() else {
            return Err(err(
                off,
                format!(
                    "a record of type {t} (0x{t:02X}) with no FMT record defining it: the log's \
                     FMT for it is missing or damaged"
                ),
            ));
        };
        let end = off + usize::from(len);
        if end > bytes.len() && records > 0 {
            return Ok(Walk {
                records,
                partial_at: Some(off),
            });
        }
        if end > bytes.len() {
            return Err(err(
                off,
                format!(
                    "the log ends partway through a record ({} of its {len} bytes): the file is \
                     truncated (power lost while logging?)",
                    bytes.len() - off
                ),
            ));
        }
        if t == FMT_TYPE {
            let (defined, dlen) = (
                bytes.get(off + 3).copied().unwrap_or(0),
                bytes.get(off + 4).copied().unwrap_or(0),
            );
            if dlen < 3 {
                return Err(err(
                    off,
                    format!("an FMT record gives type {defined} a length of {dlen} bytes"),
                ));
            }
            if let Some(l) = lens.get_mut(usize::from(defined)) {
                *l = Some(dlen);
            }
        }
        records += 1;
        off = end;
    }
    Ok(Walk {
        records,
        partial_at: None,
    })
}

/// A `PARM` record's parameter name (a text field).
fn param_name(entry: &ardupilot_binlog::Entry) -> Option<String> {
    entry
        .fields()
        .find(|(label, _)| *label == "Name")
        .and_then(|(_, v)| match v {
            ardupilot_binlog::FieldValue::String(s) => Some(s.trim_end_matches('\0').to_string()),
            _ => None,
        })
}

/// Reads the DataFlash log in `bytes`; `file` names it in errors.
pub(super) fn read(file: &str, bytes: &[u8]) -> Result<Tables, DataError> {
    let Walk {
        records,
        partial_at,
    } = walk(file, bytes)?;
    let total = bytes.len();
    let bytes = bytes.get(..partial_at.unwrap_or(total)).unwrap_or(bytes);
    let notes = partial_at
        .map(|at| {
            format!(
                "{file}: the log ends partway through a record at byte {at} ({} bytes, as when \
                 the logger stops mid-record): that partial record is dropped, the {records} \
                 records before it are whole",
                total - at
            )
        })
        .into_iter()
        .collect();
    let mut messages: HashMap<(String, u8), Message> = HashMap::new();
    let mut order: Vec<(String, u8)> = Vec::new();
    let mut decoded = 0usize;
    let mut params = Vec::new();
    for entry in Reader::new(bytes) {
        let entry = entry.map_err(|e| DataError::Log {
            file: file.to_string(),
            offset: 0,
            what: format!("a record does not decode: {e}"),
        })?;
        decoded += 1;
        if entry.name == "PARM"
            && let (Some(name), Some(value)) = (param_name(&entry), entry.get_f64("Value"))
        {
            params.push((name, value));
            continue;
        }
        let Some(t) = entry.timestamp_usec else {
            continue;
        };
        let instance = entry
            .get_f64("I")
            .filter(|i| (0.0..=255.0).contains(i))
            .map_or(0, |i| i as u8);
        let key = (entry.name.clone(), instance);
        let m = messages.entry(key.clone()).or_insert_with(|| {
            order.push(key.clone());
            Message {
                name: key.0.clone(),
                instance: key.1,
                ..Message::default()
            }
        });
        let values = entry.fields().filter_map(|(label, v)| {
            if label == "TimeUS" || label == "I" {
                return None;
            }
            v.as_f64().map(|x| (label.to_string(), x))
        });
        m.push(t, values);
    }
    if decoded != records {
        return Err(DataError::Log {
            file: file.to_string(),
            offset: 0,
            what: format!(
                "{records} records by their lengths, but {decoded} decode: a record's fields do \
                 not match its FMT (the log is damaged)"
            ),
        });
    }
    let messages = order
        .into_iter()
        .filter_map(|k| messages.remove(&k))
        .collect();
    Ok(Tables {
        messages,
        params,
        notes,
    })
}
