//! The printed table of `tcomp calibrate`: one line per channel with the held-out RMS of raw,
//! poly3 and the model, what ships and the change it brings, then every flag in capitals.

use super::unit::UnitResult;
use crate::output::json;
use crate::render::num::{num, pct};
use std::fmt::Write as _;

/// The table as text.
pub fn text(u: &UnitResult) -> String {
    let mut t = String::new();
    let _ = writeln!(
        t,
        "{:<16} {:>14} {:>14} {:>14} {:>8} {:>14} {:>9}  status",
        "channel", "raw rms", "poly3 rms", "model rms", "ships", "residual rms", "change"
    );
    let n = |v: Option<f64>, unit: &str| v.map_or_else(|| "no data".into(), |v| num(v, unit));
    for c in &u.channels {
        let unit = crate::output::printable::text(&c.unit);
        let f = &c.model.figures;
        let status = if c.choice.flags.is_empty() {
            "ok".to_string()
        } else {
            format!("FLAGGED ({} flag(s))", c.choice.flags.len())
        };
        let _ = writeln!(
            t,
            "{:<16} {:>14} {:>14} {:>14} {:>8} {:>14} {:>9}  {status}",
            crate::output::printable::text(&c.plan.name),
            n(f.raw_rms, &unit),
            n(c.poly3.figures.residual_rms, &unit),
            n(f.residual_rms, &unit),
            c.choice.shipped.name(),
            n(c.choice.residual_rms, &unit),
            pct(json::change(f.raw_rms, c.choice.residual_rms)),
        );
    }
    for c in &u.channels {
        for fl in &c.choice.flags {
            let _ = writeln!(
                t,
                "!! {}: {fl}; ships {}: {}",
                c.plan.name,
                c.choice.shipped.name(),
                c.choice.reason
            );
        }
        if let Some(a) = &c.accepted {
            let _ = writeln!(
                t,
                "accepted {}: {} (held-out model rms {} → {})",
                c.plan.name,
                a.instruction,
                n(a.before.figures.residual_rms, &c.unit),
                n(c.model.figures.residual_rms, &c.unit)
            );
        }
    }
    let _ = writeln!(
        t,
        "held-out RMS against the reference; what ships is chosen on the held-out run (a \
         verification gate), so its figure is optimistic: see report.html"
    );
    t
}
