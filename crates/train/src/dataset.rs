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
//!
//! Autopilot logs read as tables too ([`log`]): a PX4 ULog (`.ulg`) or an ArduPilot DataFlash log
//! (`.bin`) is recognised by its first bytes, and its messages become columns named
//! `topic.field` / `MSG.Field`. And what chamber loggers write — repeated or backward time, empty
//! and NaN cells — is handled by the documented policies of [`clean`], whose counts the dataset
//! carries as [`Dataset::notes`].

use crate::progress::{CountingReader, Progress, Silent, Unit};
use flate2::read::MultiGzDecoder;
use std::io::Read;
use std::path::Path;
use std::sync::Arc;

pub mod clean;
mod csv_read;
mod dataflash;
mod error;
pub mod log;
mod ulog;

pub use clean::{LoadOptions, Missing, RepeatedTime};
use csv_read::{Newlines, check_duplicates, csv_error, other_separator, separator_error};
pub use error::{CellRef, DataError, MAX_ECHO_CHARS, clip};

/// What is wrong with a cell.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum BadKind {
    /// Empty, or NaN: how a logger writes a failed read ([`Missing`] decides).
    Missing,
    /// Text that is not a number.
    NonNumeric,
    /// An infinite number.
    NonFinite,
}

#[derive(Clone, Debug)]
pub(crate) struct BadCell {
    row: usize,
    text: String,
    kind: BadKind,
}

/// Per column: its first bad cell, and its first bad cell that is not a missing value.
#[derive(Clone, Debug, Default)]
pub(crate) struct Bad {
    first: Option<BadCell>,
    other: Option<BadCell>,
}

impl Bad {
    fn note(&mut self, cell: BadCell) {
        if self.other.is_none() && cell.kind != BadKind::Missing {
            self.other = Some(cell.clone());
        }
        if self.first.is_none() {
            self.first = Some(cell);
        }
    }
}

/// A loaded measurement table: named f64 columns, the line of every row, and the first bad cell of
/// each column.
#[derive(Clone, Debug)]
pub struct Dataset {
    file: String,
    names: Vec<String>,
    /// Shared: a fit's selection of the whole run, and every candidate refit of discovery, clones the
    /// dataset, and the numbers never change after loading.
    cols: Arc<Vec<Vec<f64>>>,
    lines: Arc<Vec<u64>>,
    bad: Vec<Bad>,
    notes: Vec<String>,
}

impl Dataset {
    /// Loads a measurement file with the default [`LoadOptions`]: a CSV file (gzip-decompressed
    /// when the name ends with `.gz`), or an autopilot log recognised by its first bytes.
    pub fn load(path: &Path) -> Result<Self, DataError> {
        Self::load_with(path, &LoadOptions::default(), &Silent)
    }

    /// [`Dataset::load`], reporting the bytes of the file read so far to `progress`.
    pub fn load_with_progress(path: &Path, progress: &dyn Progress) -> Result<Self, DataError> {
        Self::load_with(path, &LoadOptions::default(), progress)
    }

    /// Loads a measurement file for a command that uses `opts.columns`: for an autopilot log, the
    /// message of the first of them gives the rows ([`log`]); then the policies of [`clean`]
    /// (repeated time, missing cells) apply, their counts kept as [`Dataset::notes`].
    pub fn load_with(
        path: &Path,
        opts: &LoadOptions,
        progress: &dyn Progress,
    ) -> Result<Self, DataError> {
        let file = path.display().to_string();
        let io = |source| DataError::Io {
            file: file.clone(),
            source,
        };
        let mut f = std::fs::File::open(path).map_err(io)?;
        let mut head = [0u8; 8];
        let got = read_head(&mut f, &mut head).map_err(io)?;
        let head = head.get(..got).unwrap_or(&[]);
        if let Some(kind) = log::Kind::of(path, head) {
            let bytes = std::fs::read(path).map_err(io)?;
            let tables = match kind {
                log::Kind::ULog => ulog::read(&file, &bytes)?,
                log::Kind::DataFlash => dataflash::read(&file, &bytes)?,
            };
            let data = tables.dataset(&file, opts)?;
            return clean::apply(data, opts);
        }
        drop(f);
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
        clean::apply(out?, opts)
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
        let mut bad: Vec<Bad> = vec![Bad::default(); names.len()];
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
                        let kind = match other {
                            _ if field.is_empty() => BadKind::Missing,
                            Some(v) if v.is_nan() => BadKind::Missing,
                            Some(_) => BadKind::NonFinite,
                            None => BadKind::NonNumeric,
                        };
                        if bad.first.is_none() || (bad.other.is_none() && kind != BadKind::Missing)
                        {
                            bad.note(BadCell {
                                row,
                                text: clip(&String::from_utf8_lossy(field)),
                                kind,
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
            cols: Arc::new(cols),
            lines: Arc::new(lines),
            bad,
            notes: Vec::new(),
        })
    }

    /// A dataset from in-memory columns (rows numbered as if read from a file with a header).
    pub fn from_columns(file: &str, names: Vec<String>, cols: Vec<Vec<f64>>) -> Self {
        let n = cols.first().map_or(0, Vec::len);
        Self::from_parts(file, names, cols, (2..n as u64 + 2).collect())
    }

    /// A dataset from in-memory columns and the file line (or log record) of each row; a cell that
    /// is NaN is a missing value, an infinite one a bad cell.
    pub(crate) fn from_parts(
        file: &str,
        names: Vec<String>,
        cols: Vec<Vec<f64>>,
        lines: Vec<u64>,
    ) -> Self {
        let bad = cols.iter().map(|c| Self::scan_bad(c)).collect();
        Self {
            file: file.to_string(),
            names,
            cols: Arc::new(cols),
            lines: Arc::new(lines),
            bad,
            notes: Vec::new(),
        }
    }

    /// The first missing (NaN) and first infinite cell of a column of numbers.
    fn scan_bad(c: &[f64]) -> Bad {
        let mut bad = Bad::default();
        for (row, v) in c.iter().enumerate() {
            if v.is_finite() {
                continue;
            }
            let kind = if v.is_nan() {
                BadKind::Missing
            } else {
                BadKind::NonFinite
            };
            if bad.first.is_some() && (bad.other.is_some() || kind == BadKind::Missing) {
                continue;
            }
            bad.note(BadCell {
                row,
                text: format!("{v}"),
                kind,
            });
            if bad.other.is_some() {
                break;
            }
        }
        bad
    }

    /// What the loading policies did to the file (rows averaged, dropped, clock restarts), one
    /// sentence each; empty for a clean file.
    pub fn notes(&self) -> &[String] {
        &self.notes
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
        // Text or infinity is an error under every policy, so it is said first.
        if let Some(b) = self
            .bad
            .get(i)
            .and_then(|b| b.other.as_ref().or(b.first.as_ref()))
        {
            let at = self.cell(b.row, i);
            let text = b.text.clone();
            return Err(match b.kind {
                BadKind::NonFinite => DataError::NonFinite { at, text },
                BadKind::NonNumeric => DataError::NonNumeric { at, text },
                BadKind::Missing => DataError::Missing {
                    at,
                    text: if text.is_empty() {
                        "an empty cell".into()
                    } else {
                        format!("`{text}`")
                    },
                },
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
                w.push(format!("--from {}", crate::num::exact(lo)));
            }
            if hi < f64::INFINITY || hi.is_nan() {
                w.push(format!("--until {}", crate::num::exact(hi)));
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
        let mut out = self.keep_rows(&keep);
        out.file = format!("{} [{lo} s, {hi} s)", self.file);
        Ok(out)
    }

    /// The rows `keep` (ascending indices), with their lines, bad cells and notes.
    pub(crate) fn keep_rows(&self, keep: &[usize]) -> Self {
        let pick = |v: &Vec<f64>| keep.iter().filter_map(|&i| v.get(i).copied()).collect();
        let remap = |b: &Option<BadCell>| {
            b.as_ref().and_then(|b| {
                keep.binary_search(&b.row).ok().map(|row| BadCell {
                    row,
                    text: b.text.clone(),
                    kind: b.kind,
                })
            })
        };
        let cols: Vec<Vec<f64>> = self.cols.iter().map(pick).collect();
        let bad = self
            .bad
            .iter()
            .zip(&cols)
            .map(|(b, c)| {
                let kept = Bad {
                    first: remap(&b.first),
                    other: remap(&b.other),
                };
                // A bad cell whose row went leaves its later ones unnamed: find them again.
                if kept.first.is_none() && c.iter().any(|v| !v.is_finite()) {
                    Self::scan_bad(c)
                } else {
                    kept
                }
            })
            .collect();
        Self {
            file: self.file.clone(),
            names: self.names.clone(),
            cols: Arc::new(cols),
            lines: Arc::new(keep.iter().map(|&i| self.line(i)).collect()),
            bad,
            notes: self.notes.clone(),
        }
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

/// Row indices where a gap-free stretch of the run starts (always including 0): a step longer than
/// `max(gap_s, 10 × median step)` is a gap, which the feature state is carried across (see
/// [`crate::features`]).
pub fn stretch_starts(time: &[f64], gap_s: Option<f64>) -> Vec<usize> {
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

/// Reads up to `buf.len()` bytes from the start of a file (fewer at its end); the count read.
fn read_head(f: &mut std::fs::File, buf: &mut [u8]) -> std::io::Result<usize> {
    let mut got = 0;
    while got < buf.len() {
        match f.read(buf.get_mut(got..).unwrap_or(&mut [])) {
            Ok(0) => break,
            Ok(n) => got += n,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
            Err(e) => return Err(e),
        }
    }
    Ok(got)
}
