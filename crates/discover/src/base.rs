//! The base model prepared once for scoring: the model's own features fitted on binned data by the
//! trainer's evidence search, its design matrix, and its held-out residual (on a verification run
//! or on contiguous blocks of the training run).
//!
//! Why apart from [`crate::score`]: every candidate is scored against this one base (see the
//! reasons there); preparing it is a job of its own, done once per diagnosis.

use crate::column_cache::ColumnCache;
use crate::design::{
    Columns, Transform, compute_binned, compute_per_sample, error_of, floor_estimate, hcat, mean_sd,
};
use crate::error::{DiscoverError, Result};
use nalgebra::{DMatrix, DVector};
use rayon::prelude::*;
use serde::Serialize;
use tcomp_train::bayes::{self, BayesOptions};
use tcomp_train::binning::{bin_mean, bins};
use tcomp_train::dataset::stretch_starts;
use tcomp_train::evidence::{self, GroupFit};
use tcomp_train::features::FeatureSpec;
use tcomp_train::options::Bound;
use tcomp_train::{Dataset, Roles, TrainError};

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
    pub(crate) y: DVector<f64>,
    ym: f64,
    ys: f64,
    pub(crate) phi: DMatrix<f64>,
    pub(crate) groups: Vec<usize>,
    pub(crate) n_linear: usize,
    pub(crate) base: GroupFit,
    heldout: HeldOut,
    /// Gap threshold (s) of the feature computation.
    pub(crate) gap_s: Option<f64>,
    /// Base figures.
    pub figures: BaseFigures,
    /// Binned columns computed on the training run, and on the verification run.
    train_cols: ColumnCache,
    verify_cols: ColumnCache,
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
    let opts = &adapted_bins(opts, time, verify, roles)?;
    let starts = stretch_starts(time, opts.gap_s);
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
    // The joint model of the evidence search, without the additive structure: the candidates are
    // scored against this base (see `score`), and the additive search's AR(1) evidence is a
    // different yardstick from the one the acceptance rule is calibrated on.
    let opts_base = BayesOptions {
        additive: false,
        ..BayesOptions::default()
    };
    let fit = bayes::fit(&x, &yb, &opts_base).ok_or_else(|| {
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
    let heldout = held_out(spec, roles, verify, opts, &tr, n)?;
    let train_cols = ColumnCache::for_run(&starts);
    let verify_cols = match &heldout {
        HeldOut::Verify { starts, .. } => ColumnCache::for_run(starts),
        HeldOut::Blocks(_) => ColumnCache::for_run(&[]),
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
        gap_s: opts.gap_s,
        figures: BaseFigures::default(),
        train_cols,
        verify_cols,
    };
    p.figures = base_figures(&p, opts, tr.rbf.centers.len())?;
    Ok(p)
}

/// The options with bins fitted to the data: bursty records get shorter bins than asked (see
/// `adaptive_bin`); the figures report them.
fn adapted_bins(
    opts: &ScoreOptions,
    time: &[f64],
    verify: Option<&Dataset>,
    roles: &Roles,
) -> Result<ScoreOptions> {
    let mut adapted = opts.clone();
    adapted.bin_s = tcomp_train::binning::adaptive_bin(time, opts.bin_s, 24);
    if let Some(v) = verify {
        adapted.heldout_bin_s =
            tcomp_train::binning::adaptive_bin(v.time(&roles.time)?, opts.heldout_bin_s, 10);
    }
    Ok(adapted)
}

/// The held-out data: the verification run binned through the base transform `tr`, or contiguous
/// blocks of the `n` training bins.
fn held_out(
    spec: &FeatureSpec,
    roles: &Roles,
    verify: Option<&Dataset>,
    opts: &ScoreOptions,
    tr: &Transform,
    n: usize,
) -> Result<HeldOut> {
    Ok(match verify {
        Some(v) => {
            let vt = v.time(&roles.time)?;
            let vstarts = stretch_starts(vt, opts.gap_s);
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
    })
}

/// The base model's figures under the scoring machinery.
fn base_figures(p: &Prepared, opts: &ScoreOptions, centers: usize) -> Result<BaseFigures> {
    let n = p.y.len();
    let ys = p.ys;
    let base_fit = &p.base;
    let (held, runs) = p
        .heldout_residuals(&p.phi, None, &p.groups, base_fit)
        .ok_or_else(|| DiscoverError::Invalid("held-out prediction failed".into()))?;
    Ok(BaseFigures {
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
        train_residual_std: p.train_std(&p.phi, base_fit),
        heldout_residual_std: mean_sd(&held).1,
        noise_floor_estimate: floor_estimate(&runs),
        centers,
    })
}

impl Prepared {
    /// Std of the binned training residual (target units) of the fit `fit` of design `phi`.
    pub(crate) fn train_std(&self, phi: &DMatrix<f64>, fit: &GroupFit) -> f64 {
        let r = &self.y - phi * &fit.w;
        mean_sd(r.as_slice()).1 * self.ys
    }

    /// Held-out residuals (in target units) and the runs of bins they form.
    pub(crate) fn heldout_residuals(
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

    /// The scoring design with `cols` appended as one more prior group, the groups, and the base
    /// fit's α (one more, 1, for the new group) to start the evidence iteration from: how every
    /// candidate — and every placebo of one — is scored against the same base.
    pub(crate) fn with_columns(&self, cols: &[Vec<f64>]) -> (DMatrix<f64>, Vec<usize>, Vec<f64>) {
        let phi = hcat(&self.phi, cols);
        let g = self.groups.iter().copied().max().unwrap_or(0) + 1;
        let mut groups = self.groups.clone();
        groups.extend(std::iter::repeat_n(g, cols.len()));
        let mut a0 = self.base.alpha.clone();
        a0.push(1.0);
        (phi, groups, a0)
    }

    /// The training run's duration (s), first row to last.
    pub(crate) fn duration_s(&self) -> f64 {
        self.data
            .time(&self.time)
            .ok()
            .and_then(|t| Some(t.last()? - t.first()?))
            .unwrap_or(0.0)
    }

    /// The training run with one row per bin, every column its bin's mean: what a screen over many
    /// expressions evaluates them on, sixty times fewer rows (a stateful function's time scales
    /// shorter than a bin are blurred there, so a screen's best is computed again on every row).
    pub(crate) fn bin_rows(&self) -> Dataset {
        let names = self.data.names().to_vec();
        let cols = names
            .iter()
            .map(|n| {
                self.data
                    .column(n)
                    .map(|c| bin_mean(c, &self.tbins))
                    .unwrap_or_default()
            })
            .collect();
        Dataset::from_columns(self.data.file(), names, cols)
    }

    /// The model's signals (`NAME = EXPR`), which candidate expressions may use.
    pub(crate) fn signals(&self) -> &[String] {
        &self.signals
    }

    /// The name of the time column.
    pub(crate) fn time_name(&self) -> &str {
        &self.time
    }

    /// The first sample of each stretch of the training run (a gap restarts the stateful
    /// functions).
    pub(crate) fn stretch_starts(&self) -> &[usize] {
        &self.starts
    }

    /// The training columns of `exprs` on every sample, not binned.
    pub(crate) fn per_sample(&self, exprs: &[String]) -> Result<Vec<Vec<f64>>> {
        let mut out = Vec::with_capacity(exprs.len());
        for chunk in exprs.chunks(tcomp_train::features::F) {
            out.extend(compute_per_sample(
                &self.signals,
                chunk,
                &self.data,
                &self.time,
                &self.starts,
            )?);
        }
        Ok(out)
    }

    /// The training columns of `exprs` on every sample ([`Prepared::per_sample`]) and the binned
    /// column of `keep` ([`Prepared::binned`]), in one pass over the run where that gives the
    /// same columns: on a run without gaps a column does not depend on what it is computed beside
    /// ([`crate::column_cache`]), so `keep` joins `exprs`' programs and its binned column is kept
    /// as `binned` keeps it; with gaps each is computed as its own call computes it. Why: the
    /// composition search judges a shape's regimes on the per-sample columns of its calls and then
    /// scores its binned column, and each pass reads every input and computes the model's signals
    /// on all 22,000 samples of a run again.
    pub(crate) fn per_sample_and_binned(
        &self,
        exprs: &[String],
        keep: &str,
    ) -> (Result<Vec<Vec<f64>>>, Result<Vec<f64>>) {
        let apart = || {
            let binned = self
                .binned(&[keep.to_string()])
                .map(|c| c.into_iter().next().unwrap_or_default());
            (self.per_sample(exprs), binned)
        };
        if !self.train_cols.keeps() {
            return apart();
        }
        let mut all = exprs.to_vec();
        let at = all.iter().position(|e| e == keep).unwrap_or_else(|| {
            all.push(keep.to_string());
            all.len() - 1
        });
        let Ok(mut cols) = self.per_sample(&all) else {
            return apart();
        };
        let binned = cols.get(at).map(|c| bin_mean(c, &self.tbins));
        let kept = self
            .train_cols
            .columns(&[keep.to_string()], |_| Ok(binned.into_iter().collect()))
            .map(|c| c.into_iter().next().unwrap_or_default());
        cols.truncate(exprs.len());
        (Ok(cols), kept)
    }

    /// The binned training columns of `exprs`, as they are (not standardised).
    pub(crate) fn binned(&self, exprs: &[String]) -> Result<Columns> {
        let compute = |e: &[String]| {
            compute_binned(
                &self.signals,
                e,
                &self.data,
                &self.time,
                &self.starts,
                &self.tbins,
            )
        };
        if self.train_cols.keeps() {
            self.train_cols
                .columns(exprs, |missing| together(missing, &compute))
        } else {
            self.train_cols.columns(exprs, compute)
        }
    }

    /// Computes and keeps the training columns of `exprs` — with `verification`, the verification
    /// run's too, as [`Prepared::standardised`] reads them — ahead of the calls that use them one
    /// candidate at a time: [`together`], on a run without gaps (with gaps nothing is kept, and
    /// this does nothing). An expression that fails here is left to the call that uses it, which
    /// reports it.
    pub(crate) fn prefetch(&self, exprs: &[String], verification: bool) {
        if !self.train_cols.keeps() {
            return;
        }
        let mut unique: Vec<String> = Vec::with_capacity(exprs.len());
        for e in exprs {
            if !unique.contains(e) {
                unique.push(e.clone());
            }
        }
        unique
            .par_chunks(tcomp_train::features::F)
            .for_each(|chunk| {
                if verification {
                    let _ = self.standardised(chunk);
                } else {
                    let _ = self.binned(chunk);
                }
            });
    }

    /// Standardised training columns only (what a search over many members scores with).
    pub(crate) fn standardised_training(&self, exprs: &[String]) -> Result<Columns> {
        let cols = self.binned(exprs)?;
        let mut out = Vec::with_capacity(cols.len());
        for (e, c) in exprs.iter().zip(cols) {
            let (m, s) = mean_sd(&c);
            if s <= 1e-12 {
                return Err(DiscoverError::Invalid(format!(
                    "`{e}` is constant over the training run"
                )));
            }
            out.push(c.iter().map(|v| (v - m) / s).collect());
        }
        Ok(out)
    }

    /// Standardised training columns and, with a verification run, its columns.
    pub(crate) fn standardised(&self, exprs: &[String]) -> Result<(Columns, Option<Columns>)> {
        let cols = self.binned(exprs)?;
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
            } => {
                let compute =
                    |e: &[String]| compute_binned(&self.signals, e, data, &self.time, starts, bins);
                let cols = if self.verify_cols.keeps() {
                    self.verify_cols
                        .columns(exprs, |missing| together(missing, &compute))?
                } else {
                    self.verify_cols.columns(exprs, compute)?
                };
                Some(z(cols))
            }
            HeldOut::Blocks(_) => None,
        };
        Ok((z(cols), v))
    }
}

/// The columns of `exprs` on a run without gaps, where a column does not depend on what it is
/// computed beside ([`ColumnCache`]): [`tcomp_train::features::F`] to a program, the programs
/// run in parallel, so that the model's signals and the inputs' reading are paid once per
/// program, not once per column (a lag bank's ten time constants, a family's members). A
/// program that cannot hold its share (too many nodes) is run one expression at a time.
fn together(
    exprs: &[String],
    compute: &(dyn Fn(&[String]) -> Result<Columns> + Sync),
) -> Result<Columns> {
    let parts: Vec<Result<Columns>> = exprs
        .par_chunks(tcomp_train::features::F)
        .map(|chunk| {
            compute(chunk).or_else(|e| {
                if chunk.len() == 1 {
                    return Err(e);
                }
                let mut out = Vec::with_capacity(chunk.len());
                for x in chunk {
                    out.extend(compute(std::slice::from_ref(x))?);
                }
                Ok(out)
            })
        })
        .collect();
    let mut out = Vec::with_capacity(exprs.len());
    for p in parts {
        out.extend(p?);
    }
    Ok(out)
}

/// Binned values of `expr` on the training data (for plots of residual against a candidate).
pub fn binned_feature(p: &Prepared, expr: &str) -> Result<Vec<f64>> {
    let cols = p.binned(&[expr.to_string()])?;
    Ok(cols.into_iter().next().unwrap_or_default())
}

/// Binned training residual of the base design (target units), aligned with [`binned_feature`].
pub fn base_residual(p: &Prepared) -> Vec<f64> {
    let r = &p.y - &p.phi * &p.base.w;
    r.iter().map(|v| v * p.ys).collect()
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
pub(crate) mod tests {
    use super::*;

    /// A 4,000 s run of a thermometer swinging ±10 °C every hour; `gap` seconds missing half-way.
    pub(crate) fn prepared(gap: f64) -> Prepared {
        let time: Vec<f64> = (0..4000)
            .map(|i| f64::from(i) + if i >= 2000 { gap } else { 0.0 })
            .collect();
        let t: Vec<f64> = time
            .iter()
            .map(|s| 20.0 + 10.0 * (s / 600.0).sin())
            .collect();
        let y: Vec<f64> = t
            .iter()
            .enumerate()
            .map(|(i, v)| 0.01 * v + 1e-3 * (f64::from(i as u32) * 0.7).sin())
            .collect();
        let data = Dataset::from_columns(
            "run.csv",
            vec!["time_s".into(), "t".into(), "y".into()],
            vec![time, t, y],
        );
        let spec = FeatureSpec {
            signals: Vec::new(),
            features: vec!["t".into()],
        };
        let roles = Roles {
            time: "time_s".into(),
            target: "y".into(),
            reference: None,
            reference_value: Some(0.0),
            power_on_s: None,
        };
        let opts = ScoreOptions {
            gap_s: Some(30.0),
            ..ScoreOptions::default()
        };
        prepare(&spec, &roles, &data, None, &opts).unwrap()
    }

    /// The one pass gives the very columns the two calls compute on their own, with and without
    /// a gap, whether the kept expression is among the others or not; an expression that cannot
    /// be computed fails alone.
    #[test]
    fn one_pass_gives_the_columns_of_two() {
        for gap in [0.0, 2000.0] {
            let p = prepared(gap);
            assert_eq!(p.train_cols.keeps(), gap == 0.0);
            let exprs = vec!["hyst(t - 20, 2)".to_string(), "t - 20".to_string()];
            let alone = |e: &str| {
                compute_binned(
                    &p.signals,
                    &[e.to_string()],
                    &p.data,
                    &p.time,
                    &p.starts,
                    &p.tbins,
                )
                .unwrap()
                .remove(0)
            };
            for keep in ["lag(hyst(t - 20, 2), 300)", "hyst(t - 20, 2)"] {
                let (cols, binned) = p.per_sample_and_binned(&exprs, keep);
                assert_eq!(cols.unwrap(), p.per_sample(&exprs).unwrap(), "{gap} {keep}");
                assert_eq!(binned.unwrap(), alone(keep), "{gap} {keep}");
                assert_eq!(p.binned(&[keep.to_string()]).unwrap()[0], alone(keep));
            }
            let (cols, binned) = p.per_sample_and_binned(&exprs, "nosuch(t)");
            assert_eq!(cols.unwrap(), p.per_sample(&exprs).unwrap());
            assert!(binned.is_err());
        }
    }
}
