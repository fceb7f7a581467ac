//! The CSV reader's helpers: line endings made exact, and what a logger got wrong (another
//! separator, a decimal comma, duplicate names, a broken gzip stream) named in the error.

use super::{DataError, MAX_ECHO_CHARS, clip};
use std::io::Read;

/// A reader that turns `\r\n` and a lone `\r` into `\n`.
///
/// Why: the CSV parser counts lines by `\n` but ends a record at the `\r` of a `\r\n`, so in a
/// Windows file every row after the header was reported one line early (the row on line 2 as
/// line one), as the reader's fuzz test found. With one line ending the count is exact; a cell
/// never holds a line break that matters (numbers do not).
pub(super) struct Newlines<R> {
    inner: R,
    /// The last byte handed out was a `\r` turned into `\n`: drop a `\n` that follows it.
    after_cr: bool,
}

impl<R> Newlines<R> {
    pub(super) fn new(inner: R) -> Self {
        Self {
            inner,
            after_cr: false,
        }
    }
}

impl<R: Read> Read for Newlines<R> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        loop {
            let n = self.inner.read(buf)?;
            if n == 0 {
                return Ok(0);
            }
            // In place: the output never gets ahead of the input.
            let mut w = 0;
            for r in 0..n {
                let Some(&b) = buf.get(r) else { break };
                let after_cr = std::mem::replace(&mut self.after_cr, false);
                let out = match b {
                    b'\n' if after_cr => continue,
                    b'\r' => {
                        self.after_cr = true;
                        b'\n'
                    }
                    other => other,
                };
                if let Some(slot) = buf.get_mut(w) {
                    *slot = out;
                }
                w += 1;
            }
            // A chunk that was one dropped `\n` holds nothing: read on (0 would mean the end).
            if w > 0 {
                return Ok(w);
            }
        }
    }
}

/// The separator a one-column header seems to use instead of commas, described, if any.
pub(super) fn other_separator(names: &[String]) -> Option<&'static str> {
    match names {
        [only] if only.contains(';') => Some("semicolons (`;`)"),
        [only] if only.contains('\t') => Some("tabs (`\\t`)"),
        _ => None,
    }
}

/// Refuses a header that names two columns alike.
pub(super) fn check_duplicates(file: &str, names: &[String]) -> Result<(), DataError> {
    let mut seen: std::collections::HashMap<&str, usize> = std::collections::HashMap::new();
    for (i, n) in names.iter().enumerate() {
        if let Some(first) = seen.insert(n.as_str(), i) {
            return Err(DataError::DuplicateColumn {
                file: file.to_string(),
                name: clip(n),
                first: first + 1,
                second: i + 1,
            });
        }
    }
    Ok(())
}

/// A CSV reader error as a [`DataError`], with `reached` (1-based) as the line when the error
/// carries none (I/O errors, e.g. of the gzip decoder).
pub(super) fn csv_error(file: &str, e: csv::Error, reached: u64, gz: bool) -> DataError {
    let line = e.position().map_or(reached, |p| p.line()).max(1);
    let message = match e.kind() {
        csv::ErrorKind::Io(io) => {
            if gz {
                return DataError::Gzip {
                    file: file.to_string(),
                    line,
                    what: gzip_meaning(io),
                };
            }
            format!("read error: {io}")
        }
        csv::ErrorKind::UnequalLengths {
            expected_len, len, ..
        } => format!("{len} fields, but the header has {expected_len}"),
        csv::ErrorKind::Utf8 { err, .. } => format!(
            "not UTF-8 text (field {}); is this a CSV file{}?",
            err.field() + 1,
            if gz {
                ""
            } else {
                ", or a compressed one not named .gz"
            }
        ),
        _ => clip_message(&e.to_string()),
    };
    DataError::Csv {
        file: file.to_string(),
        line,
        message,
    }
}

/// What a gzip decoder's I/O error means, in words.
pub(super) fn gzip_meaning(e: &std::io::Error) -> String {
    let text = e.to_string();
    if e.kind() == std::io::ErrorKind::UnexpectedEof {
        "the gzip stream ends early: the file is truncated".into()
    } else if text.contains("invalid gzip header") {
        "not gzip data (the name ends in .gz, but the file does not start like a gzip stream)"
            .into()
    } else if text.contains("corrupt deflate stream")
        || e.kind() == std::io::ErrorKind::InvalidInput
    {
        "the gzip stream is corrupt: the file is damaged".into()
    } else {
        format!("gzip read error: {}", clip_message(&text))
    }
}

/// A library message cut to a sane length (it may quote input).
pub(super) fn clip_message(text: &str) -> String {
    match text.char_indices().nth(4 * MAX_ECHO_CHARS) {
        Some((at, _)) => format!("{}…", text.get(..at).unwrap_or_default()),
        None => text.to_string(),
    }
}

/// The error for a header split by another separator than `,` (`sep` names it), with a hint
/// when the first row shows a decimal comma.
pub(super) fn separator_error<R: Read>(
    file: &str,
    names: &[String],
    sep: &'static str,
    rdr: &mut csv::Reader<R>,
) -> DataError {
    // One record more tells whether numbers are written with a decimal comma: in a
    // `;`-separated row `20,5;0,01` the comma splits each number into two fields.
    let mut rec = csv::StringRecord::new();
    let first_row = match rdr.read_record(&mut rec) {
        Ok(true) => rec.iter().collect::<Vec<_>>().join(","),
        _ => String::new(),
    };
    let sep_char = if sep.starts_with("tabs") { '\t' } else { ';' };
    let decimal_comma = first_row.split(sep_char).any(|f| {
        let f = f.trim();
        f.split_once(',').is_some_and(|(a, b)| {
            !a.is_empty()
                && !b.is_empty()
                && a.trim_start_matches('-')
                    .bytes()
                    .all(|c| c.is_ascii_digit())
                && b.bytes().all(|c| c.is_ascii_digit())
        })
    });
    DataError::Separator {
        file: file.to_string(),
        header: clip(names.first().map_or("", String::as_str)),
        sep,
        decimal_comma,
    }
}
