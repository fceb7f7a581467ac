//! End to end: `tcomp fit`, `tcomp eval --json`, `tcomp inspect` of a good and a corrupt blob.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic, missing_docs)]

use std::process::Command;

fn tcomp(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_tcomp"))
        .args(args)
        .output()
        .unwrap()
}

/// Fails the test with the command's stderr unless it succeeded.
fn succeeded(out: &std::process::Output) {
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

#[test]
fn fit_eval_inspect() {
    let dir = tempfile::tempdir().unwrap();
    let csv = dir.path().join("run.csv");
    let mut s = String::from("time_s,t_coil_c,gyro_dph,ref_dph\n");
    for i in 0..4000 {
        let t = i as f64;
        let temp = 20.0 + 15.0 * (t / 700.0).sin();
        let noise = 0.01 * ((i * 7919 % 1000) as f64 / 1000.0 - 0.5);
        s.push_str(&format!(
            "{t},{temp},{},10\n",
            10.0 + 0.02 * temp + 1e-3 * temp * temp + noise
        ));
    }
    std::fs::write(&csv, s).unwrap();
    let model = dir.path().join("m.tcm");
    let (c, m) = (csv.to_str().unwrap(), model.to_str().unwrap());
    let out = tcomp(&[
        "fit",
        "--data",
        c,
        "--target",
        "gyro_dph",
        "--reference",
        "ref_dph",
        "--feature",
        "t_coil_c",
        "--feature",
        "rate(t_coil_c)",
        "--out",
        m,
    ]);
    succeeded(&out);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains("method      bayes") && text.contains("log evidence"),
        "{text}"
    );
    // --quiet: the same model, nothing on standard output
    let quiet = dir.path().join("quiet.tcm");
    let out = tcomp(&[
        "fit",
        "--data",
        c,
        "--target",
        "gyro_dph",
        "--reference",
        "ref_dph",
        "--feature",
        "t_coil_c",
        "--feature",
        "rate(t_coil_c)",
        "--out",
        quiet.to_str().unwrap(),
        "--quiet",
    ]);
    succeeded(&out);
    assert!(
        out.stdout.is_empty(),
        "{}",
        String::from_utf8_lossy(&out.stdout)
    );
    assert_eq!(std::fs::read(&quiet).unwrap(), std::fs::read(m).unwrap());

    let out = tcomp(&["eval", "--model", m, "--data", c, "--json", "--quiet"]);
    succeeded(&out);
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    for k in [
        "raw_std",
        "residual_std",
        "improvement_pct",
        "msd_before",
        "msd_after",
    ] {
        assert!(v[k].is_number(), "{k} missing: {v}");
    }
    for k in ["seconds", "raw_std", "residual_std", "improvement_pct"] {
        assert!(v["binned"][k].is_number(), "binned.{k} missing");
    }
    let segs = v["segments"].as_array().unwrap();
    assert!(!segs.is_empty());
    for k in ["kind", "start_s", "end_s", "raw_std", "residual_std"] {
        assert!(!segs[0][k].is_null(), "segments[].{k} missing");
    }
    assert!(v["improvement_pct"].as_f64().unwrap() > 90.0, "{v}");

    let out = tcomp(&["inspect", m]);
    assert!(out.status.success());
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains("valid tcomp model blob") && text.contains("rate(t_coil_c)"),
        "{text}"
    );

    let mut bytes = std::fs::read(&model).unwrap();
    let mid = bytes.len() / 2;
    bytes[mid] ^= 0x40;
    let bad = dir.path().join("bad.tcm");
    std::fs::write(&bad, bytes).unwrap();
    let out = tcomp(&["inspect", bad.to_str().unwrap()]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("bad.tcm") && err.contains("corrupt") && err.contains("checksum"),
        "{err}"
    );

    // a misspelled column fails with a suggestion and writes nothing
    let none = dir.path().join("none.tcm");
    let out = tcomp(&[
        "fit",
        "--data",
        c,
        "--target",
        "gyro_dps",
        "--feature",
        "t_coil_c",
        "--out",
        none.to_str().unwrap(),
        "--quiet",
    ]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("did you mean `gyro_dph`"), "{err}");
    assert!(!none.exists());
}

/// A model larger than the firmware holds: `fit` writes it with a warning naming what is too
/// large, and `image` refuses to pack it (a board would reject it at boot); a model that fits packs.
/// `--method mse --select ols` places its centers by orthogonal least squares and says so.
#[test]
fn image_refuses_a_model_the_firmware_cannot_hold() {
    let dir = tempfile::tempdir().unwrap();
    let csv = write_five_input_run(dir.path());
    let c = csv.to_str().unwrap();
    let big = dir.path().join("big.tcm");
    let small = dir.path().join("small.tcm");
    let image = dir.path().join("models.bin");
    let fit = |out: &std::path::Path, extra: &[&str]| {
        let mut args = vec![
            "fit",
            "--data",
            c,
            "--target",
            "gyro",
            "--reference-value",
            "0",
            "--average",
            "10",
            "--out",
            out.to_str().unwrap(),
        ];
        args.extend_from_slice(extra);
        tcomp(&args)
    };
    let five = [
        "--feature",
        "a",
        "--feature",
        "b",
        "--feature",
        "c",
        "--feature",
        "d",
        "--feature",
        "e",
    ];
    // A description whose channel 3 takes the small model (inputs a, b, c); the flight check
    // refuses the big one before the channel's own checks.
    let board = write_test_board(dir.path());
    let out = fit(&big, &five);
    succeeded(&out);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("does not fit the firmware: 5 features (the firmware holds 4)"),
        "{err}"
    );
    let out = tcomp(&[
        "image",
        "--board",
        &board,
        "--serial",
        "1",
        "--model",
        &format!("0={}", big.display()),
        "--out",
        image.to_str().unwrap(),
    ]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("5 features (the firmware holds 4)"), "{err}");
    assert!(!image.exists(), "nothing half-written");

    let out = fit(
        &small,
        &[
            "--feature",
            "a",
            "--feature",
            "b * c",
            "--method",
            "mse",
            "--select",
            "ols",
            "--centers",
            "12",
            "--axis",
            "x",
            "--unit",
            "V",
        ],
    );
    succeeded(&out);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains("12 (width") && text.contains("chosen by orthogonal least squares"),
        "{text}"
    );
    let out = tcomp(&[
        "image",
        "--board",
        &board,
        "--serial",
        "1",
        "--model",
        &format!("3={}", small.display()),
        "--out",
        image.to_str().unwrap(),
    ]);
    succeeded(&out);
    assert!(image.exists());
}

/// A 3000-row run whose `gyro` depends on five inputs (`a`–`e`), too many for the firmware.
fn write_five_input_run(dir: &std::path::Path) -> std::path::PathBuf {
    let csv = dir.join("run.csv");
    let mut s = String::from("time_s,a,b,c,d,e,gyro\n");
    for i in 0..3000 {
        let t = i as f64;
        let a = 20.0 + 15.0 * (t / 500.0).sin();
        let b = 20.0 + 10.0 * (t / 310.0).cos();
        let c = 5.0 * (t / 170.0).sin();
        let d = 3.0 * (t / 90.0).cos();
        let e = 2.0 * (t / 1300.0).sin();
        let noise = 0.01 * ((i * 7919 % 1000) as f64 / 1000.0 - 0.5);
        s.push_str(&format!(
            "{t},{a},{b},{c},{d},{e},{}\n",
            0.02 * a + 0.01 * b * c + 0.005 * d * e + noise
        ));
    }
    std::fs::write(&csv, s).unwrap();
    csv
}

/// A board description with channel 0 (input `a`) and channel 3 (inputs `a`, `b`, `c`).
fn write_test_board(dir: &std::path::Path) -> String {
    let board = dir.join("board.toml");
    std::fs::write(
        &board,
        r#"name = "test"
[[thermometer]]
name = "ta"
adc = 0
input = 0
type = "pt100"
[[thermometer]]
name = "tb"
adc = 0
input = 1
type = "pt100"
[[thermometer]]
name = "tc"
adc = 0
input = 2
type = "pt100"
[[channel]]
id = 0
name = "zero"
sensor = "other"
axis = "x"
unit = "V"
counter = 0
scale = 1.0
inputs = { a = "ta" }
[[channel]]
id = 3
name = "three"
sensor = "other"
axis = "x"
unit = "V"
counter = 3
scale = 1.0
inputs = { a = "ta", b = "tb", c = "tc" }
"#,
    )
    .unwrap();
    board.display().to_string()
}
