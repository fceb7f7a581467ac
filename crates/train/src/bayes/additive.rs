//! Additive structure: the model as a sum of one-feature Gaussians, each weight with its own prior
//! precision, beside a linear term whose every feature has its own prior precision too — built by
//! the evidence on the training run, one basis function at a time.
//!
//! Why: a thermal bias plus a term in a supply voltage is a sum. One RBF over all features puts its
//! Gaussians in the joint space, and a verification run that visits temperature and voltage
//! combinations the training run never had finds them faded to the bias. Gaussians over each
//! feature alone extrapolate each along its own axis (an interaction is the joint model's, and the
//! evidence chooses between the two). An input with no effect gets a prior precision of its own and
//! is switched off instead of diluting the others' prior. And a one-dimensional curve with a knee
//! needs narrow Gaussians at the knee and wide ones, or a polynomial, on the flat parts: Gaussians
//! of one shared width cannot do both, Gaussians placed and sized one by one can.
//!
//! # The search (sparse Bayesian learning, Tipping and Faul 2003)
//! A dictionary of candidate Gaussians over each feature alone: positions evenly spread over its
//! training range, σ of 1, 2, 4, 8 and 16 times the narrowest the binned data resolve (half of what
//! one bin spans where the feature moves, see [`Search::resolution`]). The model starts as the bias
//! and the linear term (one α per feature). Each step scores every candidate by the rise of the
//! log evidence its addition would give with the other hyperparameters held (the closed form of
//! Tipping and Faul: `ΔL = ½[(Q² − S)/S + ln(S/Q²)]` for `Q² > S`), refits the best four with every
//! α and β ([`crate::evidence`]) and the noise model below, and keeps the best if it raises the
//! evidence by the Occam margin [`super::PARSIMONY`]. It stops there, or at 32 Gaussians (the
//! reference firmware's capacity) or one per 3 bins. A Gaussian whose α a later refit drives to
//! infinity is removed.
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
//!
//! Every basis function is averaged over each bin's parts ([`crate::rows::SUB_BINS`]) as the
//! target is averaged over the bin: a 120 s bin on a 3 °C/min ramp spans 6 °C, and a Gaussian of
//! the bin's mean temperature is not the bin's mean of the Gaussian.
//!
//! The result competes with the pick of [`super::search`] (linear, cubic or joint Gaussians),
//! refitted under the same AR(1) noise model, in `Search::choose`: it replaces the pick when its
//! evidence is higher by the joint search's Occam margin (a structure change needs strong evidence).

use super::search::Search;
use super::{Fitted, to_target_units};
use crate::ar1::{fit_best_rho, whiten, whitened};
use crate::rbf64::Rbf64;
use nalgebra::{DMatrix, DVector};
use rayon::prelude::*;

/// Most positions per feature in the dictionary.
const MAX_POSITIONS: usize = 24;
/// σ of a candidate Gaussian, in multiples of the narrowest the data resolve.
const WIDTHS: [f64; 5] = [1.0, 2.0, 4.0, 8.0, 16.0];
/// The most Gaussians an additive model gets: the reference firmware's capacity.
pub(super) const MAX_GAUSSIANS: usize = tcomp_core::FLIGHT_CENTERS;
/// Candidates refitted per step, the best by `ΔL`.
const REFITTED: usize = 4;
/// α above which a Gaussian counts as switched off and is removed.
const SWITCHED_OFF: f64 = 1e10;

/// One candidate Gaussian over one feature.
#[derive(Clone, Debug)]
pub(super) struct Atom {
    /// The features, ascending.
    pub(super) feats: Vec<usize>,
    /// Center over `feats`, standardised units.
    pub(super) center: Vec<f64>,
    /// σ, standardised units.
    pub(super) sigma: f64,
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
        fit_best_rho(phi, &self.yn, groups, (&start, 10.0), self.rho_max()).map(|(_, e, r)| (e, r))
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
        let col = self.xmat.column(0);
        let (lo, hi) = col
            .iter()
            .fold((f64::MAX, f64::MIN), |(l, h), v| (l.min(*v), h.max(*v)));
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
            let col = self.xmat.column(k);
            let (lo, hi) = col
                .iter()
                .fold((f64::MAX, f64::MIN), |(l, h), v| (l.min(*v), h.max(*v)));
            let range = hi - lo;
            if range <= 1e-9 {
                continue;
            }
            // The narrowest Gaussian: half what one bin spans where the feature moves (its full
            // width at half height is then about one bin's span), and never below range / 48.
            let narrowest = (0.5 * self.resolution(k)).max(range / (2.0 * MAX_POSITIONS as f64));
            let positions = ((range / narrowest).ceil() as usize).clamp(4, MAX_POSITIONS);
            let spacing = range / positions as f64;
            for w in WIDTHS {
                let sigma = w * narrowest;
                if sigma > range {
                    break;
                }
                for i in 0..positions {
                    atoms.push(Atom {
                        feats: vec![k],
                        center: vec![lo + (i as f64 + 0.5) * spacing],
                        sigma,
                    });
                }
            }
        }
        atoms
    }

    /// An atom's column: its Gaussian averaged over each bin's parts (or at the bin's mean).
    fn column(&self, a: &Atom) -> DVector<f64> {
        let h = 0.5 / (a.sigma * a.sigma);
        let g = |row: &dyn Fn(usize) -> f64| {
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
        let (f, log_evidence, rho) =
            fit_best_rho(&phi, &self.yn, &groups, (&a0, b0), self.rho_max())?;
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

    /// Tipping and Faul's `ΔL` of adding each candidate column to the current model.
    fn gains(
        &self,
        lin: &DMatrix<f64>,
        cur: &Additive,
        cur_cols: &[&DVector<f64>],
        cand: &DMatrix<f64>,
    ) -> Option<Vec<f64>> {
        let (phi, _) = self.atoms_design(lin, cur_cols);
        let phi = whitened(&phi, cur.rho);
        let cand = &whitened(cand, cur.rho);
        let mut yw = self.yn.clone();
        whiten(yw.as_mut_slice(), cur.rho);
        let beta = cur.fit.ev.beta;
        let mut a = phi.tr_mul(&phi) * beta;
        for (i, al) in cur.alpha.iter().enumerate() {
            a[(i, i)] += al;
        }
        let sigma = a.cholesky()?.inverse();
        let pty = phi.tr_mul(&yw);
        let ptc = phi.tr_mul(cand);
        let sp = &sigma * &ptc;
        let spy = &sigma * &pty;
        let cty = cand.tr_mul(&yw);
        Some(
            (0..cand.ncols())
                .map(|j| {
                    let c = cand.column(j);
                    let s = beta * c.dot(&c) - beta * beta * ptc.column(j).dot(&sp.column(j));
                    let q = beta * cty[j] - beta * beta * ptc.column(j).dot(&spy);
                    let (q2, s) = (q * q, s.max(1e-300));
                    if q2 > s {
                        0.5 * ((q2 - s) / s + (s / q2).ln())
                    } else {
                        0.0
                    }
                })
                .collect(),
        )
    }

    /// The additive search of the module doc; `None` when nothing could be fitted.
    pub(super) fn additive(&self, evaluated: &mut usize) -> Option<Additive> {
        if self.xmat.ncols() == 0 || self.opts.centers.is_some() {
            return None;
        }
        let dict = self.dictionary();
        let cols: Vec<DVector<f64>> = dict.par_iter().map(|a| self.column(a)).collect();
        let cand = DMatrix::from_columns(&cols);
        let lin = if self.opts.linear {
            self.xmat.clone()
        } else {
            DMatrix::zeros(self.xmat.nrows(), 0)
        };
        // The serial correlation is modelled (AR(1), see the module doc), not compensated by a
        // wider margin: the plain Occam margin.
        self.sparse(&dict, &cols, &cand, &lin, super::PARSIMONY, evaluated)
    }

    /// The sparse Bayesian search of the module doc from the linear columns `lin`, over the
    /// dictionary `dict` whose columns are `cols` (`cand` as one matrix).
    fn sparse(
        &self,
        dict: &[Atom],
        cols: &[DVector<f64>],
        cand: &DMatrix<f64>,
        lin: &DMatrix<f64>,
        margin: f64,
        evaluated: &mut usize,
    ) -> Option<Additive> {
        let n = self.xmat.nrows();
        let nl = lin.ncols();
        let mut active: Vec<usize> = Vec::new();
        let mut best = self.fit_atoms(lin, Vec::new(), &[], None)?;
        *evaluated += 1;
        let cap = MAX_GAUSSIANS.min(n / 3);
        while active.len() < cap {
            let cur_cols: Vec<&DVector<f64>> = active.iter().map(|&i| &cols[i]).collect();
            let Some(gain) = self.gains(lin, &best, &cur_cols, cand) else {
                break;
            };
            // The best few by ΔL, each refitted: the refit decides.
            let mut order: Vec<usize> = (0..dict.len()).filter(|i| !active.contains(i)).collect();
            order.sort_by(|a, b| gain[*b].total_cmp(&gain[*a]));
            order.truncate(REFITTED);
            order.retain(|&i| gain[i] > 0.0);
            if order.is_empty() {
                break;
            }
            *evaluated += order.len();
            let start_alpha = best.alpha.clone();
            let beta = best.fit.ev.beta;
            let trials: Vec<Option<(usize, Additive)>> = order
                .par_iter()
                .map(|&i| {
                    let mut idx = active.clone();
                    idx.push(i);
                    let c: Vec<&DVector<f64>> = idx.iter().map(|&j| &cols[j]).collect();
                    let mut a0 = start_alpha.clone();
                    a0.push(1.0);
                    let atoms = idx.iter().map(|&j| dict[j].clone()).collect();
                    self.fit_atoms(lin, atoms, &c, Some((&a0, beta)))
                        .map(|f| (i, f))
                })
                .collect();
            let Some((i, next)) = trials
                .into_iter()
                .flatten()
                .max_by(|a, b| a.1.ev().total_cmp(&b.1.ev()))
            else {
                break;
            };
            if next.ev() < best.ev() + margin {
                break;
            }
            active.push(i);
            best = next;
            // Remove what a later refit switched off.
            let off: Vec<usize> = (0..active.len())
                .filter(|&j| {
                    best.alpha
                        .get(1 + nl + j)
                        .is_some_and(|a| *a >= SWITCHED_OFF)
                })
                .collect();
            if !off.is_empty() {
                let keep: Vec<usize> = (0..active.len()).filter(|j| !off.contains(j)).collect();
                active = keep.iter().map(|&j| active[j]).collect();
                let c: Vec<&DVector<f64>> = active.iter().map(|&j| &cols[j]).collect();
                let mut a0: Vec<f64> = best.alpha.iter().take(1 + nl).copied().collect();
                a0.extend(keep.iter().map(|&j| best.alpha[1 + nl + j]));
                let atoms = active.iter().map(|&j| dict[j].clone()).collect();
                *evaluated += 1;
                best = self.fit_atoms(lin, atoms, &c, Some((&a0, best.fit.ev.beta)))?;
            }
        }
        Some(best)
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
            gamma.push(0.5 / (atom.sigma * atom.sigma));
            masks.push(atom.feats.iter().fold(0u8, |m, &k| m | (1 << k)));
        }
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
        };
        (rbf, to_target_units(a.fit.ev.clone(), ys, self.n()))
    }

    /// An additive model in words over the feature names.
    pub(super) fn describe(&self, a: &Additive) -> String {
        let d = a.nl;
        let name = |k: usize| self.feature_name(k);
        let mut groups: Vec<(Vec<usize>, Vec<f64>)> = Vec::new();
        for atom in &a.atoms {
            match groups.iter_mut().find(|(f, _)| *f == atom.feats) {
                Some((_, s)) => s.push(atom.sigma),
                None => groups.push((atom.feats.clone(), vec![atom.sigma])),
            }
        }
        let mut parts: Vec<String> = groups
            .iter()
            .map(|(f, s)| {
                let names: Vec<String> = f.iter().map(|&k| name(k)).collect();
                let (lo, hi) = s
                    .iter()
                    .fold((f64::MAX, f64::MIN), |(l, h), v| (l.min(*v), h.max(*v)));
                let width = if (hi - lo).abs() < 1e-12 {
                    format!("σ {lo:.2}")
                } else {
                    format!("σ {lo:.2}–{hi:.2}")
                };
                format!("{} Gaussians over ({}), {width}", s.len(), names.join(", "))
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
                .filter(|&k| !groups.iter().any(|(f, _)| f.contains(&k)))
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

fn geometric_mean(v: &[f64]) -> f64 {
    if v.is_empty() {
        return 0.0;
    }
    (v.iter().map(|x| x.max(1e-300).ln()).sum::<f64>() / v.len() as f64).exp()
}
