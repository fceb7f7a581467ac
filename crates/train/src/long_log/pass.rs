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

/// A finite float from a field's bytes, spaces around it ignored (as the in-memory reader trims
/// them), or [`Stop`].
#[inline]
fn num(field: Option<&[u8]>) -> Result<f64, Stop> {
    let f = field.ok_or(Stop)?.trim_ascii();
    let v = match decimal(f) {
        Some(v) => v,
        None => std::str::from_utf8(f)
            .ok()
            .and_then(|s| s.parse::<f64>().ok())
            .ok_or(Stop)?,
    };
    if v.is_finite() { Ok(v) } else { Err(Stop) }
}

/// Exact powers of ten (every one up to 10²² is a double).
const POW10: [f64; 23] = [
    1e0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10, 1e11, 1e12, 1e13, 1e14, 1e15, 1e16,
    1e17, 1e18, 1e19, 1e20, 1e21, 1e22,
];

/// A plain decimal `[±]digits[.digits]` whose digits make an integer `m ≤ 2⁵³` with at most 22
/// after the point, as `m / 10^k`: both exact doubles, so the one division is correctly rounded
/// and gives the bits `str::parse` gives (Clinger's fast path). `None` for anything else
/// (exponents, long mantissas, text), which `str::parse` then reads.
#[inline]
pub(super) fn decimal(b: &[u8]) -> Option<f64> {
    let (neg, digits) = match b.split_first() {
        Some((b'-', rest)) => (true, rest),
        Some((b'+', rest)) => (false, rest),
        _ => (false, b),
    };
    let (mut m, mut n, mut frac, mut dot) = (0u64, 0u32, 0usize, false);
    for &c in digits {
        match c {
            b'0'..=b'9' => {
                if n >= 19 {
                    return None;
                }
                m = m * 10 + u64::from(c - b'0');
                n += 1;
                frac += usize::from(dot);
            }
            b'.' if !dot => dot = true,
            _ => return None,
        }
    }
    if n == 0 || m > 1 << 53 {
        return None;
    }
    let v = m as f64 / *POW10.get(frac)?;
    Some(if neg { -v } else { v })
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
            // Headers trimmed as the in-memory reader trims them; fields by `num`, in place
            // (the reader's own field trimming builds a new record per row).
            .trim(csv::Trim::Headers)
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

    /// The time of the next row inside the window (the row's other cells unread), `None` at the
    /// end of the file; time is checked to increase over every row, in the window or not.
    #[inline]
    pub fn next_time(&mut self) -> Result<Option<f64>, Stop> {
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
            if t >= self.lo && t < self.hi {
                return Ok(Some(t));
            }
        }
    }

    /// The next row inside the window, `None` at the end of the file.
    #[inline]
    pub fn next_row(&mut self) -> Result<Option<Row>, Stop> {
        let Some(t) = self.next_time()? else {
            return Ok(None);
        };
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
        Ok(Some(Row {
            t,
            raw: num(self.rec.get(self.target))?,
            reference,
            temperature,
        }))
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::decimal;
    use proptest::prelude::*;

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(20_000))]
        #[test]
        fn decimals_parse_as_std_does(int in 0u64..100_000_000, frac in 0u64..1_000_000_000, places in 0usize..12, neg: bool) {
            let text = if places == 0 {
                format!("{}{int}", if neg { "-" } else { "" })
            } else {
                let f = format!("{frac:09}");
                format!("{}{int}.{}", if neg { "-" } else { "" }, &f[..places.min(9)])
            };
            let fast = decimal(text.as_bytes());
            let std: f64 = text.parse().unwrap();
            // Up to 15 digits the fast path always applies; past 2⁵³ it leaves the text to std.
            let digits = text.bytes().filter(u8::is_ascii_digit).count();
            if digits <= 15 {
                prop_assert!(fast.is_some(), "{}", text);
            }
            if let Some(v) = fast {
                prop_assert_eq!(v.to_bits(), std.to_bits(), "{}", text);
            }
        }

        #[test]
        fn anything_else_is_left_to_std(text in "[-+0-9.eE]{0,30}") {
            if let Some(v) = decimal(text.as_bytes()) {
                prop_assert_eq!(Some(v.to_bits()), text.parse::<f64>().ok().map(f64::to_bits), "{}", text);
            }
        }
    }

    #[test]
    fn edge_cases() {
        for t in [
            "0",
            "-0",
            "-0.0000",
            "5.",
            ".5",
            "9007199254740992",
            "0.1",
            "21600.0050",
            "1e3",
            "",
            ".",
            "-",
            "1.2.3",
            "12345678901234567890",
        ] {
            if let Some(v) = decimal(t.as_bytes()) {
                assert_eq!(v.to_bits(), t.parse::<f64>().unwrap().to_bits(), "{t}");
            }
        }
        assert!(decimal(b"1e3").is_none() && decimal(b"").is_none() && decimal(b".").is_none());
        assert!(decimal(b"12345678901234567890").is_none());
    }
}
