//! Scoring: refit the model's features plus each candidate, in parallel, and measure what the
//! candidate buys — in log evidence on the training run and in residual on held-out data.
//!
//! Why this shape: a candidate is only worth adding if it explains structure the model's own
//! features cannot, and if that structure is still there on data the fit has not seen.
//! * **Binned first.** Bias instability makes 1 Hz samples strongly correlated; evidence computed
//!   on them as if independent would call drift an effect. Errors and features are averaged into
//!   bins (`bin_s`, default 60 s) before anything is fitted.
//! * **Same base for everyone.** The model's features are fitted once by the trainer's evidence
//!   search (`tcomp_train::bayes`), which fixes the Gaussian centers, width and length scales. Each
//!   candidate is then scored as that design plus the candidate's standardised column(s) with their
//!   own prior precision; all weights and α, β are re-estimated by the evidence iteration. A column
//!   that explains nothing is switched off (α → ∞) and its Δ log evidence tends to 0, so the
//!   comparison is between models that differ by the candidate alone.
//! * **Collinear candidates are refused,** not scored: a column the model's features already span
//!   linearly (1 − R² < 1e-4 against bias + features) adds no information, whatever its name. A
//!   candidate the Gaussians can mimic in-sample (T·dT/dt on a run with one ramp rate) is still
//!   scored: its evidence gain is then small, and the held-out residual decides.
//! * **Held-out residual** on `--verify` (bins of `heldout_bin_s`, default 100 s) or, without one,
//!   on `folds` contiguous blocks of the training run, each predicted from the others with the
//!   converged hyperparameters.
//! * **Families** (a lag's τ, a threshold, a rate window) are marginalised over their grid:
//!   `ln mean(exp Δ)`, so searching more values does not buy evidence; τ of the best member is
//!   reported, and [`crate::confirm`] re-chooses it among that member and its grid neighbours by
//!   the real refits' evidence (the fixed base Gaussians here absorb part of a slow effect and bias
//!   τ short).

use crate::candidates::{Candidate, EffectKind, Family};
use crate::error::{DiscoverError, Result};
use nalgebra::{DMatrix, DVector};
use rayon::prelude::*;
use serde::Serialize;
use tcomp_train::TrainError;
use tcomp_train::bayes::{self, BayesOptions};
use tcomp_train::dataset::segments;
use tcomp_train::evidence::{self, GroupFit};
use tcomp_train::features::{self, FeatureSpec, bin_mean, bins};
use tcomp_train::options::Bound;
use tcomp_train::rbf64::Rbf64;
use tcomp_train::{Dataset, Roles};

/// The number of contiguous blocks in cross-validation on the training run: two at least (one to
/// fit, one to predict); more than 100 leaves blocks of a few bins that say nothing.
pub const FOLDS: Bound = Bound {
    flag: "folds",
    key: "",
    min: 2.0,
    min_exclusive: false,
    max: 100.0,
    unit: "",
    why: "contiguous blocks of the training run held out in turn",
};

/// Scoring options.
#[derive(Clone, Debug)]
pub struct ScoreOptions {
    /// Averaging bin before fitting (s).
    pub bin_s: f64,
    /// Bin of the held-out residual on a verification run (s).
    pub heldout_bin_s: f64,
    /// Contiguous blocks of the training run when there is no verification run.
    pub folds: usize,
    /// Gap threshold (s).
    pub gap_s: Option<f64>,
}

impl Default for ScoreOptions {
    fn default() -> Self {
        Self {
            bin_s: 60.0,
            heldout_bin_s: 100.0,
            folds: 5,
            gap_s: None,
        }
    }
}

/// A bin length in seconds: positive, and under 10⁷ s (longer than any chamber run). Against the
/// data, a bin must also hold samples; [`tcomp_train::options::check_bin`] checks that once the
/// data are known.
const fn bin_bound(flag: &'static str) -> Bound {
    Bound {
        flag,
        key: "",
        min: 0.0,
        min_exclusive: true,
        max: 1e7,
        unit: "s",
        why: "an averaging bin",
    }
}

impl ScoreOptions {
    /// Checks the bins, the folds and the gap against their valid ranges.
    pub fn validate(&self) -> std::result::Result<(), TrainError> {
        bin_bound("--bin").check(self.bin_s)?;
        bin_bound("heldout_bin_s").check(self.heldout_bin_s)?;
        FOLDS.check_count(self.folds, "")?;
        if let Some(g) = self.gap_s {
            tcomp_train::options::GAP.check(g)?;
        }
        Ok(())
    }
}

/// Held-out data.
enum HeldOut {
    /// A verification run: binned error and base design.
    Verify {
        data: Box<Dataset>,
        bins: Vec<(usize, usize)>,
        starts: Vec<usize>,
        y: Vec<f64>,
        phi: DMatrix<f64>,
    },
    /// Contiguous blocks of the training bins.
    Blocks(Vec<Vec<usize>>),
}

/// The base model prepared for scoring.
pub struct Prepared {
    data: Dataset,
    time: String,
    signals: Vec<String>,
    tbins: Vec<(usize, usize)>,
    starts: Vec<usize>,
    /// Binned training error, normalised.
    y: DVector<f64>,
    ym: f64,
    ys: f64,
    phi: DMatrix<f64>,
    groups: Vec<usize>,
    n_linear: usize,
    base: GroupFit,
    heldout: HeldOut,
    /// Base figures.
    pub figures: BaseFigures,
}

/// Figures of the base model under the scoring machinery.
#[derive(Clone, Debug, Default, Serialize)]
pub struct BaseFigures {
    /// Training bins.
    pub train_bins: usize,
    /// Bin of the fit (s).
    pub bin_s: f64,
    /// What the held-out figures are measured on.
    pub heldout: String,
    /// Bin of the held-out figures (s).
    pub heldout_bin_s: f64,
    /// Log evidence of the base design.
    pub log_evidence: f64,
    /// Std of the binned training residual.
    pub train_residual_std: f64,
    /// Std of the binned held-out residual.
    pub heldout_residual_std: f64,
    /// Noise floor estimated from the held-out residual: std of successive bin differences / √2
    /// (robust). Slow model errors cancel in the differences; the noise does not.
    pub noise_floor_estimate: f64,
    /// Centers of the base design.
    pub centers: usize,
}

/// One scored candidate (the best member of its family).
#[derive(Clone, Debug, Serialize)]
pub struct Scored {
    /// Feature expression to add (the first when several).
    pub expression: String,
    /// All expressions to add.
    pub expressions: Vec<String>,
    /// Physical name.
    pub effect: String,
    /// Effect kind.
    pub kind: EffectKind,
    /// The searched parameter of the best member (τ s, threshold, window s).
    pub parameter: Option<f64>,
    /// Δ log evidence of the family (marginalised over its grid).
    pub delta_log_evidence: f64,
    /// Δ log evidence of the best member alone.
    pub delta_log_evidence_best: f64,
    /// Std of the binned held-out residual with the candidate (the real refit's figure once
    /// confirmed, else the scoring estimate).
    pub residual_std_after: f64,
    /// Std of the binned held-out residual without it.
    pub residual_std_before: f64,
    /// 100·(1 − after/before) on held-out data.
    pub improvement_pct: f64,
    /// The scoring's own estimate of `improvement_pct` (centers and widths of the base held fixed).
    pub scored_improvement_pct: f64,
    /// The real refit of this candidate ([`crate::confirm`]), when it was among those refitted.
    pub confirmation: Option<crate::confirm::Confirmation>,
    /// Why there is no confirmation.
    pub unconfirmed: Option<String>,
    /// Std of the binned training residual with the candidate.
    pub train_residual_std_after: f64,
    /// Members scored.
    pub members: usize,
    /// The family members next to the best one in its grid (a lag's τ/2 and 2τ, say), which the
    /// confirmation refits to choose the parameter by the real fit's evidence.
    #[serde(skip)]
    pub neighbours: Vec<Candidate>,
    /// Set when the confirmation's refits moved the parameter away from the scoring's choice.
    pub parameter_scored: Option<f64>,
    /// Whether it clears the criterion (set by the verdict).
    pub passes: bool,
    /// Why it does not (set by the verdict).
    pub fails: Vec<String>,
}

/// A candidate that was not scored.
#[derive(Clone, Debug, Serialize)]
pub struct Skipped {
    /// Expression.
    pub expression: String,
    /// Physical name.
    pub effect: String,
    /// Why.
    pub reason: String,
}

/// Feature columns (one `Vec` per feature, one value per bin).
type Columns = Vec<Vec<f64>>;

fn compute_binned(
    signals: &[String],
    exprs: &[String],
    data: &Dataset,
    time_col: &str,
    starts: &[usize],
    b: &[(usize, usize)],
) -> Result<Vec<Vec<f64>>> {
    let spec = FeatureSpec {
        signals: signals.to_vec(),
        features: exprs.to_vec(),
    };
    let program = spec.program()?;
    let nf = program.n_features();
    let time = data.time(time_col)?;
    let rows = features::compute(&program, data, time, starts)?;
    Ok((0..nf)
        .map(|k| {
            let c: Vec<f64> = rows.iter().map(|r| f64::from(r[k])).collect();
            bin_mean(&c, b)
        })
        .collect())
}

fn error_of(data: &Dataset, roles: &Roles) -> Result<Vec<f64>> {
    let target = data.column(&roles.target)?;
    let reference = roles.reference_series(data)?;
    Ok(target.iter().zip(&reference).map(|(a, b)| a - b).collect())
}

/// Base design transform: standardised linear columns and the Gaussians of `rbf`.
struct Transform {
    mean: Vec<f64>,
    sd: Vec<f64>,
    rbf: Rbf64,
}

impl Transform {
    fn design(&self, cols: &[Vec<f64>], n: usize) -> DMatrix<f64> {
        let d = cols.len();
        let m = 1 + d + self.rbf.centers.len();
        let mut phi = DMatrix::zeros(n, m);
        let mut x = vec![0.0; d];
        for i in 0..n {
            for (k, c) in cols.iter().enumerate() {
                x[k] = c.get(i).copied().unwrap_or(0.0);
            }
            phi[(i, 0)] = 1.0;
            for k in 0..d {
                phi[(i, 1 + k)] = (x[k] - self.mean[k]) / self.sd[k];
            }
            let z = self.rbf.normalise(&x);
            for (j, (c, g)) in self.rbf.centers.iter().zip(&self.rbf.gamma).enumerate() {
                let d2: f64 = z.iter().zip(c).map(|(a, b)| (a - b) * (a - b)).sum();
                phi[(i, 1 + d + j)] = (-g * d2).exp();
            }
        }
        phi
    }
}

fn mean_sd(v: &[f64]) -> (f64, f64) {
    let n = v.len().max(1) as f64;
    let m = v.iter().sum::<f64>() / n;
    let s = (v.iter().map(|x| (x - m) * (x - m)).sum::<f64>() / n).sqrt();
    (m, s)
}

/// Robust noise floor from successive differences of binned residuals, within runs of bins.
fn floor_estimate(runs: &[Vec<f64>]) -> f64 {
    let mut d: Vec<f64> = runs
        .iter()
        .flat_map(|r| r.windows(2).map(|w| (w[1] - w[0]).abs()))
        .collect();
    if d.is_empty() {
        return 0.0;
    }
    d.sort_by(f64::total_cmp);
    let med = d[d.len() / 2];
    1.4826 * med / std::f64::consts::SQRT_2
}

/// Prepares the base model `spec` (signals and features) with `roles` on `data`, with an optional
/// verification run.
pub fn prepare(
    spec: &FeatureSpec,
    roles: &Roles,
    data: &Dataset,
    verify: Option<&Dataset>,
    opts: &ScoreOptions,
) -> Result<Prepared> {
    let time = data.time(&roles.time)?;
    // Bursty records get shorter bins than asked (see `adaptive_bin`); the figures report them.
    let mut adapted = opts.clone();
    adapted.bin_s = tcomp_train::features::adaptive_bin(time, opts.bin_s, 24);
    if let Some(v) = verify {
        adapted.heldout_bin_s =
            tcomp_train::features::adaptive_bin(v.time(&roles.time)?, opts.heldout_bin_s, 10);
    }
    let opts = &adapted;
    let starts = segments(time, opts.gap_s);
    let tbins = bins(time, opts.bin_s);
    let err = error_of(data, roles)?;
    let yb = bin_mean(&err, &tbins);
    let n = yb.len();
    if n < 12 {
        return Err(DiscoverError::Invalid(format!(
            "{}: only {n} bins of {} s; diagnosis needs at least 12",
            data.file(),
            opts.bin_s
        )));
    }
    let cols = compute_binned(
        &spec.signals,
        &spec.features,
        data,
        &roles.time,
        &starts,
        &tbins,
    )?;
    let x: Vec<Vec<f64>> = (0..n)
        .map(|i| cols.iter().map(|c| c[i]).collect())
        .collect();
    let fit = bayes::fit(&x, &yb, &BayesOptions::default()).ok_or_else(|| {
        DiscoverError::Invalid("the evidence iteration of the base model failed".into())
    })?;
    let (mean, sd): (Vec<f64>, Vec<f64>) = cols
        .iter()
        .map(|c| {
            let (m, s) = mean_sd(c);
            (m, s.max(1e-300))
        })
        .unzip();
    let tr = Transform {
        mean,
        sd,
        rbf: fit.rbf,
    };
    let phi = tr.design(&cols, n);
    let d = cols.len();
    let groups: Vec<usize> = (0..phi.ncols())
        .map(|j| match j {
            0 => 0,
            j if j <= d => 1,
            _ => 2,
        })
        .collect();
    let (ym, ys) = mean_sd(&yb);
    let ys = ys.max(1e-300);
    let y = DVector::from_iterator(n, yb.iter().map(|v| (v - ym) / ys));
    let base = evidence::fit(&phi, &y, &groups, None)
        .ok_or_else(|| DiscoverError::Invalid("the base design is singular".into()))?;
    let heldout = match verify {
        Some(v) => {
            let vt = v.time(&roles.time)?;
            let vstarts = segments(vt, opts.gap_s);
            let vb = bins(vt, opts.heldout_bin_s);
            let vy = bin_mean(&error_of(v, roles)?, &vb);
            let vcols =
                compute_binned(&spec.signals, &spec.features, v, &roles.time, &vstarts, &vb)?;
            let phi_v = tr.design(&vcols, vy.len());
            HeldOut::Verify {
                data: Box::new(v.clone()),
                bins: vb,
                starts: vstarts,
                y: vy,
                phi: phi_v,
            }
        }
        None => {
            let k = opts.folds.clamp(2, n / 4);
            HeldOut::Blocks(
                (0..k)
                    .map(|f| (f * n / k..(f + 1) * n / k).collect())
                    .collect(),
            )
        }
    };
    let mut p = Prepared {
        data: data.clone(),
        time: roles.time.clone(),
        signals: spec.signals.clone(),
        tbins,
        starts,
        y,
        ym,
        ys,
        phi,
        groups,
        n_linear: d,
        base,
        heldout,
        figures: BaseFigures::default(),
    };
    let base_fit = p.base.clone();
    let (held, runs) = p
        .heldout_residuals(&p.phi, None, &p.groups, &base_fit)
        .ok_or_else(|| DiscoverError::Invalid("held-out prediction failed".into()))?;
    p.figures = BaseFigures {
        train_bins: n,
        bin_s: opts.bin_s,
        heldout: match &p.heldout {
            HeldOut::Verify { data, .. } => format!("verification run {}", data.file()),
            HeldOut::Blocks(b) => format!(
                "{} contiguous blocks of the training run, each predicted from the others",
                b.len()
            ),
        },
        heldout_bin_s: match &p.heldout {
            HeldOut::Verify { .. } => opts.heldout_bin_s,
            HeldOut::Blocks(_) => opts.bin_s,
        },
        log_evidence: base_fit.log_evidence - n as f64 * ys.ln(),
        train_residual_std: p.train_std(&p.phi, &base_fit),
        heldout_residual_std: mean_sd(&held).1,
        noise_floor_estimate: floor_estimate(&runs),
        centers: tr.rbf.centers.len(),
    };
    Ok(p)
}

fn hcat(a: &DMatrix<f64>, cols: &[Vec<f64>]) -> DMatrix<f64> {
    let (n, m) = a.shape();
    let mut out = a.clone().resize_horizontally(m + cols.len(), 0.0);
    for (k, c) in cols.iter().enumerate() {
        for i in 0..n {
            out[(i, m + k)] = c.get(i).copied().unwrap_or(0.0);
        }
    }
    out
}

impl Prepared {
    fn train_std(&self, phi: &DMatrix<f64>, fit: &GroupFit) -> f64 {
        let r = &self.y - phi * &fit.w;
        mean_sd(r.as_slice()).1 * self.ys
    }

    /// Held-out residuals (in target units) and the runs of bins they form.
    fn heldout_residuals(
        &self,
        phi: &DMatrix<f64>,
        extra_v: Option<&[Vec<f64>]>,
        groups: &[usize],
        fit: &GroupFit,
    ) -> Option<(Vec<f64>, Vec<Vec<f64>>)> {
        match &self.heldout {
            HeldOut::Verify { y, phi: pv, .. } => {
                let pv = match extra_v {
                    Some(c) => hcat(pv, c),
                    None => pv.clone(),
                };
                let pred = pv * &fit.w;
                let r: Vec<f64> = y
                    .iter()
                    .zip(pred.iter())
                    .map(|(a, p)| a - (p * self.ys + self.ym))
                    .collect();
                Some((r.clone(), vec![r]))
            }
            HeldOut::Blocks(blocks) => {
                let n = phi.nrows();
                let mut all = Vec::new();
                let mut runs = Vec::new();
                for test in blocks {
                    let keep: Vec<usize> = (0..n).filter(|i| !test.contains(i)).collect();
                    let w =
                        evidence::weights_on(phi, &self.y, groups, &fit.alpha, fit.beta, &keep)?;
                    let run: Vec<f64> = test
                        .iter()
                        .map(|&i| {
                            let p: f64 = phi.row(i).iter().zip(w.iter()).map(|(a, b)| a * b).sum();
                            (self.y[i] - p) * self.ys
                        })
                        .collect();
                    all.extend_from_slice(&run);
                    runs.push(run);
                }
                Some((all, runs))
            }
        }
    }

    /// Standardised training columns and, with a verification run, its columns.
    fn standardised(&self, exprs: &[String]) -> Result<(Columns, Option<Columns>)> {
        let time_col = self.time.clone();
        let cols = compute_binned(
            &self.signals,
            exprs,
            &self.data,
            &time_col,
            &self.starts,
            &self.tbins,
        )?;
        let stats: Vec<(f64, f64)> = cols.iter().map(|c| mean_sd(c)).collect();
        let z = |cols: Vec<Vec<f64>>| -> Vec<Vec<f64>> {
            cols.into_iter()
                .zip(&stats)
                .map(|(c, (m, s))| c.iter().map(|v| (v - m) / s.max(1e-300)).collect())
                .collect()
        };
        for (e, (_, s)) in exprs.iter().zip(&stats) {
            if *s <= 1e-12 {
                return Err(DiscoverError::Invalid(format!(
                    "`{e}` is constant over the training run"
                )));
            }
        }
        let v = match &self.heldout {
            HeldOut::Verify {
                data, bins, starts, ..
            } => Some(z(compute_binned(
                &self.signals,
                exprs,
                data,
                &time_col,
                starts,
                bins,
            )?)),
            HeldOut::Blocks(_) => None,
        };
        Ok((z(cols), v))
    }
}

/// A member's score.
#[derive(Clone, Debug)]
struct MemberScore {
    delta: f64,
    heldout_std: f64,
    train_std: f64,
}

fn score_member(p: &Prepared, c: &Candidate) -> std::result::Result<MemberScore, String> {
    let (cols, vcols) = p.standardised(&c.expressions).map_err(|e| e.to_string())?;
    // Refuse columns the model's features already span linearly (bias + linear columns). The
    // Gaussians are left out on purpose: a product or square of existing features is expressible
    // by them in-sample, yet as an explicit feature it changes how the model extrapolates.
    let lin = p.phi.columns(0, p.n_linear + 1).into_owned();
    for (e, col) in c.expressions.iter().zip(&cols) {
        let cv = DVector::from_column_slice(col);
        let g = lin.tr_mul(&lin) + DMatrix::identity(lin.ncols(), lin.ncols()) * 1e-9;
        let b = g
            .cholesky()
            .map(|ch| ch.solve(&lin.tr_mul(&cv)))
            .ok_or("singular base design")?;
        let r = &cv - &lin * b;
        let unexplained = r.dot(&r) / cv.dot(&cv).max(1e-300);
        if unexplained < 1e-4 {
            return Err(format!(
                "`{e}` is already expressed by the model's features (1 − R² = {unexplained:.1e})"
            ));
        }
    }
    let phi = hcat(&p.phi, &cols);
    let cand_group = p.groups.iter().copied().max().unwrap_or(0) + 1;
    let mut groups = p.groups.clone();
    groups.extend(std::iter::repeat_n(cand_group, cols.len()));
    let mut a0 = p.base.alpha.clone();
    a0.push(1.0);
    let fit = evidence::fit(&phi, &p.y, &groups, Some((&a0, p.base.beta)))
        .ok_or("the evidence iteration failed")?;
    let (held, _) = p
        .heldout_residuals(&phi, vcols.as_deref(), &groups, &fit)
        .ok_or("held-out prediction failed")?;
    Ok(MemberScore {
        delta: fit.log_evidence - p.base.log_evidence,
        heldout_std: mean_sd(&held).1,
        train_std: p.train_std(&phi, &fit),
    })
}

/// Scores every family in parallel; returns the scored families (unsorted) and the skipped ones.
pub fn score(p: &Prepared, families: &[Family]) -> (Vec<Scored>, Vec<Skipped>) {
    let members: Vec<(usize, &Candidate)> = families
        .iter()
        .enumerate()
        .flat_map(|(f, fam)| fam.members.iter().map(move |m| (f, m)))
        .collect();
    let results: Vec<(usize, &Candidate, std::result::Result<MemberScore, String>)> = members
        .par_iter()
        .map(|&(f, m)| (f, m, score_member(p, m)))
        .collect();
    let mut scored = Vec::new();
    let mut skipped = Vec::new();
    let before = p.figures.heldout_residual_std;
    for (f, _) in families.iter().enumerate() {
        let mine: Vec<&(usize, &Candidate, _)> = results.iter().filter(|r| r.0 == f).collect();
        let ok: Vec<(&Candidate, &MemberScore)> = mine
            .iter()
            .filter_map(|r| r.2.as_ref().ok().map(|s| (r.1, s)))
            .collect();
        let Some(&(best_c, best)) = ok.iter().max_by(|a, b| a.1.delta.total_cmp(&b.1.delta)) else {
            if let Some((_, c, Err(reason))) = mine.first().map(|r| (r.0, r.1, &r.2)) {
                skipped.push(Skipped {
                    expression: c.expressions.join(", "),
                    effect: c.effect.clone(),
                    reason: reason.clone(),
                });
            }
            continue;
        };
        let k = mine.len() as f64;
        let mx = best.delta;
        let lse = mx
            + ok.iter()
                .map(|(_, s)| (s.delta - mx).exp())
                .sum::<f64>()
                .ln()
            - k.ln();
        scored.push(Scored {
            expression: best_c.expressions.first().cloned().unwrap_or_default(),
            expressions: best_c.expressions.clone(),
            effect: best_c.effect.clone(),
            kind: best_c.kind,
            parameter: best_c.parameter,
            delta_log_evidence: lse,
            delta_log_evidence_best: best.delta,
            residual_std_after: best.heldout_std,
            residual_std_before: before,
            improvement_pct: if before > 0.0 {
                100.0 * (1.0 - best.heldout_std / before)
            } else {
                0.0
            },
            scored_improvement_pct: if before > 0.0 {
                100.0 * (1.0 - best.heldout_std / before)
            } else {
                0.0
            },
            confirmation: None,
            unconfirmed: None,
            train_residual_std_after: best.train_std,
            members: mine.len(),
            neighbours: {
                let fam = families.get(f).map_or(&[][..], |x| x.members.as_slice());
                let at = fam.iter().position(|m| std::ptr::eq(m, best_c));
                at.map(|i| {
                    [i.checked_sub(1), Some(i + 1)]
                        .into_iter()
                        .flatten()
                        .filter_map(|j| fam.get(j).cloned())
                        .collect()
                })
                .unwrap_or_default()
            },
            parameter_scored: None,
            passes: false,
            fails: Vec::new(),
        });
    }
    (scored, skipped)
}

/// Binned values of `expr` on the training data (for plots of residual against a candidate).
pub fn binned_feature(p: &Prepared, expr: &str) -> Result<Vec<f64>> {
    let cols = compute_binned(
        &p.signals,
        &[expr.to_string()],
        &p.data,
        &p.time,
        &p.starts,
        &p.tbins,
    )?;
    Ok(cols.into_iter().next().unwrap_or_default())
}

/// Binned training residual of the base design (target units), aligned with [`binned_feature`].
pub fn base_residual(p: &Prepared) -> Vec<f64> {
    let r = &p.y - &p.phi * &p.base.w;
    r.iter().map(|v| v * p.ys).collect()
}
