//! The held-out splits a confirmation refits on: blocks of the training run (one per temperature
//! ramp when the run has a few, else equal blocks), each predicted by a fit on the rest, which the
//! criterion reads; and the verification run, which is only reported.
//!
//! Why a module of its own: which rows are held out, and how, is what makes the selection honest
//! (the choice made on the training run alone) and what decides whether a block tests
//! interpolation or the prediction of a regime the fit has not seen.

use crate::Result;
use tcomp_train::{Dataset, Roles, metrics};

use super::ConfirmOptions;

/// One train/test split.
pub(super) struct Split {
    pub(super) train: Dataset,
    pub(super) test: Dataset,
    pub(super) bin_s: f64,
    /// The rows of `test` scored, `[lo, hi)` s: a block of the training run is predicted by
    /// running the refit over the whole run (the filters' state and warm-up's clock continuous, as
    /// on the board) and scoring the block's rows only; a block run on its own would start its
    /// lags cold and warm-up's clock at the block's first row.
    pub(super) score: Option<(f64, f64)>,
}

/// The rows of `data` whose time is outside `[lo, hi)`.
fn without(data: &Dataset, time: &[f64], lo: f64, hi: f64) -> Dataset {
    let keep: Vec<usize> = time
        .iter()
        .enumerate()
        .filter(|(_, t)| **t < lo || **t >= hi)
        .map(|(i, _)| i)
        .collect();
    let cols = data
        .names()
        .iter()
        .map(|n| {
            let c = data.column(n).unwrap_or(&[]);
            keep.iter()
                .map(|&i| c.get(i).copied().unwrap_or(f64::NAN))
                .collect()
        })
        .collect();
    Dataset::from_columns(
        &format!("{} without [{lo:.0}, {hi:.0}) s", data.file()),
        data.names().to_vec(),
        cols,
    )
}

/// Contiguous blocks of the training run, each predicted by a fit on the rest.
pub(super) fn training_blocks(
    roles: &Roles,
    data: &Dataset,
    opts: &ConfirmOptions,
    run: Option<&metrics::Run>,
) -> Result<Vec<Split>> {
    let t = data.time(&roles.time)?;
    let edges = run
        .and_then(|r| regime_edges(r, opts.folds.max(2)))
        .unwrap_or_else(|| equal_edges(t, opts.folds.max(2)));
    let mut out = Vec::new();
    for w in edges.windows(2) {
        out.push(window(roles, data, opts, t, w[0], w[1])?);
    }
    Ok(out)
}

/// The split that predicts the window `[lo, hi)` of the run from a fit on the rest of it, scored
/// at the window's own adaptive bin.
fn window(
    roles: &Roles,
    data: &Dataset,
    opts: &ConfirmOptions,
    t: &[f64],
    lo: f64,
    hi: f64,
) -> Result<Split> {
    let block = data.select_time(&roles.time, lo, hi)?;
    let bin_s =
        tcomp_train::binning::adaptive_bin(block.time(&roles.time)?, opts.heldout_bin_s, 10);
    Ok(Split {
        train: without(data, t, lo, hi),
        test: data.clone(),
        bin_s,
        score: Some((lo, hi)),
    })
}

/// The window `[lo, hi)` of the training run (bounded by its first and last rows) cut into `k`
/// equal parts, each predicted by a fit on the rest of the run: how an effect confined to one
/// block is tested (see `super::localized`).
pub(super) fn parts_of(
    roles: &Roles,
    data: &Dataset,
    opts: &ConfirmOptions,
    (lo, hi): (f64, f64),
    k: usize,
) -> Result<Vec<Split>> {
    let t = data.time(&roles.time)?;
    let (t0, t1) = (
        t.first().copied().unwrap_or(0.0),
        t.last().copied().unwrap_or(0.0),
    );
    let (lo, hi) = (lo.max(t0), hi.min(t1));
    let mut out = Vec::new();
    if hi.partial_cmp(&lo) != Some(std::cmp::Ordering::Greater) {
        return Ok(out);
    }
    for i in 0..k {
        let a = lo + (hi - lo) * i as f64 / k as f64;
        let b = if i + 1 == k {
            f64::INFINITY.min(hi + 1e-9 * hi.abs().max(1.0))
        } else {
            lo + (hi - lo) * (i + 1) as f64 / k as f64
        };
        out.push(window(roles, data, opts, t, a, b)?);
    }
    Ok(out)
}

/// `k` equal blocks of the run's time span (the last one open-ended).
fn equal_edges(t: &[f64], k: usize) -> Vec<f64> {
    let (t0, t1) = (
        t.first().copied().unwrap_or(0.0),
        t.last().copied().unwrap_or(0.0),
    );
    let mut e: Vec<f64> = (0..k)
        .map(|i| t0 + (t1 - t0) * i as f64 / k as f64)
        .collect();
    e.push(f64::INFINITY);
    e
}

/// One block per temperature ramp, from its start to the next ramp's start (the hold after it
/// included; the first block from the run's start), when the run has between 3 and
/// `2 × folds` ramps. Why: a block that cuts a ramp in two leaves its other half in the fit, so the
/// held-out half is interpolated, not predicted; holding out a whole ramp asks the fit on the
/// others to predict a regime it has not seen — what a verification run on another profile
/// asks, from the training run alone.
fn regime_edges(run: &metrics::Run, folds: usize) -> Option<Vec<f64>> {
    let ramps: Vec<f64> = metrics::segment_table(run)
        .iter()
        .filter(|s| s.kind != "hold")
        .map(|s| s.start_s)
        .collect();
    if !(3..=2 * folds).contains(&ramps.len()) {
        return None;
    }
    let mut e = vec![f64::NEG_INFINITY];
    e.extend(ramps.iter().skip(1));
    e.push(f64::INFINITY);
    Some(e)
}

/// The held-out splits of the verdict: the verification run, or the training run's blocks.
pub(super) fn verification_split(
    roles: &Roles,
    data: &Dataset,
    verify: Option<&Dataset>,
    opts: &ConfirmOptions,
) -> Result<Option<(Split, String)>> {
    let Some(v) = verify else {
        return Ok(None);
    };
    let bin_s = tcomp_train::binning::adaptive_bin(v.time(&roles.time)?, opts.heldout_bin_s, 10);
    let split = Split {
        train: data.clone(),
        test: v.clone(),
        bin_s,
        score: None,
    };
    Ok(Some((split, format!("verification run {}", v.file()))))
}

/// The training run's contiguous blocks as the splits the criterion reads.
pub(super) fn block_splits(blocks: &[Split]) -> (Vec<Split>, String) {
    (
        blocks
            .iter()
            .map(|b| Split {
                train: b.train.clone(),
                test: b.test.clone(),
                bin_s: b.bin_s,
                score: b.score,
            })
            .collect(),
        format!(
            "{} blocks of the training run (one per temperature ramp when it has a few), each \
             predicted by a fit on the rest",
            blocks.len()
        ),
    )
}
