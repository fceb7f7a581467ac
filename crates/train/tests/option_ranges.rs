//! Every numeric option is range-checked where it is resolved, with the flag and spec key named.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic, missing_docs)]

use std::sync::Mutex;
use tcomp_train::progress::{Progress, Unit};
use tcomp_train::{Dataset, FitOptions, Spec, fit, fit_with_progress};

fn data(rows: usize) -> Dataset {
    let mut s = String::from("time_s,t_coil_c,gyro_dph,ref_dph\n");
    for i in 0..rows {
        let t = i as f64;
        let temp = 20.0 + 10.0 * (t / 600.0).sin();
        s.push_str(&format!(
            "{t},{temp},{},0\n",
            0.01 * temp + 1e-4 * temp * temp
        ));
    }
    Dataset::from_reader("run.csv", s.as_bytes()).unwrap()
}

fn spec() -> Spec {
    let mut s = Spec::default();
    s.channel.target = Some("gyro_dph".into());
    s.run.reference = Some("ref_dph".into());
    s.features.feature = vec!["t_coil_c".into()];
    s
}

/// [`spec`] changed by `f`.
fn with(f: impl FnOnce(&mut Spec)) -> Spec {
    let mut s = spec();
    f(&mut s);
    s
}

fn refused(s: Spec, named: &[&str]) {
    let e = FitOptions::from_spec(&s).unwrap_err().to_string();
    for n in named {
        assert!(e.contains(n), "`{n}` not in: {e}");
    }
}

#[test]
fn nan_inf_zero_negative_and_huge_values_are_refused_by_name() {
    for a in [f64::NAN, f64::INFINITY, -1.0, 1e300] {
        refused(
            with(|s| {
                s.method.average = Some(a);
            }),
            &["--average", "spec key `average`", "between 0 and"],
        );
    }
    for v in [f64::NAN, f64::INFINITY, -1e300] {
        refused(
            with(|s| {
                s.run.reference_value = Some(v);
            }),
            &["--reference-value", "reference-value"],
        );
    }
    for m in ["mse", "gradient"] {
        refused(
            with(|s| {
                s.method.centers = Some(0);
                s.method.method = Some(m.into());
            }),
            &["--centers 0", "centers", &format!("--method {m}")],
        );
    }
    refused(
        with(|s| {
            s.method.centers = Some(1000);
        }),
        &["--centers 1000", "64"],
    );
    refused(
        with(|s| {
            s.method.settings.gradient.iterations = Some(0);
        }),
        &["--iterations 0"],
    );
    for g in [0.0, -5.0, f64::NAN] {
        refused(
            with(|s| {
                s.run.gap = Some(g);
            }),
            &["--gap"],
        );
    }
    refused(
        with(|s| {
            s.run.from = Some(f64::NAN);
        }),
        &["--from NaN", "spec key `from`"],
    );
    refused(
        with(|s| {
            s.run.from = Some(100.0);
            s.run.until = Some(50.0);
        }),
        &["--from 100", "--until 50", "empty window"],
    );
    // Bayes with no centers is its linear part alone: valid.
    assert!(
        FitOptions::from_spec(&with(|s| {
            s.method.centers = Some(0);
        }))
        .is_ok()
    );
}

#[test]
fn an_averaging_bin_shorter_than_the_sampling_step_is_refused() {
    let d = data(3000);
    // Within the table's range (at least 1 ms) but shorter than this run's 1 s step.
    let opts = FitOptions::from_spec(&with(|s| {
        s.method.average = Some(0.5);
    }))
    .unwrap();
    let e = fit(&d, &opts).unwrap_err().to_string();
    assert!(
        e.contains("--average") && e.contains("sampling step"),
        "{e}"
    );
}

#[test]
fn the_evaluators_bin_must_hold_samples_and_leave_two_bins() {
    let d = data(3000);
    let fitted = fit(&d, &FitOptions::from_spec(&spec()).unwrap()).unwrap();
    let bytes = fitted.model.to_bytes().unwrap();
    let model = tcomp_train::blob_io::decode("m.tcm".as_ref(), &bytes).unwrap();
    let roles = tcomp_train::Roles::of_model(&model);
    for bin in [1e-300, 0.0, -1.0, f64::NAN, 1e9] {
        let e = tcomp_train::evaluate(&model, &d, &roles, bin, None, None)
            .unwrap_err()
            .to_string();
        assert!(e.contains("--bin") && e.contains("sampling step"), "{e}");
    }
    assert!(tcomp_train::evaluate(&model, &d, &roles, 100.0, None, None).is_ok());
    let mut inf_ref = roles.clone();
    inf_ref.reference = None;
    inf_ref.reference_value = Some(f64::INFINITY);
    let e = tcomp_train::evaluate(&model, &d, &inf_ref, 100.0, None, None)
        .unwrap_err()
        .to_string();
    assert!(e.contains("--reference-value inf"), "{e}");
}

#[test]
fn a_fit_over_the_memory_budget_is_refused_with_an_averaging_suggestion() {
    let d = data(3000);
    let mut opts = FitOptions::from_spec(&with(|s| {
        s.method.average = Some(0.0);
        s.method.method = Some("mse".into());
        s.method.settings.mse.select = Some("ols".into());
    }))
    .unwrap();
    opts.memory_budget = 4_000_000;
    let e = fit(&d, &opts).unwrap_err().to_string();
    assert!(e.contains("memory") && e.contains("unaveraged"), "{e}");
    assert!(e.contains("--average "), "{e}");
    // The suggested bin fits the same budget.
    let a: f64 = e
        .split("--average ")
        .nth(1)
        .and_then(|r| r.split([',', ' ']).next())
        .and_then(|v| v.parse().ok())
        .unwrap_or_else(|| panic!("no number in {e}"));
    opts.average_s = Some(a);
    fit(&d, &opts).unwrap();
}

#[derive(Default)]
struct Recorder {
    tasks: Mutex<Vec<(String, u64, Unit)>>,
    last: Mutex<u64>,
}

impl Progress for Recorder {
    fn start(&self, what: &str, total: u64, unit: Unit) {
        self.tasks.lock().unwrap().push((what.into(), total, unit));
    }
    fn set(&self, done: u64) {
        *self.last.lock().unwrap() = done;
    }
    fn finish(&self) {}
}

#[test]
fn gradient_descent_reports_its_iterations() {
    let d = data(3000);
    let opts = FitOptions::from_spec(&with(|s| {
        s.method.method = Some("gradient".into());
        s.method.settings.gradient.iterations = Some(25);
        s.method.centers = Some(4);
    }))
    .unwrap();
    let rec = Recorder::default();
    fit_with_progress(&d, &opts, &rec).unwrap();
    let tasks = rec.tasks.lock().unwrap();
    assert!(
        tasks
            .iter()
            .any(|(_, total, unit)| *total == 25 && *unit == Unit::Iterations),
        "{tasks:?}"
    );
}
