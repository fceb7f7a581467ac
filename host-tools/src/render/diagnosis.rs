//! The text of `tcomp diagnose`: where the model fails (segments and worst intervals, on the data
//! and on the verification run), the candidate table, the criterion and the verdict.

use super::candidates::{Layout, table};
use super::num::{num, plain, signed};
use std::fmt::Write as _;
use tcomp_discover::Analysis;
use tcomp_discover::segments::{Interval, SegmentRow};

/// The human-readable diagnosis, with the first `top` candidates.
pub fn text(a: &Analysis, top: usize) -> String {
    let d = &a.diagnosis;
    let u = &super::num::unit_or_column(&d.model.unit, &d.model.target);
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
        "  held-out residual of the model's features {} (refitted by the trainer: {}); noise floor estimate {}",
        num(b.heldout_residual_std, u),
        num(d.refit_residual_std_before, u),
        num(b.noise_floor_estimate, u)
    );
    table(&mut s, &d.candidates, top, Layout::Columns { unit: u });
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
        "  {:<24} {:>15} {:>16} {:>16} {:>16}",
        "segment", "when (min)", "raw std", "resid std", "resid mean"
    );
    for r in rows {
        let when = if r.kind == "band" {
            "spread".to_string()
        } else {
            format!(
                "{}–{}",
                plain(r.start_s / 60.0, 3),
                plain(r.end_s / 60.0, 3)
            )
        };
        let _ = writeln!(
            s,
            "  {:<24} {:>15} {:>16} {:>16} {:>16}",
            r.label,
            when,
            num(r.raw_std, unit),
            num(r.residual_std, unit),
            num(r.residual_mean, unit)
        );
    }
    let _ = writeln!(s, "  worst intervals:");
    for w in worst {
        let _ = writeln!(
            s,
            "    {:>16}  mean residual {}  at {}° {}°/min  {}",
            format!(
                "{}–{} min",
                plain(w.start_s / 60.0, 3),
                plain(w.end_s / 60.0, 3)
            ),
            num(w.residual_mean, unit),
            plain(w.temperature, 3),
            signed(w.rate_per_min, 2),
            w.during
        );
    }
}
