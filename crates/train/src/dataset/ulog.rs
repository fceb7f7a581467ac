//! PX4 ULog files through PX4's own Rust parser (`px4-ulog`): every topic instance a message,
//! every numeric field (arrays flattened as `gyro_rad[0]`) a column, `timestamp` the time.
//!
//! A damaged file is refused with the byte range where the parser stopped: a header that is not
//! ULog's, a record that does not parse, or a file that ends partway through a record (power lost
//! while logging). Nothing of it is used then, so no model is fitted on a silently shortened log.

use super::DataError;
use super::log::{Message, Tables};
use px4_ulog::full_parser::FlattenedFieldType as T;
use px4_ulog::stream_parser::{DataMessage, LogParser};
use std::collections::HashMap;

/// Bytes fed to the parser at a time: an error is placed within this many bytes.
const CHUNK: usize = 1024;

/// A numeric field's value from a record's bytes (`None` for characters or a short record).
fn value(kind: &T, data: &[u8], offset: usize) -> Option<f64> {
    fn le<const N: usize>(data: &[u8], at: usize) -> Option<[u8; N]> {
        data.get(at..at + N)?.try_into().ok()
    }
    Some(match kind {
        T::Int8 => f64::from(i8::from_le_bytes(le(data, offset)?)),
        T::UInt8 => f64::from(u8::from_le_bytes(le(data, offset)?)),
        T::Int16 => f64::from(i16::from_le_bytes(le(data, offset)?)),
        T::UInt16 => f64::from(u16::from_le_bytes(le(data, offset)?)),
        T::Int32 => f64::from(i32::from_le_bytes(le(data, offset)?)),
        T::UInt32 => f64::from(u32::from_le_bytes(le(data, offset)?)),
        T::Int64 => i64::from_le_bytes(le(data, offset)?) as f64,
        T::UInt64 => u64::from_le_bytes(le(data, offset)?) as f64,
        T::Float => f64::from(f32::from_le_bytes(le(data, offset)?)),
        T::Double => f64::from_le_bytes(le(data, offset)?),
        T::Bool => f64::from(u8::from_le_bytes(le(data, offset)?)),
        T::Char => return None,
    })
}

/// Reads the ULog in `bytes`; `file` names it in errors.
pub(super) fn read(file: &str, bytes: &[u8]) -> Result<Tables, DataError> {
    let log_err = |offset: usize, what: String| DataError::Log {
        file: file.to_string(),
        offset: offset as u64,
        what,
    };
    if !bytes.starts_with(super::log::ULOG_MAGIC) {
        return Err(log_err(
            0,
            "not a ULog file: it does not start with the ULog magic (`ULog` 01 12 35)".into(),
        ));
    }
    let mut messages: HashMap<(String, u8), Message> = HashMap::new();
    let mut order: Vec<(String, u8)> = Vec::new();
    let mut callback = |msg: &DataMessage| {
        let format = msg.flattened_format;
        let Some(ts) = format.timestamp_field.as_ref() else {
            return;
        };
        let Some(t) = msg
            .data
            .get(ts.offset as usize..ts.offset as usize + 8)
            .and_then(|b| b.try_into().ok())
            .map(u64::from_le_bytes)
        else {
            return;
        };
        let key = (format.message_name.clone(), msg.multi_id.value());
        let m = messages.entry(key.clone()).or_insert_with(|| {
            order.push(key.clone());
            Message {
                name: key.0.clone(),
                instance: key.1,
                ..Message::default()
            }
        });
        let values = format.fields.iter().filter_map(|f| {
            if f.flattened_field_name == "timestamp"
                || f.flattened_field_name.starts_with("_padding")
            {
                return None;
            }
            value(&f.field_type, msg.data, f.offset as usize)
                .map(|v| (f.flattened_field_name.clone(), v))
        });
        m.push(t, values);
    };
    let mut parser = LogParser::default();
    parser.set_data_message_callback(&mut callback);
    for (k, chunk) in bytes.chunks(CHUNK).enumerate() {
        if let Err(e) = parser.consume_bytes(chunk) {
            let at = k * CHUNK;
            let where_ = if parser.in_data() {
                "a record of the data section does not parse"
            } else {
                "the header or the definitions do not parse"
            };
            return Err(log_err(
                at,
                format!(
                    "{where_} (within bytes {at}..{}: {}); the log is damaged",
                    at + chunk.len(),
                    super::csv_read::clip_message(&e.description)
                ),
            ));
        }
    }
    if parser.has_leftover() || !parser.in_data() {
        return Err(log_err(
            bytes.len(),
            if parser.in_data() {
                "the log ends partway through a record: the file is truncated (power lost or \
                 the card pulled while logging?)"
                    .into()
            } else {
                "the log ends before its data section: the file is truncated".into()
            },
        ));
    }
    drop(parser);
    let messages = order
        .into_iter()
        .filter_map(|k| messages.remove(&k))
        .collect();
    Ok(Tables {
        messages,
        params: Vec::new(),
        notes: Vec::new(),
    })
}
