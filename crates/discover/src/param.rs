//! A family's parameter estimated on a continuous scale: the profile of the training criterion
//! over the parameter, its maximum found by golden-section search on a log scale, and the interval
//! of values the training run cannot tell apart.
//!
//! Why: a grid that doubles τ cannot come closer than a factor of √2 to the true value, and the
//! held-out residual can change several-fold over that (a QMA's proof mass lagging its thermometer:
//! τ twice the true one left 3.5× the noise floor). So the parameter is estimated:
//! 1. **Profile.** The training criterion — the log evidence of the trainer's real refit with the
//!    member at that value, on the training run alone — on [`GRID`] values spaced evenly in log p
//!    over the family's range, in parallel.
//! 2. **Golden section.** Around the best grid value, between its neighbours, [`GOLDEN_STEPS`]
//!    steps of golden-section search on log p (the bracket shrinks to 0.618^steps of its width).
//! 3. **Interval.** The values whose evidence is within [`FLAT_NATS`] of the best (odds of about
//!    7 : 1 or less against the best) — nats of real information: the evidence treats every bin as
//!    independent, so with the surrogate's residual correlated from bin to bin (lag-1
//!    autocorrelation ρ) the threshold is divided by the fraction (1 − ρ)/(1 + ρ) of independent
//!    bins — read from the profile with linear interpolation in log p;
//!    an end of the range when the profile never falls that far (the data do not bound it).
//! 4. **Flat evidence.** When that interval spans more than a factor of [`FLAT_RATIO`] — adding
//!    `lag(T, τ)` beside `T` lets many τ fit the training run, as the QMA showed (flat
//!    within 3 nats over a factor of two, while the held-out residual changed sevenfold) — the
//!    evidence cannot choose, and contiguous blocks of the training run do: each block is predicted
//!    by a fit on the others, at [`CV_POINTS`] values across the interval, and the value with the
//!    lowest pooled held-out residual is taken. The report says so, gives the interval, and names
//!    the profile that would resolve it.
//!
//! The value printed is the estimate rounded to two significant figures (`lag(T, 1800)`, not
//! `lag(T, 1834.27)`): the interval is reported beside it, and no training run resolves τ to 1 %.

use crate::families::{ParamKind, Search};
use rayon::prelude::*;
use serde::Serialize;

/// Values of the first profile, evenly spaced in log p over the family's range.
pub const GRID: usize = 25;
/// Golden-section steps around the best grid value.
pub const GOLDEN_STEPS: usize = 12;
/// Nats below the best log evidence that bound the interval of unresolved values.
pub const FLAT_NATS: f64 = 2.0;
/// Smallest fraction of the bins counted as independent observations (a residual correlated
/// from bin to bin with ρ = 0.96).
pub const MIN_INFORMATION: f64 = 0.02;
/// Interval ratio above which the evidence is called flat and cross-validation chooses.
pub const FLAT_RATIO: f64 = 2.0;
/// Values of the interval compared by cross-validation when the evidence is flat.
pub const CV_POINTS: usize = 5;

/// How the value was chosen.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum ChosenBy {
    /// The maximum of the log evidence of the refits on the training run.
    Evidence,
    /// The lowest held-out residual over contiguous blocks of the training run (the evidence was
    /// flat).
    CrossValidation,
    /// The language's default (a rate's 60 s window), which the flat evidence does not reject.
    Default,
}

/// The estimate of one family's parameter.
#[derive(Clone, Debug, Serialize)]
pub struct Estimate {
    /// What the parameter is.
    pub kind: ParamKind,
    /// The value used in the expression (two significant figures).
    pub value: f64,
    /// The optimum before rounding.
    pub optimum: f64,
    /// Values the training run cannot tell apart from the optimum: within [`FLAT_NATS`] of the
    /// best log evidence.
    pub interval: [f64; 2],
    /// Whether the interval is bounded on both sides within the range searched.
    pub bounded: bool,
    /// How the value was chosen.
    pub chosen_by: ChosenBy,
    /// The estimate in one sentence, with the profile that would resolve it when it is not.
    pub note: String,
    /// Refits whose evidence was computed.
    pub evaluations: usize,
    /// The profile: (value, log evidence of the refit), sorted by value.
    pub profile: Vec<[f64; 2]>,
}

/// `v` rounded to two significant figures.
pub fn two_significant(v: f64) -> f64 {
    significant(v, 2)
}

/// `v` to `n` significant figures, through the decimal text, so that the value prints as typed
/// (`0.051`, not the `0.051000000000000004` that scaling by a power of ten leaves: measured, a
/// heating/cooling hysteresis named as `hyst(rate(t_coil_c), 0.051000000000000004)`).
pub(crate) fn significant(v: f64, n: usize) -> f64 {
    if !v.is_finite() || v == 0.0 {
        return v;
    }
    format!("{:.*e}", n.saturating_sub(1), v)
        .parse()
        .unwrap_or(v)
}

/// Golden-section maximisation of `f` over `[a, b]` with `steps` evaluations after the first
/// two: the better of the last two points and its value. The one search of the crate (a family's
/// parameter here, the lag bank's time constants, the rounds' joint re-estimation).
pub(crate) fn golden(mut f: impl FnMut(f64) -> f64, a: f64, b: f64, steps: usize) -> (f64, f64) {
    let r = (5f64.sqrt() - 1.0) / 2.0;
    let (mut a, mut b) = (a, b);
    let mut c = b - r * (b - a);
    let mut d = a + r * (b - a);
    let (mut fc, mut fd) = (f(c), f(d));
    for _ in 0..steps {
        if fc >= fd {
            b = d;
            d = c;
            fd = fc;
            c = b - r * (b - a);
            fc = f(c);
        } else {
            a = c;
            c = d;
            fc = fd;
            d = a + r * (b - a);
            fd = f(d);
        }
    }
    if fc >= fd { (c, fc) } else { (d, fd) }
}

/// Where the profile (sorted by `u`) falls below `thr`, walking from index `i` in direction
/// `step`: the crossing interpolated in `u`, or `None` when it never does.
fn crossing(profile: &[(f64, f64)], i: usize, thr: f64, left: bool) -> Option<f64> {
    let mut k = i;
    loop {
        let next = if left { k.checked_sub(1)? } else { k + 1 };
        let (&(u0, f0), &(u1, f1)) = (profile.get(k)?, profile.get(next)?);
        if f1 < thr {
            let t = if f0 > f1 { (f0 - thr) / (f0 - f1) } else { 0.5 };
            return Some(u0 + t.clamp(0.0, 1.0) * (u1 - u0));
        }
        k = next;
    }
}

/// Estimates the parameter of a family searched as `search`: `evidence(p)` is the training run's
/// log evidence of the refit with the member at `p` (−∞ when it fails), `heldout(p)` the pooled
/// held-out residual of the member over contiguous blocks of the training run (`None` when it
/// fails). `None` when no refit succeeded.
pub fn estimate(
    search: &Search,
    evidence: &(dyn Fn(f64) -> f64 + Sync),
    information: &(dyn Fn(f64) -> f64 + Sync),
    heldout: &(dyn Fn(f64) -> Option<f64> + Sync),
) -> Option<Estimate> {
    let (ulo, uhi) = (search.lo.ln(), search.hi.ln());
    let at = |k: usize| ulo + (uhi - ulo) * k as f64 / (GRID - 1) as f64;
    let f = |u: f64| {
        let v = evidence(u.exp());
        if v.is_finite() { v } else { f64::NEG_INFINITY }
    };
    let mut seen: Vec<(f64, f64)> = (0..GRID)
        .into_par_iter()
        .map(|k| (at(k), f(at(k))))
        .collect();
    let value = |k: usize| seen.get(k).map_or(f64::NEG_INFINITY, |s| s.1);
    let best_grid = (0..GRID).max_by(|&a, &b| value(a).total_cmp(&value(b)))?;
    if !value(best_grid).is_finite() {
        return None;
    }
    golden(
        |u| {
            let v = f(u);
            seen.push((u, v));
            v
        },
        at(best_grid.saturating_sub(1)),
        at((best_grid + 1).min(GRID - 1)),
        GOLDEN_STEPS - 2,
    );
    seen.sort_by(|a, b| a.0.total_cmp(&b.0));
    let (ib, &(ub, fb)) = seen
        .iter()
        .enumerate()
        .max_by(|a, b| a.1.1.total_cmp(&b.1.1))?;
    // The evidence counts every bin as an independent observation; a correlated residual (bias
    // instability, a random walk) carries fewer: FLAT_NATS of real information is
    // FLAT_NATS / fraction of the computed evidence.
    let fraction = information(ub.exp()).clamp(MIN_INFORMATION, 1.0);
    let thr = fb - FLAT_NATS / fraction;
    let lo = crossing(&seen, ib, thr, true);
    let hi = crossing(&seen, ib, thr, false);
    let interval = [lo.unwrap_or(ulo).exp(), hi.unwrap_or(uhi).exp()];
    let bounded = lo.is_some() && hi.is_some();
    let kind = search.template.param_kind();
    let what = match kind {
        ParamKind::TimeConstant => "τ",
        ParamKind::Window => "the window",
        ParamKind::Threshold => "the threshold",
    };
    let mut chosen_by = ChosenBy::Evidence;
    let mut optimum = ub.exp();
    let mut note = format!(
        "{what} by the maximum of the refits' log evidence on the training run ({} refits); \
         values within {FLAT_NATS} nats: {} … {}{}",
        seen.len(),
        crate::hypothesis::num(two_significant(interval[0])),
        crate::hypothesis::num(two_significant(interval[1])),
        if bounded {
            ""
        } else {
            " (an end of the range searched: the run does not bound it)"
        }
    );
    let flat = interval[1] > FLAT_RATIO * interval[0];
    let default = search
        .template
        .default_value()
        .filter(|d| (interval[0]..=interval[1]).contains(d));
    if let (true, Some(d)) = (flat, default) {
        chosen_by = ChosenBy::Default;
        optimum = d;
        note = format!(
            "the training run's evidence is flat in {what} (within {FLAT_NATS} nats from {} to {}): \
             the language's default, which it does not reject; {} would resolve it",
            crate::hypothesis::num(two_significant(interval[0])),
            crate::hypothesis::num(two_significant(interval[1])),
            search.template.resolving_profile()
        );
    } else if flat {
        let (a, b) = (interval[0].ln(), interval[1].ln());
        let points: Vec<f64> = (0..CV_POINTS)
            .map(|k| (a + (b - a) * k as f64 / (CV_POINTS - 1) as f64).exp())
            .collect();
        let cv: Vec<(f64, Option<f64>)> = points.par_iter().map(|&p| (p, heldout(p))).collect();
        if let Some((p, _)) = cv
            .iter()
            .filter_map(|(p, r)| r.filter(|r| r.is_finite()).map(|r| (*p, r)))
            .min_by(|a, b| a.1.total_cmp(&b.1))
        {
            chosen_by = ChosenBy::CrossValidation;
            optimum = p;
            note = format!(
                "the training run's evidence is flat in {what} (within {FLAT_NATS} nats from {} to \
                 {}): chosen by cross-validation over contiguous blocks of the training run; {} \
                 would resolve it",
                crate::hypothesis::num(two_significant(interval[0])),
                crate::hypothesis::num(two_significant(interval[1])),
                search.template.resolving_profile()
            );
        }
    }
    Some(Estimate {
        kind,
        value: two_significant(optimum),
        optimum,
        interval,
        bounded,
        chosen_by,
        note,
        evaluations: seen.len(),
        profile: seen.iter().map(|&(u, v)| [u.exp(), v]).collect(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::families::Template;

    #[test]
    fn values_are_rounded_as_typed() {
        assert_eq!(two_significant(0.051_234).to_string(), "0.051");
        assert_eq!(two_significant(1_234.0).to_string(), "1200");
        assert_eq!(two_significant(-0.000_717_9).to_string(), "-0.00072");
        assert_eq!(significant(26.43, 3).to_string(), "26.4");
    }

    fn lag_search() -> Search {
        Search {
            template: Template::Lag { of: "T".into() },
            lo: 100.0,
            hi: 20_000.0,
        }
    }

    #[test]
    fn a_peaked_profile_is_found_on_a_continuous_scale() {
        // A log evidence peaked at τ = 1834 s, 40 nats per unit of ln τ squared.
        let ev = |p: f64| -40.0 * (p / 1834.0).ln().powi(2);
        let e = estimate(&lag_search(), &ev, &|_| 1.0, &|_| None).unwrap_or_else(|| unreachable!());
        assert!((e.optimum / 1834.0 - 1.0).abs() < 0.02, "{e:?}");
        assert_eq!(e.value, 1800.0);
        assert_eq!(e.chosen_by, ChosenBy::Evidence);
        assert!(e.bounded);
        // ±√(2/40) in ln τ.
        let w = (2.0f64 / 40.0).sqrt();
        assert!(
            (e.interval[0] / (1834.0 * (-w).exp()) - 1.0).abs() < 0.05,
            "{e:?}"
        );
        assert!(
            (e.interval[1] / (1834.0 * w.exp()) - 1.0).abs() < 0.05,
            "{e:?}"
        );
    }

    #[test]
    fn a_flat_profile_is_decided_by_cross_validation_and_says_so() {
        // Flat within a nat from 500 to 5000 s; the held-out residual is lowest at 2000 s.
        let ev = |p: f64| {
            if (500.0..5000.0).contains(&p) {
                0.0
            } else {
                -10.0
            }
        };
        let cv = |p: f64| Some((p / 2000.0).ln().abs() + 1.0);
        let e = estimate(&lag_search(), &ev, &|_| 1.0, &cv).unwrap_or_else(|| unreachable!());
        assert_eq!(e.chosen_by, ChosenBy::CrossValidation);
        assert!(e.interval[0] < 700.0 && e.interval[1] > 3500.0, "{e:?}");
        assert!((e.optimum / 2000.0).ln().abs() < 0.4, "{e:?}");
        assert!(e.note.contains("step"), "{}", e.note);
    }

    #[test]
    fn rounding_keeps_two_significant_figures() {
        assert_eq!(two_significant(1834.27), 1800.0);
        assert_eq!(two_significant(0.0456), 0.046);
        assert_eq!(two_significant(96.0), 96.0);
    }
}
