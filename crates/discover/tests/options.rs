//! Diagnosis thresholds are range-checked before any work: a NaN threshold compares false
//! everywhere and would silently flip the verdict.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic, missing_docs)]

use tcomp_discover::DiagnoseOptions;

#[test]
fn nan_negative_and_huge_thresholds_are_refused_by_flag() {
    assert!(DiagnoseOptions::default().validate().is_ok());
    for v in [f64::NAN, f64::INFINITY, -1.0, 1e9] {
        let mut o = DiagnoseOptions::default();
        o.criterion.min_delta_log_evidence = v;
        let e = o.validate().unwrap_err().to_string();
        assert!(e.contains("--min-evidence"), "{e}");
        let mut o = DiagnoseOptions::default();
        o.criterion.min_improvement_pct = v;
        let e = o.validate().unwrap_err().to_string();
        assert!(e.contains("--min-improvement"), "{e}");
    }
    for v in [f64::NAN, 0.0, -60.0, 1e300] {
        let mut o = DiagnoseOptions::default();
        o.score.bin_s = v;
        let e = o.validate().unwrap_err().to_string();
        assert!(e.contains("--bin"), "{e}");
    }
    let mut o = DiagnoseOptions::default();
    o.score.folds = 1;
    assert!(o.validate().unwrap_err().to_string().contains("folds"));
}
