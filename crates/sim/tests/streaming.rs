//! A 6-hour run at 100 Hz (2.16 M rows) streams to disk in bounded memory.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use std::cell::Cell;
use std::fs::File;
use std::io::{BufRead, BufReader, Write};
use std::rc::Rc;

use tcomp_sim::writer::WRITE_BUFFER_BYTES;
use tcomp_sim::{CsvWriter, Profile, Result, RowSink, Scenario, Segment, SensorKind};

/// Counts the bytes and lines that actually reach the file.
struct Counting {
    file: File,
    bytes: Rc<Cell<u64>>,
    lines: Rc<Cell<u64>>,
}

impl Write for Counting {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        let n = self.file.write(buf)?;
        self.bytes.set(self.bytes.get() + n as u64);
        let nl = buf
            .get(..n)
            .unwrap_or(&[])
            .iter()
            .filter(|&&b| b == b'\n')
            .count();
        self.lines.set(self.lines.get() + nl as u64);
        Ok(n)
    }
    fn flush(&mut self) -> std::io::Result<()> {
        self.file.flush()
    }
}

/// Checks after every row that the CSV writer holds at most its fixed buffer, i.e. that rows are
/// not accumulating anywhere between the simulator and the file.
struct Checked {
    inner: CsvWriter<Counting>,
    lines: Rc<Cell<u64>>,
    rows: u64,
    max_pending_rows: u64,
    max_buffered: usize,
}

impl RowSink for Checked {
    fn header(&mut self, names: &[String], decimals: &[usize]) -> Result<()> {
        self.inner.header(names, decimals)
    }
    fn row(&mut self, values: &[f64]) -> Result<()> {
        self.inner.row(values)?;
        self.rows += 1;
        // +1: the header line.
        let pending = self.rows + 1 - self.lines.get();
        self.max_pending_rows = self.max_pending_rows.max(pending);
        self.max_buffered = self.max_buffered.max(self.inner.buffered_bytes());
        Ok(())
    }
    fn finish(&mut self) -> Result<()> {
        self.inner.finish()
    }
}

#[test]
fn six_hours_at_100_hz_streams_in_bounded_memory() {
    let profile = Profile::new(
        20.0,
        vec![
            Segment::hold_h(2.0),
            Segment::ramp(50.0, 1.0),
            Segment::hold_h(1.5),
            Segment::ramp(20.0, 1.0),
            Segment::hold_h(1.5),
        ],
    );
    assert_eq!(profile.duration_s(), 6.0 * 3600.0);
    let mut sc = Scenario::new(SensorKind::Qma, profile).with_rate(100.0, 0.01);
    sc.effects = tcomp_sim::presets::preset("qma").unwrap().train.effects;
    let path = std::env::temp_dir().join(format!("tcomp-sim-6h-{}.csv", std::process::id()));
    let bytes = Rc::new(Cell::new(0));
    let lines = Rc::new(Cell::new(0));
    let counting = Counting {
        file: File::create(&path).unwrap(),
        bytes: bytes.clone(),
        lines: lines.clone(),
    };
    let mut sink = Checked {
        inner: CsvWriter::new(counting),
        lines: lines.clone(),
        rows: 0,
        max_pending_rows: 0,
        max_buffered: 0,
    };
    let truth = tcomp_sim::simulate_into(&sc, &mut sink).unwrap();
    sink.inner.into_inner().unwrap();
    assert_eq!(truth.rows, 2_160_000);
    assert_eq!(sink.rows, 2_160_000);
    // The writer never holds more than its fixed buffer (rows are ≥ 40 bytes here).
    assert!(
        sink.max_buffered <= WRITE_BUFFER_BYTES,
        "{}",
        sink.max_buffered
    );
    assert!(
        sink.max_pending_rows <= (WRITE_BUFFER_BYTES / 40) as u64 + 1,
        "{}",
        sink.max_pending_rows
    );
    // Everything reached the file: header + 2.16 M rows.
    assert_eq!(lines.get(), 2_160_001);
    let file_lines = BufReader::new(File::open(&path).unwrap()).lines().count();
    assert_eq!(file_lines, 2_160_001);
    assert_eq!(std::fs::metadata(&path).unwrap().len(), bytes.get());
    std::fs::remove_file(&path).ok();
}
