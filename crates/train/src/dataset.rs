//! Measurement CSV (or CSV.gz) loading with errors that point at file, line and column.
//!
//! Why a module of its own: a chamber run is hours of data recorded by someone else's logger, and the
//! first thing a user meets is what is wrong with their file. Every error names the file, the line
//! (1-based, the header is line 1) and the column (1-based, with its name), and a misspelled column
//! name gets the closest existing one suggested. Cells are parsed eagerly into f64 columns, but a bad
//! cell is only an error when its column is *used* (a notes column full of text does no harm): the
//! first bad cell of every column is remembered and reported by [`Dataset::column`].

use flate2::read::MultiGzDecoder;
use std::fmt;
use std::io::Read;
use std::path::Path;

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
        let file = path.display().to_string();
        let io = |source| DataError::Io {
            file: file.clone(),
            source,
        };
        let f = std::fs::File::open(path).map_err(io)?;
        let reader: Box<dyn Read> = if path.extension().is_some_and(|e| e == "gz") {
            Box::new(MultiGzDecoder::new(std::io::BufReader::new(f)))
        } else {
            Box::new(f)
        };
        Self::from_reader(&file, reader)
    }

    /// Parses CSV text from any reader; `file` is the name used in errors.
    pub fn from_reader<R: Read>(file: &str, reader: R) -> Result<Self, DataError> {
        let mut rdr = csv::ReaderBuilder::new()
            .has_headers(true)
            .trim(csv::Trim::All)
            .from_reader(reader);
        let csv_err = |e: csv::Error| {
            let line = e.position().map_or(0, |p| p.line());
            match e.kind() {
                csv::ErrorKind::Io(_) => DataError::Csv {
                    file: file.to_string(),
                    line,
                    message: format!("read error: {e}"),
                },
                csv::ErrorKind::UnequalLengths {
                    expected_len, len, ..
                } => DataError::Csv {
                    file: file.to_string(),
                    line,
                    message: format!("{len} fields, but the header has {expected_len}"),
                },
                _ => DataError::Csv {
                    file: file.to_string(),
                    line,
                    message: e.to_string(),
                },
            }
        };
        let names: Vec<String> = rdr
            .headers()
            .map_err(csv_err)?
            .iter()
            .map(str::to_string)
            .collect();
        if names.is_empty() || names.iter().all(String::is_empty) {
            return Err(DataError::Empty {
                file: file.to_string(),
                what: "no header row",
            });
        }
        let mut cols: Vec<Vec<f64>> = vec![Vec::new(); names.len()];
        let mut bad: Vec<Option<BadCell>> = vec![None; names.len()];
        let mut lines = Vec::new();
        let mut rec = csv::ByteRecord::new();
        while rdr.read_byte_record(&mut rec).map_err(csv_err)? {
            let row = lines.len();
            lines.push(rec.position().map_or(0, |p| p.line()));
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
                                text: String::from_utf8_lossy(field).into_owned(),
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
            name: name.to_string(),
            suggestion: closest(name, &self.names),
            available: self.names.clone(),
        })
    }

    /// Where a cell is, for messages.
    pub fn cell(&self, row: usize, col: usize) -> CellRef {
        CellRef {
            file: self.file.clone(),
            line: self.line(row),
            column: col + 1,
            name: self.names.get(col).cloned().unwrap_or_default(),
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

    /// The rows whose time (column `time`) lies in `[lo, hi)`, keeping their file lines.
    pub fn select_time(&self, time: &str, lo: f64, hi: f64) -> Result<Self, DataError> {
        let t = self.time(time)?;
        let keep: Vec<usize> = (0..t.len())
            .filter(|&i| t.get(i).is_some_and(|&v| v >= lo && v < hi))
            .collect();
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
