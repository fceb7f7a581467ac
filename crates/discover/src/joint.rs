//! The parameters of every effect the rounds added, re-estimated together by the trainer's own
//! evidence.
//!
//! Why: each round estimates its candidate's parameter with the others held where earlier rounds
//! left them. Two thermal paths of very different time constants show what that costs: the first
//! round names one lag half-way between them (the best single lag), the second adds another, and
//! neither is ever moved again — two wrong τ's. The added parameters must be estimated jointly
//! once they are all in the model.
//!
//! How: every numeric parameter of the features the rounds added — a lag's τ, a rate's window, a
//! heating/cooling relay's threshold, a warm-up's τ ([`params_of`]) — in turn, the others held,
//! by a golden-section search over ln p within a factor of [`REACH`] of where it is and inside
//! its family's range; up to [`SWEEPS`] sweeps. The objective is the log evidence of the first round's
//! scoring design (the model the rounds started from, its Gaussians fixed, [`crate::score`]) with
//! every added feature's column beside it, each its own prior group: the criterion the rounds
//! estimated each parameter by. Not the trainer's refit: its evidence search places Gaussians
//! discretely, and its evidence jumps by tens of nats between neighbouring τ's (measured on the
//! lag-in-every-term case: −579 at the true 1800 s, −472 at a wrong pair), a surface no search
//! can climb. A parameter moves only when the evidence rises by more than
//! [`crate::score::INDISTINCT_NATS`]: values the run cannot tell apart stay where the diagnosis
//! put them.

use crate::base::Prepared;
use crate::candidates::{HYST_RANGE, LAG_RANGE_S, RATE_RANGE_S, WARMUP_RANGE_S};
use crate::param::two_significant;
use serde::Serialize;
use tcomp_train::evidence;

/// A parameter may move by up to this factor each way per sweep.
pub const REACH: f64 = 3.0;

/// Sweeps over the parameters at most: coordinate ascent on parameters that trade off (a lag
/// and a rate window both describe a ramp's response) climbs a ridge in small steps. The sweeps
/// stop early when none moves.
pub const SWEEPS: usize = 8;

/// Golden-section steps per parameter and sweep.
const STEPS: usize = 10;

/// One numeric parameter inside a feature expression.
#[derive(Clone, Debug, PartialEq)]
pub struct Param {
    /// Index of the feature in the list.
    pub feature: usize,
    /// Byte range of the number in the feature's text.
    pub at: (usize, usize),
    /// Its value.
    pub value: f64,
    /// The range its family searches.
    pub range: (f64, f64),
}

/// A parameter that moved.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct Moved {
    /// The feature before.
    pub from: String,
    /// The feature after.
    pub to: String,
    /// Log evidence the scoring design gained by the whole re-estimation.
    pub delta_log_evidence: f64,
}

/// The index of the `)` closing the `(` at `open` in `s`.
fn closing(s: &str, open: usize) -> Option<usize> {
    let mut depth = 0usize;
    for (i, ch) in s.char_indices().skip_while(|(i, _)| *i < open) {
        match ch {
            '(' => depth += 1,
            ')' => {
                depth = depth.checked_sub(1)?;
                if depth == 0 {
                    return Some(i);
                }
            }
            _ => {}
        }
    }
    None
}

/// The byte range of the last top-level argument of the call whose `(` is at `open` and whose
/// `)` is at `close`, trimmed.
fn last_argument(s: &str, open: usize, close: usize) -> (usize, usize) {
    let mut depth = 0usize;
    let mut start = open + 1;
    for (i, ch) in s
        .char_indices()
        .take_while(|(i, _)| *i < close)
        .skip(open + 1)
    {
        match ch {
            '(' => depth += 1,
            ')' => depth = depth.saturating_sub(1),
            ',' if depth == 0 => start = i + 1,
            _ => {}
        }
    }
    let arg = &s[start..close];
    let lead = arg.len() - arg.trim_start().len();
    (start + lead, start + lead + arg.trim().len())
}

/// The searchable parameters of feature `k`, `e`: the last argument of `lag(…, τ)`,
/// `rate(…, w)`, `hyst(rate(…), h)` and the argument of `warmup(τ)`, where it is a plain number.
/// (A relay on a shifted input, `hyst(x − c, h)`, has two parameters that move together; it is
/// left where it is.)
pub fn params_of(k: usize, e: &str) -> Vec<Param> {
    let mut out = Vec::new();
    let ident = |c: char| c.is_ascii_alphanumeric() || c == '_';
    for (name, range) in [
        ("lag", LAG_RANGE_S),
        ("rate", RATE_RANGE_S),
        ("hyst", HYST_RANGE),
        ("warmup", WARMUP_RANGE_S),
    ] {
        let call = format!("{name}(");
        let mut from = 0;
        while let Some(pos) = e[from..].find(&call).map(|p| p + from) {
            from = pos + call.len();
            if e[..pos].chars().next_back().is_some_and(ident) {
                continue;
            }
            let open = pos + name.len();
            let Some(close) = closing(e, open) else {
                continue;
            };
            let (a, b) = last_argument(e, open, close);
            // `rate(x)` and `lag`'s single argument have no parameter to move.
            if name != "warmup" && !e[open + 1..close].contains(',') {
                continue;
            }
            if name == "hyst" && !e[open + 1..].trim_start().starts_with("rate(") {
                continue;
            }
            if let Ok(value) = e[a..b].parse::<f64>()
                && value > 0.0
            {
                out.push(Param {
                    feature: k,
                    at: (a, b),
                    value,
                    range,
                });
            }
        }
    }
    out.sort_by_key(|p| p.at.0);
    out
}

/// `features` with the parameter `p` set to `v` (written as the expressions print numbers).
fn with_value(features: &[String], p: &Param, v: f64) -> Vec<String> {
    let mut f = features.to_vec();
    if let Some(e) = f.get_mut(p.feature) {
        let text = crate::hypothesis::num(v);
        e.replace_range(p.at.0..p.at.1, &text);
    }
    f
}

/// The parameters of `features` at the indices `added` (the features the rounds put in).
fn params(features: &[String], added: &[usize]) -> Vec<Param> {
    added
        .iter()
        .filter_map(|&k| features.get(k).map(|e| params_of(k, e)))
        .flatten()
        .collect()
}

/// `features` — the features of `model` with others added, at the indices `added` — with the
/// added parameters re-estimated together on `data` (see the module doc), and what moved.
pub fn reestimate_added(
    model: &crate::HostModel<'_>,
    data: &tcomp_train::Dataset,
    features: &[String],
    added: &[usize],
    opts: &crate::score::ScoreOptions,
) -> crate::Result<(Vec<String>, Vec<Moved>)> {
    let info = crate::model_info(model);
    let p = crate::score::prepare(&info.spec, &info.roles, data, None, opts)?;
    Ok(reestimate(&p, features, added))
}

/// Log evidence of the scoring design `p` with the columns of `features` at `added` beside it,
/// each its own prior group (−∞ when a column cannot be computed or the fit fails).
fn objective(p: &Prepared, features: &[String], added: &[usize]) -> f64 {
    let mut cols = Vec::with_capacity(added.len());
    for &k in added {
        let Some(e) = features.get(k) else {
            return f64::NEG_INFINITY;
        };
        match p.standardised_training(std::slice::from_ref(e)) {
            Ok(c) => cols.extend(c),
            Err(_) => return f64::NEG_INFINITY,
        }
    }
    let (phi, mut groups, mut a0) = p.with_columns(&cols);
    let g = p.groups.iter().copied().max().unwrap_or(0) + 1;
    let k = groups.len() - cols.len();
    for (j, slot) in groups.iter_mut().skip(k).enumerate() {
        *slot = g + j;
    }
    a0.resize(g + cols.len(), 1.0);
    evidence::fit(&phi, &p.y, &groups, Some((&a0, p.base.beta)))
        .map_or(f64::NEG_INFINITY, |f| f.log_evidence)
}

/// `features` with the parameters of the features at `added` re-estimated together (see the
/// module doc), and what moved.
pub(crate) fn reestimate(
    pr: &Prepared,
    features: &[String],
    added: &[usize],
) -> (Vec<String>, Vec<Moved>) {
    let mut current = features.to_vec();
    let mut best = objective(pr, &current, added);
    if !best.is_finite() || params(&current, added).is_empty() {
        return (current, Vec::new());
    }
    for _ in 0..SWEEPS {
        let before = current.clone();
        let n = params(&current, added).len();
        for i in 0..n {
            // Positions shift as numbers are rewritten: read the parameter afresh.
            let Some(p) = params(&current, added).get(i).cloned() else {
                continue;
            };
            let eval = |u: f64| {
                let v = two_significant(u.exp());
                objective(pr, &with_value(&current, &p, v), added)
            };
            let lo = (p.value / REACH).max(p.range.0).ln();
            let hi = (p.value * REACH).min(p.range.1).ln();
            if hi <= lo {
                continue;
            }
            let (u, f) = crate::param::golden(eval, lo, hi, STEPS);
            if f > best + crate::score::INDISTINCT_NATS {
                current = with_value(&current, &p, two_significant(u.exp()));
                best = f;
            }
        }
        if current == before {
            break;
        }
    }
    let start = objective(pr, features, added);
    let moved = added
        .iter()
        .filter_map(|&k| {
            let (from, to) = (features.get(k)?, current.get(k)?);
            (from != to).then(|| Moved {
                from: from.clone(),
                to: to.clone(),
                delta_log_evidence: best - start,
            })
        })
        .collect();
    (current, moved)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parameters_are_found_where_they_can_move() {
        let e = "lag(t_a, 1400) + rate(lag(T, 300), 120) * hyst(rate(T), 0.05) + warmup(600)";
        let p = params_of(0, e);
        let values: Vec<f64> = p.iter().map(|p| p.value).collect();
        assert_eq!(values, vec![1400.0, 300.0, 120.0, 0.05, 600.0]);
        for p in &p {
            assert_eq!(e[p.at.0..p.at.1].parse::<f64>().ok(), Some(p.value));
        }
        // No parameter: the default rate window, a relay on a shifted input, a name ending in
        // `lag`.
        assert!(params_of(0, "rate(T)").is_empty());
        assert!(params_of(0, "hyst(T - 30, 5)").is_empty());
        assert!(params_of(0, "xlag(T, 5)").is_empty());
    }

    #[test]
    fn a_value_is_written_in_place() {
        let f = vec!["T".to_string(), "rate(lag(T, 300), 120)".to_string()];
        let p = params_of(1, &f[1]);
        assert_eq!(with_value(&f, &p[0], 450.0)[1], "rate(lag(T, 450), 120)");
        assert_eq!(with_value(&f, &p[1], 90.0)[1], "rate(lag(T, 300), 90)");
    }
}
