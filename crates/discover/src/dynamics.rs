//! The residual's dynamics read from the data: through which first-order lags of each input the
//! residual responds, and how many time constants that takes.
//!
//! Why: the lag families ([`crate::candidates`]) try one τ at a time. A thermal path with two very
//! different time constants on one thermometer is then named as one lag half-way between them,
//! and a non-thermal input whose effect arrives through a lag is named raw. Here the data say how
//! many time constants there are and where.
//!
//! How: a bank — `x` itself and `lag(x, τ)` at [`BANK`] log-spaced τ over the lag families'
//! range — is added to the scoring design (the base model's Gaussians fixed, [`crate::score`]),
//! every column with its own prior precision: automatic relevance determination by MacKay's
//! evidence switches off a τ the residual does not respond through. `x` itself is in the bank so
//! that a response without delay (or the model's own misfit of an input it already has) is not
//! read as a lag. The lag columns that stay on, grouped where they are neighbours on the grid, are
//! the time constants; each group's τ is the geometric mean of its members weighted by their
//! weights' sizes, and the time constants are then refined together (`refined`: golden-section
//! search of the evidence, one τ at a time). Two or more on a temperature propose "thermal paths
//! from x, τ ≈ a and b" (one is what the lag families already find); one or more on a non-thermal
//! input propose "x acts through a lag of τ ≈ a" (with `x` itself when its column stays on and the
//! model lacks it). The proposals are then scored, refitted, placebo-tested — each placebo the
//! bank's own reading of the shifted bank ([`crate::candidates::Searched::Bank`]) — and judged
//! like every other candidate, with one more leg: the trainer's refit with a bank's reading must
//! have more evidence than without it ([`crate::verdict`]). This module only proposes.
//!
//! Pruned by physics (only the sensor's temperatures and its non-thermal inputs, never the
//! chamber's air or another inertial output — [`crate::candidates::Sources`] has sorted them) and by
//! evidence (the bank is one fit per input; only the time constants it keeps are proposed).

use crate::base::Prepared;
use crate::candidates::{Candidate, EffectKind, Family, LAG_RANGE_S, Searched, Sources};
use crate::design::hcat;
use rayon::prelude::*;
use std::collections::HashMap;
use tcomp_core::expr;
use tcomp_train::evidence;

/// Time constants in the bank: about one per factor of 1.8 over 120 s … 20,000 s.
pub const BANK: usize = 10;

/// A column whose prior precision stays below this (normalised units: a prior std above 1 %) is on.
const ON_ALPHA: f64 = 1e4;

/// Two time constants closer than this ratio are one.
const DISTINCT_RATIO: f64 = 3.0;

/// The bank's time constants (s).
fn taus() -> Vec<f64> {
    let (lo, hi) = LAG_RANGE_S;
    (0..BANK)
        .map(|i| lo * (hi / lo).powf(i as f64 / (BANK - 1) as f64))
        .collect()
}

/// A time constant rounded to two significant figures (what a user types).
fn rounded(tau: f64) -> f64 {
    crate::param::two_significant(tau)
}

/// "τ ≈ 25 min" or "τ ≈ 300 s".
fn minutes(tau: f64) -> String {
    if tau >= 600.0 {
        format!("τ ≈ {:.0} min", tau / 60.0)
    } else {
        format!("τ ≈ {tau:.0} s")
    }
}

/// The bank over `x`: `x` itself (a response without delay), then `lag(x, τ)` at every τ of
/// `taus`.
pub fn bank(x: &str) -> Vec<String> {
    std::iter::once(x.to_string())
        .chain(
            taus()
                .iter()
                .map(|&t| expr::lag(expr::name(x), rounded(t)).to_string()),
        )
        .collect()
}

/// The standardised, binned training columns of `lag(x, τ)` over one input, each computed once:
/// the golden-section search of [`refined`] moves one τ and holds the others.
struct Lags<'a> {
    p: &'a Prepared,
    x: &'a str,
    /// The column of `x` itself.
    raw: Option<Vec<f64>>,
    done: HashMap<u64, Option<Vec<f64>>>,
}

impl<'a> Lags<'a> {
    fn new(p: &'a Prepared, x: &'a str) -> Self {
        let raw = p
            .standardised_training(&[x.to_string()])
            .ok()
            .and_then(|c| c.into_iter().next());
        Lags {
            p,
            x,
            raw,
            done: HashMap::new(),
        }
    }

    /// The column of `lag(x, tau)` (`None` when it cannot be computed).
    fn column(&mut self, tau: f64) -> Option<Vec<f64>> {
        let (p, x) = (self.p, self.x);
        self.done
            .entry(tau.to_bits())
            .or_insert_with(|| {
                // One expression at a time: a feature program holds a few features, not a bank.
                let e = expr::lag(expr::name(x), tau).to_string();
                p.standardised_training(std::slice::from_ref(&e))
                    .ok()
                    .and_then(|c| c.into_iter().next())
            })
            .clone()
    }

    /// The evidence fit of the scoring design plus `x` and `lag(x, τ)` for every τ of `taus`,
    /// each column its own prior group (`None` when a column cannot be computed or the fit
    /// fails). `x` itself is always in: a residual that follows the input without delay (or the
    /// model's own misfit of it, when the model has it) is not read as a lag.
    fn fit(&mut self, taus: &[f64]) -> Option<evidence::GroupFit> {
        let missing: Vec<String> = taus
            .iter()
            .filter(|t| !self.done.contains_key(&t.to_bits()))
            .map(|&t| expr::lag(expr::name(self.x), t).to_string())
            .collect();
        if missing.len() > 1 {
            self.p.prefetch(&missing, false);
        }
        let mut cols = vec![self.raw.clone()?];
        for &t in taus {
            cols.push(self.column(t)?);
        }
        let p = self.p;
        let phi = hcat(&p.phi, &cols);
        let g0 = p.groups.iter().copied().max().unwrap_or(0) + 1;
        let mut groups = p.groups.clone();
        groups.extend((0..cols.len()).map(|k| g0 + k));
        let mut a0 = p.base.alpha.clone();
        a0.resize(g0 + cols.len(), 1.0);
        evidence::fit(&phi, &p.y, &groups, Some((&a0, p.base.beta)))
    }

    /// Log evidence of [`Lags::fit`] (−∞ when it fails).
    fn evidence(&mut self, taus: &[f64]) -> f64 {
        self.fit(taus).map_or(f64::NEG_INFINITY, |f| f.log_evidence)
    }
}

/// How the residual responds to one input, read off the bank.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Reading {
    /// Whether it responds to the input without delay too (its column stays on).
    pub direct: bool,
    /// The time constants it responds through (s, ascending).
    pub taus: Vec<f64>,
}

/// The time constants the residual responds to `x` through, by the bank's evidence fit on `p`
/// (ascending; empty when the bank cannot be fitted).
pub fn time_constants(p: &Prepared, x: &str) -> Vec<f64> {
    read(p, x).taus
}

/// How the residual responds to `x` (see the module doc).
pub fn read(p: &Prepared, x: &str) -> Reading {
    let taus: Vec<f64> = taus().into_iter().map(rounded).collect();
    let mut lags = Lags::new(p, x);
    let Some(fit) = lags.fit(&taus) else {
        return Reading::default();
    };
    let g0 = p.groups.iter().copied().max().unwrap_or(0) + 1;
    let base_cols = p.phi.ncols();
    let is_on = |k: usize| {
        let alpha = fit.alpha.get(g0 + k).copied().unwrap_or(f64::INFINITY);
        let w = fit.w.get(base_cols + k).copied().unwrap_or(0.0).abs();
        (alpha < ON_ALPHA && w > 0.0).then_some(w)
    };
    // Column 0 is `x` itself, the lags follow.
    let direct = is_on(0).is_some();
    let on: Vec<(usize, f64)> = (0..taus.len())
        .filter_map(|k| is_on(k + 1).map(|w| (k, w)))
        .collect();
    // Neighbours on the grid are one time constant.
    let mut groups_on: Vec<Vec<(usize, f64)>> = Vec::new();
    for (k, w) in on {
        match groups_on.last_mut() {
            Some(g) if g.last().is_some_and(|(j, _)| k == j + 1) => g.push((k, w)),
            _ => groups_on.push(vec![(k, w)]),
        }
    }
    let mut out: Vec<f64> = groups_on
        .iter()
        .filter_map(|g| {
            let wsum: f64 = g.iter().map(|(_, w)| w).sum();
            if wsum <= 0.0 {
                return None;
            }
            let ln: f64 = g
                .iter()
                .map(|(k, w)| w * taus.get(*k).copied().unwrap_or(1.0).ln())
                .sum::<f64>()
                / wsum;
            Some(rounded(ln.exp()))
        })
        .collect();
    // Groups that ended up closer than the distinct ratio are one.
    out.dedup_by(|b, a| *b / *a < DISTINCT_RATIO);
    let mut out = refined(&mut lags, out);
    out.sort_by(f64::total_cmp);
    out.dedup_by(|b, a| *b / *a < DISTINCT_RATIO);
    Reading { direct, taus: out }
}

/// The bank's time constants re-estimated together: each in turn by a golden-section search of
/// the evidence over ln τ (within a factor of [`DISTINCT_RATIO`] of where it was, inside the lag
/// range) with the others held, two sweeps — the grid's step is a factor of 1.8, and a slow path
/// the model's own temperature terms half absorb pulls its neighbour along.
fn refined(lags: &mut Lags<'_>, mut taus: Vec<f64>) -> Vec<f64> {
    const SWEEPS: usize = 2;
    const STEPS: usize = 12;
    let (lo_r, hi_r) = (LAG_RANGE_S.0.ln(), LAG_RANGE_S.1.ln());
    for _ in 0..SWEEPS {
        for i in 0..taus.len() {
            let Some(&t0) = taus.get(i) else { continue };
            let a = (t0 / DISTINCT_RATIO).ln().max(lo_r);
            let b = (t0 * DISTINCT_RATIO).ln().min(hi_r);
            let (best, _) = crate::param::golden(
                |v| {
                    if let Some(slot) = taus.get_mut(i) {
                        *slot = v.exp();
                    }
                    lags.evidence(&taus)
                },
                a,
                b,
                STEPS,
            );
            if let Some(slot) = taus.get_mut(i) {
                *slot = rounded(best.exp());
            }
        }
    }
    taus
}

/// The hypotheses the bank proposes over `src` (see the module doc), each a one-member family;
/// `features` are the model's, so that an input it already has is not proposed again.
pub fn propose(p: &Prepared, src: &Sources, features: &[String]) -> Vec<Family> {
    let mut inputs: Vec<(String, bool)> = src
        .temperatures
        .iter()
        .map(|t| (t.clone(), true))
        .chain(src.inputs.iter().map(|x| (x.clone(), false)))
        .collect();
    inputs.dedup();
    inputs
        .par_iter()
        .filter_map(|(x, thermal)| {
            let r = read(p, x);
            let wanted = if *thermal { 2 } else { 1 };
            if r.taus.len() < wanted {
                return None;
            }
            let list = r
                .taus
                .iter()
                .map(|t| minutes(*t))
                .collect::<Vec<_>>()
                .join(" and ");
            // A non-thermal input the residual also follows without delay, which the model
            // lacks, is proposed with its lags.
            let direct = !*thermal && r.direct && !features.iter().any(|f| f == x);
            let lags = if r.taus.len() == 1 { "a lag" } else { "lags" };
            let (kind, effect) = if *thermal {
                (
                    EffectKind::LaggedElement,
                    format!("{} thermal paths from {x}, {list}", r.taus.len()),
                )
            } else if direct {
                (
                    EffectKind::NonThermal,
                    format!("{x} acts directly and through {lags} of {list}"),
                )
            } else {
                (
                    EffectKind::NonThermal,
                    format!("{x} acts through {lags} of {list}"),
                )
            };
            let expressions = direct
                .then(|| x.clone())
                .into_iter()
                .chain(
                    r.taus
                        .iter()
                        .map(|&t| expr::lag(expr::name(x), t).to_string()),
                )
                .collect();
            Some(Family {
                members: vec![Candidate {
                    kind,
                    effect,
                    expressions,
                    // One time constant is the parameter the bank estimated; several are named.
                    parameter: if r.taus.len() == 1 {
                        r.taus.first().copied()
                    } else {
                        None
                    },
                    replaces: Vec::new(),
                    refines: None,
                }],
                search: None,
                searched: Searched::Bank(bank(x)),
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_bank_spans_the_lag_range() {
        let t = taus();
        assert_eq!(t.len(), BANK);
        assert!((t[0] - LAG_RANGE_S.0).abs() < 1e-9);
        assert!((t[BANK - 1] - LAG_RANGE_S.1).abs() < 1e-6);
        assert!(t.windows(2).all(|w| w[1] / w[0] < DISTINCT_RATIO));
    }

    #[test]
    fn minutes_read_as_typed() {
        assert_eq!(minutes(300.0), "τ ≈ 300 s");
        assert_eq!(minutes(1500.0), "τ ≈ 25 min");
    }
}
