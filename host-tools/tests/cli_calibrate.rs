//! `tcomp calibrate SPEC --out DIR` on the real MEMS thermal cycle (the repository's spec: split at
//! 3130 s, six channels, feature `temp_imu_C`): `summary.json` holds six channels, each with its
//! held-out figures, and no shipped channel is worse than raw there; the image holds a model for
//! each channel that does not ship raw; a bad spec is refused with its file, line and column and
//! nothing is written; `--accept` reports before and after.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic, missing_docs)]

use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

fn tcomp(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_tcomp"))
        .args(args)
        .output()
        .unwrap()
}

fn mems_spec() -> String {
    root()
        .join("data/realdata/mems_thermal_cycle.calibrate.toml")
        .display()
        .to_string()
}

#[test]
fn the_mems_cycle_in_one_command() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("cal");
    let o = tcomp(&[
        "calibrate",
        &mems_spec(),
        "--quiet",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let s: Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(s["command"], "calibrate");
    let channels = s["channels"].as_array().unwrap();
    assert_eq!(channels.len(), 6);
    let mut raw_shipped = 0;
    for c in channels {
        let name = c["name"].as_str().unwrap();
        let h = &c["heldout"];
        let raw = h["raw_rms"].as_f64().unwrap();
        let res = h["residual_rms"].as_f64().unwrap();
        let (model, poly3) = (
            h["model_rms"].as_f64().unwrap(),
            h["poly3_rms"].as_f64().unwrap(),
        );
        assert!(res <= raw, "{name}: ships {res} > raw {raw}");
        assert!(h["rows"].as_u64().unwrap() > 1000, "{name}: {h}");
        assert!(h["from_s"].as_f64().unwrap() >= 3130.0, "{name}: {h}");
        assert!(c["train"]["until_s"].as_f64().unwrap() < 3130.0, "{name}");
        let shipped = c["shipped"].as_str().unwrap();
        let expect = match shipped {
            "model" => model,
            "poly3" => poly3,
            "raw" => raw,
            other => panic!("{name}: shipped {other}"),
        };
        assert_eq!(res, expect, "{name}");
        // A model worse than raw or poly3 on the held-out run is flagged, and then not shipped.
        let worse = model > raw || model > poly3;
        assert_eq!(!c["flags"].as_array().unwrap().is_empty(), worse, "{name}");
        if worse {
            assert_ne!(shipped, "model", "{name}");
        }
        assert!(
            (h["change_pct"].as_f64().unwrap() - 100.0 * (res / raw - 1.0)).abs() < 1e-9,
            "{name}"
        );
        assert!(c["diagnosis"]["verdict"].is_string(), "{name}");
        assert!(out.join(c["model_file"].as_str().unwrap()).is_file());
        raw_shipped += usize::from(shipped == "raw");
    }
    assert!(s["gate_note"].as_str().unwrap().contains("not an unbiased"));
    // The image: one model per channel that does not ship raw.
    let o = tcomp(&["inspect", out.join("image.bin").to_str().unwrap()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(
        text.contains(&format!("{} models", 6 - raw_shipped)),
        "{text}"
    );
    let html = std::fs::read_to_string(out.join("report.html")).unwrap();
    assert!(html.contains("Overview") && html.contains("verification gate"));
}

/// The MEMS spec with `edit` applied, written into `dir` with its paths made absolute.
fn spec_in(dir: &Path, edit: impl Fn(String) -> String) -> PathBuf {
    let text = std::fs::read_to_string(mems_spec()).unwrap();
    let text = text
        .replace(
            "\"mems_thermal_cycle.csv\"",
            &format!("{:?}", root().join("data/realdata/mems_thermal_cycle.csv")),
        )
        .replace(
            "\"../../firmware",
            &format!("\"{}/firmware", root().display()),
        );
    let edited = edit(text.clone());
    assert_ne!(edited, text, "the edit applies");
    let spec = dir.join("s.calibrate.toml");
    std::fs::write(&spec, edited).unwrap();
    spec
}

#[test]
fn a_bad_spec_names_file_line_and_column_and_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("cal");
    let spec = spec_in(dir.path(), |t| {
        t.replace("id = 4 }", "id = 4, featuer = [\"x\"] }")
    });
    let o = tcomp(&[
        "calibrate",
        spec.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("s.calibrate.toml: line 6, column 36") && err.contains("`featuer`"),
        "{err}"
    );
    assert!(!out.exists(), "nothing written");
    // A channel id the board does not have.
    let spec = spec_in(dir.path(), |t| t.replace("id = 5 }", "id = 9 }"));
    let o = tcomp(&[
        "calibrate",
        spec.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("id 9 is not in"), "{err}");
    assert!(!out.exists(), "nothing written");
}

/// `--accept`: each channel whose diagnosis (on the training run) confirmed an effect is refitted
/// with it; the summary and the report carry before and after.
#[test]
fn accept_reports_before_and_after() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("cal");
    let o = tcomp(&[
        "calibrate",
        &mems_spec(),
        "--quiet",
        "--accept",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let s: Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let mut accepted = 0;
    for c in s["channels"].as_array().unwrap() {
        let confirmed = c["diagnosis"]["verdict"] == "missing_effect";
        let a = &c["accepted"];
        assert_eq!(!a.is_null(), confirmed, "{c}");
        if confirmed {
            accepted += 1;
            assert!(
                a["instruction"].as_str().unwrap().starts_with("add")
                    || a["instruction"].as_str().unwrap().starts_with("replace")
            );
            assert_eq!(a["after_rms"], c["heldout"]["model_rms"]);
            assert!(out.join(a["before_file"].as_str().unwrap()).is_file());
        }
    }
    assert!(
        accepted > 0,
        "the MEMS cycle's diagnosis confirms a lag on some channel"
    );
    let html = std::fs::read_to_string(out.join("report.html")).unwrap();
    assert!(html.contains("before --accept"));
}

/// A production line of 20 simulated units with 4 planted outliers (two with doubled polynomial
/// coefficients, two with ten times the noise): `--units` calibrates each into its own folder with
/// its own image, and the fleet names exactly the planted units.
#[test]
fn a_fleet_names_its_planted_outliers() {
    let dir = tempfile::tempdir().unwrap();
    let units = dir.path().join("units");
    let o = tcomp(&[
        "simulate",
        "--preset",
        "qma",
        "--units",
        "20",
        "--outliers",
        "4",
        "--step-s",
        "5",
        "--quiet",
        "--out",
        units.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let truth: Value =
        serde_json::from_str(&std::fs::read_to_string(units.join("fleet-truth.json")).unwrap())
            .unwrap();
    let mut planted: Vec<String> = truth["outliers"]
        .as_array()
        .unwrap()
        .iter()
        .map(|p| p["unit"].as_str().unwrap().to_string())
        .collect();
    planted.sort();
    assert_eq!(planted.len(), 4);
    let spec = root().join("examples/calibrate/fleet.calibrate.toml");
    let out = dir.path().join("cal");
    let o = tcomp(&[
        "calibrate",
        spec.to_str().unwrap(),
        "--units",
        units.to_str().unwrap(),
        "--no-diagnosis",
        "--json",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: Value = serde_json::from_slice(&o.stdout).unwrap();
    let fleet = &v["fleet"];
    assert_eq!(fleet["units"], 20);
    let named: Vec<String> = fleet["outlier_units"]
        .as_array()
        .unwrap()
        .iter()
        .map(|u| u.as_str().unwrap().to_string())
        .collect();
    assert_eq!(named, planted, "{}", fleet["outliers"]);
    for p in &planted {
        assert!(out.join(p).join("image.bin").is_file(), "{p}: image");
        assert!(out.join(p).join("summary.json").is_file(), "{p}: summary");
    }
    let html = std::fs::read_to_string(out.join("fleet.html")).unwrap();
    for p in &planted {
        assert!(html.contains(p.as_str()), "{p} on the fleet page");
    }
    // The same line as Slurm array tasks (the example script as written, one task per unit),
    // then `--collect`: the same outliers.
    let script = root().join("examples/calibrate/slurm-array.sh");
    let batch = dir.path().join("batch");
    for task in 0..20 {
        let o = Command::new("bash")
            .arg(&script)
            .arg(&spec)
            .arg(&units)
            .arg(&batch)
            .env("SLURM_ARRAY_TASK_ID", task.to_string())
            .env("TCOMP", env!("CARGO_BIN_EXE_tcomp"))
            .output()
            .unwrap();
        assert!(
            o.status.success(),
            "task {task}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
    }
    let o = tcomp(&[
        "calibrate",
        spec.to_str().unwrap(),
        "--collect",
        batch.to_str().unwrap(),
        "--json",
        "--out",
        batch.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["fleet"]["units"], 20);
    assert_eq!(v["fleet"]["outlier_units"], fleet["outlier_units"]);
    assert!(batch.join("unit-0001/report.html").is_file());
}
