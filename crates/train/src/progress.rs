//! Progress of long work (loading a big CSV, gradient iterations), reported through a small trait
//! so the library needs no terminal code.
//!
//! Why: an unaveraged fit of a 100 Hz run is millions of rows; loading it takes seconds and
//! gradient descent over it minutes. The command-line tool draws a bar (position, rate, time left)
//! from these calls; tests and library users pass [`Silent`]. Callers report at a coarse grain (every
//! few thousand rows or every iteration), so a report costs nothing measurable.

/// What the units of a task are, for display.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum Unit {
    /// Bytes of a file.
    Bytes,
    /// Data rows.
    Rows,
    /// Iterations of an optimiser.
    Iterations,
}

/// Receives the progress of long work: one task at a time.
pub trait Progress: Sync {
    /// A new task of `total` units begins.
    fn start(&self, what: &str, total: u64, unit: Unit);
    /// `done` units of the current task are complete.
    fn set(&self, done: u64);
    /// The current task is complete.
    fn finish(&self);
}

/// Reports nothing.
#[derive(Clone, Copy, Debug, Default)]
pub struct Silent;

impl Progress for Silent {
    fn start(&self, _what: &str, _total: u64, _unit: Unit) {}
    fn set(&self, _done: u64) {}
    fn finish(&self) {}
}

/// A reader that reports how many bytes of the underlying file have been read.
pub(crate) struct CountingReader<'p, R> {
    inner: R,
    done: u64,
    reported: u64,
    progress: &'p dyn Progress,
}

/// Bytes between two reports while reading.
const REPORT_BYTES: u64 = 1 << 20;

impl<'p, R> CountingReader<'p, R> {
    pub(crate) fn new(inner: R, progress: &'p dyn Progress) -> Self {
        Self {
            inner,
            done: 0,
            reported: 0,
            progress,
        }
    }
}

impl<R: std::io::Read> std::io::Read for CountingReader<'_, R> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let n = self.inner.read(buf)?;
        self.done += n as u64;
        if self.done - self.reported >= REPORT_BYTES || n == 0 {
            self.reported = self.done;
            self.progress.set(self.done);
        }
        Ok(n)
    }
}
