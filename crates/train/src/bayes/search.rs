//! The evidence search of [`super::fit_offering_cubic`], step by step: a first scan of every
//! number of centers and width, a coordinate search along the length scales and the width, the
//! other numbers of centers at the scales found, and the parsimony rule that picks the simplest
//! model within the Occam margin of the best.
//!
//! Why a struct: every step fits candidates on the same standardised rows and records the best of
//! each number of centers for the parsimony rule; [`Search`] holds both, so each step is a short
//! method instead of one long function of closures.

use super::StructureReport;
use super::additive::Additive;
use super::{
    Basis, BayesFit, BayesOptions, CubicCandidate, FIRST_WIDTHS, Fitted, PARSIMONY, evidence_fit,
    margin_inflation, to_target_units,
};
use crate::kmeans::kmeans;
use crate::pin::Pin;
use crate::rbf64::{Rbf64, mean_std, normalise_rows, split_weights};
use nalgebra::{DMatrix, DVector};
use rayon::prelude::*;
use std::collections::BTreeMap;
use std::sync::{Arc, Mutex};

/// Centers in standardised feature units, shared by the candidates of one scan.
type Centers = Arc<Vec<Vec<f64>>>;

#[derive(Clone)]
pub(super) struct Candidate {
    pub(super) m: usize,
    sigma: f64,
    ls: Vec<f64>,
    /// Centers in standardised feature units (before the length scales).
    centers: Centers,
    pub(super) fit: Fitted,
}

const WIDTHS: [f64; 8] = [0.35, 0.5, 0.7, 1.0, 1.4, 2.0, 2.8, 4.0];
const CENTER_GRID: [usize; 5] = [0, 4, 8, 16, 32];
const LENGTH_SCALES: [f64; 8] = [0.25, 0.5, 1.0, 2.0, 4.0, 8.0, 16.0, 64.0];

/// The design matrix of one candidate, straight from the standardised rows: `[1 | x_std | G]`
/// with `G_ij = exp(−‖(x_i − c_j)/ls‖²/(2σ²))`. The linear columns are the standardised features
/// themselves, whatever the length scales, so their prior does not move with them.
fn candidate_design(
    xstd: &DMatrix<f64>,
    linear: bool,
    ls: &[f64],
    centers: &[Vec<f64>],
    sigma: f64,
) -> DMatrix<f64> {
    let (n, d) = (xstd.nrows(), xstd.ncols());
    let nl = if linear { d } else { 0 };
    let mut phi = DMatrix::zeros(n, 1 + nl + centers.len());
    let half_inv_s2 = 0.5 / (sigma * sigma);
    let w: Vec<f64> = ls.iter().map(|l| half_inv_s2 / (l * l)).collect();
    // Column-major storage: column j is the slice [j·n, (j+1)·n).
    let x = xstd.as_slice();
    let out = phi.as_mut_slice();
    let mut cols = out.chunks_exact_mut(n.max(1));
    if let Some(ones) = cols.next() {
        ones.fill(1.0);
    }
    for (col, xk) in cols.by_ref().take(nl).zip(x.chunks_exact(n.max(1))) {
        col.copy_from_slice(xk);
    }
    for (col, c) in cols.zip(centers) {
        for ((ck, wk), xk) in c.iter().zip(&w).zip(x.chunks_exact(n.max(1))) {
            for (acc, xv) in col.iter_mut().zip(xk) {
                let dv = xv - ck;
                *acc += wk * dv * dv;
            }
        }
        for a in col.iter_mut() {
            *a = (-*a).exp();
        }
    }
    phi
}

/// A local search along one discrete grid, from `current`: both neighbours and, when `far_end`,
/// the last grid value (a length scale of 64 standard deviations switches a feature off for the
/// Gaussians, and the evidence often has a separate optimum there); then onward from the best of
/// those, in the direction that raised the evidence, until it stops rising. This costs 3–5 fits
/// instead of a scan of the whole grid and reaches the same optimum on the evidence surfaces of
/// the test cases (`cargo run --release -p tcomp-train --example search_eval`).
fn walk<E>(
    grid: &[f64],
    current: f64,
    far_end: bool,
    margin: f64,
    best: Candidate,
    eval: E,
    evaluated: &mut usize,
) -> Candidate
where
    E: Fn(f64) -> Option<Candidate> + Sync,
{
    let better = |a: &Candidate, b: &Candidate| a.fit.ev.log_evidence > b.fit.ev.log_evidence;
    let Some(i0) = grid.iter().position(|&v| v == current) else {
        return best;
    };
    let last = grid.len().saturating_sub(1);
    let mut first: Vec<usize> = [i0.checked_sub(1), (i0 < last).then_some(i0 + 1)]
        .into_iter()
        .flatten()
        .collect();
    if far_end && i0 + 1 < last {
        first.push(last);
    }
    *evaluated += first.len();
    let found: Vec<(usize, Option<Candidate>)> = first
        .par_iter()
        .filter_map(|&i| grid.get(i).map(|&v| (i, eval(v))))
        .collect();
    let mut off = (far_end && i0 == last).then(|| best.clone());
    let mut best = best;
    let mut at = i0;
    for (i, c) in found {
        if let Some(c) = c {
            if far_end && i == last {
                off = Some(c.clone());
            }
            if better(&c, &best) {
                best = c;
                at = i;
            }
        }
    }
    // Occam on the feature: it enters the Gaussians only on strong evidence over leaving it to
    // the linear term (the far end switches it off for them).
    let prefer_off = |best: Candidate, off: Option<Candidate>| match off {
        Some(o) if o.fit.ev.log_evidence >= best.fit.ev.log_evidence - margin => o,
        _ => best,
    };
    if at == i0 {
        return prefer_off(best, off);
    }
    // From a neighbour, keep going away from the start; from the far end, come back down.
    let up = at > i0 && at != last || at == i0 + 1;
    let mut tried_next = |next: usize, best: &mut Candidate, at: &mut usize| -> bool {
        let Some(&v) = grid.get(next) else {
            return false;
        };
        if next == i0 || (far_end && next == last) {
            return false;
        }
        *evaluated += 1;
        match eval(v) {
            Some(c) if better(&c, best) => {
                *best = c;
                *at = next;
                true
            }
            _ => false,
        }
    };
    loop {
        let next = if up { at + 1 } else { at.wrapping_sub(1) };
        if !tried_next(next, &mut best, &mut at) {
            break;
        }
    }
    prefer_off(best, off)
}

/// The standardised problem of one evidence search, and the best candidate seen so far for each
/// number of centers (for the parsimony rule).
pub(super) struct Search<'o> {
    pub(super) opts: &'o BayesOptions,
    /// Feature means and inverse standard deviations.
    pub(super) xm: Vec<f64>,
    pub(super) unit: Vec<f64>,
    /// Target mean and standard deviation.
    pub(super) ym: f64,
    pub(super) ys: f64,
    /// Standardised rows, as rows and as a matrix.
    xstd: Vec<Vec<f64>>,
    pub(super) xmat: DMatrix<f64>,
    /// Standardised targets.
    pub(super) yn: DVector<f64>,
    /// Per row, its feature means over the parts of its bin, standardised (see
    /// [`super::additive`]); `None`: the rows are points.
    pub(super) sub: Option<Vec<Vec<Vec<f64>>>>,
    /// Linear columns.
    pub(super) nl: usize,
    best_per_m: Mutex<BTreeMap<usize, Candidate>>,
}

impl<'o> Search<'o> {
    pub(super) fn new(
        x: &[Vec<f64>],
        y: &[f64],
        sub: Option<&[Vec<Vec<f64>>]>,
        opts: &'o BayesOptions,
    ) -> Self {
        let n = x.len();
        let d = x.first().map_or(0, Vec::len);
        let (xm, xs) = mean_std(x);
        let unit: Vec<f64> = xs.iter().map(|s| 1.0 / s.max(1e-300)).collect();
        let xstd = normalise_rows(x, &xm, &unit);
        let ym = y.iter().sum::<f64>() / n.max(1) as f64;
        let ys = (y.iter().map(|v| (v - ym) * (v - ym)).sum::<f64>() / n.max(1) as f64)
            .sqrt()
            .max(1e-300);
        let yn = DVector::from_iterator(n, y.iter().map(|v| (v - ym) / ys));
        let xmat = DMatrix::from_fn(n, d, |i, k| {
            xstd.get(i).and_then(|r| r.get(k)).copied().unwrap_or(0.0)
        });
        let sub = sub.filter(|s| s.len() == n).map(|s| {
            s.iter()
                .map(|parts| normalise_rows(parts, &xm, &unit))
                .collect()
        });
        Self {
            opts,
            sub,
            xm,
            unit,
            ym,
            ys,
            xstd,
            xmat,
            yn,
            nl: if opts.linear { d } else { 0 },
            best_per_m: Mutex::new(BTreeMap::new()),
        }
    }

    /// Feature `k`'s name for the report (`f0`, `f1`… when none were given).
    pub(super) fn feature_name(&self, k: usize) -> String {
        self.opts
            .names
            .get(k)
            .cloned()
            .unwrap_or_else(|| format!("f{k}"))
    }

    /// How feature `k` may enter the Gaussians.
    pub(super) fn pin(&self, k: usize) -> Pin {
        self.opts.pins.get(k).copied().unwrap_or_default()
    }

    /// Unit length scales, but 64 (the far end: off for the joint Gaussians) for a pinned feature.
    fn start_ls(&self) -> Vec<f64> {
        (0..self.d())
            .map(|k| match self.pin(k) {
                Pin::Free => 1.0,
                Pin::Linear | Pin::Additive => LENGTH_SCALES[LENGTH_SCALES.len() - 1],
            })
            .collect()
    }

    pub(super) fn n(&self) -> usize {
        self.xstd.len()
    }

    fn d(&self) -> usize {
        self.xmat.ncols()
    }

    /// The numbers of centers compared: the one asked for, or those the data can carry (3 rows per
    /// center at least).
    pub(super) fn grid(&self) -> Vec<usize> {
        match self.opts.centers {
            Some(m) => vec![m],
            None => CENTER_GRID
                .iter()
                .copied()
                .filter(|&m| m == 0 || m * 3 <= self.n())
                .collect(),
        }
    }

    /// k-means in the space the length scales define, returned in standardised units.
    fn cluster(&self, m: usize, ls: &[f64]) -> Centers {
        let scaled: Vec<Vec<f64>> = self
            .xstd
            .iter()
            .map(|r| r.iter().zip(ls).map(|(v, l)| v / l).collect())
            .collect();
        Arc::new(
            kmeans(&scaled, m, self.opts.seed)
                .into_iter()
                .map(|c| c.iter().zip(ls).map(|(v, l)| v * l).collect())
                .collect(),
        )
    }

    /// The evidence fit of one setting, remembered as the best of its number of centers if it is.
    fn evaluate(&self, m: usize, sigma: f64, ls: &[f64], centers: &Centers) -> Option<Candidate> {
        let phi = candidate_design(&self.xmat, self.opts.linear, ls, centers, sigma);
        let fit = evidence_fit(&phi, &self.yn, self.nl)?;
        let c = Candidate {
            m,
            sigma,
            ls: ls.to_vec(),
            centers: Arc::clone(centers),
            fit,
        };
        if let Ok(mut per) = self.best_per_m.lock() {
            let e = per.entry(m).or_insert_with(|| c.clone());
            if c.fit.ev.log_evidence > e.fit.ev.log_evidence {
                *e = c.clone();
            }
        }
        Some(c)
    }

    /// Every number of centers with every other width and unit length scales.
    pub(super) fn first_scan(&self, grid: &[usize], evaluated: &mut usize) -> Option<Candidate> {
        let ones = self.start_ls();
        let per_m: Vec<(usize, Centers)> = grid
            .par_iter()
            .map(|&m| (m, self.cluster(m, &ones)))
            .collect();
        let settings: Vec<(usize, f64, &Centers)> = per_m
            .iter()
            .flat_map(|(m, c)| {
                let ws: &[f64] = if *m == 0 {
                    &WIDTHS[3..4]
                } else {
                    &FIRST_WIDTHS
                };
                ws.iter().map(move |&s| (*m, s, c))
            })
            .collect();
        *evaluated += settings.len();
        pick(
            settings
                .par_iter()
                .map(|&(m, s, c)| self.evaluate(m, s, &ones, c))
                .collect(),
            None,
        )
    }

    /// The Occam margin, from the serial correlation of the first scan's best model's residual.
    pub(super) fn margin(&self, best: &Candidate) -> f64 {
        PARSIMONY * margin_inflation(self.residual(best).as_slice())
    }

    fn residual(&self, best: &Candidate) -> DVector<f64> {
        let phi = self.design_of(best);
        &self.yn - phi * DVector::from_column_slice(&best.fit.w)
    }

    fn design_of(&self, c: &Candidate) -> DMatrix<f64> {
        candidate_design(&self.xmat, self.opts.linear, &c.ls, &c.centers, c.sigma)
    }

    /// The prior groups of a joint candidate's design (bias, linear, Gaussians).
    fn groups_of(&self, c: &Candidate) -> Vec<usize> {
        (0..1 + self.nl + c.centers.len())
            .map(|i| match i {
                0 => 0,
                i if i <= self.nl => 1,
                _ => 2,
            })
            .collect()
    }

    /// One round of coordinate search: a walk along each feature's length scale, one re-clustering
    /// for the scales found (kept if the evidence agrees), a walk along the width.
    pub(super) fn refine(
        &self,
        mut best: Candidate,
        margin: f64,
        evaluated: &mut usize,
    ) -> Option<Candidate> {
        let start_ls = best.ls.clone();
        for k in (0..self.d()).filter(|&k| self.pin(k) == Pin::Free) {
            let (m, s, old_ls) = (best.m, best.sigma, best.ls.clone());
            let centers = Arc::clone(&best.centers);
            let with = |v: f64| {
                let mut ls = old_ls.clone();
                if let Some(l) = ls.get_mut(k) {
                    *l = v;
                }
                self.evaluate(m, s, &ls, &centers)
            };
            let current = old_ls.get(k).copied().unwrap_or(1.0);
            best = walk(&LENGTH_SCALES, current, true, margin, best, with, evaluated);
        }
        if best.ls != start_ls {
            *evaluated += 1;
            let c = self.cluster(best.m, &best.ls);
            let again = self.evaluate(best.m, best.sigma, &best.ls, &c);
            best = pick(vec![again], Some(best))?;
        }
        let (m, s, ls) = (best.m, best.sigma, best.ls.clone());
        let centers = Arc::clone(&best.centers);
        Some(walk(
            &WIDTHS,
            s,
            false,
            margin,
            best,
            |s| self.evaluate(m, s, &ls, &centers),
            evaluated,
        ))
    }

    /// The other numbers of centers at the width and length scales found.
    pub(super) fn other_centers(
        &self,
        grid: &[usize],
        best: Candidate,
        evaluated: &mut usize,
    ) -> Option<Candidate> {
        let others: Vec<usize> = grid.iter().copied().filter(|&m| m != best.m).collect();
        *evaluated += others.len();
        let (s, ls) = (best.sigma, best.ls.clone());
        let res = others
            .par_iter()
            .map(|&m| self.evaluate(m, s, &ls, &self.cluster(m, &ls)))
            .collect();
        pick(res, Some(best))
    }

    /// Parsimony: the simplest model whose evidence is not strongly worse than the best's, in the
    /// order linear alone (0 centers), the cubic, then ever more centers. `additive_pinned`: the
    /// additive structure (when its search found a term) is taken as is. (A pinned cubic never
    /// gets here: [`super::fit_binned`] takes it without a search.)
    pub(super) fn choose(
        &self,
        mut best: Candidate,
        cubic: Option<CubicCandidate>,
        additive: Option<Additive>,
        margin: f64,
        evaluated: usize,
        additive_pinned: bool,
    ) -> Option<BayesFit> {
        let n = self.n();
        let per: Vec<Candidate> = self
            .best_per_m
            .lock()
            .map(|mut per| std::mem::take(&mut *per).into_values().collect())
            .unwrap_or_default();
        let ev = |f: &Fitted| f.ev.log_evidence;
        let top = cubic
            .as_ref()
            .map_or(ev(&best.fit), |c| ev(&best.fit).max(ev(&c.fit)));
        let gauss_top = ev(&best.fit);
        let linear_only = per.iter().find(|c| c.m == 0 && ev(&c.fit) >= top - margin);
        let choose_cubic =
            linear_only.is_none() && cubic.as_ref().is_some_and(|c| ev(&c.fit) >= top - margin);
        // The structures compared, in target units, for the report.
        let units = |e: f64| e - n as f64 * self.ys.ln();
        let d = self.d();
        let mut compared: Vec<(String, f64)> = Vec::new();
        if let Some(l) = per.iter().find(|c| c.m == 0) {
            compared.push(("linear term alone".into(), units(ev(&l.fit))));
        }
        if let Some(c) = cubic.as_ref() {
            compared.push(("cubic in the first feature".into(), units(ev(&c.fit))));
        }
        compared.push((self.joint_name(&best), units(gauss_top)));
        // The parsimonious pick among linear, cubic and joint Gaussians, as before. The additive
        // structure replaces it only on strong evidence (the Occam margin), both judged under
        // AR(1) noise whose coefficient the evidence chooses for each (see [`super::additive`]).
        let pick_ev = additive.as_ref().and_then(|_| {
            let (name, phi, groups) = if let Some(l) = linear_only {
                (
                    "linear term alone".to_string(),
                    self.design_of(l),
                    self.groups_of(l),
                )
            } else if let (true, Some(c)) = (choose_cubic, cubic.as_ref()) {
                let groups = (0..c.phi.ncols()).map(|i| usize::from(i > 0)).collect();
                (
                    "cubic in the first feature".to_string(),
                    c.phi.clone(),
                    groups,
                )
            } else {
                let p = per
                    .iter()
                    .find(|c| ev(&c.fit) >= top - margin)
                    .unwrap_or(&best);
                (self.joint_name(p), self.design_of(p), self.groups_of(p))
            };
            self.evidence_ar1(&phi, &groups).map(|(e, r)| (name, e, r))
        });
        if let Some(a) = additive.as_ref() {
            compared.push((
                format!("{}, AR(1) noise ρ {:.2}", self.describe(a), a.rho),
                units(self.occam(a)),
            ));
            if let Some((name, e, r)) = &pick_ev {
                compared.push((format!("{name}, AR(1) noise ρ {r:.2}"), units(*e)));
            }
        }
        let pick_ev = pick_ev.map(|(_, e, _)| e);
        compared.sort_by(|a, b| b.1.total_cmp(&a.1));
        if let Some(a) = additive
            && (additive_pinned || pick_ev.is_some_and(|p| self.occam(&a) > p + margin))
            && Self::has_atoms(&a)
        {
            let (rbf, evidence) = self.additive_fit(&a);
            let chosen = self.describe(&a);
            return Some(BayesFit {
                rbf,
                evidence,
                width: a.atoms.first().map_or(0.0, |b| b.sigma),
                // As for a joint model, 64 marks a feature left to the linear term.
                length_scales: (0..d)
                    .map(|k| {
                        if a.atoms.iter().any(|t| t.feats.contains(&k)) {
                            1.0
                        } else {
                            64.0
                        }
                    })
                    .collect(),
                evaluated,
                basis: Basis::Additive,
                other_basis_log_evidence: cubic.map(|c| units(ev(&c.fit))),
                structure: StructureReport { chosen, compared },
            });
        }
        if let (true, Some(c)) = (choose_cubic && linear_only.is_none(), cubic.as_ref()) {
            let (xm, unit, ym, ys) = (&self.xm, &self.unit, self.ym, self.ys);
            let mut f = c.finish(xm, unit, ym, ys, n, evaluated, Some(gauss_top));
            f.structure = StructureReport {
                chosen: "cubic in the first feature".into(),
                compared,
            };
            return Some(f);
        }
        if let Some(c) = per.into_iter().find(|c| ev(&c.fit) >= top - margin) {
            best = c;
        }
        let other = cubic.map(|c| ev(&c.fit) - n as f64 * self.ys.ln());
        let chosen = if best.m == 0 {
            "linear term alone".to_string()
        } else {
            self.joint_name(&best)
        };
        let mut f = self.gaussian_fit(best, evaluated, other);
        f.structure = StructureReport { chosen, compared };
        Some(f)
    }

    /// The cubic in the first feature as the basis pinned: the one fit made, the one structure
    /// compared.
    pub(super) fn pinned_cubic(&self, c: &CubicCandidate) -> BayesFit {
        let n = self.n();
        let mut f = c.finish(&self.xm, &self.unit, self.ym, self.ys, n, 1, None);
        let name = "cubic in the first feature".to_string();
        let log_evidence = c.fit.ev.log_evidence - n as f64 * self.ys.ln();
        f.structure = StructureReport {
            chosen: name.clone(),
            compared: vec![(name, log_evidence)],
        };
        f
    }

    /// A joint model in words.
    fn joint_name(&self, c: &Candidate) -> String {
        if c.m == 0 {
            return "linear term alone".into();
        }
        let name = |k: usize| self.feature_name(k);
        let on: Vec<String> = (0..self.d())
            .filter(|&k| c.ls.get(k).is_some_and(|l| *l < 64.0))
            .map(name)
            .collect();
        format!(
            "joint: {} Gaussians over ({}), σ {:.2}",
            c.m,
            on.join(", "),
            c.sigma
        )
    }

    /// The chosen Gaussian model as an [`Rbf64`] in the target's units.
    fn gaussian_fit(&self, best: Candidate, evaluated: usize, other: Option<f64>) -> BayesFit {
        let (d, ys) = (self.d(), self.ys);
        let zc: Vec<Vec<f64>> = best
            .centers
            .iter()
            .map(|c| c.iter().zip(&best.ls).map(|(v, l)| v / l).collect())
            .collect();
        let (b0, lin, wg) = split_weights(&best.fit.w, self.nl);
        let scale: Vec<f64> = self.unit.iter().zip(&best.ls).map(|(u, l)| u / l).collect();
        let rbf = Rbf64 {
            offset: self.xm.clone(),
            scale,
            gamma: vec![1.0 / (2.0 * best.sigma * best.sigma); zc.len()],
            centers: zc,
            weights: wg.iter().map(|w| w * ys).collect(),
            linear: if self.opts.linear {
                lin.iter().zip(&best.ls).map(|(w, l)| w * l * ys).collect()
            } else {
                vec![0.0; d]
            },
            bias: self.ym + ys * b0,
            masks: Vec::new(),
            kinds: Vec::new(),
        };
        BayesFit {
            rbf,
            evidence: to_target_units(best.fit.ev, ys, self.n()),
            width: best.sigma,
            length_scales: best.ls,
            evaluated,
            basis: Basis::Gaussians,
            other_basis_log_evidence: other,
            structure: StructureReport::default(),
        }
    }
}

/// The best of `cands` and `best` by log evidence (the earlier on a tie).
fn pick(cands: Vec<Option<Candidate>>, best: Option<Candidate>) -> Option<Candidate> {
    let mut best = best;
    for c in cands.into_iter().flatten() {
        if best
            .as_ref()
            .is_none_or(|b| c.fit.ev.log_evidence > b.fit.ev.log_evidence)
        {
            best = Some(c);
        }
    }
    best
}
