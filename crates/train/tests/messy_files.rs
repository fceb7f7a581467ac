//! The policies for what chamber loggers write (`dataset::clean`): repeated time averaged or
//! dropped, a clock restart continued after a gap, empty and NaN cells dropped as dropouts — each
//! counted in the notes — and refusing as an option.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic, missing_docs)]

use tcomp_train::dataset::{LoadOptions, Missing, RepeatedTime};
use tcomp_train::progress::Silent;
use tcomp_train::{Dataset, FitOptions, fit};

fn write(dir: &tempfile::TempDir, name: &str, text: &str) -> std::path::PathBuf {
    let p = dir.path().join(name);
    std::fs::write(&p, text).unwrap();
    p
}

/// A 1 Hz run of `rows` rows: time, temperature, gyro (a linear function of temperature).
fn rows(rows: usize) -> Vec<String> {
    let mut v = vec!["time_s,t_coil_c,gyro_dph".to_string()];
    for i in 0..rows {
        let t = i as f64;
        let temp = 20.0 + 10.0 * (t / 600.0).sin();
        v.push(format!("{t},{temp},{}", 0.01 * temp));
    }
    v
}

fn load(p: &std::path::Path, opts: &LoadOptions) -> Dataset {
    Dataset::load_with(p, opts, &Silent).unwrap()
}

#[test]
fn repeated_time_is_averaged_by_default_and_counted() {
    let dir = tempfile::tempdir().unwrap();
    let mut l = rows(10);
    // Line 6 repeats line 5's time with another reading; line 9 repeats line 8's row exactly.
    l[5] = "3,30,0.5".into();
    l[8] = l[7].clone();
    let p = write(&dir, "dup.csv", &(l.join("\n") + "\n"));
    let d = Dataset::load(&p).unwrap();
    assert_eq!(d.len(), 8);
    let t = d.time("time_s").unwrap();
    assert!(t.windows(2).all(|w| w[1] > w[0]), "{t:?}");
    let temp = d.column("t_coil_c").unwrap();
    let line5: f64 = l[4].split(',').nth(1).unwrap().parse().unwrap();
    assert_eq!(
        temp[3],
        (line5 + 30.0) / 2.0,
        "the two readings of time 3 averaged"
    );
    let note = d.notes().join(" ");
    assert!(
        note.contains("2 rows repeated") && note.contains("averaged") && note.contains("line 6"),
        "{note}"
    );
    // drop keeps the first reading
    let opts = LoadOptions {
        repeated_time: RepeatedTime::Drop,
        ..Default::default()
    };
    let d = load(&p, &opts);
    assert_eq!(d.column("t_coil_c").unwrap()[3], line5);
    // refuse names the row
    let opts = LoadOptions {
        repeated_time: RepeatedTime::Refuse,
        ..Default::default()
    };
    let e = load(&p, &opts).time("time_s").unwrap_err().to_string();
    assert!(e.contains("dup.csv:6:1") && e.contains("equal to"), "{e}");
}

#[test]
fn a_clock_restart_continues_after_a_gap() {
    let dir = tempfile::tempdir().unwrap();
    let mut l = rows(100);
    // From line 52 on the logger's clock starts again at 0.
    for (k, row) in l.iter_mut().enumerate().skip(51) {
        let mut f: Vec<String> = row.split(',').map(str::to_string).collect();
        f[0] = format!("{}", k - 51);
        *row = f.join(",");
    }
    let p = write(&dir, "restart.csv", &(l.join("\n") + "\n"));
    let d = Dataset::load(&p).unwrap();
    assert_eq!(d.len(), 100);
    let t = d.time("time_s").unwrap();
    assert_eq!(t[49], 49.0);
    assert_eq!(t[50] - t[49], 20.0, "a gap of 20 median steps");
    assert_eq!(t[99] - t[50], 49.0);
    let starts = tcomp_train::dataset::stretch_starts(t, None);
    assert_eq!(starts, [0, 50]);
    let note = d.notes().join(" ");
    assert!(
        note.contains("1 clock restart") && note.contains("line 52"),
        "{note}"
    );
}

#[test]
fn missing_cells_in_used_columns_are_dropouts() {
    let dir = tempfile::tempdir().unwrap();
    let mut l = rows(400);
    l[10] = "9,,0.2".into();
    l[20] = "19,NaN,0.2".into();
    l[30] = "29,20,nan".into();
    let p = write(&dir, "holes.csv", &(l.join("\n") + "\n"));
    let used = LoadOptions {
        columns: vec!["gyro_dph".into(), "t_coil_c".into()],
        ..Default::default()
    };
    let d = load(&p, &used);
    assert_eq!(d.len(), 397);
    assert!(d.column("t_coil_c").is_ok() && d.column("gyro_dph").is_ok());
    let note = d.notes().join(" ");
    assert!(
        note.contains("3 rows")
            && note.contains("`t_coil_c`: 2, first at line 11")
            && note.contains("`gyro_dph`: 1, first at line 31"),
        "{note}"
    );
    // A fit through them works, and says so.
    let mut o = FitOptions::new("gyro_dph", &["t_coil_c"]);
    o.reference_value = Some(0.0);
    o.method = tcomp_train::Method::Poly3;
    let d = Dataset::load_with(&p, &o.load_options(), &Silent).unwrap();
    let f = fit(&d, &o).unwrap();
    assert!(
        f.summary
            .warnings
            .iter()
            .any(|w| w.contains("dropped as logger dropouts"))
    );
    // refuse names the first
    let refuse = LoadOptions {
        missing: Missing::Refuse,
        ..used
    };
    let e = load(&p, &refuse)
        .column("t_coil_c")
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("holes.csv:11:2") && e.contains("missing value (an empty cell)"),
        "{e}"
    );
    // text is not a missing value: still an error, under the default too
    l[40] = "39,ERR,0.2".into();
    let p = write(&dir, "text.csv", &(l.join("\n") + "\n"));
    let e = load(
        &p,
        &LoadOptions {
            columns: vec!["t_coil_c".into()],
            ..Default::default()
        },
    )
    .column("t_coil_c")
    .unwrap_err()
    .to_string();
    assert!(
        e.contains("text.csv:41:2") && e.contains("not a number: `ERR`"),
        "{e}"
    );
}

#[test]
fn an_overflowing_training_mean_is_named_as_itself() {
    let dir = tempfile::tempdir().unwrap();
    let mut l = rows(200);
    for row in l.iter_mut().skip(1).take(3) {
        let mut f: Vec<String> = row.split(',').map(str::to_string).collect();
        f[2] = "1e308".into();
        *row = f.join(",");
    }
    let p = write(&dir, "huge.csv", &(l.join("\n") + "\n"));
    let d = Dataset::load(&p).unwrap();
    let o = FitOptions::new("gyro_dph", &["t_coil_c"]);
    let e = fit(&d, &o).unwrap_err().to_string();
    assert!(
        e.contains("the training mean of `gyro_dph` is not finite"),
        "{e}"
    );
    assert!(!e.contains("--reference-value inf"), "{e}");
}
