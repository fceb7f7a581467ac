//! `tcomp image --board` and `tcomp inspect IMAGE` with the shipped board descriptions and six MEMS
//! models fitted on the real recording: the wrong channel, a repeated channel and the MEMS models
//! on the RLG/QMA board are refused (exit ≠ 0, the message names the channel, nothing written);
//! the same models on the MEMS board succeed and `inspect` lists six channels, each with its model.
//! Units are parsed, not compared as text: accelerometer models fitted with `--unit m/s2` and
//! `--unit "m s-2"` pack into the same image, byte for byte, as those fitted with `m/s^2` (the
//! board's spelling); a gyro fitted in `deg/s` on the `rad/s` channel is refused with the factor.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic, missing_docs)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::sync::OnceLock;

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

fn board(name: &str) -> String {
    root()
        .join("firmware/descriptions")
        .join(name)
        .display()
        .to_string()
}

fn tcomp(dir: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_tcomp"))
        .current_dir(dir)
        .args(args)
        .output()
        .unwrap()
}

/// `tcomp fit` of one MEMS channel of the real recording (before 3130 s) into `dir/out`.
fn fit_channel(dir: &Path, col: &str, sensor: &str, ax: &str, unit: &str, out: &str) {
    let data = root().join("data/realdata/mems_thermal_cycle.csv");
    let o = tcomp(
        dir,
        &[
            "fit",
            "--data",
            data.to_str().unwrap(),
            "--target",
            col,
            "--reference-value",
            "0",
            "--feature",
            "temp_imu_C",
            "--sensor",
            sensor,
            "--axis",
            ax,
            "--unit",
            unit,
            "--until",
            "3130",
            "--out",
            out,
        ],
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
}

/// A directory with the six MEMS models (`gx.tcm` … `az.tcm`), fitted once per test process on
/// the real MEMS cycle before 3130 s.
fn models() -> &'static Path {
    static DIR: OnceLock<tempfile::TempDir> = OnceLock::new();
    DIR.get_or_init(|| {
        let dir = tempfile::tempdir().unwrap();
        for ax in ["x", "y", "z"] {
            let (g, a) = (format!("gyro_{ax}_rad_s"), format!("acc_{ax}_m_s2"));
            fit_channel(
                dir.path(),
                &g,
                "mems-gyro",
                ax,
                "rad/s",
                &format!("g{ax}.tcm"),
            );
            fit_channel(
                dir.path(),
                &a,
                "mems-accel",
                ax,
                "m/s^2",
                &format!("a{ax}.tcm"),
            );
        }
        dir
    })
    .path()
}

const SIX: [&str; 12] = [
    "--model", "0=gx.tcm", "--model", "1=gy.tcm", "--model", "2=gz.tcm", "--model", "3=ax.tcm",
    "--model", "4=ay.tcm", "--model", "5=az.tcm",
];

fn image(board_file: &str, extra: &[&str], out: &str) -> Output {
    let b = board(board_file);
    let mut args = vec![
        "image",
        "--board",
        &b,
        "--serial",
        "0x5EED",
        "--created",
        "1763900000",
    ];
    args.extend_from_slice(&SIX);
    args.extend_from_slice(extra);
    args.extend_from_slice(&["--out", out]);
    tcomp(models(), &args)
}

fn refused(o: &Output, out: &str, says: &[&str]) {
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "stderr: {err}");
    assert!(err.starts_with("error: "), "{err}");
    for s in says {
        assert!(err.contains(s), "`{s}` not in: {err}");
    }
    assert!(!models().join(out).exists(), "{out} was written");
}

#[test]
fn channel_99_is_refused() {
    let o = image("mems6.toml", &["--model", "99=gx.tcm"], "c99.bin");
    refused(
        &o,
        "c99.bin",
        &["--model 99=gx.tcm", "channel 99", "mems6.toml"],
    );
}

#[test]
fn a_duplicate_channel_is_refused() {
    let o = image("mems6.toml", &["--model", "2=gz.tcm"], "dup.bin");
    refused(
        &o,
        "dup.bin",
        &["--model 2=gz.tcm", "channel 2 is given twice"],
    );
}

#[test]
fn mems_models_on_the_rlg_board_are_refused() {
    let o = image("imu6-rlg-qma.toml", &[], "rlg.bin");
    refused(
        &o,
        "rlg.bin",
        &["--model 0=gx.tcm", "channel 0 (rlg-x)", "Rlg", "MemsGyro"],
    );
}

#[test]
fn a_model_whose_input_has_no_thermometer_is_refused() {
    // The IFOG triad's channels have the same sensor kind and unit as no MEMS model, so check the
    // input on a board of our own: the MEMS board with its die thermometer renamed.
    let text = std::fs::read_to_string(board("mems6.toml")).unwrap();
    let renamed = text.replace("temp_imu_C = ", "t_die_c = ");
    let path = models().join("renamed.toml");
    std::fs::write(&path, renamed).unwrap();
    let mut args = vec!["image", "--board", "renamed.toml", "--serial", "1"];
    args.extend_from_slice(&SIX);
    args.extend_from_slice(&["--out", "renamed.bin"]);
    let o = tcomp(models(), &args);
    refused(
        &o,
        "renamed.bin",
        &["channel 0 (gyro-x)", "`temp_imu_C`", "t_die_c"],
    );
}

#[test]
fn a_model_for_another_axis_or_unit_is_refused() {
    let mut args = vec!["image", "--board"];
    let b = board("mems6.toml");
    args.extend_from_slice(&[
        &b, "--serial", "1", "--model", "1=gx.tcm", "--out", "ax.bin",
    ]);
    let o = tcomp(models(), &args);
    refused(&o, "ax.bin", &["channel 1 (gyro-y)", "axis \"y\"", "\"x\""]);
}

#[test]
fn the_mems_board_takes_them_and_inspect_lists_six_channels() {
    let out = "mems.bin";
    let o = image("mems6.toml", &[], out);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let bytes = std::fs::read(models().join(out)).unwrap();
    // Reproducible with a pinned creation time.
    let o = image("mems6.toml", &[], "again.bin");
    assert!(o.status.success());
    assert_eq!(std::fs::read(models().join("again.bin")).unwrap(), bytes);

    let o = tcomp(models(), &["inspect", out, "--json"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["version"], 2);
    assert_eq!(v["header"]["serial"], 0x5EED);
    assert_eq!(v["header"]["created"], 1_763_900_000u64);
    let channels = v["channels"].as_array().unwrap();
    assert_eq!(channels.len(), 6);
    for (k, c) in channels.iter().enumerate() {
        assert_eq!(c["id"], k);
        assert!(c["no_model"].is_null(), "{c}");
        assert_eq!(c["model"]["inputs"][0], "temp_imu_C");
        assert_eq!(c["inputs"][0]["thermometer"], "imu-die");
        assert!(
            c["provenance"]["data"]
                .as_str()
                .unwrap()
                .ends_with("mems_thermal_cycle.csv")
        );
        assert_ne!(c["provenance"]["data_hash"], "0000000000000000");
    }
    assert_eq!(channels[4]["model"]["unit"], "m/s^2");

    let o = tcomp(models(), &["inspect", out]);
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(text.contains("unit serial  24301"), "{text}");
    for name in ["gyro-x", "gyro-y", "gyro-z", "acc-x", "acc-y", "acc-z"] {
        let line = text.lines().find(|l| l.contains(name)).unwrap();
        assert!(line.contains("model: bayes"), "{line}");
    }
}

#[test]
fn the_board_hash_ignores_comments_and_layout() {
    let text = std::fs::read_to_string(board("mems6.toml")).unwrap();
    let noisy: String = text
        .lines()
        .filter(|l| !l.trim_start().starts_with('#'))
        .map(|l| format!("  {}   # note\n", l.split(" #").next().unwrap()))
        .collect();
    std::fs::write(models().join("noisy.toml"), noisy).unwrap();
    let hash = |b: &str, out: &str| {
        let mut args = vec![
            "image", "--board", b, "--serial", "1", "--model", "0=gx.tcm",
        ];
        args.extend_from_slice(&["--out", out]);
        let o = tcomp(models(), &args);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let o = tcomp(models(), &["inspect", out, "--json"]);
        let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        v["header"]["board_hash"].as_str().unwrap().to_string()
    };
    let b = board("mems6.toml");
    assert_eq!(hash(&b, "h1.bin"), hash("noisy.toml", "h2.bin"));
    let changed = std::fs::read_to_string(models().join("noisy.toml"))
        .unwrap()
        .replace("sample = 5", "sample = 6");
    std::fs::write(models().join("changed.toml"), changed).unwrap();
    assert_ne!(hash(&b, "h3.bin"), hash("changed.toml", "h4.bin"));
}

#[test]
fn one_unit_spelt_three_ways_packs_into_one_image() {
    let dir = models();
    fit_channel(dir, "acc_x_m_s2", "mems-accel", "x", "m/s2", "ax-s2.tcm");
    fit_channel(dir, "acc_y_m_s2", "mems-accel", "y", "m s-2", "ay-s-2.tcm");
    // The blobs carry the unit as the user spelt it …
    let o = tcomp(dir, &["inspect", "ay-s-2.tcm", "--json"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["unit"], "m s-2", "{v}");
    // … and the image of the board (`m/s^2`) is the one the `m/s^2` models make.
    let reference = image("mems6.toml", &[], "spelt-ref.bin");
    assert!(
        reference.status.success(),
        "{}",
        String::from_utf8_lossy(&reference.stderr)
    );
    let b = board("mems6.toml");
    let mut args = vec![
        "image",
        "--board",
        &b,
        "--serial",
        "0x5EED",
        "--created",
        "1763900000",
    ];
    let mixed = [
        "0=gx.tcm",
        "1=gy.tcm",
        "2=gz.tcm",
        "3=ax-s2.tcm",
        "4=ay-s-2.tcm",
        "5=az.tcm",
    ];
    for m in &mixed {
        args.extend_from_slice(&["--model", m]);
    }
    args.extend_from_slice(&["--out", "spelt.bin"]);
    let o = tcomp(dir, &args);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(
        std::fs::read(dir.join("spelt.bin")).unwrap(),
        std::fs::read(dir.join("spelt-ref.bin")).unwrap(),
        "m/s2 and m s-2 models should pack exactly as m/s^2 ones"
    );
    let o = tcomp(dir, &["inspect", "spelt.bin", "--json"]);
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    for c in &v["channels"].as_array().unwrap()[3..6] {
        assert_eq!(c["model"]["unit"], "m/s^2", "{c}");
    }
}

#[test]
fn a_gyro_in_deg_per_s_on_a_rad_per_s_channel_is_refused_with_the_factor() {
    let dir = models();
    fit_channel(dir, "gyro_x_rad_s", "mems-gyro", "x", "deg/s", "gx-deg.tcm");
    let b = board("mems6.toml");
    let o = tcomp(
        dir,
        &[
            "image",
            "--board",
            &b,
            "--serial",
            "1",
            "--model",
            "0=gx-deg.tcm",
            "--out",
            "deg.bin",
        ],
    );
    refused(
        &o,
        "deg.bin",
        &["gx-deg.tcm", "deg/s", "rad/s", "0.0174532925"],
    );
}
