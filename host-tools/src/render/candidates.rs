//! The candidate table: which effects could be missing, how much evidence each carries, and what
//! the held-out residual becomes with it.
//!
//! One function in two layouts: `diagnose` prints columns an engineer scans (with the expressions to
//! paste), the demo prints a narrative line per candidate (before → after in the model's unit).
//! Both take the same rows in the same order and mark a candidate that passes the criterion the
//! same way, and both write the held-out change the same way: negative when the residual fell.
//! The columns show each refitted candidate against its placebos ([`tcomp_discover::placebo`]).

use super::num::{change_pct, num, pct};
use std::fmt::Write as _;
use tcomp_discover::score::Scored;

/// How the table is laid out.
#[derive(Clone, Copy, Debug)]
pub enum Layout<'a> {
    /// A header and one row of columns per candidate, with its expressions (`tcomp diagnose`).
    Columns {
        /// The model's output unit.
        unit: &'a str,
    },
    /// One indented sentence per candidate: held-out before → after in `unit` (`tcomp demo`).
    Narrative {
        /// The model's output unit.
        unit: &'a str,
    },
}

/// The candidate's Δ log evidence under AR(1) noise against the best placebo's ("—" when it was
/// not tested): `+7.2 > +3.1` passes the placebo leg, `+1.0 ≤ +3.1` does not.
pub fn placebo(c: &Scored) -> String {
    c.placebo.as_ref().map_or_else(
        || "—".to_string(),
        |p| {
            format!(
                "{:+.1} {} {:+.1}",
                p.statistic,
                if p.passes() { ">" } else { "≤" },
                p.threshold
            )
        },
    )
}

/// Width of the effect column of [`Layout::Columns`]: a longer name wraps inside it, so the row's
/// figures stay where the header puts them and the table fits a 100-column page.
pub const EFFECT_WIDTH: usize = 40;

/// Indent of a row's continuation lines (the rest of its effect, then its expressions).
const CONTINUATION: &str = "       ";

/// Appends the first `top` candidates of `candidates` (best first) to `out`.
///
/// In [`Layout::Columns`] a row is its effect wrapped to [`EFFECT_WIDTH`] with the figures beside
/// its first line, then the expressions to paste on a line of their own after `= `: a table one
/// page wide, whose held-out column a long name (a composition, two effects named together) never
/// pushes off the page.
pub fn table(out: &mut String, candidates: &[Scored], top: usize, layout: Layout<'_>) {
    if let Layout::Columns { .. } = layout {
        let _ = writeln!(
            out,
            "  {:<3}{:<w$} {:>8} {:>13} {:>8}  {:<7} {:>13}",
            "",
            "effect",
            "Δ ln E",
            "held-out",
            "change",
            "from",
            "AR(1)/placebo",
            w = EFFECT_WIDTH
        );
    }
    for c in candidates.iter().take(top) {
        let refitted = c.confirmation.is_some();
        match layout {
            Layout::Columns { unit } => {
                let lines = textwrap::wrap(&c.effect, EFFECT_WIDTH);
                let first = lines.first().map_or("", |l| l.as_ref());
                let _ = writeln!(
                    out,
                    "  {:<3}{:<w$} {:>+8.1} {:>13} {:>8}  {:<7} {:>13}",
                    if c.passes { "✔" } else { "" },
                    first,
                    c.delta_log_evidence,
                    num(c.residual_std_after, unit),
                    pct(change_pct(c.residual_std_before, c.residual_std_after)),
                    if refitted { "refit" } else { "scoring" },
                    placebo(c),
                    w = EFFECT_WIDTH
                );
                for l in lines.iter().skip(1) {
                    let _ = writeln!(out, "{CONTINUATION}{l}");
                }
                let _ = writeln!(out, "{CONTINUATION}= {}", c.expressions.join(" ; "));
            }
            Layout::Narrative { unit } => {
                let _ = writeln!(
                    out,
                    "   {} {:<52} Δ log evidence {:+8.1}   held-out {} → {} ({}){}",
                    if c.passes { "✔" } else { " " },
                    c.effect,
                    c.delta_log_evidence,
                    num(c.residual_std_before, ""),
                    num(c.residual_std_after, unit),
                    pct(change_pct(c.residual_std_before, c.residual_std_after)),
                    if refitted {
                        ", refitted"
                    } else {
                        ", scoring estimate"
                    }
                );
            }
        }
    }
}
