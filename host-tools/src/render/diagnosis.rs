//! The text of `tcomp diagnose`: where the model fails (segments and worst intervals, on the data
//! and on the verification run), the candidate table, the criterion and the verdict.

use super::candidates::{Layout, table};
use std::fmt::Write as _;
use tcomp_discover::Analysis;
use tcomp_discover::segments::{Interval, SegmentRow};

/// The human-readable diagnosis, with the first `top` candidates.
pub fn text(a: &Analysis, top: usize) -> String {
    let d = &a.diagnosis;
    let u = &d.model.unit;
    let mut s = String::new();
    let _ = writeln!(
        s,
        "model: {} ~ {}{}",
        d.model.target,
        d.model.features.join(", "),
        if d.model.signals.is_empty() {
            String::new()
        } else {
            format!("  (signals: {})", d.model.signals.join("; "))
        }
    );
    let _ = writeln!(s, "\nWhere it fails (residual of the model as given):");
    segments(&mut s, &d.segments, &d.worst_intervals, u);
    if !d.verify_segments.is_empty() {
        let _ = writeln!(s, "\nOn the verification run:");
        segments(&mut s, &d.verify_segments, &d.verify_worst_intervals, u);
    }
    let b = &d.base;
    let _ = writeln!(
        s,
        "\nCandidates ({} fits in {:.2} s; {} s bins; held-out: {}, {} s bins):",
        d.fits, d.elapsed_s, b.bin_s, b.heldout, b.heldout_bin_s
    );
    let _ = writeln!(
        s,
        "  held-out residual of the model's features {:.4e} {u} (refitted by the trainer: {:.4e} {u}); noise floor estimate {:.4e} {u}",
        b.heldout_residual_std, d.refit_residual_std_before, b.noise_floor_estimate
    );
    table(&mut s, &d.candidates, top, Layout::Columns);
    for k in &d.skipped {
        let _ = writeln!(s, "  skipped {}: {}", k.expression, k.reason);
    }
    let _ = writeln!(s, "\nCriterion: {}.", d.criterion);
    let _ = writeln!(s, "Verdict: {}", d.verdict_text);
    s
}

/// The segment table of one run and its worst intervals (residuals in `unit`).
fn segments(s: &mut String, rows: &[SegmentRow], worst: &[Interval], unit: &str) {
    let _ = writeln!(
        s,
        "  {:<24} {:>9} {:>9} {:>12} {:>12} {:>12}",
        "segment", "start s", "end s", "raw std", "resid std", "resid mean"
    );
    for r in rows {
        let _ = writeln!(
            s,
            "  {:<24} {:>9.0} {:>9.0} {:>12.4e} {:>12.4e} {:>+12.4e}",
            r.label, r.start_s, r.end_s, r.raw_std, r.residual_std, r.residual_mean
        );
    }
    let _ = writeln!(s, "  worst intervals:");
    for w in worst {
        let _ = writeln!(
            s,
            "    {:>7.0}–{:<7.0} s  mean residual {:+.4e} {unit}  at {:.1}° {:+.2}°/min  {}",
            w.start_s, w.end_s, w.residual_mean, w.temperature, w.rate_per_min, w.during
        );
    }
}
