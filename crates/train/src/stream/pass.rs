//! The rows of a streamed CSV: the header mapped to the columns the model uses, then one row at a
//! time from a reused `ByteRecord`, only those columns parsed, time checked to increase over the
//! whole file and the `--from/--until` window applied.
//!
//! Anything wrong stops the reading ([`Stop`]): the caller reads the file again in memory, whose
//! error names the file, line and column (one wording of every error, see the parent module).

use super::StreamOptions;
use std::io::Read;
use tcomp_core::Model;

/// The streamed reading stopped: the in-memory path must take over (for its error, or for a
/// record this path does not handle).
#[derive(Clone, Copy, Debug)]
pub struct Stop;

/// Where the reference comes from.
enum Reference {
    Column(usize),
    Value(f64),
}

/// One row of the window.
#[derive(Clone, Copy, Debug)]
pub struct Row {
    /// Time (s).
    pub t: f64,
    /// Target (sensor output).
    pub raw: f64,
    /// Reference.
    pub reference: f64,
    /// Temperature for segment detection (0 when the program has no input).
    pub temperature: f64,
}

/// The record reader and the columns it parses.
pub struct Rows<R: Read> {
    rdr: csv::Reader<R>,
    rec: csv::ByteRecord,
    fields: usize,
    time: usize,
    target: usize,
    reference: Reference,
    temperature: Option<usize>,
    input_cols: Vec<usize>,
    inputs: Vec<f32>,
    lo: f64,
    hi: f64,
    prev_t: f64,
}

/// A finite float from a field's bytes (the reader trims spaces), or [`Stop`].
#[inline]
fn num(field: Option<&[u8]>) -> Result<f64, Stop> {
    let v: f64 = field
        .and_then(|f| std::str::from_utf8(f).ok())
        .and_then(|s| s.parse().ok())
        .ok_or(Stop)?;
    if v.is_finite() { Ok(v) } else { Err(Stop) }
}

impl<R: Read> Rows<R> {
    /// Reads the header and maps the model's and the roles' columns.
    pub fn open<const C2: usize, const F2: usize, const N2: usize>(
        reader: R,
        model: &Model<'_, C2, F2, N2>,
        opts: &StreamOptions,
    ) -> Result<Self, Stop> {
        let mut rdr = csv::ReaderBuilder::new()
            .has_headers(true)
            .trim(csv::Trim::All)
            .flexible(true)
            .buffer_capacity(1 << 16)
            .from_reader(reader);
        let names: Vec<String> = rdr
            .headers()
            .map_err(|_| Stop)?
            .iter()
            .map(str::to_string)
            .collect();
        let mut seen = std::collections::HashSet::new();
        if names.len() < 2 || !names.iter().all(|n| seen.insert(n.as_str())) {
            // One column (another separator?) or a duplicate name: worded in memory.
            return Err(Stop);
        }
        let col = |name: &str| names.iter().position(|n| n == name).ok_or(Stop);
        let roles = &opts.roles;
        let reference = match (&roles.reference, roles.reference_value) {
            (Some(c), _) => Reference::Column(col(c)?),
            (None, Some(v)) => {
                Reference::Value(crate::options::REFERENCE_VALUE.check(v).map_err(|_| Stop)?)
            }
            (None, None) => return Err(Stop),
        };
        let input_cols = model
            .program
            .inputs
            .iter()
            .map(|n| col(n))
            .collect::<Result<Vec<_>, _>>()?;
        let temperature = match &opts.temperature {
            Some(n) => Some(col(n)?),
            None => input_cols.first().copied(),
        };
        Ok(Self {
            fields: names.len(),
            time: col(&roles.time)?,
            target: col(&roles.target)?,
            reference,
            temperature,
            inputs: vec![0.0; input_cols.len()],
            input_cols,
            lo: opts.from.unwrap_or(f64::NEG_INFINITY),
            hi: opts.until.unwrap_or(f64::INFINITY),
            prev_t: f64::NEG_INFINITY,
            rdr,
            rec: csv::ByteRecord::new(),
        })
    }

    /// The model's inputs of the last row returned, in program input order.
    pub fn inputs(&self) -> &[f32] {
        &self.inputs
    }

    /// The next row inside the window, `None` at the end of the file.
    #[inline]
    pub fn next_row(&mut self) -> Result<Option<Row>, Stop> {
        loop {
            if !self.rdr.read_byte_record(&mut self.rec).map_err(|_| Stop)? {
                return Ok(None);
            }
            if self.rec.len() != self.fields {
                return Err(Stop);
            }
            let t = num(self.rec.get(self.time))?;
            if t <= self.prev_t {
                return Err(Stop);
            }
            self.prev_t = t;
            if !(t >= self.lo && t < self.hi) {
                continue;
            }
            for (v, &c) in self.inputs.iter_mut().zip(&self.input_cols) {
                *v = num(self.rec.get(c))? as f32;
            }
            let reference = match self.reference {
                Reference::Column(c) => num(self.rec.get(c))?,
                Reference::Value(v) => v,
            };
            let temperature = match self.temperature {
                Some(c) => num(self.rec.get(c))?,
                None => 0.0,
            };
            return Ok(Some(Row {
                t,
                raw: num(self.rec.get(self.target))?,
                reference,
                temperature,
            }));
        }
    }
}
