//! `eval` of a long log in bounded memory: the CSV read one record at a time, each row fed to the
//! core's compensator as it comes and its figures to the same [`Accumulator`] the in-memory
//! [`crate::metrics::report`] uses.
//!
//! Why: a 6-hour 200 Hz log is 4.3 M rows; loading it as columns costs hundreds of MB for figures
//! that need a few running sums. Memory here is O(bins), whatever the length (plus at most
//! [`steps::MAX_DISTINCT`] counted time steps):
//! one reused `ByteRecord`, floats parsed from its bytes without allocating, only the columns the
//! model uses parsed at all.
//!
//! One definition of each thing: the figures come from the shared accumulator; gaps are the steps
//! [`crate::dataset::stretch_starts`] calls gaps (its median step found exactly by [`steps`], a record
//! where an early gap was misjudged read a second time); and every error — a bad cell, a time going
//! backwards, an unknown column, a broken gzip stream, a `--bin` too long — is produced by the
//! in-memory path: the first problem stops the stream and the file is read again by [`Dataset`],
//! which names the file, line and column exactly as `eval` always has. A record with more distinct
//! time steps than [`steps::MAX_DISTINCT`] (a jittery clock) has its median found by reading its
//! time column four more times ([`steps::radix_median`]), then is evaluated with it.

use crate::dataset::Dataset;
use crate::error::TrainError;
use crate::metrics::Roles;
use crate::metrics::online::{Accumulator, Flags};
use crate::metrics::step::{AtCapacity, Stepper, in_flight_capacity};
use crate::{EvalReport, features};
use flate2::read::MultiGzDecoder;
use std::io::{Read, Seek, SeekFrom};
use std::path::Path;
use tcomp_core::stream::gap_resets;
use tcomp_core::{HostModel, Model};

mod pass;
pub mod steps;

/// What a streamed evaluation needs besides the model and the data (the options of `tcomp eval`).
#[derive(Clone, Debug, Default)]
pub struct StreamOptions {
    /// Column roles (time, target, reference, power-on).
    pub roles: Roles,
    /// Bin length (s) of the binned figures.
    pub bin_s: f64,
    /// Column for segment detection (default: the program's first input).
    pub temperature: Option<String>,
    /// `--gap`: steps longer than this (or 10 × the median step) are gaps.
    pub gap_s: Option<f64>,
    /// `--from`: first time kept (s), inclusive.
    pub from: Option<f64>,
    /// `--until`: time (s) where the window ends, exclusive.
    pub until: Option<f64>,
    /// `--repeated-time`: a record whose time repeats or goes back is read in memory under it.
    pub repeated_time: crate::dataset::RepeatedTime,
    /// `--missing`: a record with an empty or NaN cell is read in memory under it.
    pub missing: crate::dataset::Missing,
}

impl StreamOptions {
    /// How the in-memory path loads the file for `model`: its time column, the columns it uses
    /// (target first), and the policies.
    fn load_options(&self, model: &HostModel<'_>) -> crate::dataset::LoadOptions {
        let mut columns = vec![self.roles.target.clone()];
        columns.extend(self.roles.reference.clone());
        columns.extend(model.program.inputs.iter().map(|s| s.to_string()));
        columns.extend(self.temperature.clone());
        crate::dataset::LoadOptions {
            time: Some(self.roles.time.clone()),
            columns,
            repeated_time: self.repeated_time,
            missing: self.missing,
        }
    }
}

/// Evaluates `model` on the CSV (or `.csv.gz`) file at `path`, streaming; the same report as
/// loading it into a [`Dataset`], selecting the window and calling [`crate::evaluate`], and the
/// same errors.
pub fn eval_stream(
    path: &Path,
    model: &HostModel<'_>,
    opts: &StreamOptions,
) -> Result<EvalReport, TrainError> {
    let file = path.display().to_string();
    let f = std::fs::File::open(path).map_err(|source| crate::DataError::Io {
        file: file.clone(),
        source,
    })?;
    let mut head = [0u8; 8];
    let got = std::io::Read::read(&mut &f, &mut head).unwrap_or(0);
    if crate::dataset::log::Kind::of(path, head.get(..got).unwrap_or(&[])).is_some() {
        // A binary log is compact and read whole: the in-memory path.
        let data = Dataset::load_with(path, &opts.load_options(model), &crate::progress::Silent)?;
        return evaluate_window(data, model, opts);
    }
    let gz = path.extension().is_some_and(|e| e == "gz");
    eval_stream_reader(&file, f, gz, model, opts)
}

/// [`eval_stream`] over any seekable reader (`gz`: gzip-compressed); `file` names it in errors.
/// The reader is rewound and read again for a second reading or for an error.
pub fn eval_stream_reader<R: Read + Seek>(
    file: &str,
    mut reader: R,
    gz: bool,
    model: &HostModel<'_>,
    opts: &StreamOptions,
) -> Result<EvalReport, TrainError> {
    if let Some(r) = streamed_only(&mut reader, gz, model, opts) {
        return Ok(r);
    }
    reader
        .seek(SeekFrom::Start(0))
        .map_err(|source| io_error(file, source))?;
    in_memory(file, reader, gz, model, opts)
}

/// The streaming reading alone: `None` when the record needs the in-memory path for its error.
/// A record read with a misjudged early gap is read again with the true median step; one with
/// too many distinct steps to count has its median found first by [`steps::radix_median`]'s
/// readings of the time column.
pub fn streamed_only<R: Read + Seek>(
    mut reader: R,
    gz: bool,
    model: &HostModel<'_>,
    opts: &StreamOptions,
) -> Option<EvalReport> {
    let mut median = None;
    for _ in 0..3 {
        reader.seek(SeekFrom::Start(0)).ok()?;
        match streamed(&mut reader, gz, model, opts, median) {
            Ok(Outcome::Report(r)) => return Some(r),
            Ok(Outcome::Again(m)) => median = Some(m),
            Ok(Outcome::TooManySteps) => {
                let m = steps::radix_median(|f: &mut dyn FnMut(f64)| {
                    reader.seek(SeekFrom::Start(0)).ok()?;
                    each_step(&mut reader, gz, model, opts, f).ok()
                })?;
                median = Some(m);
            }
            Err(pass::Stop) => return None,
        }
    }
    None
}

/// Feeds every time step of the window to `f` (the time column alone is parsed).
fn each_step<R: Read>(
    reader: R,
    gz: bool,
    model: &HostModel<'_>,
    opts: &StreamOptions,
    f: &mut dyn FnMut(f64),
) -> Result<(), pass::Stop> {
    fn steps<R: Read>(mut rows: pass::Rows<R>, f: &mut dyn FnMut(f64)) -> Result<(), pass::Stop> {
        let mut prev = None;
        while let Some(t) = rows.next_time()? {
            if let Some(p) = prev {
                f(t - p);
            }
            prev = Some(t);
        }
        Ok(())
    }
    if gz {
        let r = MultiGzDecoder::new(std::io::BufReader::with_capacity(1 << 16, reader));
        steps(pass::Rows::open(r, model, opts)?, f)
    } else {
        steps(pass::Rows::open(reader, model, opts)?, f)
    }
}

fn io_error(file: &str, source: std::io::Error) -> TrainError {
    crate::DataError::Io {
        file: file.to_string(),
        source,
    }
    .into()
}

/// What a streamed reading ended with.
enum Outcome {
    /// The report.
    Report(EvalReport),
    /// A gap was misjudged before the median was known: read again with this median step.
    Again(f64),
    /// More distinct time steps than [`steps::MAX_DISTINCT`]: find the median, then read again.
    TooManySteps,
}

/// One streamed reading, in the model's flight capacity when it fits (as [`crate::metrics::run_model`]).
fn streamed<R: Read>(
    reader: R,
    gz: bool,
    model: &HostModel<'_>,
    opts: &StreamOptions,
    median: Option<f64>,
) -> Result<Outcome, pass::Stop> {
    /// [`read`] with its arguments, for [`in_flight_capacity`].
    struct ReadAt<'o, R> {
        reader: R,
        gz: bool,
        opts: &'o StreamOptions,
        median: Option<f64>,
    }
    impl<R: Read> AtCapacity for ReadAt<'_, R> {
        type Output = Result<Outcome, pass::Stop>;
        fn run<const C2: usize, const F2: usize, const N2: usize>(
            self,
            model: &Model<'_, C2, F2, N2>,
        ) -> Self::Output {
            read(self.reader, self.gz, model, self.opts, self.median)
        }
    }
    in_flight_capacity(
        model,
        ReadAt {
            reader,
            gz,
            opts,
            median,
        },
    )
}

fn read<R: Read, const C2: usize, const F2: usize, const N2: usize>(
    reader: R,
    gz: bool,
    model: &Model<'_, C2, F2, N2>,
    opts: &StreamOptions,
    median: Option<f64>,
) -> Result<Outcome, pass::Stop> {
    if gz {
        let r = MultiGzDecoder::new(std::io::BufReader::with_capacity(1 << 16, reader));
        run(r, model, opts, median)
    } else {
        run(reader, model, opts, median)
    }
}

/// Feeds every row of the window to the compensator and the accumulator.
fn run<R: Read, const C2: usize, const F2: usize, const N2: usize>(
    reader: R,
    model: &Model<'_, C2, F2, N2>,
    opts: &StreamOptions,
    median: Option<f64>,
) -> Result<Outcome, pass::Stop> {
    if let Some(g) = opts.gap_s {
        crate::options::GAP.check(g).map_err(|_| pass::Stop)?;
    }
    let mut rows = pass::Rows::open(reader, model, opts)?;
    let mut steps = steps::Steps::new(opts.gap_s.unwrap_or(0.0), median);
    let mut acc = Accumulator::new(opts.bin_s);
    let mut stepper = Stepper::new(model);
    let mut flags = Flags::default();
    let (mut first, mut prev) = (None::<f64>, 0.0);
    while let Some(row) = rows.next_row()? {
        let gap = match first {
            None => {
                first = Some(row.t);
                let on =
                    features::time_on_s(&[row.t], opts.roles.power_on_s).map_err(|_| pass::Stop)?;
                stepper.set_time_on(on as f32);
                false
            }
            Some(_) => {
                let d = row.t - prev;
                let Some(gap) = steps.push(d) else {
                    return Ok(Outcome::TooManySteps);
                };
                if gap {
                    flags.gaps += 1;
                    if gap_resets(&model.program, d as f32) {
                        flags.restarted += 1;
                    }
                }
                gap
            }
        };
        prev = row.t;
        let residual = stepper.step(row.t, gap, rows.inputs(), row.raw, row.reference);
        acc.push(row.t, row.raw - row.reference, residual, row.temperature);
    }
    flags.out_of_range = stepper.out_of_range;
    flags.faults = stepper.faults;
    let Some((true_median, _, consistent)) = steps.finish() else {
        return Ok(Outcome::TooManySteps);
    };
    if !consistent {
        return if median.is_some() {
            Err(pass::Stop)
        } else {
            Ok(Outcome::Again(true_median))
        };
    }
    let median = true_median;
    let (t0, t1) = (first.unwrap_or(0.0), prev);
    let span = t1 - t0;
    if acc.samples() < 2
        || !(opts.bin_s.is_finite() && opts.bin_s >= median && opts.bin_s <= span / 2.0)
    {
        // Too few rows or a `--bin` the data refuses: the in-memory path words the error.
        return Err(pass::Stop);
    }
    Ok(Outcome::Report(acc.finish(median, flags)))
}

/// The in-memory path: load, select the window, evaluate — for the errors, and for records whose
/// time steps are too many to count.
fn in_memory<R: Read>(
    file: &str,
    reader: R,
    gz: bool,
    model: &HostModel<'_>,
    opts: &StreamOptions,
) -> Result<EvalReport, TrainError> {
    let reader = std::io::BufReader::new(reader);
    let data = if gz {
        Dataset::from_gz_reader(file, reader)?
    } else {
        Dataset::from_reader(file, reader)?
    };
    let data = crate::dataset::clean::apply(data, &opts.load_options(model))?;
    evaluate_window(data, model, opts)
}

/// Selects the window of `data` and evaluates `model` on it, the notes of the loading kept.
fn evaluate_window(
    mut data: Dataset,
    model: &HostModel<'_>,
    opts: &StreamOptions,
) -> Result<EvalReport, TrainError> {
    let notes = data.notes().to_vec();
    if opts.from.is_some() || opts.until.is_some() {
        data = data.select_time(
            &opts.roles.time,
            opts.from.unwrap_or(f64::NEG_INFINITY),
            opts.until.unwrap_or(f64::INFINITY),
        )?;
    }
    let mut report = crate::evaluate(
        model,
        &data,
        &opts.roles,
        opts.bin_s,
        opts.temperature.as_deref(),
        opts.gap_s,
    )?;
    report.notes = notes;
    Ok(report)
}
