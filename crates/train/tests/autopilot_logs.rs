//! Autopilot logs in, autopilot parameters out: the real PX4 ULog of `data/autopilot/` read as
//! tables (columns `message.field`, instances apart, time from the log's timestamps), a fit on it,
//! PX4's TC_* parameters equal to those PX4's own tool wrote from the same log (recorded beside
//! it), and DataFlash logs (built here record by record) read the same way.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic, missing_docs)]

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use tcomp_train::dataset::LoadOptions;
use tcomp_train::progress::Silent;
use tcomp_train::{Dataset, FitOptions, Method, fit};

fn repo(p: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..").join(p)
}

const ULOG: &str = "data/autopilot/px4_sample_small.ulg";

fn load(path: &Path, columns: &[&str]) -> Result<Dataset, tcomp_train::DataError> {
    let opts = LoadOptions {
        columns: columns.iter().map(|s| s.to_string()).collect(),
        ..Default::default()
    };
    Dataset::load_with(path, &opts, &Silent)
}

#[test]
fn a_real_ulog_reads_as_tables_with_instances_apart() {
    let d = load(
        &repo(ULOG),
        &["sensor_gyro[1].x", "sensor_gyro[1].temperature"],
    )
    .unwrap();
    assert_eq!(d.len(), 18);
    assert!(d.names().iter().any(|n| n == "sensor_gyro[1].device_id"));
    let t = d.time("time_s").unwrap();
    assert!(t.windows(2).all(|w| w[1] > w[0]));
    // time_s is the log's own timestamp (µs) in seconds
    let ts = d.column("sensor_gyro[1].timestamp_sample").unwrap();
    assert!((t[0] - ts[0] * 1e-6).abs() < 0.01, "{} vs {}", t[0], ts[0]);
    let e = load(&repo(ULOG), &["sensor_gyro.x"])
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("3 instances of sensor_gyro") && e.contains("sensor_gyro[0].x"),
        "{e}"
    );
    let e = load(&repo(ULOG), &["sensor_gyro[0].xx"])
        .unwrap_err()
        .to_string();
    assert!(e.contains("did you mean `sensor_gyro[0].x`"), "{e}");
}

#[test]
fn fit_on_a_real_ulog() {
    let mut o = FitOptions::new("sensor_combined.gyro_rad[2]", &["sensor_baro.temperature"]);
    o.method = Method::Poly3;
    let d = Dataset::load_with(&repo(ULOG), &o.load_options(), &Silent).unwrap();
    // the baro's 18 records interpolated onto sensor_combined's 3627; rows outside its span dropped
    assert!(d.len() > 3000 && d.len() < 3627, "{}", d.len());
    let f = fit(&d, &o).unwrap();
    assert_eq!(f.summary.train_rows, d.len());
    assert!(f.summary.train.residual_std.is_finite());
}

/// `NAME -> value` of a PX4 `.params` file.
fn params(text: &str) -> BTreeMap<String, f64> {
    text.lines()
        .filter(|l| !l.starts_with('#'))
        .filter_map(|l| {
            let f: Vec<&str> = l.split('\t').collect();
            Some((f.get(2)?.to_string(), f.get(3)?.parse().ok()?))
        })
        .collect()
}

#[test]
fn px4_parameters_equal_px4s_own_tool_on_the_same_log() {
    let tool = params(
        &std::fs::read_to_string(repo("data/autopilot/px4_sample_small.px4-tool.params")).unwrap(),
    );
    let ours = tcomp_train::autopilot::from_log(&repo(ULOG)).unwrap();
    let mine = params(&ours.text());
    assert_eq!(mine.len(), 4 * 16, "TC_G0, TC_G1, TC_A0, TC_A1");
    let mut worst = 0.0f64;
    for (k, v) in &tool {
        match mine.get(k) {
            // the tool prints 17 significant digits: agreement to its rounding and the float
            // differences of two least-squares solvers on the same numbers
            Some(m) => {
                worst = worst.max((m - v).abs() / v.abs().max(1e-9));
                assert!(
                    (m - v).abs() <= 1e-9 * v.abs().max(1e-9),
                    "{k}: tcomp {m}, PX4's tool {v}"
                );
            }
            // instances the tool could not fit are zeros in its file; tcomp says why instead
            None => assert_eq!(*v, 0.0, "{k}"),
        }
    }
    eprintln!("largest relative difference of a PX4 parameter: {worst:e}");
    assert!(
        ours.skipped
            .iter()
            .any(|s| s.contains("TC_A2") && s.contains("never varies"))
    );
    assert!(
        ours.skipped
            .iter()
            .any(|s| s.contains("TC_G2") && s.contains("no temperature"))
    );
    // the firmware's correction: X0 + X1 dT + X2 dT² + X3 dT³, dT clamped
    let g0 = ours
        .px4
        .iter()
        .find(|s| s.kind == 'G' && s.instance == 0)
        .unwrap();
    let at = |t: f64| g0.offset(2, t);
    assert_eq!(at(-100.0), at(f64::from(g0.tmin)));
    assert!((at(f64::from(g0.tref)) - g0.coef[2][0]).abs() < 1e-15);
}

const BIN: &str = "data/autopilot/ardupilot_cubeorangeplus.bin";

/// `NAME -> value` of an ArduPilot parameter file (`NAME VALUE` lines).
fn ardu_params(text: &str) -> BTreeMap<String, f64> {
    text.lines()
        .filter_map(|l| {
            let mut f = l.split_whitespace();
            Some((f.next()?.to_string(), f.next()?.parse().ok()?))
        })
        .collect()
}

#[test]
fn fit_on_a_real_dataflash_log() {
    let mut o = FitOptions::new("IMU[1].GyrZ", &["IMU[1].T"]);
    o.method = Method::Poly3;
    let d = Dataset::load_with(&repo(BIN), &o.load_options(), &Silent).unwrap();
    // 1255 IMU records per instance, 50 s at 25 Hz, time from TimeUS
    assert_eq!(d.len(), 1255);
    let t = d.time("time_s").unwrap();
    assert!(
        (t[t.len() - 1] - t[0] - 50.16).abs() < 0.01,
        "{}",
        t[t.len() - 1] - t[0]
    );
    let f = fit(&d, &o).unwrap();
    assert!(f.summary.train.residual_std.is_finite());
    // the three IMUs are apart: IMU[2] runs ~9 °C cooler than IMU[0]
    let d = load(&repo(BIN), &["IMU[0].T", "IMU[2].T"]).unwrap();
    let (t0, t2) = (d.column("IMU[0].T").unwrap(), d.column("IMU[2].T").unwrap());
    assert!(t0[0] - t2[0] > 8.0, "{} {}", t0[0], t2[0]);
}

#[test]
fn ardupilot_parameters_equal_ardupilots_own_tool_on_the_same_log() {
    let tool = ardu_params(
        &std::fs::read_to_string(repo(
            "data/autopilot/ardupilot_cubeorangeplus.tempcal-tool.parm",
        ))
        .unwrap(),
    );
    let ours = tcomp_train::autopilot::from_log(&repo(BIN)).unwrap();
    assert_eq!(ours.format, "ardupilot");
    assert!(ours.skipped.is_empty(), "{:?}", ours.skipped);
    let mine = ardu_params(&ours.text());
    assert_eq!(mine.len(), 3 * 21);
    assert_eq!(
        mine.keys().collect::<Vec<_>>(),
        tool.keys().collect::<Vec<_>>()
    );
    // TMIN/TMAX and ENABLE as printed (%.1f, 1)
    for (k, v) in tool
        .iter()
        .filter(|(k, _)| !k.contains("_ACC") && !k.contains("_GYR"))
    {
        assert_eq!(mine[k], *v, "{k}");
    }
    // The coefficients: the cubic about 35 °C over 1 °C of data is ill-conditioned (values
    // to 1e11), so two least-squares solvers (LAPACK's through numpy, nalgebra's SVD) agree to
    // the conditioning, not to the printed 9 decimals: each coefficient to 1e-8 of its own size
    // (measured: 4.9e-10), and the correction the firmware applies over [TMIN, TMAX] (the
    // polynomial's values there) to 1e-6 m/s² and 1e-7 rad/s. Leaving the log's own calibration
    // in the data (not taking it out first, as the tool does) moves that correction by 2.6e-6
    // m/s², which this catches.
    let mut worst = 0.0f64;
    for (k, v) in tool
        .iter()
        .filter(|(k, _)| k.contains("_ACC") || k.contains("_GYR"))
    {
        let rel = (mine[k] - v).abs() / v.abs();
        worst = worst.max(rel);
        assert!(rel < 1e-8, "{k}: tcomp {}, ArduPilot's tool {v}", mine[k]);
    }
    eprintln!("largest relative difference of a coefficient: {worst:e}");
    for imu in 1..=3 {
        let lo = tool[&format!("INS_TCAL{imu}_TMIN")];
        let hi = tool[&format!("INS_TCAL{imu}_TMAX")];
        for (kind, tol) in [("ACC", 1e-6), ("GYR", 1e-7)] {
            for axis in ["X", "Y", "Z"] {
                let poly = |p: &BTreeMap<String, f64>, t: f64| {
                    (1..=3)
                        .map(|k| {
                            p[&format!("INS_TCAL{imu}_{kind}{k}_{axis}")]
                                * 1e-6
                                * (t - 35.0).powi(k)
                        })
                        .sum::<f64>()
                };
                for step in 0..=10 {
                    let t = lo + (hi - lo) * f64::from(step) / 10.0;
                    // relative to the value at TMIN: the constant is the offsets' business
                    let d = (poly(&mine, t) - poly(&mine, lo)) - (poly(&tool, t) - poly(&tool, lo));
                    assert!(d.abs() < tol, "INS_TCAL{imu} {kind} {axis} at {t}: {d:e}");
                }
            }
        }
    }
}

/// A DataFlash record of `kind` with `payload`.
fn record(kind: u8, payload: &[u8]) -> Vec<u8> {
    [&[0xA3, 0x95, kind][..], payload].concat()
}

/// An FMT record defining `kind`.
fn fmt(kind: u8, len: u8, name: &str, format: &str, labels: &str) -> Vec<u8> {
    let mut p = vec![kind, len];
    let mut n = [0u8; 4];
    n[..name.len()].copy_from_slice(name.as_bytes());
    p.extend_from_slice(&n);
    let mut f = [0u8; 16];
    f[..format.len()].copy_from_slice(format.as_bytes());
    p.extend_from_slice(&f);
    let mut l = [0u8; 64];
    l[..labels.len()].copy_from_slice(labels.as_bytes());
    p.extend_from_slice(&l);
    record(0x80, &p)
}

/// A DataFlash log of two IMUs over a 40 °C ramp: gyro = cubic in (T − 35), 50 Hz, 200 s.
fn dataflash(cubic: [f64; 4]) -> Vec<u8> {
    let mut b = fmt(0x80, 89, "FMT", "BBnNZ", "Type,Length,Name,Format,Labels");
    b.extend(fmt(
        129,
        3 + 8 + 1 + 7 * 4,
        "IMU",
        "QBfffffff",
        "TimeUS,I,GyrX,GyrY,GyrZ,AccX,AccY,AccZ,T",
    ));
    for k in 0..10_000u64 {
        for i in 0..2u8 {
            let t_s = k as f64 * 0.02;
            let temp = 15.0 + 40.0 * t_s / 200.0 + f64::from(i);
            let d = temp - 35.0;
            let g = cubic[0] + d * (cubic[1] + d * (cubic[2] + d * cubic[3]));
            let mut p = (k * 20_000 + u64::from(i) * 7).to_le_bytes().to_vec();
            p.push(i);
            for v in [g, -g, 0.5 * g, 0.01 * d, 0.0, -9.8 + 0.001 * d * d, temp] {
                p.extend_from_slice(&(v as f32).to_le_bytes());
            }
            b.extend(record(129, &p));
        }
    }
    b
}

#[test]
fn dataflash_logs_read_with_instances_apart_and_give_ardupilots_cubic() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("imu.bin");
    let cubic = [0.01, 2e-4, -3e-6, 4e-8];
    std::fs::write(&p, dataflash(cubic)).unwrap();
    let d = load(&p, &["IMU[1].GyrX", "IMU[1].T"]).unwrap();
    assert_eq!(d.len(), 10_000);
    let t = d.time("time_s").unwrap();
    assert!((t[1] - t[0] - 0.02).abs() < 1e-9);
    assert_eq!(d.column("IMU[1].T").unwrap()[0], 16.0);
    let e = load(&p, &["IMU.GyrX"]).unwrap_err().to_string();
    assert!(e.contains("2 instances of IMU"), "{e}");
    let a = tcomp_train::autopilot::from_log(&p).unwrap();
    assert_eq!(a.format, "ardupilot");
    assert_eq!(a.ardupilot.len(), 2);
    let imu0 = &a.ardupilot[0];
    // highest power first; the constant is fitted but not a parameter
    for (got, want) in imu0.gyr[0]
        .iter()
        .zip([cubic[3], cubic[2], cubic[1], cubic[0]])
    {
        assert!(
            (got - want).abs() < 1e-4 * want.abs() + 1e-7,
            "{:?}",
            imu0.gyr[0]
        );
    }
    let text = a.text();
    assert!(
        text.contains("INS_TCAL1_ENABLE 1\nINS_TCAL1_TMIN 15."),
        "{text}"
    );
    let gyr1x: f64 = text
        .lines()
        .find_map(|l| l.strip_prefix("INS_TCAL1_GYR1_X "))
        .unwrap()
        .parse()
        .unwrap();
    assert!(
        (gyr1x - cubic[1] * 1e6).abs() < 1e-3 * cubic[1] * 1e6,
        "{gyr1x}"
    );
    assert!(text.contains("INS_TCAL2_GYR3_Z"), "{text}");
}

#[test]
fn a_damaged_dataflash_log_is_refused_at_its_byte() {
    let dir = tempfile::tempdir().unwrap();
    let mut b = dataflash([0.0, 1e-4, 0.0, 0.0]);
    let p = dir.path().join("cut.bin");
    let whole = b.clone();
    b.truncate(b.len() - 5);
    std::fs::write(&p, &b).unwrap();
    // a partial last record (the logger stopped mid-record) is dropped, with a note
    let d = load(&p, &["IMU[1].GyrX"]).unwrap();
    let q = dir.path().join("whole.bin");
    std::fs::write(&q, &whole).unwrap();
    let n = load(&q, &["IMU[1].GyrX"]).unwrap().len();
    assert_eq!(d.len() + 1, n);
    assert!(
        d.notes()
            .iter()
            .any(|s| s.contains("cut.bin") && s.contains("partway through a record at byte")),
        "{:?}",
        d.notes()
    );
    // damage before the end is refused at its byte: a stray byte after the first records
    let mut damaged = whole.clone();
    damaged.insert(89 * 2, 0x00);
    std::fs::write(&p, &damaged).unwrap();
    let e = Dataset::load(&p).unwrap_err().to_string();
    assert!(
        e.contains("cut.bin: byte 178") && e.contains("no record header"),
        "{e}"
    );
    // a record type with no FMT: the IMU's FMT dropped
    let full = dataflash([0.0, 1e-4, 0.0, 0.0]);
    let nofmt: Vec<u8> = [&full[..89], &full[178..]].concat();
    let p = dir.path().join("nofmt.bin");
    std::fs::write(&p, nofmt).unwrap();
    let e = Dataset::load(&p).unwrap_err().to_string();
    assert!(
        e.contains("nofmt.bin: byte 89") && e.contains("type 129") && e.contains("no FMT"),
        "{e}"
    );
}
