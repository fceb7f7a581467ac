//! The two-pass definitions the online accumulator replaced (whole columns in memory, std by
//! mean then deviations), kept as the reference the accumulator is checked against.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::indexing_slicing)]

use super::*;
use crate::binning::{bin_mean, bins};

fn msd(v: &[f64]) -> f64 {
    v.iter().map(|x| x * x).sum::<f64>() / v.len().max(1) as f64
}

/// Computes the report of a run with bins of `bin_s` seconds.
pub(super) fn report(run: &Run, bin_s: f64) -> EvalReport {
    let raw_std = std(&run.error);
    let residual_std = std(&run.residual);
    let b = bins(&run.time, bin_s);
    let be = bin_mean(&run.error, &b);
    let br = bin_mean(&run.residual, &b);
    let (braw, bres) = (std(&be), std(&br));
    EvalReport {
        samples: run.time.len(),
        raw_std,
        residual_std,
        improvement_pct: improvement(raw_std, residual_std),
        raw_rms: msd(&run.error).sqrt(),
        residual_rms: msd(&run.residual).sqrt(),
        max_abs_residual: run.residual.iter().fold(0.0, |m, v| m.max(v.abs())),
        msd_before: msd(&run.error),
        msd_after: msd(&run.residual),
        binned: Binned {
            seconds: bin_s,
            bins: b.len(),
            raw_std: braw,
            residual_std: bres,
            improvement_pct: improvement(braw, bres),
        },
        segments: segment_table(run),
        out_of_range_pct: 100.0 * run.out_of_range as f64 / run.time.len().max(1) as f64,
        input_faults: run.faults,
        gaps: run.gaps,
        gaps_restarted: run.restarted.len(),
        notes: Vec::new(),
    }
}

/// Splits a run into holds, heating and cooling ramps from the temperature rate (60 s bins, central
/// differences; runs shorter than 5 bins are merged into the previous one).
pub(super) fn segment_table(run: &Run) -> Vec<SegmentStats> {
    let b = bins(&run.time, 60.0);
    if b.len() < 3 {
        return Vec::new();
    }
    let tm = bin_mean(&run.temperature, &b);
    let ts = bin_mean(&run.time, &b);
    let n = b.len();
    let rate: Vec<f64> = (0..n)
        .map(|i| {
            let (a, c) = (i.saturating_sub(1), (i + 1).min(n - 1));
            let dt = ts.get(c).copied().unwrap_or(0.0) - ts.get(a).copied().unwrap_or(0.0);
            let dtemp = tm.get(c).copied().unwrap_or(0.0) - tm.get(a).copied().unwrap_or(0.0);
            if dt > 0.0 { 60.0 * dtemp / dt } else { 0.0 }
        })
        .collect();
    let kind = |r: f64| -> i8 {
        if r > HOLD_RATE_PER_MIN {
            1
        } else if r < -HOLD_RATE_PER_MIN {
            -1
        } else {
            0
        }
    };
    // Runs of equal kind over bins: (kind, first bin, last bin exclusive).
    let mut runs: Vec<(i8, usize, usize)> = Vec::new();
    for (i, r) in rate.iter().enumerate() {
        let k = kind(*r);
        match runs.last_mut() {
            Some(last) if last.0 == k => last.2 = i + 1,
            _ => runs.push((k, i, i + 1)),
        }
    }
    let mut merged: Vec<(i8, usize, usize)> = Vec::new();
    for r in runs {
        match merged.last_mut() {
            Some(last) if last.0 == r.0 || r.2 - r.1 < 5 => last.2 = r.2,
            Some(last) if last.2 - last.1 < 5 => {
                last.0 = r.0;
                last.2 = r.2;
            }
            _ => merged.push(r),
        }
    }
    merged
        .iter()
        .map(|&(k, b0, b1)| {
            let s = b.get(b0).map_or(0, |x| x.0);
            let e = if b1 >= n {
                run.time.len()
            } else {
                b.get(b1).map_or(run.time.len(), |x| x.0)
            };
            let err = run.error.get(s..e).unwrap_or(&[]);
            let res = run.residual.get(s..e).unwrap_or(&[]);
            let rates = rate.get(b0..b1).unwrap_or(&[]);
            SegmentStats {
                kind: match k {
                    1 => "heating",
                    -1 => "cooling",
                    _ => "hold",
                }
                .to_string(),
                start_s: run.time.get(s).copied().unwrap_or(0.0),
                end_s: run.time.get(e.saturating_sub(1)).copied().unwrap_or(0.0),
                samples: e.saturating_sub(s),
                rate_per_min: rates.iter().sum::<f64>() / rates.len().max(1) as f64,
                raw_std: std(err),
                residual_std: std(res),
            }
        })
        .collect()
}

/// A synthetic run: `n` samples `dt` apart, a gap of `gap_s` every `gap_every` rows, temperature
/// holding and ramping, error a drift plus a deterministic pseudo-noise, residual a fraction.
fn synthetic(n: usize, dt: f64, gap_every: usize, gap_s: f64, seed: u64) -> Run {
    let mut state = seed;
    let mut noise = || {
        state = state
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        ((state >> 11) as f64 / (1u64 << 53) as f64) - 0.5
    };
    let mut t = 1234.5;
    let mut run = Run::default();
    for i in 0..n {
        if i > 0 {
            t += dt;
            if gap_every > 0 && i % gap_every == 0 {
                t += gap_s;
            }
        }
        let phase = (t / 3600.0).rem_euclid(4.0);
        let temp = match phase as u32 {
            0 => 20.0,
            1 => 20.0 + 30.0 * (phase - 1.0),
            2 => 50.0,
            _ => 50.0 - 30.0 * (phase - 3.0),
        };
        let e = 3.0 + 0.02 * temp + 0.1 * noise();
        run.time.push(t);
        run.temperature.push(temp);
        run.error.push(e);
        run.residual.push(0.2 * (e - 3.5) + 0.01 * noise());
    }
    run
}

fn close(a: f64, b: f64, what: &str) {
    let tol = 1e-9 * a.abs().max(b.abs()).max(1e-300);
    assert!((a - b).abs() <= tol, "{what}: {a} vs {b}");
}

fn same(a: &EvalReport, b: &EvalReport) {
    assert_eq!(a.samples, b.samples);
    for (x, y, w) in [
        (a.raw_std, b.raw_std, "raw_std"),
        (a.residual_std, b.residual_std, "residual_std"),
        (a.improvement_pct, b.improvement_pct, "improvement"),
        (a.raw_rms, b.raw_rms, "raw_rms"),
        (a.residual_rms, b.residual_rms, "residual_rms"),
        (a.max_abs_residual, b.max_abs_residual, "max"),
        (a.msd_before, b.msd_before, "msd_before"),
        (a.msd_after, b.msd_after, "msd_after"),
        (a.binned.raw_std, b.binned.raw_std, "binned raw"),
        (
            a.binned.residual_std,
            b.binned.residual_std,
            "binned residual",
        ),
        (a.out_of_range_pct, b.out_of_range_pct, "oor"),
    ] {
        close(x, y, w);
    }
    assert_eq!(a.binned.bins, b.binned.bins);
    assert_eq!(a.segments.len(), b.segments.len());
    for (s, u) in a.segments.iter().zip(&b.segments) {
        assert_eq!(
            (&s.kind, s.start_s, s.end_s, s.samples),
            (&u.kind, u.start_s, u.end_s, u.samples)
        );
        close(s.rate_per_min, u.rate_per_min, "rate");
        close(s.raw_std, u.raw_std, "segment raw");
        close(s.residual_std, u.residual_std, "segment residual");
    }
    assert_eq!(
        (a.input_faults, a.gaps, a.gaps_restarted),
        (b.input_faults, b.gaps, b.gaps_restarted)
    );
}

#[test]
fn online_report_matches_the_two_pass_definitions() {
    let cases = [
        synthetic(40_000, 1.0, 0, 0.0, 1),
        synthetic(30_000, 1.0, 7_001, 950.0, 2),
        synthetic(200_000, 0.01, 50_000, 31.7, 3),
        synthetic(5_000, 0.5, 333, 45.0, 4),
        synthetic(2, 1.0, 0, 0.0, 5),
    ];
    for (k, run) in cases.iter().enumerate() {
        for bin_s in [0.0, 1.0, 100.0, 1000.0] {
            let online = super::report(run, bin_s);
            let reference = report(run, bin_s);
            same(&online, &reference);
            if k < 2 {
                assert!(online.segments.len() >= 3, "case {k} has holds and ramps");
                assert!(online.binned.bins > 0);
            }
        }
        let seg = super::segment_table(run);
        assert_eq!(seg.len(), segment_table(run).len());
    }
}
