//! `tcomp simulate` with a bad option or scenario leaves an existing output directory untouched,
//! and names the option as typed (negative numbers after a space reach the range check).
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic, missing_docs)]

use std::process::Command;

const SENTINEL: &str = "time_s,x\n0,precious\n";

#[test]
fn failing_runs_never_damage_an_existing_train_csv() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run");
    std::fs::create_dir(&out).unwrap();
    std::fs::write(out.join("train.csv"), SENTINEL).unwrap();
    let bad_toml = dir.path().join("bad.toml");
    std::fs::write(&bad_toml, "[sensor]\nkind = \"ifog\"\n[profile]\nstart_c = 20\nsegments = [{ kind = \"hold\", duration_s = -5 }]\n").unwrap();
    let o = out.to_str().unwrap();
    let cases: Vec<(Vec<&str>, &str)> = vec![
        (vec!["--preset", "qma", "--rate-hz", "0"], "--rate-hz"),
        (vec!["--preset", "qma", "--rate-hz", "-1"], "--rate-hz"),
        (vec!["--preset", "qma", "--rate-hz", "nan"], "--rate-hz"),
        (vec!["--preset", "qma", "--rate-hz", "1e9"], "--rate-hz"),
        (vec!["--preset", "qma", "--step-s", "0"], "--step-s"),
        (vec!["--preset", "qma", "--step-s", "-1"], "--step-s"),
        (vec!["--preset", "qma", "--step-s", "1e6"], "--step-s"),
        (vec!["--scenario", bad_toml.to_str().unwrap()], "duration_s"),
    ];
    for (args, named) in cases {
        let run = Command::new(env!("CARGO_BIN_EXE_tcomp"))
            .arg("simulate")
            .args(&args)
            .args(["--out", o, "--quiet"])
            .env("RUST_BACKTRACE", "0")
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&run.stderr);
        assert!(!run.status.success(), "{args:?} succeeded");
        assert!(err.contains(named), "{args:?}: {err}");
        assert_eq!(
            std::fs::read_to_string(out.join("train.csv")).unwrap(),
            SENTINEL,
            "{args:?} changed train.csv"
        );
        let names: Vec<_> = std::fs::read_dir(&out).unwrap().collect();
        assert_eq!(names.len(), 1, "{args:?} left files behind");
    }
}
