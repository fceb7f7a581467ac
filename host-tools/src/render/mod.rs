//! Rendering of what the analysis found: the text tables the commands print and the HTML report.
//!
//! Why one module: `diagnose`, `demo` and `report` show the same things (candidates, segments,
//! verdict); each is written here once, so a change of column or wording reaches every command.
//! The analysis crate (`tcomp-discover`) only computes; nothing here decides anything.
//!
//! [`candidates`] is the candidate table, [`diagnosis`] the text of `tcomp diagnose`, [`html`] the
//! self-contained report of `tcomp report` and `tcomp demo`.

pub mod candidates;
pub mod diagnosis;
pub mod html;
pub use tcomp_train::num;
