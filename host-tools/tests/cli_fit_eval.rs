//! End to end: `tcomp fit`, `tcomp eval --json`, `tcomp inspect` of a good and a corrupt blob.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic, missing_docs)]

use std::process::Command;

fn tcomp(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_tcomp"))
        .args(args)
        .output()
        .unwrap()
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
        "--quiet",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains("method      bayes") && text.contains("log evidence"),
        "{text}"
    );

    let out = tcomp(&["eval", "--model", m, "--data", c, "--json", "--quiet"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
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
