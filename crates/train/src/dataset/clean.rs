//! What a chamber logger gets wrong, handled by a documented policy instead of a refusal, and
//! counted.
//!
//! Why: a logger writes two rows in one tick of a coarse clock, restarts its clock after a crash,
//! and writes `NaN` or nothing when a read fails. Refusing the whole file for one such row sends
//! the user to a spreadsheet; silently repairing it hides what was done. So each has a policy with
//! a flag, the default is what a careful user would do by hand, and every row touched is counted in
//! [`Dataset::notes`] (printed by the commands, kept in `fit`'s warnings):
//!
//! - **Repeated time** (`--repeated-time`): rows whose time equals the previous row's are
//!   `average`d into one row (the default: both are real readings of that instant, and their mean
//!   is the better estimate), or all but the first are `drop`ped, or the file is refused
//!   (`refuse`, the old behaviour). With `average` or `drop`, a step back in time by more than
//!   10 median steps is a **clock restart**: the rows from there continue the time axis after a
//!   gap of 20 median steps (what the gap machinery calls a gap), so the feature state is carried
//!   across it as across a logger dropout; a smaller step back is a row out of order, dropped.
//! - **Missing cells** (`--missing`): an empty or `NaN` cell in a column the command uses (time,
//!   target, reference, the program's inputs) drops its row by default (`dropout`): the step over
//!   it is then a gap, across which the filters are carried. `refuse` stops at the first one. Text
//!   that is not a number and infinite values are errors under both policies: they are not a
//!   failed read but a wrong column or a broken export.

use super::{BadKind, DataError, Dataset};
use serde::{Deserialize, Serialize};

/// What to do with rows whose time repeats or goes back (`--repeated-time`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum))]
#[serde(rename_all = "kebab-case")]
pub enum RepeatedTime {
    /// Average rows of one time into one row; a clock restart starts a new segment after a gap.
    #[default]
    Average,
    /// Keep the first row of one time; a clock restart starts a new segment after a gap.
    Drop,
    /// Refuse the file at the first time that does not increase.
    Refuse,
}

/// What to do with an empty or NaN cell in a used column (`--missing`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum))]
#[serde(rename_all = "kebab-case")]
pub enum Missing {
    /// Drop the row, as a logger dropout the feature state is carried across.
    #[default]
    Dropout,
    /// Refuse the file at the first one.
    Refuse,
}

/// How a command reads a file: the columns it uses and the policies.
#[derive(Clone, Debug, Default)]
pub struct LoadOptions {
    /// The time column [default: `time_s`].
    pub time: Option<String>,
    /// The columns used (target first: in an autopilot log its message gives the rows).
    pub columns: Vec<String>,
    /// Repeated or backward time.
    pub repeated_time: RepeatedTime,
    /// Empty or NaN cells in used columns.
    pub missing: Missing,
}

impl LoadOptions {
    /// The time column's name.
    pub fn time(&self) -> &str {
        self.time.as_deref().unwrap_or("time_s")
    }
}

/// Applies the policies of `opts` to `data` (see the module doc).
pub fn apply(data: Dataset, opts: &LoadOptions) -> Result<Dataset, DataError> {
    let data = missing(data, opts)?;
    repeated_time(data, opts)
}

/// Drops the rows with a missing cell in a used column (`dropout`), or leaves them for
/// [`Dataset::column`] to refuse.
fn missing(data: Dataset, opts: &LoadOptions) -> Result<Dataset, DataError> {
    if opts.missing == Missing::Refuse {
        return Ok(data);
    }
    let mut used: Vec<usize> = Vec::new();
    for name in std::iter::once(opts.time()).chain(opts.columns.iter().map(String::as_str)) {
        let Ok(i) = data.index(name) else { continue };
        let Some(bad) = data.bad.get(i) else { continue };
        // Text or infinity in a used column is an error, said by `column`.
        if bad.other.is_some() || bad.first.is_none() || used.contains(&i) {
            continue;
        }
        used.push(i);
    }
    if used.is_empty() {
        return Ok(data);
    }
    let n = data.len();
    let mut drop = vec![false; n];
    let mut counts = Vec::new();
    for &i in &used {
        let col = data.cols.get(i).map_or(&[][..], Vec::as_slice);
        let mut count = 0usize;
        let mut first = None;
        for (row, v) in col.iter().enumerate() {
            if v.is_nan() {
                if let Some(d) = drop.get_mut(row) {
                    *d = true;
                }
                count += 1;
                first.get_or_insert(row);
            }
        }
        if let Some(row) = first {
            counts.push(format!(
                "`{}`: {count}, first at line {}",
                data.names.get(i).map_or("", String::as_str),
                data.line(row)
            ));
        }
    }
    let keep: Vec<usize> = (0..n)
        .filter(|&r| !drop.get(r).copied().unwrap_or(false))
        .collect();
    let dropped = n - keep.len();
    let mut out = data.keep_rows(&keep);
    out.notes.push(format!(
        "{}: {dropped} row{} with an empty or NaN cell in a used column dropped as logger \
         dropouts ({}); the feature state is carried across them (--missing refuse to refuse)",
        data.file,
        if dropped == 1 { "" } else { "s" },
        counts.join("; ")
    ));
    Ok(out)
}

/// Averages or drops rows of a repeated time and continues the time axis after a clock restart
/// (`average`, `drop`), or leaves them for [`Dataset::time`] to refuse.
fn repeated_time(data: Dataset, opts: &LoadOptions) -> Result<Dataset, DataError> {
    if opts.repeated_time == RepeatedTime::Refuse {
        return Ok(data);
    }
    let Ok(ti) = data.index(opts.time()) else {
        return Ok(data);
    };
    let Some(t) = data.cols.get(ti) else {
        return Ok(data);
    };
    // A time column with a bad cell is refused by `column` before any of this matters.
    if t.iter().any(|v| !v.is_finite()) || t.windows(2).all(|w| w[1] > w[0]) {
        return Ok(data);
    }
    let mut steps: Vec<f64> = t
        .windows(2)
        .map(|w| w[1] - w[0])
        .filter(|d| *d > 0.0)
        .collect();
    let step = if steps.is_empty() {
        1.0
    } else {
        let mid = steps.len() / 2;
        *steps.select_nth_unstable_by(mid, f64::total_cmp).1
    };
    // Groups of rows that become one row each, and the time shift of each group.
    let mut groups: Vec<(Vec<usize>, f64)> = Vec::new();
    let (mut repeated, mut out_of_order) = (0usize, 0usize);
    let mut restarts: Vec<String> = Vec::new();
    let mut first_repeat = None;
    let mut shift = 0.0;
    let mut last = f64::NEG_INFINITY;
    for (row, &v) in t.iter().enumerate() {
        let here = v + shift;
        if here == last {
            repeated += 1;
            first_repeat.get_or_insert(row);
            if opts.repeated_time == RepeatedTime::Average
                && let Some((g, _)) = groups.last_mut()
            {
                g.push(row);
            }
            continue;
        }
        if here < last {
            if last - here <= 10.0 * step {
                out_of_order += 1;
                continue;
            }
            let gap = 20.0 * step;
            let new_shift = last + gap - v;
            restarts.push(format!(
                "line {}: time {} s after {} s",
                data.line(row),
                crate::num::plain(v, 6),
                crate::num::plain(last - shift, 6)
            ));
            shift = new_shift;
        }
        let here = v + shift;
        groups.push((vec![row], shift));
        last = here;
    }
    let mut cols: Vec<Vec<f64>> = vec![Vec::with_capacity(groups.len()); data.cols.len()];
    for (k, col) in data.cols.iter().enumerate() {
        let Some(out) = cols.get_mut(k) else { continue };
        for (rows, shift) in &groups {
            let sum: f64 = rows.iter().filter_map(|&r| col.get(r)).sum();
            let mean = sum / rows.len().max(1) as f64;
            out.push(if k == ti { mean + shift } else { mean });
        }
    }
    let lines = groups
        .iter()
        .map(|(rows, _)| data.line(rows.first().copied().unwrap_or(0)))
        .collect();
    let mut out = Dataset::from_parts(&data.file, data.names.clone(), cols, lines);
    // Bad cells keep their own wording (text the averaging turned into NaN is still text).
    for (b, old) in out.bad.iter_mut().zip(&data.bad) {
        if let Some(o) = &old.first
            && o.kind != BadKind::Missing
            && let Some(f) = b.first.as_mut()
        {
            f.kind = o.kind;
            f.text = o.text.clone();
        }
    }
    out.notes = data.notes.clone();
    let mut said = Vec::new();
    if repeated > 0 {
        said.push(format!(
            "{repeated} row{} repeated the previous row's time and {} (first at line {})",
            if repeated == 1 { "" } else { "s" },
            match opts.repeated_time {
                RepeatedTime::Average => "were averaged into it",
                _ => "were dropped",
            },
            data.line(first_repeat.unwrap_or(0))
        ));
    }
    if out_of_order > 0 {
        said.push(format!(
            "{out_of_order} row{} out of order (time back by less than 10 median steps) dropped",
            if out_of_order == 1 { "" } else { "s" }
        ));
    }
    if !restarts.is_empty() {
        said.push(format!(
            "{} clock restart{} ({}): the rows from there continue the time axis after a gap of \
             {} s (20 median steps), the feature state carried across it",
            restarts.len(),
            if restarts.len() == 1 { "" } else { "s" },
            restarts.join("; "),
            crate::num::plain(20.0 * step, 4)
        ));
    }
    out.notes.push(format!(
        "{}: {} (--repeated-time {})",
        data.file,
        said.join("; "),
        match opts.repeated_time {
            RepeatedTime::Average => "average; drop or refuse are the others",
            _ => "drop; average or refuse are the others",
        }
    ));
    Ok(out)
}
