//! The streaming evaluator (`tcomp_train::eval_stream`) against the in-memory path (load into a
//! `Dataset`, select the window, `evaluate`): the same `EvalReport` bit for bit on a simulated RLG
//! run with dropouts (plain and gzip), a `--from/--until` window, a gappy 2 Hz QMA log with `--gap`,
//! a record whose early steps mislead the gap limit, and the real MEMS thermal cycle; and the same
//! error, word for word, on bad input.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic, missing_docs)]

use std::io::{Cursor, Write};
use tcomp_sim::dropout::RandomDropouts;
use tcomp_sim::{Scenario, presets, simulate};
use tcomp_train::{
    Dataset, FitOptions, Method, Roles, StreamOptions, blob_io, eval_stream, eval_stream_reader,
    fit, long_log::streamed_only,
};

fn csv_text(names: &[String], cols: &[Vec<f64>]) -> Vec<u8> {
    let mut out = names.join(",").into_bytes();
    out.push(b'\n');
    let n = cols.first().map_or(0, Vec::len);
    for i in 0..n {
        let row: Vec<String> = cols.iter().map(|c| format!("{}", c[i])).collect();
        out.extend_from_slice(row.join(",").as_bytes());
        out.push(b'\n');
    }
    out
}

fn gzip(bytes: &[u8]) -> Vec<u8> {
    let mut e = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
    e.write_all(bytes).unwrap();
    e.finish().unwrap()
}

fn with_dropouts(sc: Scenario, seed: u64) -> Scenario {
    let holes = RandomDropouts {
        count: 5,
        length_s: 400.0,
        seed,
    }
    .resolve(sc.profile.duration_s())
    .unwrap();
    sc.with_dropouts(holes)
}

/// A model blob fitted on `data` (features as given, `Bayes`, the default centers).
fn model(data: &Dataset, target: &str, reference: Option<&str>, features: &[&str]) -> Vec<u8> {
    let mut o = FitOptions::new(target, &[]);
    o.spec.features = features.iter().map(|s| s.to_string()).collect();
    o.reference = reference.map(str::to_string);
    o.method = Method::Bayes;
    fit(data, &o).unwrap().model.to_bytes().unwrap()
}

/// The in-memory report (or error text) of `bytes`.
fn in_memory(bytes: &[u8], gz: bool, blob: &[u8], o: &StreamOptions) -> Result<String, String> {
    let m = blob_io::decode(std::path::Path::new("m.tcm"), blob).unwrap();
    let run = || -> Result<String, tcomp_train::TrainError> {
        let d = if gz {
            Dataset::from_gz_reader("log.csv", bytes)?
        } else {
            Dataset::from_reader("log.csv", bytes)?
        };
        // The policies for repeated or backward time and missing cells, as `tcomp eval` loads.
        let mut columns = vec![o.roles.target.clone()];
        columns.extend(o.roles.reference.clone());
        columns.extend(m.program.inputs.iter().map(|s| s.to_string()));
        columns.extend(o.temperature.clone());
        let load = tcomp_train::dataset::LoadOptions {
            time: Some(o.roles.time.clone()),
            columns,
            repeated_time: o.repeated_time,
            missing: o.missing,
        };
        let mut d = tcomp_train::dataset::clean::apply(d, &load)?;
        if o.from.is_some() || o.until.is_some() {
            d = d.select_time(
                &o.roles.time,
                o.from.unwrap_or(f64::NEG_INFINITY),
                o.until.unwrap_or(f64::INFINITY),
            )?;
        }
        let r =
            tcomp_train::evaluate(&m, &d, &o.roles, o.bin_s, o.temperature.as_deref(), o.gap_s)?;
        Ok(serde_json::to_string(&r).unwrap())
    };
    run().map_err(|e| e.to_string())
}

fn streamed(bytes: &[u8], gz: bool, blob: &[u8], o: &StreamOptions) -> Result<String, String> {
    let m = blob_io::decode(std::path::Path::new("m.tcm"), blob).unwrap();
    eval_stream_reader("log.csv", Cursor::new(bytes), gz, &m, o)
        .map(|r| serde_json::to_string(&r).unwrap())
        .map_err(|e| e.to_string())
}

/// Both paths agree; returns the report's JSON.
fn agree(bytes: &[u8], blob: &[u8], o: &StreamOptions) -> String {
    let a = in_memory(bytes, false, blob, o);
    let b = streamed(bytes, false, blob, o);
    assert_eq!(a, b);
    let gz = gzip(bytes);
    assert_eq!(streamed(&gz, true, blob, o), b, "gzip");
    // And the stream did it, not the in-memory path it falls back on.
    let m = blob_io::decode(std::path::Path::new("m.tcm"), blob).unwrap();
    assert!(streamed_only(Cursor::new(bytes), false, &m, o).is_some());
    assert!(streamed_only(Cursor::new(&gz), true, &m, o).is_some());
    b.unwrap_or_else(|e| panic!("{e}"))
}

fn gaps(json: &str) -> u64 {
    let v: serde_json::Value = serde_json::from_str(json).unwrap();
    v["gaps"].as_u64().unwrap()
}

fn options(blob: &[u8], bin_s: f64) -> StreamOptions {
    let m = blob_io::decode(std::path::Path::new("m.tcm"), blob).unwrap();
    StreamOptions {
        roles: Roles::of_model(&m),
        bin_s,
        ..StreamOptions::default()
    }
}

const RLG: [&str; 4] = [
    "mean(t_anode_c, t_cathode_c, t_shell_c)",
    "rate(mean(t_anode_c, t_cathode_c, t_shell_c))",
    "t_anode_c - t_shell_c",
    "t_cathode_c - t_shell_c",
];

fn rlg() -> (Vec<u8>, Vec<u8>, tcomp_sim::Table) {
    let p = presets::preset("rlg").unwrap();
    let (tt, truth) = simulate(&p.train).unwrap();
    let (vt, _) = simulate(&with_dropouts(p.verify, 7)).unwrap();
    let train = Dataset::from_columns("train", tt.names, tt.columns);
    let blob = model(
        &train,
        &truth.columns.target,
        Some(&truth.columns.reference),
        &RLG,
    );
    (blob, csv_text(&vt.names, &vt.columns), vt)
}

#[test]
fn simulated_rlg_with_dropouts_windows_and_misleading_early_steps() {
    let (blob, csv, table) = rlg();
    let json = agree(&csv, &blob, &options(&blob, 100.0));
    assert!(gaps(&json) >= 3, "{json}");
    assert!(json.contains("\"kind\":\"heating\""), "{json}");
    agree(&csv, &blob, &options(&blob, 1000.0));
    let t = table.column("time_s").unwrap();
    let mid = t[t.len() / 2];
    let mut o = options(&blob, 100.0);
    (o.from, o.until) = (Some(t[100] + 0.5), Some(mid));
    agree(&csv, &blob, &o);
    o.from = None;
    o.gap_s = Some(1000.0);
    let json = agree(&csv, &blob, &o);
    assert_eq!(gaps(&json), 0, "{json}");
    // The first 1,500 steps are 1 s, the rest 0.1 s: the provisional limit (10 s) misses the
    // 1 s steps, which the true median (0.1 s) makes gaps; the record must be read again.
    let mut cols = table.columns.clone();
    let ti = table.names.iter().position(|n| n == "time_s").unwrap();
    let mut now = 0.0;
    for (i, v) in cols[ti].iter_mut().enumerate() {
        *v = now;
        now += if i < 1500 { 1.0 } else { 0.1 };
    }
    let json = agree(
        &csv_text(&table.names, &cols),
        &blob,
        &options(&blob, 100.0),
    );
    assert_eq!(gaps(&json), 1500, "{json}");
}

#[test]
fn a_gappy_qma_log_with_gap_option() {
    let p = presets::preset("qma").unwrap();
    let (tt, truth) = simulate(&with_dropouts(p.train.with_rate(2.0, 0.5), 3)).unwrap();
    let (vt, _) = simulate(&with_dropouts(p.verify.with_rate(2.0, 0.5), 4)).unwrap();
    let train = Dataset::from_columns("train", tt.names, tt.columns);
    let t = &truth.columns;
    let mut features: Vec<&str> = Vec::new();
    for x in truth.effects.iter().flat_map(|e| e.expressions.iter()) {
        if !features.contains(&x.as_str()) {
            features.push(x);
        }
    }
    let blob = model(&train, &t.target, Some(&t.reference), &features);
    let csv = csv_text(&vt.names, &vt.columns);
    let json = agree(&csv, &blob, &options(&blob, 100.0));
    assert!(gaps(&json) >= 3, "{json}");
    let mut o = options(&blob, 100.0);
    o.gap_s = Some(100.0);
    agree(&csv, &blob, &o);
    o.gap_s = Some(1e4);
    let json = agree(&csv, &blob, &o);
    assert_eq!(gaps(&json), 0, "{json}");
}

#[test]
fn the_real_mems_cycle() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../data/realdata/mems_thermal_cycle.csv");
    let bytes = std::fs::read(&path).unwrap();
    let data = Dataset::from_reader("mems", &bytes[..]).unwrap();
    let train = data
        .select_time("time_s", f64::NEG_INFINITY, 3130.0)
        .unwrap();
    let mut o = FitOptions::new("gyro_z_rad_s", &["temp_imu_C"]);
    o.method = Method::Bayes;
    let blob = fit(&train, &o).unwrap().model.to_bytes().unwrap();
    let mut so = options(&blob, 100.0);
    so.roles.reference_value = Some(0.0);
    agree(&bytes, &blob, &so);
    so.from = Some(3130.0);
    so.bin_s = 50.0;
    agree(&bytes, &blob, &so);
    // And from a path.
    let m = blob_io::decode(std::path::Path::new("m.tcm"), &blob).unwrap();
    let r = eval_stream(&path, &m, &so).unwrap();
    assert_eq!(
        serde_json::to_string(&r).unwrap(),
        in_memory(&bytes, false, &blob, &so).unwrap()
    );
}

#[test]
fn bad_input_gives_the_in_memory_error() {
    let (blob, csv, _) = rlg();
    let o = options(&blob, 100.0);
    let text = String::from_utf8(csv).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    let bad = |f: &dyn Fn(usize, &str) -> String| -> Vec<u8> {
        lines
            .iter()
            .enumerate()
            .map(|(i, l)| f(i, l) + "\n")
            .collect::<String>()
            .into_bytes()
    };
    let cases: Vec<Vec<u8>> = vec![
        // A text cell in a used column, late in the file.
        bad(&|i, l| {
            if i == 3000 {
                l.replacen(',', ",x", 2)
            } else {
                l.to_string()
            }
        }),
        // Time going backwards.
        bad(&|i, l| {
            if i == 2000 {
                format!("1{}", &l[l.find(',').unwrap()..])
            } else {
                l.to_string()
            }
        }),
        // A short row.
        bad(&|i, l| {
            if i == 10 {
                l.rsplit_once(',').unwrap().0.to_string()
            } else {
                l.to_string()
            }
        }),
        // A misspelled header.
        bad(&|i, l| {
            if i == 0 {
                l.replace("t_shell_c", "t_shel_c")
            } else {
                l.to_string()
            }
        }),
    ];
    // Time going backwards is bad input under `--repeated-time refuse`; under the default it is
    // handled (as a restart or out-of-order rows), the same way by both paths.
    let handled = in_memory(&cases[1], false, &blob, &o);
    assert!(handled.is_ok(), "{handled:?}");
    assert_eq!(handled, streamed(&cases[1], false, &blob, &o));
    let mut o = o.clone();
    o.repeated_time = tcomp_train::dataset::RepeatedTime::Refuse;
    for bytes in &cases {
        let a = in_memory(bytes, false, &blob, &o);
        assert!(a.is_err(), "the case is bad input");
        assert_eq!(a, streamed(bytes, false, &blob, &o));
    }
    // A `--bin` longer than half the record.
    let mut long = o.clone();
    long.bin_s = 1e7;
    let a = in_memory(&cases[0][..0], false, &blob, &long);
    assert!(a.is_err());
    let csv = text.into_bytes();
    assert_eq!(
        in_memory(&csv, false, &blob, &long),
        streamed(&csv, false, &blob, &long)
    );
    assert!(streamed(&csv, false, &blob, &long).is_err());
}

/// A jittery logger clock: 80,000 rows at 100 Hz ± 1.5 ms with two dropouts, every step a
/// different double, more than the streaming reader counts (`MAX_DISTINCT`): its median comes
/// from the radix selection, and the report is still the in-memory one.
#[test]
fn a_jittery_clock_with_more_distinct_steps_than_counted() {
    let (blob, _, _) = rlg();
    let mut state = 99u64;
    let mut csv = b"time_s,t_anode_c,t_cathode_c,t_shell_c,gyro_dph,ref_dph\n".to_vec();
    let rows = 80_000;
    assert!(rows > tcomp_train::long_log::steps::MAX_DISTINCT);
    let mut dropout = 0.0;
    for i in 0..rows {
        state = state
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        let u = (state >> 11) as f64 / (1u64 << 53) as f64;
        if i == 30_000 || i == 60_000 {
            dropout += 7.0;
        }
        let t = 100.0 + i as f64 * 0.01 + 0.003 * (u - 0.5) + dropout;
        let temp = 20.0 + 10.0 * (t / 300.0).sin();
        let gyro = 10.0 + 0.01 * temp + 0.05 * (u - 0.5);
        csv.extend_from_slice(
            format!(
                "{t},{},{},{temp:.4},{gyro:.6},10.0\n",
                temp + 0.3,
                temp + 0.1
            )
            .as_bytes(),
        );
    }
    let json = agree(&csv, &blob, &options(&blob, 50.0));
    assert_eq!(gaps(&json), 2, "{json}");
}
