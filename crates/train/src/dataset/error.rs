//! Why a measurement file is unusable, with the file, line and column named; cell text echoed in a
//! message is clipped.

use std::fmt;

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
    /// A cell of a used column is empty or NaN, and `--missing refuse` was given.
    #[error("{}: missing value ({text}) in a column the model uses (`--missing dropout`, the default, drops such rows as logger dropouts)", .at)]
    Missing {
        /// Where.
        at: CellRef,
        /// "an empty cell" or the cell text quoted.
        text: String,
    },
    /// An autopilot log is damaged or not what its name says, at a byte offset.
    #[error("{file}: byte {offset}: {what}")]
    Log {
        /// File name.
        file: String,
        /// Byte offset of the record (0 for the file's start).
        offset: u64,
        /// What is wrong, in words.
        what: String,
    },
    /// An autopilot log holds no message with the column asked for.
    #[error("{file}: {what}")]
    LogColumn {
        /// File name.
        file: String,
        /// What is missing, with the messages the log has.
        what: String,
    },
    /// A value derived from the data (not given by the user) is not finite.
    #[error("{file}: {what}")]
    Derived {
        /// File name.
        file: String,
        /// The value, named as itself (e.g. "the training mean of `y` is not finite").
        what: String,
    },
    /// Time does not strictly increase.
    #[error("{}: time {value} s is {} the previous sample's {prev} s (time must strictly increase with `--repeated-time refuse`; `average`, the default, or `drop` handle repeated and backward time)", .at, if .value == .prev { "equal to" } else { "before" })]
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

pub(super) fn suggestion_text(s: &Option<String>) -> String {
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
