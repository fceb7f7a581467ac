//! Structure pins on features: `--feature 'linear:supply_v'` keeps a feature to the linear term,
//! `--feature 'additive:lag(supply_v, 240)'` lets it act only through a term of its own (never
//! jointly with the other features in one Gaussian), when the user knows the physics better than
//! one training run can tell.
//!
//! Why a mark on the feature rather than an option of its own: the pin belongs to one feature, and
//! the feature list is where a reader looks for it. The mark is stripped before the program is
//! compiled, so the blob holds the plain expression; the structure the pin led to is in the blob's
//! masks (see [`crate::bayes`]).

use crate::error::TrainError;
use serde::Serialize;

/// How a feature may enter the Gaussians.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Pin {
    /// As the evidence chooses (no mark).
    #[default]
    Free,
    /// The linear term only (`linear:`).
    Linear,
    /// Its own one-dimensional term and the linear term, never jointly (`additive:`).
    Additive,
}

/// The marks, as written before the expression.
const MARKS: [(&str, Pin); 2] = [("linear:", Pin::Linear), ("additive:", Pin::Additive)];

/// Splits each feature into its expression and its pin. A `word:` prefix that is not a mark is an
/// error naming the feature (the feature language has no `:`).
pub fn split(features: &[String]) -> Result<(Vec<String>, Vec<Pin>), TrainError> {
    let mut exprs = Vec::with_capacity(features.len());
    let mut pins = Vec::with_capacity(features.len());
    for f in features {
        let t = f.trim_start();
        match MARKS.iter().find(|(m, _)| t.starts_with(m)) {
            Some((m, p)) => {
                exprs.push(t[m.len()..].trim().to_string());
                pins.push(*p);
            }
            None if t.contains(':') => {
                return Err(TrainError::Unknown {
                    what: "--feature mark",
                    name: f.clone(),
                    known: "linear:EXPR, additive:EXPR".into(),
                });
            }
            None => {
                exprs.push(f.clone());
                pins.push(Pin::Free);
            }
        }
    }
    Ok((exprs, pins))
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    #[test]
    fn marks_are_stripped_and_unknown_ones_refused() {
        let f = |v: &[&str]| v.iter().map(|s| s.to_string()).collect::<Vec<_>>();
        let (e, p) = split(&f(&["T", "linear: supply_v", "additive:lag(v, 240)"])).unwrap();
        assert_eq!(e, f(&["T", "supply_v", "lag(v, 240)"]));
        assert_eq!(p, [Pin::Free, Pin::Linear, Pin::Additive]);
        let err = split(&f(&["lineer:T"])).unwrap_err().to_string();
        assert!(
            err.contains("--feature mark") && err.contains("lineer:T"),
            "{err}"
        );
    }
}
