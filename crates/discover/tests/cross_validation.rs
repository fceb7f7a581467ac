//! A production line's diagnosis (`tcomp calibrate`) leaves a flat parameter at the evidence's
//! maximum: with `ConfirmOptions::cross_validate` off no estimate is chosen by cross-validation,
//! and the same run diagnosed by default has some that are (so the switch is what changed them).
#![allow(clippy::unwrap_used, clippy::expect_used, missing_docs)]

mod support;
use support::*;
use tcomp_discover::param::ChosenBy;

/// How each estimated parameter was chosen, on the QMA preset's training run (the listed
/// effects, no verification run: as `tcomp calibrate` diagnoses a channel).
fn chosen_by(cross_validate: bool) -> Vec<ChosenBy> {
    let mut case = base_case(presets::preset("qma").unwrap().with_seed(0), &[]);
    case.compose = false;
    let mut opts = options(&case);
    opts.confirm.cross_validate = cross_validate;
    diagnosis(&case, false, &opts)
        .candidates
        .iter()
        .filter_map(|c| c.estimate.as_ref().map(|e| e.chosen_by))
        .collect()
}

#[test]
fn a_line_leaves_a_flat_parameter_at_the_evidence_maximum() {
    let by_default = chosen_by(true);
    assert!(
        by_default.contains(&ChosenBy::CrossValidation),
        "{by_default:?}"
    );
    let on_a_line = chosen_by(false);
    assert!(!on_a_line.is_empty());
    assert!(
        !on_a_line.contains(&ChosenBy::CrossValidation),
        "{on_a_line:?}"
    );
}
