//! Streaming output: CSV (optionally gzip) writer and an in-memory table.
//!
//! Why: a 6-hour run at 100 Hz is 2.16 M rows; the simulator hands each row to a [`RowSink`] as soon
//! as it exists and keeps none of them, so memory stays bounded whatever the length. The CSV writer
//! formats each row into a fixed-capacity buffer that is flushed as it fills.

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::Path;

use flate2::Compression;
use flate2::write::GzEncoder;

use crate::error::{Error, Result};

/// Capacity of the CSV writer's buffer, bytes: the most it ever holds before writing through.
pub const WRITE_BUFFER_BYTES: usize = 64 * 1024;

/// Receives the simulator's output one row at a time.
pub trait RowSink {
    /// Called once, before any row: column names and the decimals each is written with.
    fn header(&mut self, names: &[String], decimals: &[usize]) -> Result<()>;
    /// One row, in column order (values already rounded to their decimals).
    fn row(&mut self, values: &[f64]) -> Result<()>;
    /// Called once after the last row.
    fn finish(&mut self) -> Result<()>;
}

/// Writes rows as CSV into any [`Write`], through a buffer of [`WRITE_BUFFER_BYTES`].
pub struct CsvWriter<W: Write> {
    out: BufWriter<W>,
    decimals: Vec<usize>,
    line: String,
    rows: u64,
}

impl<W: Write> CsvWriter<W> {
    /// A writer into `inner`.
    pub fn new(inner: W) -> Self {
        CsvWriter {
            out: BufWriter::with_capacity(WRITE_BUFFER_BYTES, inner),
            decimals: Vec::new(),
            line: String::with_capacity(256),
            rows: 0,
        }
    }

    /// Data rows written so far.
    pub fn rows(&self) -> u64 {
        self.rows
    }

    /// Bytes formatted but not yet handed to the inner writer.
    pub fn buffered_bytes(&self) -> usize {
        self.out.buffer().len()
    }

    /// The inner writer (after [`RowSink::finish`]).
    pub fn into_inner(self) -> Result<W> {
        self.out
            .into_inner()
            .map_err(|e| Error::writer(e.into_error()))
    }
}

impl<W: Write> RowSink for CsvWriter<W> {
    fn header(&mut self, names: &[String], decimals: &[usize]) -> Result<()> {
        self.decimals = decimals.to_vec();
        writeln!(self.out, "{}", names.join(",")).map_err(Error::writer)
    }

    fn row(&mut self, values: &[f64]) -> Result<()> {
        use std::fmt::Write as _;
        self.line.clear();
        for (i, v) in values.iter().enumerate() {
            if i > 0 {
                self.line.push(',');
            }
            let d = self.decimals.get(i).copied().unwrap_or(6);
            // Writing into a String cannot fail.
            let _ = write!(self.line, "{v:.d$}");
        }
        self.line.push('\n');
        self.rows += 1;
        self.out
            .write_all(self.line.as_bytes())
            .map_err(Error::writer)
    }

    fn finish(&mut self) -> Result<()> {
        self.out.flush().map_err(Error::writer)
    }
}

/// A CSV file on disk, gzip-compressed when the path ends with `.gz`.
pub(crate) enum FileSink {
    Plain(CsvWriter<File>),
    Gz(CsvWriter<GzEncoder<File>>),
}

impl FileSink {
    pub fn create(path: &Path) -> Result<FileSink> {
        let file = File::create(path).map_err(|e| Error::io(path, e))?;
        Ok(if path.extension().is_some_and(|e| e == "gz") {
            FileSink::Gz(CsvWriter::new(GzEncoder::new(file, Compression::fast())))
        } else {
            FileSink::Plain(CsvWriter::new(file))
        })
    }

    /// Completes the file (gzip trailer included).
    pub fn close(self, path: &Path) -> Result<()> {
        let io = |e: Error| match e {
            Error::Io { source, .. } => Error::io(path, source),
            other => other,
        };
        match self {
            FileSink::Plain(w) => {
                let f = w.into_inner().map_err(io)?;
                f.sync_all().map_err(|e| Error::io(path, e))
            }
            FileSink::Gz(w) => {
                let gz = w.into_inner().map_err(io)?;
                gz.finish().map_err(|e| Error::io(path, e))?;
                Ok(())
            }
        }
    }
}

impl RowSink for FileSink {
    fn header(&mut self, names: &[String], decimals: &[usize]) -> Result<()> {
        match self {
            FileSink::Plain(w) => w.header(names, decimals),
            FileSink::Gz(w) => w.header(names, decimals),
        }
    }
    fn row(&mut self, values: &[f64]) -> Result<()> {
        match self {
            FileSink::Plain(w) => w.row(values),
            FileSink::Gz(w) => w.row(values),
        }
    }
    fn finish(&mut self) -> Result<()> {
        match self {
            FileSink::Plain(w) => w.finish(),
            FileSink::Gz(w) => w.finish(),
        }
    }
}

/// A whole run in memory: column names and one `Vec<f64>` per column (for tests and small runs).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Table {
    /// Column names.
    pub names: Vec<String>,
    /// Columns, in the order of `names`.
    pub columns: Vec<Vec<f64>>,
}

impl Table {
    /// The column of this name.
    pub fn column(&self, name: &str) -> Option<&[f64]> {
        self.names
            .iter()
            .position(|n| n == name)
            .and_then(|i| self.columns.get(i))
            .map(Vec::as_slice)
    }

    /// Number of rows.
    pub fn rows(&self) -> usize {
        self.columns.first().map_or(0, Vec::len)
    }
}

impl RowSink for Table {
    fn header(&mut self, names: &[String], _decimals: &[usize]) -> Result<()> {
        self.names = names.to_vec();
        self.columns = vec![Vec::new(); names.len()];
        Ok(())
    }

    fn row(&mut self, values: &[f64]) -> Result<()> {
        for (c, v) in self.columns.iter_mut().zip(values) {
            c.push(*v);
        }
        Ok(())
    }

    fn finish(&mut self) -> Result<()> {
        Ok(())
    }
}
