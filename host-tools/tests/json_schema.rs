//! Every analysing command's `--json` against the one schema, `schema/tcomp-output.schema.json`:
//! the demo's files feed `fit`, `eval`, `diagnose`, `compare` and `report`, and the bursty LSM6DSM
//! record gives an `eval` whose 100 s bins hold no data. Besides the schema: every output names
//! its target and unit, no figure is written as `-0.0`, a residual that fell has a negative
//! `change_pct` everywhere, and the schema rejects an output that breaks the vocabulary.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic, missing_docs)]

use serde_json::Value;
use std::path::Path;
use std::process::Command;

fn tcomp(args: &[&str]) -> (String, Value) {
    let o = Command::new(env!("CARGO_BIN_EXE_tcomp"))
        .args(args)
        .output()
        .unwrap();
    assert!(
        o.status.success(),
        "tcomp {args:?}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    let text = String::from_utf8(o.stdout).unwrap();
    let v = serde_json::from_str(&text).unwrap_or_else(|e| panic!("{args:?}: {e}\n{text}"));
    (text, v)
}

fn validator() -> jsonschema::Validator {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../schema/tcomp-output.schema.json");
    let schema: Value = serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
    jsonschema::validator_for(&schema).unwrap()
}

fn assert_valid(v: &jsonschema::Validator, name: &str, text: &str, out: &Value) {
    let errors: Vec<String> = v
        .iter_errors(out)
        .map(|e| format!("{} at {}", e, e.instance_path()))
        .collect();
    assert!(errors.is_empty(), "{name}: {errors:#?}");
    assert!(
        !text.contains("-0.0,") && !text.contains("-0.0\n"),
        "{name}: -0.0 in\n{text}"
    );
}

#[test]
fn every_command_speaks_the_schema() {
    let schema = validator();
    let dir = tempfile::tempdir().unwrap();
    let demo = dir.path().join("demo");
    let p = |f: &str| demo.join(f).to_str().unwrap().to_string();
    let (text, out) = tcomp(&[
        "demo",
        "--seed",
        "3",
        "--step",
        "5",
        "--json",
        "--out",
        demo.to_str().unwrap(),
    ]);
    assert_valid(&schema, "demo", &text, &out);
    let mut outputs = vec![("demo", out)];
    let fitted = dir.path().join("fit.tcm");
    let runs: [(&str, Vec<String>); 5] = [
        (
            "fit",
            vec![
                "fit".into(),
                "--data".into(),
                p("train.csv"),
                "--target".into(),
                "gyro_dph".into(),
                "--reference".into(),
                "ref_dph".into(),
                "--feature".into(),
                "t_coil_c".into(),
                "--out".into(),
                fitted.to_str().unwrap().into(),
                "--quiet".into(),
                "--json".into(),
            ],
        ),
        (
            "eval",
            vec![
                "eval".into(),
                "--model".into(),
                p("before.tcm"),
                "--data".into(),
                p("verify.csv"),
                "--quiet".into(),
                "--json".into(),
            ],
        ),
        (
            "diagnose",
            vec![
                "diagnose".into(),
                "--model".into(),
                p("before.tcm"),
                "--data".into(),
                p("train.csv"),
                "--verify".into(),
                p("verify.csv"),
                "--rounds".into(),
                "2".into(),
                "--quiet".into(),
                "--json".into(),
            ],
        ),
        (
            "compare",
            vec![
                "compare".into(),
                p("before.tcm"),
                p("after.tcm"),
                "--data".into(),
                p("verify.csv"),
                "--quiet".into(),
                "--json".into(),
            ],
        ),
        (
            "report",
            vec![
                "report".into(),
                "--model".into(),
                p("before.tcm"),
                "--model".into(),
                p("after.tcm"),
                "--data".into(),
                p("train.csv"),
                "--verify".into(),
                p("verify.csv"),
                "--out".into(),
                dir.path().join("r.html").to_str().unwrap().into(),
                "--quiet".into(),
                "--json".into(),
            ],
        ),
    ];
    for (name, args) in &runs {
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let (text, out) = tcomp(&args);
        assert_valid(&schema, name, &text, &out);
        outputs.push((name, out));
    }
    for (name, out) in &outputs {
        assert_eq!(out["command"], *name);
        assert_eq!(out["subject"]["target"], "gyro_dph", "{name}");
        assert_eq!(out["subject"]["unit"], "deg/h", "{name}");
        assert!(
            out["subject"]["models"]
                .as_array()
                .is_some_and(|m| !m.is_empty()),
            "{name}"
        );
        assert!(out["subject"]["data"].is_string(), "{name}");
    }
    let get = |name: &str| &outputs.iter().find(|(n, _)| *n == name).unwrap().1;
    // One sign: the after-model's residual fell, so every change from before to after is negative.
    assert!(get("demo")["binned_change_pct"].as_f64().unwrap() < 0.0);
    assert!(get("compare")["binned_change_pct"].as_f64().unwrap() < 0.0);
    let eval = get("eval");
    assert_eq!(
        eval["change_pct"].as_f64().unwrap(),
        -eval["improvement_pct"].as_f64().unwrap()
    );
    let top = &get("diagnose")["candidates"][0];
    assert_eq!(top["passes"], true);
    assert!(top["change_pct"].as_f64().unwrap() < 0.0, "{top}");
    assert_eq!(get("report")["plots_without_data"], 0);

    // The schema is not vacuous.
    let mut broken = get("eval").clone();
    broken["subject"].as_object_mut().unwrap().remove("target");
    assert!(
        !schema.is_valid(&broken),
        "a subject without its target passed"
    );
    let mut broken = get("compare").clone();
    broken["a"]["binned"]["raw_std"] = Value::String("0.1".into());
    assert!(!schema.is_valid(&broken), "a figure as a string passed");
}

/// The bursty LSM6DSM record has no 100 s bin with enough samples: the binned figures are null,
/// the unit comes from the column name, and the output still speaks the schema.
#[test]
fn no_data_is_null() {
    let schema = validator();
    let data =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../data/realdata/lsm6dsm_tvac_cold_ramp.csv");
    let dir = tempfile::tempdir().unwrap();
    let model = dir.path().join("m.tcm");
    let (d, m) = (data.to_str().unwrap(), model.to_str().unwrap());
    let (text, fit) = tcomp(&[
        "fit",
        "--data",
        d,
        "--target",
        "gyro_z_rad_s",
        "--reference-value",
        "0",
        "--feature",
        "temp_lsm6dsm_C",
        "--average",
        "2",
        "--quiet",
        "--json",
        "--out",
        m,
    ]);
    assert_valid(&schema, "fit", &text, &fit);
    assert!(fit["train"]["binned"]["raw_std"].is_null(), "{text}");
    let (text, eval) = tcomp(&["eval", "--model", m, "--data", d, "--bin", "100", "--json"]);
    assert_valid(&schema, "eval", &text, &eval);
    assert_eq!(eval["subject"]["unit"], "rad/s");
    assert_eq!(eval["binned"]["bins"], 0);
    for k in ["raw_std", "residual_std", "change_pct"] {
        assert!(eval["binned"][k].is_null(), "binned.{k}: {text}");
    }
    assert!(eval["residual_std"].as_f64().unwrap() > 0.0);
}

/// `tcomp calibrate`'s `summary.json` (and its `--json`, the same text) speaks the schema, and the
/// schema rejects a summary whose shipped choice is not one of model, poly3, raw.
#[test]
fn calibrate_summary_speaks_the_schema() {
    let schema = validator();
    let spec = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../data/realdata/mems_thermal_cycle.calibrate.toml");
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("cal");
    let (text, v) = tcomp(&[
        "calibrate",
        spec.to_str().unwrap(),
        "--accept",
        "--quiet",
        "--json",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_valid(&schema, "calibrate", &text, &v);
    let file = std::fs::read_to_string(out.join("summary.json")).unwrap();
    assert_eq!(file.trim(), text.trim());
    assert_eq!(v["channels"].as_array().unwrap().len(), 6);
    // `tcomp image --json` on two of the blobs calibrate wrote, for the MEMS board.
    let board = Path::new(env!("CARGO_MANIFEST_DIR")).join("../firmware/descriptions/mems6.toml");
    let image = out.join("again.bin");
    let gx = format!("0={}", out.join("gyro_x_rad_s.tcm").display());
    let az = format!("5={}", out.join("acc_z_m_s2.tcm").display());
    let (text, img) = tcomp(&[
        "image",
        "--board",
        board.to_str().unwrap(),
        "--serial",
        "7",
        "--model",
        &gx,
        "--model",
        &az,
        "--json",
        "--out",
        image.to_str().unwrap(),
    ]);
    assert_valid(&schema, "image", &text, &img);
    assert_eq!(img["channels"].as_array().unwrap().len(), 2);
    assert_eq!(
        img["bytes"].as_u64().unwrap(),
        std::fs::metadata(&image).unwrap().len()
    );
    let mut broken = v.clone();
    broken["channels"][0]["shipped"] = "best".into();
    assert!(
        !schema.is_valid(&broken),
        "the schema must reject shipped = best"
    );
}

/// `tcomp calibrate --units`'s `fleet.json` (its `--json`) speaks the schema too.
#[test]
fn calibrate_fleet_speaks_the_schema() {
    let schema = validator();
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let dir = tempfile::tempdir().unwrap();
    let units = dir.path().join("units");
    let status = Command::new(env!("CARGO_BIN_EXE_tcomp"))
        .args([
            "simulate", "--preset", "qma", "--units", "6", "--step-s", "10", "--quiet",
        ])
        .arg("--out")
        .arg(&units)
        .status()
        .unwrap();
    assert!(status.success());
    let spec = root.join("examples/calibrate/fleet.calibrate.toml");
    let out = dir.path().join("cal");
    let (text, v) = tcomp(&[
        "calibrate",
        spec.to_str().unwrap(),
        "--units",
        units.to_str().unwrap(),
        "--no-diagnosis",
        "--json",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_valid(&schema, "calibrate --units", &text, &v);
    assert_eq!(v["fleet"]["units"], 6);
    let unit: Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("unit-0001/summary.json")).unwrap())
            .unwrap();
    assert_valid(&schema, "unit summary", "", &unit);
}
