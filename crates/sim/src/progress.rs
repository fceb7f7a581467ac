//! Progress of a long simulation, reported through a small trait so the library needs no terminal.
//!
//! Why: a 6-hour run at 100 Hz is millions of rows and tens of seconds of work; the command-line
//! tool draws a bar (position, rate, estimated time left) from these calls, tests and library users
//! pass [`Silent`]. Reports are made every [`REPORT_EVERY`] rows, so they cost nothing measurable.

use crate::error::Result;
use crate::writer::RowSink;

/// Rows between two reports.
pub const REPORT_EVERY: u64 = 4096;

/// Receives the progress of a long run.
pub trait Progress {
    /// A new task of `total` units (rows) begins.
    fn start(&mut self, what: &str, total: u64);
    /// `done` units of the current task are complete.
    fn set(&mut self, done: u64);
    /// All tasks are complete.
    fn finish(&mut self);
}

/// Reports nothing.
#[derive(Clone, Copy, Debug, Default)]
pub struct Silent;

impl Progress for Silent {
    fn start(&mut self, _what: &str, _total: u64) {}
    fn set(&mut self, _done: u64) {}
    fn finish(&mut self) {}
}

/// A [`RowSink`] that counts the rows it passes on and reports them.
pub struct Counting<'p, S> {
    inner: S,
    rows: u64,
    progress: &'p mut dyn Progress,
}

impl<'p, S: RowSink> Counting<'p, S> {
    /// Wraps `inner`.
    pub fn new(inner: S, progress: &'p mut dyn Progress) -> Self {
        Counting {
            inner,
            rows: 0,
            progress,
        }
    }

    /// The wrapped sink.
    pub fn into_inner(self) -> S {
        self.inner
    }
}

impl<S: RowSink> RowSink for Counting<'_, S> {
    fn header(&mut self, names: &[String], decimals: &[usize]) -> Result<()> {
        self.inner.header(names, decimals)
    }

    fn row(&mut self, values: &[f64]) -> Result<()> {
        self.inner.row(values)?;
        self.rows += 1;
        if self.rows.is_multiple_of(REPORT_EVERY) {
            self.progress.set(self.rows);
        }
        Ok(())
    }

    fn finish(&mut self) -> Result<()> {
        self.progress.set(self.rows);
        self.inner.finish()
    }
}
