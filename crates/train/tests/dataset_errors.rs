//! Bad input gets an error naming file, line and column.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic, missing_docs)]

use std::io::Write;
use tcomp_train::{Dataset, FitOptions, TrainError, fit};

fn write(dir: &tempfile::TempDir, name: &str, text: &str) -> std::path::PathBuf {
    let p = dir.path().join(name);
    std::fs::write(&p, text).unwrap();
    p
}

/// Loads with `--repeated-time refuse`: the file as written, its time checked by `time`.
fn refusing(p: &std::path::Path) -> Dataset {
    let opts = tcomp_train::dataset::LoadOptions {
        repeated_time: tcomp_train::dataset::RepeatedTime::Refuse,
        ..Default::default()
    };
    Dataset::load_with(p, &opts, &tcomp_train::progress::Silent).unwrap()
}

fn good_csv(rows: usize) -> String {
    let mut s = String::from("time_s,t_coil_c,gyro_dph\n");
    for i in 0..rows {
        let t = i as f64;
        let temp = 20.0 + 10.0 * (t / 600.0).sin();
        s.push_str(&format!("{t},{temp},{}\n", 0.01 * temp));
    }
    s
}

#[test]
fn misspelled_column_suggests_the_closest() {
    let dir = tempfile::tempdir().unwrap();
    let p = write(&dir, "run.csv", &good_csv(10));
    let d = Dataset::load(&p).unwrap();
    let e = d.column("t_coil").unwrap_err().to_string();
    assert!(e.contains("run.csv:1"), "{e}");
    assert!(e.contains("did you mean `t_coil_c`"), "{e}");
    let e = d.column("gyro_DPH").unwrap_err().to_string();
    assert!(e.contains("did you mean `gyro_dph`"), "{e}");
}

#[test]
fn non_numeric_cell_names_line_and_column() {
    let dir = tempfile::tempdir().unwrap();
    let mut text = good_csv(10);
    text = text.replacen("3,", "3x,", 1); // time 3 → "3x" on line 5, column 1
    let p = write(&dir, "bad.csv", &text);
    let d = Dataset::load(&p).unwrap();
    let e = d.time("time_s").unwrap_err().to_string();
    assert!(e.contains("bad.csv:5:1"), "{e}");
    assert!(e.contains("`3x`"), "{e}");
    // An unused bad column is no error.
    assert!(d.column("gyro_dph").is_ok());
}

#[test]
fn nan_cell_is_rejected_with_position() {
    let dir = tempfile::tempdir().unwrap();
    let mut lines: Vec<String> = good_csv(10).lines().map(str::to_string).collect();
    lines[7] = "6,NaN,0.1".into();
    let p = write(&dir, "nan.csv", &(lines.join("\n") + "\n"));
    let d = Dataset::load(&p).unwrap();
    let e = d.column("t_coil_c").unwrap_err().to_string();
    assert!(e.contains("nan.csv:8:2"), "{e}");
    assert!(e.contains("missing value (`NaN`)"), "{e}");
}

#[test]
fn non_monotonic_and_duplicate_time() {
    let dir = tempfile::tempdir().unwrap();
    let mut lines: Vec<String> = good_csv(10).lines().map(str::to_string).collect();
    lines[5] = "3,20,0.2".into(); // line 6 repeats time 3 of line 5
    let p = write(&dir, "dup.csv", &(lines.join("\n") + "\n"));
    let e = refusing(&p).time("time_s").unwrap_err().to_string();
    assert!(e.contains("dup.csv:6:1"), "{e}");
    assert!(e.contains("equal to"), "{e}");
    lines[5] = "1.5,20,0.2".into();
    let p = write(&dir, "back.csv", &(lines.join("\n") + "\n"));
    let e = refusing(&p).time("time_s").unwrap_err().to_string();
    assert!(e.contains("back.csv:6:1") && e.contains("before"), "{e}");
}

#[test]
fn empty_file_ragged_row_and_gzip() {
    let dir = tempfile::tempdir().unwrap();
    let p = write(&dir, "empty.csv", "");
    let e = Dataset::load(&p).unwrap_err().to_string();
    assert!(e.contains("empty.csv") && e.contains("no header"), "{e}");
    let p = write(&dir, "header.csv", "time_s,x\n");
    let e = Dataset::load(&p).unwrap_err().to_string();
    assert!(e.contains("no data rows"), "{e}");
    let p = write(&dir, "ragged.csv", "time_s,x\n0,1\n1,2,3\n");
    let e = Dataset::load(&p).unwrap_err().to_string();
    assert!(e.contains("ragged.csv:3"), "{e}");
    // gzip reads the same
    let gz = dir.path().join("run.csv.gz");
    let mut enc = flate2::write::GzEncoder::new(
        std::fs::File::create(&gz).unwrap(),
        flate2::Compression::fast(),
    );
    enc.write_all(good_csv(20).as_bytes()).unwrap();
    enc.finish().unwrap();
    let d = Dataset::load(&gz).unwrap();
    assert_eq!(d.len(), 20);
}

#[test]
fn fit_level_errors() {
    let dir = tempfile::tempdir().unwrap();
    let p = write(&dir, "short.csv", &good_csv(60));
    let d = Dataset::load(&p).unwrap();
    // too few samples after averaging
    let mut opts = FitOptions::new("gyro_dph", &["t_coil_c"]);
    opts.average_s = Some(30.0);
    let e = fit(&d, &opts).unwrap_err().to_string();
    assert!(e.contains("short.csv") && e.contains("at least 10"), "{e}");
    // constant feature
    let p = write(&dir, "long.csv", &good_csv(3000));
    let d = Dataset::load(&p).unwrap();
    let opts = FitOptions::new("gyro_dph", &["t_coil_c", "t_coil_c * 0 + 3"]);
    let e = fit(&d, &opts).unwrap_err();
    assert!(matches!(e, TrainError::ConstantFeature { .. }), "{e}");
    // collinear features
    let opts = FitOptions::new("gyro_dph", &["t_coil_c", "2 * t_coil_c + 1"]);
    let e = fit(&d, &opts).unwrap_err();
    assert!(matches!(e, TrainError::Collinear { .. }), "{e}");
    // bad expression, with the position
    let opts = FitOptions::new("gyro_dph", &["rate(t_coil_c"]);
    let e = fit(&d, &opts).unwrap_err().to_string();
    assert!(e.contains("rate(t_coil_c") && e.contains('^'), "{e}");
    // unknown column in a feature
    let opts = FitOptions::new("gyro_dph", &["t_coil"]);
    let e = fit(&d, &opts).unwrap_err().to_string();
    assert!(e.contains("did you mean `t_coil_c`"), "{e}");
}

#[test]
fn gaps_are_warned_and_reset() {
    let dir = tempfile::tempdir().unwrap();
    let mut s = String::from("time_s,t_coil_c,gyro_dph\n");
    for i in 0..4000 {
        let t = if i < 2000 {
            i as f64
        } else {
            i as f64 + 5000.0
        };
        let temp = 20.0 + 10.0 * (t / 900.0).sin();
        s.push_str(&format!("{t},{temp},{}\n", 0.01 * temp));
    }
    let p = write(&dir, "gap.csv", &s);
    let d = Dataset::load(&p).unwrap();
    let f = fit(
        &d,
        &FitOptions::new("gyro_dph", &["t_coil_c", "rate(t_coil_c)"]),
    )
    .unwrap();
    let w = f.summary.warnings.join("\n");
    assert!(w.contains("gap.csv:2002") && w.contains("reset"), "{w}");
    assert_eq!(f.summary.train.gaps, 1);
}

fn gz_bytes(text: &str) -> Vec<u8> {
    let mut enc = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
    enc.write_all(text.as_bytes()).unwrap();
    enc.finish().unwrap()
}

#[test]
fn duplicate_column_names_are_refused_naming_both() {
    let text = "time_s,t_coil_c,gyro_dph,t_coil_c\n0,1,2,3\n1,2,3,4\n";
    let e = Dataset::from_reader("dup.csv", text.as_bytes())
        .unwrap_err()
        .to_string();
    assert!(e.contains("dup.csv:1"), "{e}");
    assert!(
        e.contains("columns 2 and 4") && e.contains("`t_coil_c`"),
        "{e}"
    );
}

#[test]
fn semicolons_tabs_and_decimal_commas_are_recognised() {
    let e = Dataset::from_reader("semi.csv", "time_s;t_c;gyro\n0;20,5;0,01\n".as_bytes())
        .unwrap_err()
        .to_string();
    assert!(e.contains("semi.csv:1") && e.contains("semicolons"), "{e}");
    assert!(e.contains("decimal comma"), "{e}");
    let e = Dataset::from_reader("semi.csv", "time_s;t_c;gyro\n0;20.5;0.01\n".as_bytes())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("semicolons") && !e.contains("decimal comma"),
        "{e}"
    );
    let e = Dataset::from_reader("tab.csv", "time_s\tt_c\tgyro\n0\t20.5\t0.01\n".as_bytes())
        .unwrap_err()
        .to_string();
    assert!(e.contains("tab.csv:1") && e.contains("tabs"), "{e}");
}

#[test]
fn long_cells_are_clipped_in_errors_at_a_character_boundary() {
    let huge = "9x".repeat(2_500_000); // 5 MB
    let text = format!("time_s,x\n0,1\n1,{huge}\n2,3\n");
    let d = Dataset::from_reader("huge.csv", text.as_bytes()).unwrap();
    let e = d.column("x").unwrap_err().to_string();
    assert!(e.len() < 200, "{} bytes", e.len());
    assert!(e.contains("huge.csv:3:2") && e.contains('…'), "{e}");
    // Multi-byte characters: the cut never splits one.
    let accents = "é".repeat(100);
    let text = format!("time_s,x\n0,1\n1,{accents}\n");
    let e = Dataset::from_reader("utf8.csv", text.as_bytes())
        .unwrap()
        .column("x")
        .unwrap_err()
        .to_string();
    let shown = format!("{}…", "é".repeat(tcomp_train::dataset::MAX_ECHO_CHARS));
    assert!(e.contains(&shown), "{e}");
    // A long misspelled column name is clipped too.
    let long_name = "n".repeat(10_000);
    let e = d.column(&long_name).unwrap_err().to_string();
    assert!(e.len() < 400, "{} bytes", e.len());
}

#[test]
fn truncated_and_fake_gzip_are_named_with_the_line_reached() {
    let full = gz_bytes(&good_csv(5000));
    let cut = &full[..full.len() / 2];
    let e = Dataset::from_gz_reader("run.csv.gz", cut)
        .unwrap_err()
        .to_string();
    assert!(e.contains("ends early") && e.contains("truncated"), "{e}");
    let line: u64 = e
        .strip_prefix("run.csv.gz:")
        .and_then(|r| r.split(':').next())
        .and_then(|l| l.parse().ok())
        .unwrap_or_else(|| panic!("no line in {e}"));
    assert!(line > 100, "{e}");
    let dir = tempfile::tempdir().unwrap();
    let p = write(&dir, "plain.csv.gz", &good_csv(10));
    let e = Dataset::load(&p).unwrap_err().to_string();
    assert!(
        e.contains("plain.csv.gz:1") && e.contains("not gzip data"),
        "{e}"
    );
}

#[test]
fn one_row_or_an_empty_window_is_named_not_a_constant_feature() {
    let e = Dataset::from_reader("one.csv", "time_s,x\n0,1\n".as_bytes())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("one.csv") && e.contains("only one data row"),
        "{e}"
    );
    let dir = tempfile::tempdir().unwrap();
    let p = write(&dir, "run.csv", &good_csv(3000));
    let d = Dataset::load(&p).unwrap();
    let mut opts = FitOptions::new("gyro_dph", &["t_coil_c"]);
    opts.from = Some(5000.0);
    let e = fit(&d, &opts).unwrap_err().to_string();
    assert!(!e.contains("constant"), "{e}");
    assert!(
        e.contains("--from 5000") && e.contains("select 0 rows"),
        "{e}"
    );
    assert!(e.contains("from 0 s to 2999 s"), "{e}");
    opts.from = Some(2999.0);
    let e = fit(&d, &opts).unwrap_err().to_string();
    assert!(e.contains("select 1 row "), "{e}");
    let e = d
        .select_time("time_s", f64::NEG_INFINITY, -1.0)
        .unwrap_err();
    assert!(e.to_string().contains("--until -1"), "{e}");
    let e = d.select_time("time_s", 10.0, 10.0).unwrap_err();
    assert!(e.to_string().contains("empty window"), "{e}");
    let e = d.select_time("time_s", f64::NAN, 10.0).unwrap_err();
    assert!(e.to_string().contains("--from NaN"), "{e}");
}

#[test]
fn a_runtime_division_by_zero_names_the_expression_and_the_row() {
    let dir = tempfile::tempdir().unwrap();
    let p = write(&dir, "run.csv", &good_csv(3000));
    let d = Dataset::load(&p).unwrap();
    // t_coil_c is exactly 20 on the first row (line 2).
    let opts = FitOptions::new("gyro_dph", &["t_coil_c", "1 / (t_coil_c - 20)"]);
    let e = fit(&d, &opts).unwrap_err().to_string();
    assert!(e.contains("run.csv:2"), "{e}");
    assert!(e.contains("feature 2 `1 / (t_coil_c - 20)`"), "{e}");
}

#[test]
fn a_few_rows_are_too_few_samples_not_a_constant_feature() {
    let d = Dataset::from_reader("few.csv", good_csv(3).as_bytes()).unwrap();
    let e = fit(&d, &FitOptions::new("gyro_dph", &["t_coil_c"]))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("few.csv") && e.contains("3 samples (rows)"),
        "{e}"
    );
    assert!(!e.contains("constant"), "{e}");
}
