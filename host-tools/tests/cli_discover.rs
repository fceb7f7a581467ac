//! The discovery commands end to end through the binary: `tcomp demo` writes its files and tells the
//! error falling; `tcomp diagnose --json` on the demo's "before" model names the hidden Shupe term
//! with the keys scripts rely on, and on the "after" model says "none"; `tcomp compare` shows the fall.
#![allow(clippy::unwrap_used, clippy::expect_used, missing_docs)]

use std::process::Command;

fn tcomp(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_tcomp"))
        .args(args)
        .output()
        .expect("run tcomp")
}

#[test]
fn demo_then_diagnose_and_compare() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("demo");
    let o = tcomp(&["demo", "--out", out.to_str().unwrap()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(text.contains("Shupe-type"), "{text}");
    for f in [
        "train.csv",
        "verify.csv",
        "before.tcm",
        "after.tcm",
        "report.html",
    ] {
        assert!(out.join(f).exists(), "{f} missing");
    }
    let p = |f: &str| out.join(f).to_str().unwrap().to_string();

    let o = tcomp(&[
        "diagnose",
        "--model",
        &p("before.tcm"),
        "--data",
        &p("train.csv"),
        "--verify",
        &p("verify.csv"),
        "--json",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let j: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(j["verdict"], "missing_effect");
    let top = &j["candidates"][0];
    assert_eq!(top["expression"], "t_coil_c * rate(t_coil_c)");
    for key in [
        "effect",
        "delta_log_evidence",
        "residual_std_after",
        "improvement_pct",
    ] {
        assert!(!top[key].is_null(), "candidate key {key}");
    }
    assert!(j["segments"].as_array().is_some_and(|s| !s.is_empty()));

    let o = tcomp(&[
        "diagnose",
        "--model",
        &p("after.tcm"),
        "--data",
        &p("train.csv"),
        "--verify",
        &p("verify.csv"),
        "--json",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let j: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(
        j["verdict"], "none",
        "the model with the true physics must get none"
    );

    let o = tcomp(&[
        "compare",
        &p("before.tcm"),
        &p("after.tcm"),
        "--data",
        &p("verify.csv"),
        "--json",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let j: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let before = j["a"]["binned"]["residual_std"].as_f64().unwrap();
    let after = j["b"]["binned"]["residual_std"].as_f64().unwrap();
    assert!(after < 0.5 * before, "before {before}, after {after}");
    assert!(j["binned_change_pct"].as_f64().unwrap() < -50.0);
    assert!(j["segments"].as_array().is_some_and(|s| !s.is_empty()));
}

/// Every expression a diagnosis prints is accepted as it stands by `tcomp fit` (issue 15: a
/// single-temperature model whose cubic basis won was offered `rate(Tclamped, 240)`, an internal
/// signal `fit --feature` refuses). On the real MEMS cycle, trained on t < 3130 s, for a `poly3`
/// model and a one-feature `bayes` one, diagnosed in two rounds (`--rounds`, which also refits
/// with each confirmed candidate): each candidate's features refit through the binary. Also: the
/// model's training window comes from its blob — the rest of the file is the held-out run.
#[test]
fn every_expression_a_diagnosis_prints_fits() {
    let dir = tempfile::tempdir().unwrap();
    let data = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../data/realdata/mems_thermal_cycle.csv"
    );
    for (method, features) in [("poly3", vec!["temp_imu_C"]), ("bayes", vec!["temp_imu_C"])] {
        let model = dir.path().join(format!("{method}.tcm"));
        let mut args = vec![
            "fit",
            "--data",
            data,
            "--target",
            "gyro_z_rad_s",
            "--reference-value",
            "0",
            "--until",
            "3130",
            "--method",
            method,
            "--quiet",
            "--out",
        ];
        args.push(model.to_str().unwrap());
        for f in &features {
            args.extend(["--feature", f]);
        }
        let o = tcomp(&args);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let o = tcomp(&[
            "diagnose",
            "--model",
            model.to_str().unwrap(),
            "--data",
            data,
            "--rounds",
            "2",
            "--top",
            "50",
            "--json",
            "--quiet",
        ]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        let verify = v["base"]["heldout"].as_str().unwrap_or_default();
        assert!(verify.contains("[3130 s, inf s)"), "held out: {verify}");
        let rounds = v["rounds"].as_array().unwrap();
        let mut tried = 0;
        for round in rounds {
            let signals: Vec<String> =
                serde_json::from_value(round["model"]["signals"].clone()).unwrap();
            let base: Vec<String> =
                serde_json::from_value(round["model"]["features"].clone()).unwrap();
            for c in round["candidates"].as_array().unwrap() {
                let exprs: Vec<String> = serde_json::from_value(c["expressions"].clone()).unwrap();
                for e in exprs.iter().chain(&base) {
                    assert!(!e.contains("Tclamped"), "{method}: {e}");
                }
                let mut args: Vec<String> = [
                    "fit",
                    "--data",
                    data,
                    "--target",
                    "gyro_z_rad_s",
                    "--reference-value",
                    "0",
                    "--until",
                    "3130",
                    "--method",
                    "mse",
                    "--centers",
                    "4",
                    "--quiet",
                    "--out",
                ]
                .map(String::from)
                .to_vec();
                args.push(dir.path().join("check.tcm").to_str().unwrap().to_string());
                for s in &signals {
                    args.extend(["--signal".to_string(), s.clone()]);
                }
                for e in base.iter().chain(&exprs) {
                    args.extend(["--feature".to_string(), e.clone()]);
                }
                // A quick method (4 centres): what is checked is that fit takes the expressions.
                let refs: Vec<&str> = args.iter().map(String::as_str).collect();
                let o = tcomp(&refs);
                assert!(
                    o.status.success(),
                    "{method}: `{}` refused: {}",
                    exprs.join(", "),
                    String::from_utf8_lossy(&o.stderr)
                );
                tried += 1;
            }
        }
        assert!(tried > 3, "{method}: {tried} candidates");
    }
}
