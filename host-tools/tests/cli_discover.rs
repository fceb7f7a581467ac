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
