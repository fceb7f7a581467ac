//! A production line's diagnosis (`tcomp calibrate`) leaves a flat parameter at the evidence's
//! maximum: `ConfirmOptions::cross_validate` off, no estimate is chosen by cross-validation,
//! and the same run diagnosed by default is (so the switch is what changed it).
#![allow(clippy::unwrap_used, clippy::expect_used, missing_docs)]

use tcomp_demo::simulated;
use tcomp_discover::param::ChosenBy;
use tcomp_discover::{DiagnoseOptions, diagnose};
use tcomp_sim::presets;
use tcomp_train::FitOptions;

fn chosen_by(seed: u64, cross_validate: bool) -> Vec<ChosenBy> {
    let sim = simulated(&presets::preset("qma").unwrap().with_seed(seed)).unwrap();
    let truth = &sim.train_truth;
    let feats: Vec<&str> = truth
        .true_features
        .features
        .iter()
        .map(String::as_str)
        .collect();
    let mut o = FitOptions::new(&truth.columns.target, &feats);
    o.reference = Some(truth.columns.reference.clone());
    let fitted = tcomp_train::fit(&sim.train, &o).unwrap();
    let bytes = fitted.model.to_bytes().unwrap();
    let model = tcomp_train::blob_io::decode("m.tcm".as_ref(), &bytes).unwrap();
    let mut opts = DiagnoseOptions {
        compose: false,
        ..DiagnoseOptions::default()
    };
    opts.confirm.cross_validate = cross_validate;
    let a = diagnose(&model, &sim.train, None, &opts).unwrap();
    a.diagnosis
        .candidates
        .iter()
        .filter_map(|c| c.estimate.as_ref().map(|e| e.chosen_by))
        .collect()
}

#[test]
fn a_line_leaves_a_flat_parameter_at_the_evidence_maximum() {
    let by_default = chosen_by(0, true);
    assert!(
        by_default.contains(&ChosenBy::CrossValidation),
        "{by_default:?}"
    );
    let on_a_line = chosen_by(0, false);
    assert!(!on_a_line.is_empty());
    assert!(
        !on_a_line.contains(&ChosenBy::CrossValidation),
        "{on_a_line:?}"
    );
}
