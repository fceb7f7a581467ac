//! Additive structure: the model as a sum of one-feature terms — Gaussians, logistic steps and
//! powers, each weight with its own prior precision — beside a linear term whose every feature has
//! its own prior precision too, built by the evidence on the training run, one term at a time.
//!
//! Why: a thermal bias plus a term in a supply voltage is a sum. One RBF over all features puts its
//! Gaussians in the joint space, and a verification run that visits temperature and voltage
//! combinations the training run never had finds them faded to the bias. Terms over each feature
//! alone extrapolate each along its own axis (an interaction is the joint model's, and the
//! evidence chooses between the two). An input with no effect gets a prior precision of its own and
//! is switched off instead of diluting the others' prior. And a one-dimensional curve with a knee
//! or a step needs something that changes level at one place and holds it on both sides: a
//! Gaussian fades back on both sides, so a level change costs Gaussians all along the flat part
//! (and they fade beyond it), while a logistic step is one term. A smooth thermal bias is mostly a
//! cubic (the polynomial PX4 and ArduPilot fly), which Gaussians only approximate.
//!
//! # The dictionary
//! Per feature alone: its square and cube about its mean (standardised units); Gaussians at
//! positions evenly spread over its training range with σ of 1, 2, 4, 8 and 16 times the narrowest
//! the binned data resolve (half of what one bin spans where the feature moves, see
//! [`Search::resolution`]); logistic steps `S((z − c)/s)` at the same positions and widths; and
//! saturating ramps `clamp((z − c)/s, −1, 1)` at the same positions and half-widths, those with
//! both corners inside the range and rising over at most half of it ([`ramp_fits`]). The core evaluates every kind
//! ([`tcomp_core::rbf`]; blob format 4, ramps format 5).
//!
//! **Ramps.** A bias that changes slope at one temperature and again at another (a knee, a
//! saturation: the language's `clamp`) is neither a step nor a bump: a logistic rises with soft
//! shoulders over its whole width, so a clamped ramp 16 °C wide cost a step plus Gaussians at its
//! corners, and the Gaussians fade beyond the range. A ramp is that shape in one term, and beyond
//! its corners it holds its levels as a step does, so it never extrapolates along a slope (a
//! hinge, `max(0, z − c)`, was tried and did: fitted to a thermometer gradient's linear trend, it
//! took the trend inside the range and held flat outside, 5× the floor on the verification run).
//! A ramp whose level beyond one corner the run barely reached is such a hinge, hence
//! [`ramp_fits`]: without it the two groups improved on average (1.46 → 1.26 of the limit on
//! `SEED_BASE=5000`) but one seed in twenty reached 8× the floor on fresh seeds. Measured on
//! `tests/additive_fits.rs`, fit over the least-squares limit, mean of 20 seeds (`SEED_BASE=5000`,
//! development): knee 1.12 → 1.05, step 1.02 → 0.99, supply, lagged input and two groups
//! unchanged (1.01, 0.99, 1.46).
//!
//! # The search (sparse Bayesian learning, Tipping and Faul 2003)
//! The model starts as the bias, the linear term (one α per feature) and the square and cube of
//! the first feature (the temperature, as for the cubic basis; each with its own α, so the
//! evidence switches off what it does not need). Each step scores every candidate by the rise of
//! the log evidence its addition would give with the other hyperparameters held (the closed form of
//! Tipping and Faul: `ΔL = ½[(Q² − S)/S + ln(S/Q²)]` for `Q² > S`), refits the best four, and
//! the best four of the terms found off the grid ("Off the grid" below), with every α and β
//! ([`crate::evidence`]) and the noise model below, refines the best of them, and keeps it if it
//! raises the evidence by the Occam margin [`super::PARSIMONY`], the charge for its choice
//! ("Which of M" below) and, off the grid, its parameters' Occam factor. It stops there, or at 32
//! terms (the reference firmware's capacity) or one per 3 bins. A term whose α a later refit
//! drives to infinity is removed.
//!
//! **Which of M.** Each step adds the best of `M` dictionary entries (up to 24 positions by 5
//! widths by 3 kinds per feature, and the powers: 289 to 1,309 on the path with every kind in the
//! cases of `tests/additive_fits.rs`). The hypothesis "one more term" does not say which: under
//! a uniform prior over the entries its evidence is the increment averaged over all `M`,
//! `ln(Σᵢ e^(ΔLᵢ)/M)`, not the best one's. So the best term must raise the evidence by the margin plus the
//! difference, `ln M − ln Σᵢ e^(ΔLᵢ − ΔL_max)` ([`choice_charge`], on the closed-form increments of
//! the scoring step): up to `ln M` (5.7 to 7.2 nats) when one entry stands out alone, as one
//! that fits a drift excursion does, and less when many neighbouring entries explain the same
//! shape, as a real one's do. Why: the largest of a few hundred increments of noise is about
//! `ln M`, so the margin alone let the search add terms that fit the noise's drift — a sharp
//! step at a temperature the run crossed once, a narrow Gaussian on a second gradient. Measured
//! on 20 fresh seeds of each case of `tests/additive_fits.rs` (`SEEDS=20 SEED_BASE=5000`), the
//! verification error over the least-squares limit on the exact form, mean: supply 1.07 → 1.01,
//! lagged input 1.08 → 0.98, knee 1.14 → 1.12, step 1.02 → 1.02, two groups 1.80 → 1.46 (the
//! plain `ln M`: 1.01, 0.98, 1.14, 1.02, 1.41, but the real MEMS cycle's acc_z lost its step, 0.74
//! → 0.99 of poly3 on its held-out cooling). The real cycle's acc_x lost its two Gaussians
//! either way: 0.70 → 1.00 of poly3, its figure before the additive structure (with ramps, and
//! no [`ramp_fits`], one ramp took it to 0.71). The three paths'
//! ends are compared with the charges ([`Search::occam_within`]); the additive model is compared
//! with the joint search's pick without them ([`Search::occam`]).
//!
//! **Off the grid.** A Gaussian, a step or a ramp just added has its position and width refined
//! by a pattern search on the evidence ([`Search::refine_atom`]): a sharp step one grid spacing
//! off leaves a residual of its whole height over that spacing on every run that crosses it. The
//! two fitted parameters then cost an Occam factor of `½ ln N` each ([`Search::occam`]), and the
//! refinement is kept only when it pays for them. But refining only what the grid chose is too
//! late: which term is chosen is decided on the grid, and at tens of times the noise a ramp's
//! half-width a quarter off the grid's costs tens of nats, so the grid's ranking picks a term of
//! another kind, or on a correlated feature. In the two-groups case of `tests/additive_fits.rs`
//! the true ramp on the anode gradient reaches 160 nats where it sits, 113 at the nearest grid
//! width, and a step on the cathode gradient won the first place at 126; nothing later undid
//! it. So before each choice, every feature's and kind's best entry is moved off the grid by
//! the same pattern search on `ΔL` alone ([`Search::climb`]: no refit, one column and a few dot
//! products a move), and the best four moved terms are refitted beside the grid's best four
//! ([`Search::shortlist`]). Measured on 20 seeds of each case (`SEED_BASE=5000`, development),
//! fit over the least-squares limit, mean, before → after: two groups 1.46 → 1.03, knee 1.05 →
//! 1.00, the others unchanged (supply 1.01, lagged input 0.99, step 1.00); rows within the
//! issue's target 25 → 35 of 45, the worst row 3.36 → 1.24 of its limit. Tried beside it and not
//! kept, since neither moved a figure once the moved terms were refitted: scoring the grid
//! under white noise as well as under the model's `ρ`, and an exchange pass that takes each
//! chosen term out in turn and searches its replacement.
//!
//! **Seen once.** A Gaussian whose support (where it is at least half its peak) the run visited
//! in one stretch of time — the hold at the hottest temperature, a gradient only the fastest ramp
//! reached — is left out of the dictionary. Within one visit a bump in that feature cannot be told
//! from the noise's own drift over the visit (bias instability moves a two-hour hold's mean), and
//! the evidence, which models the drift as AR(1) with a correlation shorter than the run's sweep,
//! credits the bump with the hold's whole offset. A step is exempt: its two sides are compared
//! with each other, and a drift that jumps just when the run crosses one value is not what bias
//! instability does. The powers are global and exempt too.
//!
//! **Three paths.** Greedy forward selection commits to its first choices: a wide step that takes
//! most of a smooth curve at once can shut out the Gaussians that would follow it better, and
//! the other way round. So the search runs three times, with the Gaussians, the steps and ramps
//! (the terms that change level and hold it), and all of them (each with the powers), in
//! parallel, and the evidence (with its Occam factors) picks among their ends.
//!
//! # Serial correlation
//! Bin means of a residual drift (bias instability, a thermometer's lag): a hold of an hour is 30
//! bins that share one offset, and evidence that treats them as independent credits a narrow
//! Gaussian at the hold's temperature with explaining all 30. Every model here is judged under
//! AR(1) noise: targets and basis functions whitened (Prais–Winsten), with `ρ` a hyperparameter
//! like α and β — the one of [`crate::ar1::RHO_GRID`] with the highest evidence, `ln p(y) = ln p(y′) +
//! ½ ln(1 − ρ²)` (the whitening's Jacobian), for each model. `ρ` is bounded by the run itself
//! ([`Search::rho_max`]): noise correlated for longer than the run takes to sweep its temperature
//! range at its fastest rate moves like the thermal effect, and one run cannot tell them apart.
//! Since the correlation is modelled, the margin is not grown by it as the joint search's is.
//! A record with gaps is whitened one stretch at a time ([`crate::ar1`]): the noise after a gap
//! does not continue the noise before it.
//!
//! Every term is averaged over each bin's parts ([`crate::rows::SUB_BINS`]) as the target is
//! averaged over the bin: a 120 s bin on a 3 °C/min ramp spans 6 °C, and a Gaussian of the bin's
//! mean temperature is not the bin's mean of the Gaussian.
//!
//! The result competes with the pick of [`super::search`] (linear, cubic or joint Gaussians),
//! refitted under the same AR(1) noise model, in `Search::choose`: it replaces the pick when its
//! evidence (with the refinements' Occam factors) is higher by the joint search's Occam margin (a
//! structure change needs strong evidence).

use super::search::Search;
use super::{Fitted, to_target_units};
use crate::ar1::{fit_best_rho, whiten, whitened};
use crate::rbf64::{KIND_CUBE, KIND_GAUSSIAN, KIND_RAMP, KIND_SQUARE, KIND_STEP, Rbf64};
use nalgebra::{DMatrix, DVector};
use rayon::prelude::*;

/// Most positions per feature in the dictionary.
const MAX_POSITIONS: usize = 24;
/// σ of a candidate Gaussian (and a step's width), in multiples of the narrowest the data resolve.
const WIDTHS: [f64; 5] = [1.0, 2.0, 4.0, 8.0, 16.0];
/// The most Gaussians an additive model gets: the reference firmware's capacity.
pub(super) const MAX_GAUSSIANS: usize = tcomp_core::FLIGHT_CENTERS;
/// Candidates refitted per step, the best by `ΔL`.
const REFITTED: usize = 4;
/// Halvings of the position's move in [`Search::refine_atom`].
const REFINE_HALVINGS: usize = 4;
/// Passes of [`Search::refine_atom`]'s moves.
const REFINE_PASSES: usize = 2;
/// α above which a Gaussian counts as switched off and is removed.
const SWITCHED_OFF: f64 = 1e10;

/// One candidate Gaussian over one feature.
#[derive(Clone, Debug)]
pub(super) struct Atom {
    /// The features, ascending.
    pub(super) feats: Vec<usize>,
    /// Center over `feats`, standardised units.
    pub(super) center: Vec<f64>,
    /// σ of a Gaussian; a step's width `s` (it is `S((z − c)/s)`), a ramp's half-width (it is
    /// `clamp((z − c)/s, −1, 1)`), a power's scale (it is `((z − c)/s)^n`); standardised units.
    pub(super) sigma: f64,
    /// [`KIND_GAUSSIAN`], [`KIND_STEP`], [`KIND_RAMP`], [`KIND_SQUARE`] or [`KIND_CUBE`].
    pub(super) kind: u8,
    /// The narrowest `sigma` the refinement may reach ([`Search::refine_atom`]): the data's
    /// resolution for a Gaussian, a 64th of it for a step (a step sharper than the data resolve
    /// still has a level on each side that they pin).
    pub(super) floor: f64,
    /// Moved off the grid by [`Search::refine_atom`]: two continuous parameters fitted, whose
    /// Occam factor [`Search::occam`] charges.
    pub(super) refined: bool,
    /// What choosing it among the dictionary's entries cost, nats (see "Which of M" in the
    /// module doc); zero for the terms every search starts with.
    pub(super) charge: f64,
}

/// An additive model and its evidence fit (weights laid out `[1 | linear | atoms…]`).
#[derive(Clone)]
pub(super) struct Additive {
    pub(super) atoms: Vec<Atom>,
    pub(super) fit: Fitted,
    /// α per column.
    alpha: Vec<f64>,
    /// Linear columns (one per feature with the linear term, else none).
    nl: usize,
    /// The noise's AR(1) coefficient the evidence chose.
    pub(super) rho: f64,
}

impl Additive {
    fn ev(&self) -> f64 {
        self.fit.ev.log_evidence
    }
}

impl Search<'_> {
    /// The log evidence of design `phi` with prior `groups` (one α per group, group 0 flat) under
    /// AR(1) noise whose coefficient the evidence chooses, and that coefficient.
    pub(super) fn evidence_ar1(&self, phi: &DMatrix<f64>, groups: &[usize]) -> Option<(f64, f64)> {
        let ng = groups.iter().max().copied().unwrap_or(0) + 1;
        let mut start = vec![1.0; ng];
        start[0] = 1e-8;
        fit_best_rho(
            phi,
            &self.yn,
            groups,
            (&start, 10.0),
            self.rho_max(),
            &self.opts.stretches,
        )
        .map(|(_, e, r)| (e, r))
    }

    /// The most serial correlation the noise may claim: a noise correlated for longer than the run
    /// takes to sweep its first feature's range at its fastest (range / largest step between
    /// consecutive bins, in bins) changes as slowly as the temperature itself, and one run cannot
    /// tell it from a thermal effect; so `ρ ≤ e^(−1/τ)` for that τ in bins. A run that sweeps
    /// 80 °C at most 6 °C a bin gets τ ≈ 13 bins, `ρ ≤ 0.93`.
    pub(super) fn rho_max(&self) -> f64 {
        if self.xmat.ncols() == 0 {
            return 0.0;
        }
        let (lo, hi) = self.range(0);
        let col = self.xmat.column(0);
        let step = col
            .iter()
            .zip(col.iter().skip(1))
            .map(|(a, b)| (b - a).abs())
            .fold(0.0, f64::max);
        if step <= 0.0 || hi <= lo {
            return 0.0;
        }
        (-step / (hi - lo)).exp()
    }

    /// How finely the binned data resolve feature `k` (standardised units): how far its part means
    /// spread within one bin, averaged over the feature's range as the run traversed it — each
    /// bin weighted by its own spread, `Σ s² / Σ s` — so a value of the feature the run crossed
    /// in a 6 °C bin counts as resolved to 6 °C however long the holds were. Without parts, the
    /// same of the steps between consecutive bins.
    fn resolution(&self, k: usize) -> f64 {
        let spans: Vec<f64> = match &self.sub {
            Some(sub) => sub
                .iter()
                .map(|parts| {
                    let (lo, hi) = parts
                        .iter()
                        .filter_map(|p| p.get(k))
                        .fold((f64::MAX, f64::MIN), |(l, h), v| (l.min(*v), h.max(*v)));
                    (hi - lo).max(0.0)
                })
                .collect(),
            None => {
                let col = self.xmat.column(k);
                col.iter()
                    .zip(col.iter().skip(1))
                    .map(|(a, b)| (b - a).abs())
                    .collect()
            }
        };
        let (s1, s2) = spans
            .iter()
            .fold((0.0, 0.0), |(a, b), s| (a + s, b + s * s));
        if s1 > 0.0 { s2 / s1 } else { 0.0 }
    }

    /// The candidate Gaussians of the module doc.
    fn dictionary(&self) -> Vec<Atom> {
        let d = self.xmat.ncols();
        let mut atoms = Vec::new();
        for k in (0..d).filter(|&k| self.pin(k) != crate::pin::Pin::Linear) {
            let (lo, hi) = self.range(k);
            let range = hi - lo;
            if range <= 1e-9 {
                continue;
            }
            // The narrowest Gaussian: half what one bin spans where the feature moves (its full
            // width at half height is then about one bin's span), and never below range / 48.
            let narrowest = (0.5 * self.resolution(k)).max(range / (2.0 * MAX_POSITIONS as f64));
            let positions = ((range / narrowest).ceil() as usize).clamp(4, MAX_POSITIONS);
            let spacing = range / positions as f64;
            // The feature's square and cube about its mean: its low-order polynomial.
            for kind in [KIND_SQUARE, KIND_CUBE] {
                atoms.push(Atom {
                    feats: vec![k],
                    center: vec![0.0],
                    sigma: 1.0,
                    kind,
                    floor: 1.0,
                    refined: false,
                    charge: 0.0,
                });
            }
            for kind in [KIND_GAUSSIAN, KIND_STEP, KIND_RAMP] {
                for w in WIDTHS {
                    let sigma = w * narrowest;
                    if sigma > range {
                        break;
                    }
                    for i in 0..positions {
                        let center = lo + (i as f64 + 0.5) * spacing;
                        // A ramp's corners inside the range, its levels over half of it.
                        if kind == KIND_RAMP && !ramp_fits(center, sigma, lo, hi) {
                            continue;
                        }
                        atoms.push(Atom {
                            feats: vec![k],
                            center: vec![center],
                            sigma,
                            kind,
                            floor: if kind == KIND_GAUSSIAN {
                                narrowest
                            } else {
                                narrowest / 64.0
                            },
                            refined: false,
                            charge: 0.0,
                        });
                    }
                }
            }
        }
        atoms
    }

    /// An atom's column: its Gaussian, step or power averaged over each bin's parts (or at the
    /// bin's mean).
    fn column(&self, a: &Atom) -> DVector<f64> {
        let h = 0.5 / (a.sigma * a.sigma);
        let g = |row: &dyn Fn(usize) -> f64| {
            if a.kind != KIND_GAUSSIAN {
                let u: f64 = a
                    .feats
                    .iter()
                    .zip(&a.center)
                    .map(|(&k, c)| row(k) - c)
                    .sum();
                let u = u / a.sigma;
                return match a.kind {
                    KIND_STEP => crate::rbf64::logistic(u),
                    KIND_RAMP => crate::rbf64::ramp(u),
                    KIND_SQUARE => u * u,
                    _ => u * u * u,
                };
            }
            let mut d2 = 0.0;
            for (&k, c) in a.feats.iter().zip(&a.center) {
                let v = row(k) - c;
                d2 += v * v;
            }
            (-h * d2).exp()
        };
        let n = self.xmat.nrows();
        match &self.sub {
            Some(sub) => DVector::from_fn(n, |i, _| {
                let parts = &sub[i];
                let s: f64 = parts
                    .iter()
                    .map(|p| g(&|k| p.get(k).copied().unwrap_or(0.0)))
                    .sum();
                s / parts.len().max(1) as f64
            }),
            None => DVector::from_fn(n, |i, _| g(&|k| self.xmat[(i, k)])),
        }
    }

    /// The design `[1 | lin | atoms]` from precomputed atom columns, and its prior groups: the
    /// bias (group 0, flat), one per feature's linear weight, one per Gaussian.
    fn atoms_design(
        &self,
        lin: &DMatrix<f64>,
        cols: &[&DVector<f64>],
    ) -> (DMatrix<f64>, Vec<usize>) {
        let (n, nl) = (lin.nrows(), lin.ncols());
        let m = 1 + nl + cols.len();
        let mut phi = DMatrix::zeros(n, m);
        phi.column_mut(0).fill(1.0);
        phi.columns_mut(1, nl).copy_from(lin);
        for (j, c) in cols.iter().enumerate() {
            phi.column_mut(1 + nl + j).copy_from(c);
        }
        (phi, (0..m).collect())
    }

    fn fit_atoms(
        &self,
        lin: &DMatrix<f64>,
        atoms: Vec<Atom>,
        cols: &[&DVector<f64>],
        start: Option<(&[f64], f64)>,
    ) -> Option<Additive> {
        let (phi, groups) = self.atoms_design(lin, cols);
        let nl = lin.ncols();
        let ng = groups.iter().max().copied().unwrap_or(0) + 1;
        let mut a0 = vec![1.0; ng];
        let mut b0 = 10.0;
        // `start` holds α per column: each group starts from its first column's.
        if let Some((a, b)) = start {
            for (i, &g) in groups.iter().enumerate().rev() {
                if let (Some(x), Some(v)) = (a0.get_mut(g), a.get(i)) {
                    *x = *v;
                }
            }
            b0 = b;
        }
        a0[0] = 1e-8;
        let (f, log_evidence, rho) = fit_best_rho(
            &phi,
            &self.yn,
            &groups,
            (&a0, b0),
            self.rho_max(),
            &self.opts.stretches,
        )?;
        // α per column.
        let col_alpha: Vec<f64> = groups
            .iter()
            .map(|&g| f.alpha.get(g).copied().unwrap_or(1.0))
            .collect();
        let gauss_alpha: Vec<f64> = col_alpha.iter().skip(1 + nl).copied().collect();
        Some(Additive {
            atoms,
            fit: Fitted {
                w: f.w.iter().copied().collect(),
                ev: super::Evidence {
                    alpha: geometric_mean(&gauss_alpha),
                    alpha_linear: geometric_mean(col_alpha.get(1..1 + nl).unwrap_or(&[])),
                    beta: f.beta,
                    gamma: f.gamma,
                    log_evidence,
                    iterations: f.iterations,
                },
            },
            alpha: col_alpha,
            nl,
            rho,
        })
    }

    /// Tipping and Faul's `ΔL` of adding a column to the model `cur` (whose columns are
    /// `cur_cols`), the noise whitened at the model's `ρ`: the model's design factored once, then
    /// any number of columns scored ([`Gain::of`], [`Gain::all`]).
    fn gain(
        &self,
        lin: &DMatrix<f64>,
        cur: &Additive,
        cur_cols: &[&DVector<f64>],
    ) -> Option<Gain<'_>> {
        let rho = cur.rho;
        let (phi, _) = self.atoms_design(lin, cur_cols);
        let phi = whitened(&phi, rho, &self.opts.stretches);
        let mut yw = self.yn.clone();
        whiten(yw.as_mut_slice(), rho, &self.opts.stretches);
        let beta = cur.fit.ev.beta;
        let mut a = phi.tr_mul(&phi) * beta;
        for (i, al) in cur.alpha.iter().enumerate() {
            a[(i, i)] += al;
        }
        let sigma = a.cholesky()?.inverse();
        let spy = &sigma * phi.tr_mul(&yw);
        Some(Gain {
            phi,
            sigma,
            spy,
            yw,
            beta,
            rho,
            stretches: &self.opts.stretches,
        })
    }

    /// The candidates worth refitting next to the model `cur`, each charged what choosing it
    /// cost ([`choice_charge`] over the dictionary's increments): the best [`REFITTED`]
    /// dictionary entries by `ΔL`, and the best [`REFITTED`] of the terms found by moving each
    /// feature's and kind's best entry off the grid with a pattern search on `ΔL`
    /// ([`Search::climb`]; see "Off the grid" in the module doc).
    fn shortlist(
        &self,
        lin: &DMatrix<f64>,
        cur: &Additive,
        cur_cols: &[&DVector<f64>],
        cand: &DMatrix<f64>,
        (dict, cols): (&[Atom], &[DVector<f64>]),
        taken: &[usize],
    ) -> Vec<Trial> {
        let Some(g) = self.gain(lin, cur, cur_cols) else {
            return Vec::new();
        };
        let gain = g.all(cand);
        let open: Vec<usize> = (0..gain.len())
            .filter(|i| !taken.contains(i) && gain[*i] > 0.0)
            .collect();
        let charge = choice_charge(
            (0..gain.len())
                .filter(|i| !taken.contains(i))
                .map(|i| gain[i]),
        );
        let trial = |origin: usize, atom: &Atom, col: &DVector<f64>| Trial {
            origin,
            atom: Atom {
                charge,
                ..atom.clone()
            },
            col: col.clone(),
        };
        let mut order = open.clone();
        order.sort_by(|a, b| gain[*b].total_cmp(&gain[*a]));
        order.truncate(REFITTED);
        let mut out: Vec<Trial> = order
            .iter()
            .map(|&i| trial(i, &dict[i], &cols[i]))
            .collect();
        // Each feature's and kind's best entry, moved off the grid.
        let mut heads: Vec<usize> = Vec::new();
        for &i in &open {
            if !matches!(dict[i].kind, KIND_GAUSSIAN | KIND_STEP | KIND_RAMP) {
                continue;
            }
            let same = |h: &usize| dict[*h].feats == dict[i].feats && dict[*h].kind == dict[i].kind;
            match heads.iter_mut().find(|h| same(h)) {
                Some(h) if gain[*h] >= gain[i] => {}
                Some(h) => *h = i,
                None => heads.push(i),
            }
        }
        let mut moved: Vec<(Trial, f64)> = heads
            .par_iter()
            .filter_map(|&i| {
                let (atom, col, g1) = self.climb(&g, &dict[i], &cols[i], gain[i])?;
                Some((trial(i, &atom, &col), g1))
            })
            .collect();
        moved.sort_by(|a, b| b.1.total_cmp(&a.1));
        out.extend(moved.into_iter().take(REFITTED).map(|(t, _)| t));
        out
    }

    /// `atom` (column `col`, increment `g0`) moved off the grid by the pattern search of
    /// [`Search::refine_atom`] on the increment `ΔL` alone; `None` when no move raised it.
    fn climb(
        &self,
        g: &Gain<'_>,
        atom: &Atom,
        col: &DVector<f64>,
        g0: f64,
    ) -> Option<(Atom, DVector<f64>, f64)> {
        let k = atom.feats.first().copied()?;
        let (lo, hi) = self.range(k);
        let moves = refine_moves(atom.kind, lo, hi);
        let (mut best, mut best_col, mut best_gain) = (atom.clone(), col.clone(), g0);
        for &mv in moves.iter().cycle().take(REFINE_PASSES * moves.len()) {
            let Some((a, c)) = self.moved(&best, mv, lo, hi) else {
                continue;
            };
            let v = g.of(&c);
            if v > best_gain {
                (best, best_col, best_gain) = (a, c, v);
            }
        }
        best.refined.then_some((best, best_col, best_gain))
    }

    /// Feature `k`'s training range, standardised units.
    fn range(&self, k: usize) -> (f64, f64) {
        self.xmat
            .column(k)
            .iter()
            .fold((f64::MAX, f64::MIN), |(l, h), v| (l.min(*v), h.max(*v)))
    }

    /// `atom` moved by `(position shift, width factor, width shift)` and its column, or `None`
    /// when the move leaves what the dictionary admits (a ramp's corners, see [`ramp_fits`]).
    fn moved(
        &self,
        atom: &Atom,
        (dc, fs, ds): (f64, f64, f64),
        lo: f64,
        hi: f64,
    ) -> Option<(Atom, DVector<f64>)> {
        let mut a = atom.clone();
        if let Some(c) = a.center.first_mut() {
            *c += dc;
        }
        a.sigma = (a.sigma * fs + ds).max(a.floor);
        a.refined = true;
        let column = self.column(&a);
        if a.kind == KIND_RAMP
            && !(levels_held(&column)
                && ramp_fits(a.center.first().copied().unwrap_or(0.0), a.sigma, lo, hi))
        {
            return None;
        }
        Some((a, column))
    }

    /// One step of the search from the model `cur` (atoms `atoms`, columns `acols`): the
    /// [`Search::shortlist`]'s trials refitted with every hyperparameter, the best of them (by
    /// the evidence net of its charges and Occam factors) refined with the evidence
    /// ([`Search::refine_atom`]): the dictionary entry it came from, the new atoms, their columns
    /// and the model.
    #[allow(clippy::too_many_arguments)]
    fn step(
        &self,
        lin: &DMatrix<f64>,
        atoms: &[Atom],
        acols: &[DVector<f64>],
        cur: &Additive,
        cand: &DMatrix<f64>,
        dict: (&[Atom], &[DVector<f64>]),
        taken: &[usize],
        evaluated: &mut usize,
    ) -> Option<Stepped> {
        let cur_cols: Vec<&DVector<f64>> = acols.iter().collect();
        let trials = self.shortlist(lin, cur, &cur_cols, cand, dict, taken);
        *evaluated += trials.len();
        let (t, fit) = trials
            .into_par_iter()
            .filter_map(|t| {
                let mut c = cur_cols.clone();
                c.push(&t.col);
                let mut a0 = cur.alpha.clone();
                a0.push(1.0);
                let mut with = atoms.to_vec();
                with.push(t.atom.clone());
                let f = self.fit_atoms(lin, with, &c, Some((&a0, cur.fit.ev.beta)))?;
                Some((t, f))
            })
            .collect::<Vec<_>>()
            .into_iter()
            .max_by(|a, b| self.occam_within(&a.1).total_cmp(&self.occam_within(&b.1)))?;
        let mut na = atoms.to_vec();
        na.push(t.atom);
        let mut nc = acols.to_vec();
        nc.push(t.col);
        let last = na.len() - 1;
        let fit = self.refine_atom(lin, &mut na, &mut nc, last, fit, evaluated);
        Some((t.origin, na, nc, fit))
    }

    /// The additive search of the module doc; `None` when nothing could be fitted.
    pub(super) fn additive(&self, evaluated: &mut usize) -> Option<Additive> {
        if self.xmat.ncols() == 0 || self.opts.centers.is_some() {
            return None;
        }
        let dict = self.dictionary();
        let cols: Vec<DVector<f64>> = dict.par_iter().map(|a| self.column(a)).collect();
        // A bump the run visited once is no candidate (see "Seen once" in the module doc).
        let (dict, cols): (Vec<Atom>, Vec<DVector<f64>>) = dict
            .into_iter()
            .zip(cols)
            .filter(|(a, c)| match a.kind {
                KIND_GAUSSIAN => visits(c) > 1,
                KIND_RAMP => levels_held(c),
                _ => true,
            })
            .unzip();
        if dict.is_empty() && self.xmat.ncols() == 0 {
            return None;
        }
        let cand = DMatrix::from_columns(&cols);
        let lin = if self.opts.linear {
            self.xmat.clone()
        } else {
            DMatrix::zeros(self.xmat.nrows(), 0)
        };
        // The serial correlation is modelled (AR(1), see the module doc), not compensated by a
        // wider margin: the plain Occam margin. One greedy path per basis (Gaussians, steps, both;
        // see "Three paths" in the module doc), the evidence picks among their ends.
        let paths: Vec<(Option<Additive>, usize)> = [Some(KIND_GAUSSIAN), Some(KIND_STEP), None]
            .par_iter()
            .map(|only| {
                // Each path keeps the powers.
                let keep: Vec<usize> = (0..dict.len())
                    .filter(|&i| {
                        let k = dict[i].kind;
                        // Ramps go with the steps: both change level and hold it.
                        only.is_none_or(|o| {
                            k == o
                                || (o == KIND_STEP && k == KIND_RAMP)
                                || k == KIND_SQUARE
                                || k == KIND_CUBE
                        })
                    })
                    .collect();
                let d: Vec<Atom> = keep.iter().map(|&i| dict[i].clone()).collect();
                let c: Vec<DVector<f64>> = keep.iter().map(|&i| cols[i].clone()).collect();
                let m = if only.is_none() {
                    cand.clone()
                } else {
                    DMatrix::from_columns(&c)
                };
                let mut n = 0;
                // The cubic in the first feature (the temperature, as for the cubic basis) is
                // where every path starts; the other features' powers are candidates.
                let powers: Vec<usize> = (0..d.len())
                    .filter(|&i| matches!(d[i].kind, KIND_SQUARE | KIND_CUBE) && d[i].feats == [0])
                    .collect();
                let a = self.sparse(&d, &c, &m, &lin, &powers, super::PARSIMONY, &mut n);
                (a, n)
            })
            .collect();
        *evaluated += paths.iter().map(|(_, n)| n).sum::<usize>();
        paths
            .into_iter()
            .filter_map(|(a, _)| a)
            .max_by(|a, b| self.occam_within(a).total_cmp(&self.occam_within(b)))
    }

    /// The sparse Bayesian search of the module doc from the linear columns `lin`, over the
    /// dictionary `dict` whose columns are `cols` (`cand` as one matrix).
    #[allow(clippy::too_many_arguments)]
    fn sparse(
        &self,
        dict: &[Atom],
        cols: &[DVector<f64>],
        cand: &DMatrix<f64>,
        lin: &DMatrix<f64>,
        start: &[usize],
        margin: f64,
        evaluated: &mut usize,
    ) -> Option<Additive> {
        let n = self.xmat.nrows();
        // The model's atoms and their columns (refined off the dictionary's grid), and the
        // dictionary entries already taken: first those of `start`.
        let mut atoms: Vec<Atom> = start.iter().map(|&i| dict[i].clone()).collect();
        let mut acols: Vec<DVector<f64>> = start.iter().map(|&i| cols[i].clone()).collect();
        let mut taken: Vec<usize> = start.to_vec();
        let c: Vec<&DVector<f64>> = acols.iter().collect();
        let mut best = self.fit_atoms(lin, atoms.clone(), &c, None)?;
        *evaluated += 1;
        best = self.drop_switched_off(lin, &mut atoms, &mut acols, best, evaluated)?;
        let cap = MAX_GAUSSIANS.min(n / 3);
        while atoms.len() < cap {
            let Some((i, na, nc, next)) = self.step(
                lin,
                &atoms,
                &acols,
                &best,
                cand,
                (dict, cols),
                &taken,
                evaluated,
            ) else {
                break;
            };
            if self.occam_within(&next) < self.occam_within(&best) + margin {
                break;
            }
            taken.push(i);
            (atoms, acols) = (na, nc);
            // Remove what a later refit switched off.
            best = self.drop_switched_off(lin, &mut atoms, &mut acols, next, evaluated)?;
        }
        Some(best)
    }

    /// The model without the atoms its last refit switched off (α ≥ [`SWITCHED_OFF`]), refitted.
    fn drop_switched_off(
        &self,
        lin: &DMatrix<f64>,
        atoms: &mut Vec<Atom>,
        acols: &mut Vec<DVector<f64>>,
        best: Additive,
        evaluated: &mut usize,
    ) -> Option<Additive> {
        let nl = lin.ncols();
        let off: Vec<usize> = (0..atoms.len())
            .filter(|&j| {
                best.alpha
                    .get(1 + nl + j)
                    .is_some_and(|a| *a >= SWITCHED_OFF)
            })
            .collect();
        if off.is_empty() {
            return Some(best);
        }
        let keep: Vec<usize> = (0..atoms.len()).filter(|j| !off.contains(j)).collect();
        *atoms = keep.iter().map(|&j| atoms[j].clone()).collect();
        *acols = keep.iter().map(|&j| acols[j].clone()).collect();
        let c: Vec<&DVector<f64>> = acols.iter().collect();
        let mut a0: Vec<f64> = best.alpha.iter().take(1 + nl).copied().collect();
        a0.extend(keep.iter().map(|&j| best.alpha[1 + nl + j]));
        *evaluated += 1;
        self.fit_atoms(lin, atoms.clone(), &c, Some((&a0, best.fit.ev.beta)))
    }

    /// Atom `j`'s position and width moved off the dictionary's grid by a pattern search on the
    /// evidence (every hyperparameter refitted at each trial): the position by half the grid's
    /// spacing, halved [`REFINE_HALVINGS`] times, the width by factors of `2^(±1/2)`, then `2^(±1/4)`;
    /// a ramp's corners also one at a time, by the position's steps (a ramp whose one corner sits
    /// right and the other not cannot move the wrong one alone by a shift and a scaling: measured
    /// on `SEEDS=20 SEED_BASE=5000` of `tests/additive_fits.rs`, two groups 1.28 → 1.26 of the
    /// limit, rows within the target 26 → 28 of 45).
    /// A move is kept only when it raises the evidence. Why: a step or a narrow Gaussian one
    /// grid spacing (a 120th of the range) off a sharp feature leaves a residual the size of the
    /// feature's whole height over that spacing, on every run that dwells there.
    fn refine_atom(
        &self,
        lin: &DMatrix<f64>,
        atoms: &mut [Atom],
        acols: &mut [DVector<f64>],
        j: usize,
        mut best: Additive,
        evaluated: &mut usize,
    ) -> Additive {
        let Some(k) = atoms[j].feats.first().copied() else {
            return best;
        };
        if !matches!(atoms[j].kind, KIND_GAUSSIAN | KIND_STEP | KIND_RAMP) {
            return best;
        }
        let (lo, hi) = self.range(k);
        let moves = refine_moves(atoms[j].kind, lo, hi);
        let (grid, grid_col, grid_fit) = (atoms[j].clone(), acols[j].clone(), best.clone());
        for &mv in moves.iter().cycle().take(REFINE_PASSES * moves.len()) {
            let Some((atom, column)) = self.moved(&atoms[j], mv, lo, hi) else {
                continue;
            };
            let mut c: Vec<&DVector<f64>> = acols.iter().collect();
            c[j] = &column;
            let mut with = atoms.to_vec();
            with[j] = atom.clone();
            *evaluated += 1;
            let a0 = best.alpha.clone();
            if let Some(f) = self.fit_atoms(lin, with, &c, Some((&a0, best.fit.ev.beta)))
                && f.ev() > best.ev()
            {
                atoms[j] = atom;
                acols[j] = column;
                best = f;
            }
        }
        // The refined atom stays only if it pays for its two fitted parameters.
        if self.occam_within(&best) <= self.occam_within(&grid_fit) {
            atoms[j] = grid;
            acols[j] = grid_col;
            return grid_fit;
        }
        best
    }

    /// The log evidence of `a` with the Occam factor of its refined atoms' parameters: each
    /// position or width fitted off the grid costs `½ ln N` (`N` bins; the Laplace approximation's
    /// Occam factor for a parameter the data pin to `1/√N` of its prior range, as in BIC); and
    /// each term the search chose costs what choosing it among the dictionary's entries cost
    /// (see "Which of M" in the module doc). What the additive searches compare among themselves.
    pub(super) fn occam_within(&self, a: &Additive) -> f64 {
        self.occam(a) - a.atoms.iter().map(|t| t.charge).sum::<f64>()
    }

    /// [`Self::occam_within`] without the choice among the dictionary's terms: what the additive
    /// model is compared with the joint search's pick by. The joint search chooses its size, its
    /// widths and its centers from the data too and is charged nothing for that; charging the
    /// additive model alone would tilt the choice by construction (measured on `SEEDS=20
    /// SEED_BASE=5000` of `tests/additive_fits.rs` with a charge of `ln M` per term, charged
    /// here too: the two-groups case went to the joint model on more seeds, 1.75× its limit on
    /// average against 1.41×).
    pub(super) fn occam(&self, a: &Additive) -> f64 {
        let refined = a.atoms.iter().filter(|t| t.refined).count() as f64;
        a.ev() - refined * (self.n().max(1) as f64).ln()
    }

    /// An additive model as an [`Rbf64`] in the target's units: per-feature scale `unit`
    /// (standardised units), each center over its atom's features (zeros elsewhere) with its mask.
    pub(super) fn additive_fit(&self, a: &Additive) -> (Rbf64, super::Evidence) {
        let d = self.xmat.ncols();
        let ys = self.ys;
        let (b0, lin, wg) = super::split_weights(&a.fit.w, a.nl);
        let mut centers = Vec::new();
        let mut gamma = Vec::new();
        let mut masks = Vec::new();
        for atom in &a.atoms {
            let mut full = vec![0.0; d];
            for (&k, v) in atom.feats.iter().zip(&atom.center) {
                full[k] = *v;
            }
            centers.push(full);
            gamma.push(if atom.kind == KIND_GAUSSIAN {
                0.5 / (atom.sigma * atom.sigma)
            } else {
                1.0 / atom.sigma
            });
            masks.push(atom.feats.iter().fold(0u8, |m, &k| m | (1 << k)));
        }
        // Kinds only when there is another than a Gaussian: a model of Gaussians keeps format 3.
        let kinds = if a.atoms.iter().any(|t| t.kind != KIND_GAUSSIAN) {
            a.atoms.iter().map(|t| t.kind).collect()
        } else {
            Vec::new()
        };
        let rbf = Rbf64 {
            offset: self.xm.clone(),
            scale: self.unit.clone(),
            centers,
            gamma,
            weights: wg.iter().map(|w| w * ys).collect(),
            linear: if self.opts.linear {
                lin.iter().map(|w| w * ys).collect()
            } else {
                vec![0.0; d]
            },
            bias: self.ym + ys * b0,
            masks,
            kinds,
        };
        (rbf, to_target_units(a.fit.ev.clone(), ys, self.n()))
    }

    /// An additive model in words over the feature names.
    pub(super) fn describe(&self, a: &Additive) -> String {
        let d = a.nl;
        let name = |k: usize| self.feature_name(k);
        let mut groups: Vec<(Vec<usize>, u8, Vec<f64>)> = Vec::new();
        for atom in &a.atoms {
            match groups
                .iter_mut()
                .find(|(f, st, _)| *f == atom.feats && *st == atom.kind)
            {
                Some((_, _, s)) => s.push(atom.sigma),
                None => groups.push((atom.feats.clone(), atom.kind, vec![atom.sigma])),
            }
        }
        let mut parts: Vec<String> = groups
            .iter()
            .map(|(f, kind, s)| {
                let names: Vec<String> = f.iter().map(|&k| name(k)).collect();
                let (lo, hi) = s
                    .iter()
                    .fold((f64::MAX, f64::MIN), |(l, h), v| (l.min(*v), h.max(*v)));
                let (what, symbol) = match *kind {
                    KIND_STEP => ("steps", "width"),
                    KIND_RAMP => ("ramps", "half-width"),
                    KIND_SQUARE => return format!("square of ({})", names.join(", ")),
                    KIND_CUBE => return format!("cube of ({})", names.join(", ")),
                    _ => ("Gaussians", "σ"),
                };
                let width = if (hi - lo).abs() < 1e-12 {
                    format!("{symbol} {lo:.2}")
                } else {
                    format!("{symbol} {lo:.2}–{hi:.2}")
                };
                format!("{} {what} over ({}), {width}", s.len(), names.join(", "))
            })
            .collect();
        if self.opts.linear {
            // Linear features the evidence kept (α not switched off).
            let on: Vec<String> = (0..d)
                .filter(|&k| a.alpha.get(1 + k).is_some_and(|al| *al < SWITCHED_OFF))
                .map(name)
                .collect();
            let off: Vec<String> = (0..d)
                .filter(|&k| a.alpha.get(1 + k).is_some_and(|al| *al >= SWITCHED_OFF))
                .filter(|&k| !groups.iter().any(|(f, _, _)| f.contains(&k)))
                .map(name)
                .collect();
            if !on.is_empty() {
                parts.push(format!("linear in ({})", on.join(", ")));
            }
            if !off.is_empty() {
                parts.push(format!("no effect of ({})", off.join(", ")));
            }
        }
        format!("additive: {}", parts.join(" + "))
    }

    /// Whether an additive model has any Gaussian.
    pub(super) fn has_atoms(a: &Additive) -> bool {
        !a.atoms.is_empty()
    }
}

/// The moves of the pattern searches ([`Search::refine_atom`], [`Search::climb`]) over a feature
/// whose range is `[lo, hi]`, as (position shift, width factor, width shift): the position by half
/// the grid's spacing, halved [`REFINE_HALVINGS`] times; a ramp's corners one at a time by the
/// same steps; the width by factors of `2^(±1)`, `2^(±1/2)`, `2^(±1/4)`.
fn refine_moves(kind: u8, lo: f64, hi: f64) -> Vec<(f64, f64, f64)> {
    let mut delta = (hi - lo) / (2.0 * MAX_POSITIONS as f64);
    let mut moves: Vec<(f64, f64, f64)> = Vec::new();
    for _ in 0..REFINE_HALVINGS {
        moves.push((delta, 1.0, 0.0));
        moves.push((-delta, 1.0, 0.0));
        if kind == KIND_RAMP {
            // One corner at a time (the upper, then the lower), the other held.
            for d in [delta, -delta] {
                moves.push((0.5 * d, 1.0, 0.5 * d));
                moves.push((0.5 * d, 1.0, -0.5 * d));
            }
        }
        delta *= 0.5;
    }
    for f in [2.0, 2f64.sqrt(), 2f64.powf(0.25)] {
        moves.push((0.0, f, 0.0));
        moves.push((0.0, 1.0 / f, 0.0));
    }
    moves
}

/// What one step of the search ([`Search::step`]) gives: the dictionary entry its new term came
/// from, the model's atoms and their columns with it, and the model.
type Stepped = (usize, Vec<Atom>, Vec<DVector<f64>>, Additive);

/// A candidate term for one step of the search: the dictionary entry it came from (`origin`),
/// the term (on the grid, or moved off it by [`Search::climb`]) with its charge, and its column.
struct Trial {
    origin: usize,
    atom: Atom,
    col: DVector<f64>,
}

/// A model's design factored for Tipping and Faul's `ΔL` of one more column
/// ([`Search::gain`]): whitened design `Φ`, posterior covariance `Σ`, `ΣΦᵀy`, whitened targets,
/// the noise precision, the `ρ` they are whitened at and where the record's stretches start
/// ([`crate::ar1`]).
struct Gain<'s> {
    phi: DMatrix<f64>,
    sigma: DMatrix<f64>,
    spy: DVector<f64>,
    yw: DVector<f64>,
    beta: f64,
    rho: f64,
    stretches: &'s [usize],
}

impl Gain<'_> {
    /// `ΔL` of each column of `cand`.
    fn all(&self, cand: &DMatrix<f64>) -> Vec<f64> {
        let cand = whitened(cand, self.rho, self.stretches);
        let ptc = self.phi.tr_mul(&cand);
        let sp = &self.sigma * &ptc;
        let cty = cand.tr_mul(&self.yw);
        (0..cand.ncols())
            .map(|j| {
                let c = cand.column(j);
                self.increment(
                    c.dot(&c),
                    ptc.column(j).dot(&sp.column(j)),
                    cty[j],
                    ptc.column(j).dot(&self.spy),
                )
            })
            .collect()
    }

    /// `ΔL` of one column.
    fn of(&self, col: &DVector<f64>) -> f64 {
        let mut c = col.clone();
        whiten(c.as_mut_slice(), self.rho, self.stretches);
        let ptc = self.phi.tr_mul(&c);
        let sp = &self.sigma * &ptc;
        self.increment(c.dot(&c), ptc.dot(&sp), c.dot(&self.yw), ptc.dot(&self.spy))
    }

    /// Tipping and Faul's `ΔL = ½[(Q² − S)/S + ln(S/Q²)]` for `Q² > S`, else 0, from `cᵀc`,
    /// `cᵀΦΣΦᵀc`, `cᵀy` and `cᵀΦΣΦᵀy`.
    fn increment(&self, cc: f64, cpspc: f64, cy: f64, cpspy: f64) -> f64 {
        let b = self.beta;
        let s = (b * cc - b * b * cpspc).max(1e-300);
        let q = b * cy - b * b * cpspy;
        let q2 = q * q;
        if q2 > s {
            0.5 * ((q2 - s) / s + (s / q2).ln())
        } else {
            0.0
        }
    }
}

/// How many separate times the run visited where `col` is at least half its largest value: the
/// runs of consecutive bins in that set (bins are in time order; a gap in the record splits no
/// run, which errs towards more visits, never fewer).
fn visits(col: &DVector<f64>) -> usize {
    let top = col.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let on: Vec<bool> = col
        .iter()
        .map(|v| v.abs() >= 0.5 * top && top > 0.0)
        .collect();
    on.iter()
        .enumerate()
        .filter(|(i, o)| **o && (*i == 0 || !on[*i - 1]))
        .count()
}

/// Whether a ramp at `center` with half-width `s` has both corners inside `[lo, hi]` and rises
/// over at most half of it. Why: a ramp whose level beyond one corner the run barely reached is a
/// hinge inside the range, and beyond the range it holds flat where the data only showed a slope;
/// measured on `SEEDS=20` of `tests/additive_fits.rs`' two groups, a ramp 1.5 wide (with one
/// corner outside at `SEED_BASE=7000`, both inside but a level of one bin at `5000`) took a
/// gradient's linear trend and reached 8× the floor, the limit 1.02×.
fn ramp_fits(center: f64, s: f64, lo: f64, hi: f64) -> bool {
    center - s > lo && center + s < hi && 4.0 * s <= hi - lo
}

/// Whether a ramp's column holds each of its two levels in some bin whole: the run went beyond
/// both corners (see [`ramp_fits`]).
fn levels_held(col: &DVector<f64>) -> bool {
    let held = |level: f64| col.iter().any(|v| v * level >= 1.0 - 1e-9);
    held(1.0) && held(-1.0)
}

/// What choosing one of the candidates whose evidence increments are `gains` costs, nats:
/// `ln M − ln Σᵢ e^(ΔLᵢ − ΔL_max)`, the best candidate's increment less the increment averaged
/// over all `M` (the evidence of "one more term, which one unknown" under a uniform prior over
/// them). Between 0 (every candidate as good) and `ln M` (one stands out alone).
fn choice_charge(gains: impl Iterator<Item = f64>) -> f64 {
    let g: Vec<f64> = gains.map(|v| v.max(0.0)).collect();
    let top = g.iter().copied().fold(0.0, f64::max);
    let sum: f64 = g.iter().map(|v| (v - top).exp()).sum();
    if g.is_empty() || sum.is_nan() || sum <= 0.0 {
        return 0.0;
    }
    (g.len() as f64).ln() - sum.ln()
}

fn geometric_mean(v: &[f64]) -> f64 {
    if v.is_empty() {
        return 0.0;
    }
    (v.iter().map(|x| x.max(1e-300).ln()).sum::<f64>() / v.len() as f64).exp()
}

#[cfg(test)]
#[allow(clippy::expect_used)]
mod tests {
    use super::super::BayesOptions;
    use super::super::search::Search;
    use super::{KIND_RAMP, choice_charge};

    /// Rows of a thermal run: a temperature `T`, a gradient `a` and a second gradient `b` that
    /// follows `a` closely; the target a linear bias in `T` plus a ramp in `a` whose half-width
    /// (1.5) sits between the dictionary's widths, plus a small deterministic jitter.
    fn two_gradients() -> (Vec<Vec<f64>>, Vec<f64>) {
        let n = 360;
        let mut x = Vec::new();
        let mut y = Vec::new();
        for i in 0..n {
            let t = i as f64;
            let temp = 20.0 + 30.0 * (t / 90.0).sin();
            let a = 3.0 + 7.0 * (t / 40.0).sin() * (0.75 + 0.25 * (t / 150.0).cos());
            let b = 0.8 * a + 0.6 * (t / 23.0).sin();
            let jitter = 0.01 * ((t * 12.9898).sin() * 43_758.545).fract();
            x.push(vec![temp, a, b]);
            y.push(0.02 * temp + ((a - 1.0) / 1.5).clamp(-1.0, 1.0) + jitter);
        }
        (x, y)
    }

    #[test]
    fn a_ramp_between_the_grids_widths_is_found_on_its_own_feature_at_its_own_width() {
        let (x, y) = two_gradients();
        let opts = BayesOptions::default();
        let search = Search::new(&x, &y, None, &opts);
        let mut n = 0;
        let a = search.additive(&mut n).expect("an additive model");
        let ramps: Vec<_> = a.atoms.iter().filter(|t| t.kind == KIND_RAMP).collect();
        assert_eq!(ramps.len(), 1, "{:?}", a.atoms);
        let r = ramps[0];
        assert_eq!(
            r.feats,
            vec![1],
            "the ramp is on the gradient that carries it"
        );
        // Back to the gradient's units: half-width 1.5 at 1.
        let half_width = r.sigma / search.unit[1];
        let center = r.center[0] / search.unit[1] + search.xm[1];
        assert!(
            (half_width - 1.5).abs() < 0.1,
            "half-width {half_width} center {center} {:?}",
            a.atoms
        );
        assert!((center - 1.0).abs() < 0.1, "center {center}");
        // Nothing on the other gradient.
        assert!(a.atoms.iter().all(|t| t.feats != vec![2]), "{:?}", a.atoms);
    }

    #[test]
    fn the_climb_moves_the_grids_best_ramp_to_the_true_one_on_the_increment_alone() {
        let (x, y) = two_gradients();
        let opts = BayesOptions::default();
        let search = Search::new(&x, &y, None, &opts);
        let lin = search.xmat.clone();
        let cur = search
            .fit_atoms(&lin, Vec::new(), &[], None)
            .expect("the linear model");
        let g = search.gain(&lin, &cur, &[]).expect("its factors");
        let ramps: Vec<_> = search
            .dictionary()
            .into_iter()
            .filter(|a| a.kind == KIND_RAMP && a.feats == [1])
            .collect();
        let cols: Vec<_> = ramps.iter().map(|a| search.column(a)).collect();
        // One column at a time agrees with all at once.
        let all = g.all(&nalgebra::DMatrix::from_columns(&cols));
        for (c, v) in cols.iter().zip(&all) {
            assert!(
                (g.of(c) - v).abs() <= 1e-9 * v.abs().max(1.0),
                "{} vs {v}",
                g.of(c)
            );
        }
        let (i, g0) = all
            .iter()
            .copied()
            .enumerate()
            .max_by(|a, b| a.1.total_cmp(&b.1))
            .expect("ramps in the dictionary");
        let unit = search.unit[1];
        let grid_width = ramps[i].sigma / unit;
        let (atom, _, g1) = search.climb(&g, &ramps[i], &cols[i], g0).expect("a move");
        assert!(g1 > g0 && atom.refined, "{g1} vs {g0}");
        let (half_width, center) = (atom.sigma / unit, atom.center[0] / unit + search.xm[1]);
        assert!(
            (half_width - 1.5).abs() < 0.15 && (grid_width - 1.5).abs() > 0.15,
            "half-width {half_width} (the grid's {grid_width})"
        );
        assert!((center - 1.0).abs() < 0.15, "center {center}");
    }

    #[test]
    fn a_choice_costs_ln_m_when_one_candidate_stands_alone_and_nothing_when_all_tie() {
        let m = 200usize;
        let alone = choice_charge((0..m).map(|i| if i == 7 { 40.0 } else { 0.0 }));
        assert!((alone - (m as f64).ln()).abs() < 1e-9, "{alone}");
        let tie = choice_charge((0..m).map(|_| 5.0));
        assert!(tie.abs() < 1e-9, "{tie}");
        // Ten neighbours as good as the best: the choice among them is free, the rest is not.
        let ten = choice_charge((0..m).map(|i| if i < 10 { 12.0 } else { 0.0 }));
        assert!((ten - (m as f64 / 10.0).ln()).abs() < 1e-3, "{ten}");
        // Negative or NaN increments count as a candidate the data switch off (ΔL = 0).
        let odd = choice_charge([f64::NAN, -3.0, 0.0, 0.0].into_iter());
        assert!(odd.abs() < 1e-9, "{odd}");
        assert_eq!(choice_charge(std::iter::empty()), 0.0);
    }
}
