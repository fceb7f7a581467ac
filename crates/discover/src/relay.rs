//! Relays read from the data: a bias that steps when an input rises past one point and steps back
//! when it falls past another, lower one — a laser's or a resonator's mode hop, a heater's
//! thermostat, a stick-slip — with both switching points estimated.
//!
//! Why: the hysteresis family ([`crate::families`]) is a relay on the *rate* of a temperature,
//! switching at ±h per minute: heating against cooling. A bias that switches at one temperature
//! on heating and at another on cooling is a relay on the temperature itself, `hyst(x − c, h)`:
//! up when x passes c + h, down when it falls below c − h. It has two parameters, so it is read
//! off a grid and refined here, not searched through a one-parameter template; and it is named
//! only when the data carry it — a curvature in T explains part of a hop on a run with one ramp
//! each way, and was named for one before this module.
//!
//! How: for every temperature and non-thermal input `x`, `hyst(x − c, h)` on a grid — c at
//! [`CENTERS`] points evenly across x's range over the training run (10 … 90 %), h at [`WIDTHS`]
//! fractions of the range — every member scored by the evidence of the scoring design (the base model's Gaussians
//! fixed, [`crate::score`]) plus its column; the best refined by a golden-section search of c,
//! then of h, and proposed when it has more evidence than the design without it. The proposal is
//! then scored, refitted, placebo-tested — each placebo the best of the grid's members shifted in
//! time ([`Searched::Grid`]), as the proposal is the best of the grid — and judged like every
//! other candidate: this module only proposes.
//!
//! Pruned by physics (only the sensor's temperatures and its non-thermal inputs, which
//! [`crate::candidates::Sources`] has sorted, never the chamber's air or another inertial output)
//! and by evidence (one proposal per input: the grid's best).

use crate::base::Prepared;
use crate::candidates::{Candidate, EffectKind, Family, Searched, Sources, num};
use rayon::prelude::*;
use tcomp_core::expr::{self, Expr};
use tcomp_train::evidence;

/// Switching centres tried, evenly across the input's range from 10 % to 90 % (a tenth of the
/// range apart). Evenly, not at quantiles: a chamber profile's holds put most samples at a few
/// temperatures, and a hop between two holds would fall between the quantiles.
pub const CENTERS: usize = 9;

/// Half the distance between the two switching points, as fractions of the input's range: from a
/// hop barely apart from a plain step to one that switches a quarter of the range apart each way.
pub const WIDTHS: [f64; 4] = [0.02, 0.06, 0.12, 0.25];

/// Points of a switching point's evidence profile across the input's range.
const PROFILE: usize = 40;

/// Evidence within this of the best is "cannot be told apart" (the criterion's bare-mention
/// scale, [`crate::verdict::INDISTINCT_NATS`]).
const PLATEAU_NATS: f64 = crate::verdict::INDISTINCT_NATS;

/// `v` rounded to `step`, a power of ten (a switching point as a user types it: 30.1, not
/// 30.100000000000001).
fn to_step(v: f64, step: f64) -> f64 {
    if step.is_nan() || step <= 0.0 {
        v
    } else if step < 1.0 {
        let per = (1.0 / step).round();
        (v * per).round() / per
    } else {
        (v / step).round() * step
    }
}

/// The resolution switching points are written to: a thousandth of the input's range, to one
/// significant figure (0.1 °C for a 60 °C range).
fn resolution(range: f64) -> f64 {
    10f64.powf((range / 1000.0).log10().ceil())
}

/// `hyst(x − c, h)`: up when `x` passes `c + h`, down when it falls below `c − h`.
pub fn member(x: &str, c: f64, h: f64) -> String {
    let shifted = if c < 0.0 {
        expr::name(x) + Expr::num(-c)
    } else {
        expr::name(x) - Expr::num(c)
    };
    expr::hyst(shifted, h).to_string()
}

/// Δ log evidence of the scoring design plus the column of `e` over the design's own (−∞ when the
/// column is constant — a relay that never switches — or the fit fails).
fn gain(p: &Prepared, e: &str) -> f64 {
    let Ok(cols) = p.standardised_training(&[e.to_string()]) else {
        return f64::NEG_INFINITY;
    };
    let (phi, groups, a0) = p.with_columns(&cols);
    evidence::fit(&phi, &p.y, &groups, Some((&a0, p.base.beta)))
        .map_or(f64::NEG_INFINITY, |f| f.log_evidence - p.base.log_evidence)
}

/// A relay read off the data.
#[derive(Clone, Debug, PartialEq)]
pub struct Relay {
    /// Where it switches up, on the way up.
    pub up: f64,
    /// Where it switches down, on the way down.
    pub down: f64,
    /// The switching points' intervals: where the evidence is within [`PLATEAU_NATS`] of its
    /// best.
    pub up_interval: [f64; 2],
    /// See `up_interval`.
    pub down_interval: [f64; 2],
    /// `hyst(x − c, h)` at those points.
    pub expression: String,
    /// The grid the relay was read from: what its placebos search.
    pub members: Vec<Vec<String>>,
}

/// `hyst` switching up at `up` and down at `down`, written to `step`.
fn member_between(x: &str, up: f64, down: f64, step: f64) -> String {
    member(
        x,
        to_step((up + down) / 2.0, step / 10.0),
        to_step((up - down) / 2.0, step / 10.0),
    )
}

/// The evidence profile of `build(v)` over `[lo, hi]` on [`PROFILE`] points: the posterior mean
/// of `v` (flat prior), and the interval where the evidence is within [`PLATEAU_NATS`] of its
/// best.
fn profile(
    p: &Prepared,
    build: impl Fn(f64) -> Option<String> + Sync,
    lo: f64,
    hi: f64,
) -> (f64, [f64; 2]) {
    let pts: Vec<(f64, f64)> = (0..PROFILE)
        .into_par_iter()
        .filter_map(|i| {
            let v = lo + (hi - lo) * (i as f64 + 0.5) / PROFILE as f64;
            let e = build(v)?;
            let g = gain(p, &e);
            g.is_finite().then_some((v, g))
        })
        .collect();
    let top = pts.iter().map(|p| p.1).fold(f64::NEG_INFINITY, f64::max);
    let (mut sw, mut sv) = (0.0, 0.0);
    for &(v, g) in &pts {
        let w = (g - top).exp();
        sw += w;
        sv += w * v;
    }
    let near: Vec<f64> = pts
        .iter()
        .filter(|p| p.1 >= top - PLATEAU_NATS)
        .map(|p| p.0)
        .collect();
    let a = near.iter().copied().fold(f64::INFINITY, f64::min);
    let b = near.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    (if sw > 0.0 { sv / sw } else { (lo + hi) / 2.0 }, [a, b])
}

/// The switching points the residual steps at over `x`, with their intervals and the grid they
/// were read from; `None` when no relay has more evidence than the design alone.
pub fn read(p: &Prepared, x: &str) -> Option<Relay> {
    let mut v = p.binned(&[x.to_string()]).ok()?.into_iter().next()?;
    v.retain(|x| x.is_finite());
    v.sort_by(f64::total_cmp);
    let (lo, hi) = (*v.first()?, *v.last()?);
    let range = hi - lo;
    if range.is_nan() || range <= 0.0 {
        return None;
    }
    let step = resolution(range);
    let centres: Vec<f64> = (0..CENTERS)
        .map(|i| {
            to_step(
                lo + range * (0.1 + 0.8 * i as f64 / (CENTERS - 1) as f64),
                step,
            )
        })
        .collect();
    let widths: Vec<f64> = WIDTHS
        .iter()
        .map(|w| to_step(w * range, step).max(step))
        .collect();
    let grid: Vec<(f64, f64)> = centres
        .iter()
        .flat_map(|&c| widths.iter().map(move |&h| (c, h)))
        .collect();
    let (c, h, best) = grid
        .par_iter()
        .map(|&(c, h)| (c, h, gain(p, &member(x, c, h))))
        .max_by(|a, b| a.2.total_cmp(&b.2))?;
    if !best.is_finite() {
        return None;
    }
    // Each switching point in turn, the other held: its evidence profile over the range on a
    // fine grid, and its posterior mean under that profile (a flat prior). A run with one ramp
    // each way leaves a switching point free between two temperatures it visited — the
    // evidence is flat there — and the posterior mean is the middle of that plateau, not one
    // end of it; the plateau's extent is the interval reported.
    let down = c - h;
    let (u, ui) = profile(
        p,
        |u| (u > down).then(|| member_between(x, u, down, step)),
        lo,
        hi,
    );
    let up = to_step(u, step);
    let (d, di) = profile(
        p,
        |d| (d < up).then(|| member_between(x, up, d, step)),
        lo,
        hi,
    );
    let down = to_step(d, step);
    let best = gain(p, &member_between(x, up, down, step)).max(best);
    let (ui, di) = (ui.map(|v| to_step(v, step)), di.map(|v| to_step(v, step)));
    let members = grid.iter().map(|&(c, h)| vec![member(x, c, h)]).collect();
    (best > 0.0).then_some(Relay {
        up,
        down,
        up_interval: ui,
        down_interval: di,
        expression: member_between(x, up, down, step),
        members,
    })
}

/// The relays the data propose over `src` (see the module doc), each a one-member family.
pub fn propose(p: &Prepared, src: &Sources) -> Vec<Family> {
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
            let r = read(p, x)?;
            let at = |v: f64, i: [f64; 2]| format!("≈ {} ({} … {})", num(v), num(i[0]), num(i[1]));
            let (up, down) = (at(r.up, r.up_interval), at(r.down, r.down_interval));
            let effect = if *thermal {
                format!("bias switches at {x} {up} on heating and {down} on cooling")
            } else {
                format!("bias switches when {x} rises past {up} and back when it falls past {down}")
            };
            Some(Family {
                members: vec![Candidate {
                    kind: EffectKind::Hysteresis,
                    effect,
                    expressions: vec![r.expression],
                    parameter: None,
                    replaces: Vec::new(),
                    refines: None,
                }],
                search: None,
                searched: Searched::Grid(r.members),
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_member_switches_where_it_says() {
        assert_eq!(member("T", 30.0, 5.0), "hyst(T - 30, 5)");
        assert_eq!(member("T", -2.5, 1.0), "hyst(T + 2.5, 1)");
    }

    #[test]
    fn switching_points_are_written_to_a_thousandth_of_the_range() {
        assert_eq!(resolution(60.0), 0.1);
        assert_eq!(resolution(5.0), 0.01);
        assert!((to_step(30.04, 0.1) - 30.0).abs() < 1e-12);
    }
}
