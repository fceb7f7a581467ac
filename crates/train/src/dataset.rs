//! Measurement CSV (or CSV.gz) loading with errors that point at file, line and column.
//!
//! Why a module of its own: a chamber run is hours of data recorded by someone else's logger, and the
//! first thing a user meets is what is wrong with their file. Every error names the file, the line
//! (1-based, the header is line 1) and the column (1-based, with its name), and a misspelled column
//! name gets the closest existing one suggested. Cells are parsed eagerly into f64 columns, but a bad
//! cell is only an error when its column is *used* (a notes column full of text does no harm): the
//! first bad cell of every column is remembered and reported by [`Dataset::column`].
//!
//! What a logger gets wrong is named rather than guessed around: two columns of the same name (which
//! one would be meant?), a `;`- or tab-separated export or a decimal comma (the header then reads
//! as one long column name), a truncated or mislabelled gzip file, a file or a `--from`/`--until`
//! window with fewer than two rows. Cell text and names echoed in an error are clipped to
//! [`MAX_ECHO_CHARS`] characters, so a 5 MB cell does not become a 5 MB message.

use crate::progress::{CountingReader, Progress, Silent, Unit};
use flate2::read::MultiGzDecoder;
use std::fmt;
use std::io::Read;
use std::path::Path;

/// Characters of a cell or name echoed in an error message; longer text is cut (at a character
/// boundary) and marked with `…`.
pub const MAX_ECHO_CHARS: usize = 40;

/// `text` cut to [`MAX_ECHO_CHARS`] characters, with `…` when something was cut.
pub fn clip(text: &str) -> String {
    match text.char_indices().nth(MAX_ECHO_CHARS) {
        Some((at, _)) => format!("{}…", text.get(..at).unwrap_or_default()),
        None => text.to_string(),
    }
}

/// Why a dataset cannot be used.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum DataError {
    /// The file could not be opened or read.
    #[error("{file}: {source}")]
    Io {
        /// File name.
        file: String,
        /// The I/O error.
        source: std::io::Error,
    },
    /// The CSV structure is broken (e.g. a row with a different number of fields).
    #[error("{file}:{line}: {message}")]
    Csv {
        /// File name.
        file: String,
        /// 1-based line.
        line: u64,
        /// What is wrong.
        message: String,
    },
    /// No header or no data rows.
    #[error("{file}: {what}")]
    Empty {
        /// File name.
        file: String,
        /// "no header row" or "no data rows".
        what: &'static str,
    },
    /// A column named by the user does not exist.
    #[error("{file}:1: no column `{name}`{}; columns are: {}", suggestion_text(.suggestion), .available.join(", "))]
    UnknownColumn {
        /// File name.
        file: String,
        /// The requested name.
        name: String,
        /// The closest existing name, if any is close.
        suggestion: Option<String>,
        /// All column names.
        available: Vec<String>,
    },
    /// A cell of a used column is not a number.
    #[error("{}: not a number: `{text}`", .at)]
    NonNumeric {
        /// Where.
        at: CellRef,
        /// The cell text.
        text: String,
    },
    /// A cell of a used column is NaN or infinite.
    #[error("{}: `{text}` is not finite (NaN/inf are not allowed)", .at)]
    NonFinite {
        /// Where.
        at: CellRef,
        /// The cell text.
        text: String,
    },
    /// Time does not strictly increase.
    #[error("{}: time {value} s is {} the previous sample's {prev} s (time must strictly increase)", .at, if .value == .prev { "equal to" } else { "before" })]
    TimeNotIncreasing {
        /// Where.
        at: CellRef,
        /// Previous time.
        prev: f64,
        /// This time.
        value: f64,
    },
    /// Two header cells carry the same name, so a reference to it would be ambiguous.
    #[error(
        "{file}:1: duplicate column name: columns {first} and {second} are both named `{name}`; rename one"
    )]
    DuplicateColumn {
        /// File name.
        file: String,
        /// The name (clipped).
        name: String,
        /// 1-based column of the first.
        first: usize,
        /// 1-based column of the second.
        second: usize,
    },
    /// The header is one column that holds `;` or tabs: the file uses another separator.
    #[error(
        "{file}:1: the header is a single column `{header}`; the file seems to be separated by {sep} \
         rather than commas{}: export it as comma-separated with a decimal point",
        if *.decimal_comma { " and to use a decimal comma (e.g. `20,5`)" } else { "" }
    )]
    Separator {
        /// File name.
        file: String,
        /// The header as read (clipped).
        header: String,
        /// The separator it seems to use, described (``semicolons (`;`)``, ``tabs (`\t`)``).
        sep: &'static str,
        /// Whether numbers seem to be written with a decimal comma.
        decimal_comma: bool,
    },
    /// A gzip file could not be decompressed.
    #[error("{file}:{line}: {what}")]
    Gzip {
        /// File name.
        file: String,
        /// The 1-based line reached when decompression failed.
        line: u64,
        /// What is wrong, in words.
        what: String,
    },
    /// Fewer than two rows: nothing varies, nothing can be fitted or measured.
    #[error("{file}: {what}")]
    TooFewRows {
        /// File name.
        file: String,
        /// What was found, with the context (the window asked for, the file's time span).
        what: String,
    },
    /// Fewer samples than the model needs.
    #[error("{file}: {have} samples{after}, but at least {need} are needed ({why})")]
    TooFewSamples {
        /// File name.
        file: String,
        /// Samples available.
        have: usize,
        /// Samples needed.
        need: usize,
        /// Context, e.g. " after averaging into 30 s bins".
        after: String,
        /// Why that many are needed.
        why: String,
    },
}

fn suggestion_text(s: &Option<String>) -> String {
    match s {
        Some(s) => format!(" (did you mean `{s}`?)"),
        None => String::new(),
    }
}

/// A cell position: file, 1-based line and column, column name.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct CellRef {
    /// File name.
    pub file: String,
    /// 1-based line (the header is line 1).
    pub line: u64,
    /// 1-based column.
    pub column: usize,
    /// Column name.
    pub name: String,
}

impl fmt::Display for CellRef {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{}:{}:{}: column `{}`",
            self.file, self.line, self.column, self.name
        )
    }
}

#[derive(Clone, Debug)]
struct BadCell {
    row: usize,
    text: String,
    non_finite: bool,
}

/// A loaded measurement table: named f64 columns, the line of every row, and the first bad cell of
/// each column.
#[derive(Clone, Debug)]
pub struct Dataset {
    file: String,
    names: Vec<String>,
    cols: Vec<Vec<f64>>,
    lines: Vec<u64>,
    bad: Vec<Option<BadCell>>,
}

impl Dataset {
    /// Loads a CSV file, gzip-decompressed when the name ends with `.gz`.
    pub fn load(path: &Path) -> Result<Self, DataError> {
        Self::load_with_progress(path, &Silent)
    }

    /// [`Dataset::load`], reporting the bytes of the file read so far to `progress`.
    pub fn load_with_progress(path: &Path, progress: &dyn Progress) -> Result<Self, DataError> {
        let file = path.display().to_string();
        let io = |source| DataError::Io {
            file: file.clone(),
            source,
        };
        let f = std::fs::File::open(path).map_err(io)?;
        let size = f.metadata().map_or(0, |m| m.len());
        progress.start(&format!("loading {}", clip(&file)), size, Unit::Bytes);
        let counted = std::io::BufReader::new(CountingReader::new(f, progress));
        let gz = path.extension().is_some_and(|e| e == "gz");
        let out = if gz {
            Self::from_gz_reader(&file, counted)
        } else {
            Self::from_reader(&file, counted)
        };
        progress.finish();
        out
    }

    /// Parses gzip-compressed CSV from any reader; `file` is the name used in errors.
    pub fn from_gz_reader<R: Read>(file: &str, reader: R) -> Result<Self, DataError> {
        Self::parse(
            file,
            MultiGzDecoder::new(std::io::BufReader::new(reader)),
            true,
        )
    }

    /// Parses CSV text from any reader; `file` is the name used in errors.
    pub fn from_reader<R: Read>(file: &str, reader: R) -> Result<Self, DataError> {
        Self::parse(file, reader, false)
    }

    fn parse<R: Read>(file: &str, reader: R, gz: bool) -> Result<Self, DataError> {
        let reader = Newlines::new(reader);
        let mut rdr = csv::ReaderBuilder::new()
            .has_headers(true)
            .trim(csv::Trim::All)
            // Row lengths are checked below, so that a row after a `;` header can be inspected.
            .flexible(true)
            .from_reader(reader);
        let names: Vec<String> = match rdr.headers() {
            Ok(h) => h.iter().map(str::to_string).collect(),
            Err(e) => return Err(csv_error(file, e, 1, gz)),
        };
        if names.is_empty() || names.iter().all(String::is_empty) {
            return Err(DataError::Empty {
                file: file.to_string(),
                what: "no header row",
            });
        }
        if let Some(sep) = other_separator(&names) {
            return Err(separator_error(file, &names, sep, &mut rdr));
        }
        check_duplicates(file, &names)?;
        let mut cols: Vec<Vec<f64>> = vec![Vec::new(); names.len()];
        let mut bad: Vec<Option<BadCell>> = vec![None; names.len()];
        let mut lines = Vec::new();
        let mut rec = csv::ByteRecord::new();
        loop {
            match rdr.read_byte_record(&mut rec) {
                Ok(true) => {}
                Ok(false) => break,
                Err(e) => {
                    // The line being read when the error struck: one past the last complete row.
                    let reached = lines.last().map_or(2, |l: &u64| l + 1);
                    return Err(csv_error(file, e, reached, gz));
                }
            }
            let row = lines.len();
            let line = rec.position().map_or(0, |p| p.line());
            if rec.len() != names.len() {
                return Err(DataError::Csv {
                    file: file.to_string(),
                    line,
                    message: format!("{} fields, but the header has {}", rec.len(), names.len()),
                });
            }
            lines.push(line);
            for ((field, col), bad) in rec.iter().zip(cols.iter_mut()).zip(bad.iter_mut()) {
                let parsed = std::str::from_utf8(field)
                    .ok()
                    .and_then(|s| s.parse::<f64>().ok());
                let v = match parsed {
                    Some(v) if v.is_finite() => v,
                    other => {
                        if bad.is_none() {
                            *bad = Some(BadCell {
                                row,
                                text: clip(&String::from_utf8_lossy(field)),
                                non_finite: other.is_some(),
                            });
                        }
                        f64::NAN
                    }
                };
                col.push(v);
            }
        }
        if lines.is_empty() {
            return Err(DataError::Empty {
                file: file.to_string(),
                what: "no data rows",
            });
        }
        if lines.len() < 2 {
            return Err(DataError::TooFewRows {
                file: file.to_string(),
                what: "only one data row (line 2): at least 2 are needed, since nothing can \
                       vary over a single sample"
                    .into(),
            });
        }
        Ok(Self {
            file: file.to_string(),
            names,
            cols,
            lines,
            bad,
        })
    }

    /// A dataset from in-memory columns (rows numbered as if read from a file with a header).
    pub fn from_columns(file: &str, names: Vec<String>, cols: Vec<Vec<f64>>) -> Self {
        let n = cols.first().map_or(0, Vec::len);
        let bad = cols
            .iter()
            .map(|c| {
                c.iter().position(|v| !v.is_finite()).map(|row| BadCell {
                    row,
                    text: format!("{}", c.get(row).copied().unwrap_or(f64::NAN)),
                    non_finite: true,
                })
            })
            .collect();
        Self {
            file: file.to_string(),
            names,
            cols,
            lines: (2..n as u64 + 2).collect(),
            bad,
        }
    }

    /// The file name used in messages.
    pub fn file(&self) -> &str {
        &self.file
    }

    /// Column names in file order.
    pub fn names(&self) -> &[String] {
        &self.names
    }

    /// Number of data rows.
    pub fn len(&self) -> usize {
        self.lines.len()
    }

    /// True when there are no rows.
    pub fn is_empty(&self) -> bool {
        self.lines.is_empty()
    }

    /// The 1-based file line of row `row`.
    pub fn line(&self, row: usize) -> u64 {
        self.lines.get(row).copied().unwrap_or(0)
    }

    /// Index of a column, or an error naming the closest existing column.
    pub fn index(&self, name: &str) -> Result<usize, DataError> {
        if let Some(i) = self.names.iter().position(|n| n == name) {
            return Ok(i);
        }
        Err(DataError::UnknownColumn {
            file: self.file.clone(),
            name: clip(name),
            suggestion: closest(name, &self.names).map(|n| clip(&n)),
            available: self.names.iter().map(|n| clip(n)).collect(),
        })
    }

    /// Where a cell is, for messages.
    pub fn cell(&self, row: usize, col: usize) -> CellRef {
        CellRef {
            file: self.file.clone(),
            line: self.line(row),
            column: col + 1,
            name: self.names.get(col).map(|n| clip(n)).unwrap_or_default(),
        }
    }

    /// A column's values; an error if it is missing or holds a non-numeric or non-finite cell.
    pub fn column(&self, name: &str) -> Result<&[f64], DataError> {
        let i = self.index(name)?;
        if let Some(Some(b)) = self.bad.get(i) {
            let at = self.cell(b.row, i);
            let text = b.text.clone();
            return Err(if b.non_finite {
                DataError::NonFinite { at, text }
            } else {
                DataError::NonNumeric { at, text }
            });
        }
        Ok(self.cols.get(i).map_or(&[][..], Vec::as_slice))
    }

    /// The time column, checked to increase strictly.
    pub fn time(&self, name: &str) -> Result<&[f64], DataError> {
        let t = self.column(name)?;
        let col = self.index(name)?;
        for (row, w) in t.windows(2).enumerate() {
            if let [a, b] = *w
                && b <= a
            {
                return Err(DataError::TimeNotIncreasing {
                    at: self.cell(row + 1, col),
                    prev: a,
                    value: b,
                });
            }
        }
        Ok(t)
    }

    /// The rows whose time (column `time`) lies in `[lo, hi)`, keeping their file lines. `lo` and
    /// `hi` are the `--from` and `--until` options (−∞ and +∞ when not given): NaN, a `--from` of
    /// +∞, an `--until` of −∞ and an empty window are refused, and so is a window that keeps fewer
    /// than two rows (the error gives the file's time span).
    pub fn select_time(&self, time: &str, lo: f64, hi: f64) -> Result<Self, DataError> {
        let t = self.time(time)?;
        let window = || {
            let mut w = Vec::new();
            if lo > f64::NEG_INFINITY || lo.is_nan() {
                w.push(format!("--from {}", crate::options::num(lo)));
            }
            if hi < f64::INFINITY || hi.is_nan() {
                w.push(format!("--until {}", crate::options::num(hi)));
            }
            w.join(" and ")
        };
        let span = format!(
            "its time runs from {} s to {} s",
            t.first().copied().unwrap_or(0.0),
            t.last().copied().unwrap_or(0.0)
        );
        let refuse = |what: String| DataError::TooFewRows {
            file: self.file.clone(),
            what,
        };
        if lo.is_nan() || hi.is_nan() || lo == f64::INFINITY || hi == f64::NEG_INFINITY {
            return Err(refuse(format!(
                "{} is not a time: --from and --until take a finite number of seconds ({span})",
                window()
            )));
        }
        if lo >= hi {
            return Err(refuse(format!(
                "{} is an empty window: --from must be before --until ({span})",
                window()
            )));
        }
        let keep: Vec<usize> = (0..t.len())
            .filter(|&i| t.get(i).is_some_and(|&v| v >= lo && v < hi))
            .collect();
        if keep.len() < 2 {
            return Err(refuse(format!(
                "--from/--until select {} row{} ({}; {span}): at least 2 are needed",
                keep.len(),
                if keep.len() == 1 { "" } else { "s" },
                window()
            )));
        }
        let pick = |v: &Vec<f64>| keep.iter().filter_map(|&i| v.get(i).copied()).collect();
        let bad = self
            .bad
            .iter()
            .map(|b| {
                b.as_ref().and_then(|b| {
                    keep.iter().position(|&i| i == b.row).map(|row| BadCell {
                        row,
                        text: b.text.clone(),
                        non_finite: b.non_finite,
                    })
                })
            })
            .collect();
        Ok(Self {
            file: format!("{} [{lo} s, {hi} s)", self.file),
            names: self.names.clone(),
            cols: self.cols.iter().map(pick).collect(),
            lines: keep.iter().map(|&i| self.line(i)).collect(),
            bad,
        })
    }
}

/// A reader that turns `\r\n` and a lone `\r` into `\n`.
///
/// Why: the CSV parser counts lines by `\n` but ends a record at the `\r` of a `\r\n`, so in a
/// Windows file every row after the header was reported one line early (the row on line 2 as
/// line one), as the reader's fuzz test found. With one line ending the count is exact; a cell
/// never holds a line break that matters (numbers do not).
struct Newlines<R> {
    inner: R,
    /// The last byte handed out was a `\r` turned into `\n`: drop a `\n` that follows it.
    after_cr: bool,
}

impl<R> Newlines<R> {
    fn new(inner: R) -> Self {
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
fn other_separator(names: &[String]) -> Option<&'static str> {
    match names {
        [only] if only.contains(';') => Some("semicolons (`;`)"),
        [only] if only.contains('\t') => Some("tabs (`\\t`)"),
        _ => None,
    }
}

/// Refuses a header that names two columns alike.
fn check_duplicates(file: &str, names: &[String]) -> Result<(), DataError> {
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
fn csv_error(file: &str, e: csv::Error, reached: u64, gz: bool) -> DataError {
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
fn gzip_meaning(e: &std::io::Error) -> String {
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
fn clip_message(text: &str) -> String {
    match text.char_indices().nth(4 * MAX_ECHO_CHARS) {
        Some((at, _)) => format!("{}…", text.get(..at).unwrap_or_default()),
        None => text.to_string(),
    }
}

/// The name in `names` closest to `name` (case-insensitive Levenshtein), if it is close enough to be
/// a plausible misspelling.
pub fn closest(name: &str, names: &[String]) -> Option<String> {
    let lower = name.to_lowercase();
    names
        .iter()
        .map(|n| (strsim::levenshtein(&lower, &n.to_lowercase()), n))
        .filter(|(d, n)| *d <= (n.len().max(name.len()) / 2).max(2))
        .min_by_key(|(d, _)| *d)
        .map(|(_, n)| n.clone())
}

/// Row indices where a new contiguous segment starts (always including 0): a step longer than
/// `max(gap_s, 10 × median step)` is a gap. Stateful features (`rate`, `lag`) are reset there.
pub fn segments(time: &[f64], gap_s: Option<f64>) -> Vec<usize> {
    let mut starts = vec![0];
    if time.len() < 2 {
        return starts;
    }
    let limit = gap_s.unwrap_or(0.0).max(10.0 * median_step(time));
    for (i, w) in time.windows(2).enumerate() {
        if w[1] - w[0] > limit {
            starts.push(i + 1);
        }
    }
    starts
}

/// The median time step of a time column (seconds), 1 when there is only one sample.
pub fn median_step(time: &[f64]) -> f64 {
    let mut diffs = time.windows(2).map(|w| w[1] - w[0]);
    let Some(first) = diffs.next() else {
        return 1.0;
    };
    // A uniformly sampled record (the common case) needs no selection.
    if diffs.all(|d| d == first) {
        return first;
    }
    let mut steps: Vec<f64> = time.windows(2).map(|w| w[1] - w[0]).collect();
    let mid = steps.len() / 2;
    *steps.select_nth_unstable_by(mid, f64::total_cmp).1
}

/// The error for a header split by another separator than `,` (`sep` names it), with a hint
/// when the first row shows a decimal comma.
fn separator_error<R: Read>(
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
