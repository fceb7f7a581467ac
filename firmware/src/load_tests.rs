//! Loading a version-2 calibration image: a blob runs only on the row it was made for, only on the
//! unit it was made for, and only when the image's channel table is the board's wiring; an IFOG
//! triad runs its own models through the same `App`.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

extern crate std;

use super::*;
use crate::image::{ImageError, TableError};
use std::{vec, vec::Vec};
use tcomp_core::SensorKind;
use tcomp_core::image::{ChannelRow, Entry, ImageSpec, Input, MAX_ROW_INPUTS, Source, ThermKind};

const SERIAL: u64 = 0x5EED_0001;

/// The rows of a firmware configuration, as `tcomp image --board` writes them for the matching
/// description, and one PT100 per thermometer index.
fn rows_of(
    config: &[ChannelConfig],
    sensor: impl Fn(usize) -> (SensorKind, &'static str),
) -> (
    Vec<tcomp_core::image::Thermometer<'static>>,
    Vec<ChannelRow<'static>>,
) {
    let n_therm = config
        .iter()
        .flat_map(|c| c.thermometers.iter().map(|&(_, t)| usize::from(t) + 1))
        .max()
        .unwrap_or(0);
    let therms = (0..n_therm)
        .map(|i| tcomp_core::image::Thermometer {
            name: "pt100",
            adc: i as u8,
            input: 0,
            kind: ThermKind::Rtd {
                r0: 100.0,
                a: 3.9083e-3,
                b: -5.775e-7,
            },
        })
        .collect();
    let rows = config
        .iter()
        .enumerate()
        .map(|(k, c)| {
            let mut inputs = [Input::default(); MAX_ROW_INPUTS];
            for (d, &(name, thermometer)) in inputs.iter_mut().zip(c.thermometers) {
                *d = Input { name, thermometer };
            }
            let (sensor, unit) = sensor(k);
            ChannelRow {
                id: c.id,
                name: c.name,
                sensor,
                axis: ["x", "y", "z"][k % 3],
                unit,
                source: Source::Counter(c.counter),
                scale: c.scale.per_pulse(),
                inputs,
                n_inputs: c.thermometers.len() as u8,
            }
        })
        .collect();
    (therms, rows)
}

/// An RLG-program model (inputs t_anode_c, t_cathode_c, t_shell_c) or, with `coil`, the same
/// model reading t_coil_c, labelled for `sensor`, `axis`, `unit`.
fn blob(sensor: SensorKind, axis: &'static str, unit: &'static str, seed: u32) -> Vec<u8> {
    let mut m = tcomp_core::testing::example_model::<32, 4, 16>(8, seed);
    m.meta.sensor = sensor;
    m.meta.axis = axis;
    m.meta.unit = unit;
    let mut buf = vec![0u8; 16 * 1024];
    let n = m.encode(&mut buf).unwrap();
    buf.truncate(n);
    buf
}

fn imu6_sensor(k: usize) -> (SensorKind, &'static str) {
    if k < 3 {
        (SensorKind::Rlg, "deg/h")
    } else {
        (SensorKind::Qma, "ug")
    }
}

/// An IMU6 image with RLG models on channels 0–2 (`blobs[k]` on channel `k`).
fn imu6_image(rows: &[ChannelRow<'_>], blobs: &[Vec<u8>]) -> Vec<u8> {
    let (therms, _) = rows_of(&IMU6, imu6_sensor);
    let entries: Vec<Entry<'_>> = blobs
        .iter()
        .enumerate()
        .map(|(k, b)| Entry {
            channel: k as u16,
            blob: b,
            provenance: Default::default(),
        })
        .collect();
    let spec = ImageSpec {
        serial: SERIAL,
        created: 0,
        tool: "test",
        thermometers: &therms,
        channels: rows,
        entries: &entries,
    };
    let mut image = vec![0u8; spec.image_len().unwrap()];
    spec.write(&mut image).unwrap();
    image
}

fn rlg_blobs() -> Vec<Vec<u8>> {
    ["x", "y", "z"]
        .iter()
        .enumerate()
        .map(|(k, ax)| blob(SensorKind::Rlg, ax, "deg/h", k as u32 + 1))
        .collect()
}

#[test]
fn each_blob_loads_on_its_own_row_and_the_unit_is_checked() {
    let (_, rows) = rows_of(&IMU6, imu6_sensor);
    let image = imu6_image(&rows, &rlg_blobs());
    let mut app = App::new(&IMU6);
    let r = app.load_for_unit(&image, SERIAL, None, MAX_COUNTERS, MAX_THERMOMETERS);
    assert_eq!(&r[..3], &[Ok(()), Ok(()), Ok(())]);
    assert_eq!(r[3], Err(LoadError::Image(ImageError::Missing)));
    assert_eq!(LoadError::code(&r[0]), 0);

    let r = app.load_for_unit(&image, SERIAL + 1, None, MAX_COUNTERS, MAX_THERMOMETERS);
    let other = Err(LoadError::Image(ImageError::OtherUnit));
    assert!(r.iter().all(|x| *x == other), "{r:?}");
    assert_eq!(crate::image::check_unit(&image, SERIAL), Ok(()));
    // No model runs after a refused load.
    let mut out = [Record::default(); 6];
    app.sample(&mut thermometers(), &mut [Steady; 6], &mut out);
    assert!(out.iter().all(|o| o.status & status::NO_MODEL != 0));
}

#[test]
fn an_entry_pointing_at_another_channels_valid_blob_is_refused() {
    let (_, rows) = rows_of(&IMU6, imu6_sensor);
    let mut blobs = rlg_blobs();
    // Channel 0's entry carries RLG y's blob (valid, CRC right, image sealed).
    blobs[0] = blobs[1].clone();
    // And channel 2's a QMA blob.
    blobs[2] = blob(SensorKind::Qma, "z", "ug", 9);
    let image = imu6_image(&rows, &blobs);
    let mut app = App::new(&IMU6);
    let r = app.load_for_unit(&image, SERIAL, None, MAX_COUNTERS, MAX_THERMOMETERS);
    assert_eq!(r[0], Err(LoadError::WrongChannel));
    assert_eq!(r[1], Ok(()));
    assert_eq!(r[2], Err(LoadError::WrongChannel));
}

#[test]
fn a_table_the_board_cannot_run_loads_nothing() {
    let (_, rows) = rows_of(&IMU6, imu6_sensor);
    // Another wiring: channel 1 on counter 4.
    let mut moved = rows.clone();
    moved[1].source = Source::Counter(4);
    let image = imu6_image(&moved, &rlg_blobs());
    let mut app = App::new(&IMU6);
    let r = app.load_for_unit(&image, SERIAL, None, MAX_COUNTERS, MAX_THERMOMETERS);
    assert!(
        r[..6]
            .iter()
            .all(|x| *x == Err(LoadError::Table(TableError::Wiring(1))))
    );
    // A board with fewer counters than the table names.
    let image = imu6_image(&rows, &rlg_blobs());
    let mut app = App::new(&IMU6);
    let r = app.load_for_unit(&image, SERIAL, None, 4, MAX_THERMOMETERS);
    assert_eq!(r[0], Err(LoadError::Table(TableError::Source(4))));
    // A board with fewer converters than the table's thermometers.
    let r = app.load_for_unit(&image, SERIAL, None, 6, 11);
    assert_eq!(r[0], Err(LoadError::Table(TableError::Thermometer(5))));
    // A row whose input is another thermometer than the board's wiring.
    let mut crossed = rows.clone();
    crossed[0].inputs[0].thermometer = 3;
    let image = imu6_image(&crossed, &rlg_blobs());
    let mut app = App::new(&IMU6);
    let r = app.load_for_unit(&image, SERIAL, None, MAX_COUNTERS, MAX_THERMOMETERS);
    assert_eq!(r[0], Err(LoadError::Table(TableError::Wiring(0))));
}

/// The IFOG triad of `firmware/descriptions/ifog3.toml`: three coils, three counters.
static IFOG3: [ChannelConfig; 3] = crate::wiring::IFOG3;

#[test]
fn an_ifog_triad_runs_its_own_models_through_the_same_loop() {
    let (therms, rows) = rows_of(&IFOG3, |_| (SensorKind::Ifog, "deg/h"));
    // A one-input model: T = t_coil_c, features T and rate(T).
    let blobs: Vec<Vec<u8>> = ["x", "y", "z"]
        .iter()
        .map(|ax| {
            let m = coil_model(ax);
            let mut buf = vec![0u8; 16 * 1024];
            let n = m.encode(&mut buf).unwrap();
            buf.truncate(n);
            buf
        })
        .collect();
    let entries: Vec<Entry<'_>> = blobs
        .iter()
        .enumerate()
        .map(|(k, b)| Entry {
            channel: k as u16,
            blob: b,
            provenance: Default::default(),
        })
        .collect();
    let spec = ImageSpec {
        serial: SERIAL,
        created: 0,
        tool: "test",
        thermometers: &therms,
        channels: &rows,
        entries: &entries,
    };
    let mut image = vec![0u8; spec.image_len().unwrap()];
    spec.write(&mut image).unwrap();
    let mut app = App::new(&IFOG3);
    let r = app.load_for_unit(&image, SERIAL, None, 3, 3);
    assert_eq!(&r[..3], &[Ok(()), Ok(()), Ok(())], "{r:?}");
    let mut out = [Record::default(); 3];
    for _ in 0..10 {
        app.sample(&mut thermometers()[..3], &mut [Steady; 3], &mut out);
    }
    for o in &out {
        assert_eq!(o.status & status::NO_MODEL, 0, "{o:?}");
        assert!(o.correction.is_finite() && o.correction != 0.0, "{o:?}");
    }
}

/// A small IFOG model over the coil temperature: T and rate(T), a linear term and no centers.
fn coil_model(axis: &'static str) -> FwModel<'static> {
    use tcomp_core::point::Point;
    use tcomp_core::{FeatureRange, ProgramBuilder, Rbf};
    let mut b = ProgramBuilder::<'static, NODES, FEATURES>::new();
    for line in ["T = t_coil_c", "T", "rate(T)"] {
        b.line(line).unwrap();
    }
    let program = b.finish().unwrap();
    let m = tcomp_core::testing::example_model::<CENTERS, FEATURES, NODES>(0, 3);
    let mut ranges = m.ranges.clone();
    ranges.truncate(2);
    ranges[0] = FeatureRange {
        lo: -40.0,
        hi: 80.0,
    };
    ranges[1] = FeatureRange { lo: -1.0, hi: 1.0 };
    let mut rbf = Rbf::<CENTERS, FEATURES> {
        n_features: 2,
        offset: Point([20.0, 0.0, 0.0, 0.0]),
        scale: Point([1.0 / 60.0, 1.0, 0.0, 0.0]),
        bias: 0.3,
        ..Rbf::default()
    };
    rbf.linear.0[0] = 0.5;
    rbf.linear.0[1] = 0.1;
    let mut m = Model::new(m.meta, program, ranges, rbf, m.residual);
    m.meta.sensor = SensorKind::Ifog;
    m.meta.axis = axis;
    m.meta.unit = "deg/h";
    m
}

struct At25;

impl tcomp_hal::ErrorType for At25 {
    type Error = ErrorKind;
}

impl Thermometer for At25 {
    fn read_celsius(&mut self) -> Result<f32, ErrorKind> {
        Ok(25.0)
    }
}

fn thermometers() -> [At25; MAX_THERMOMETERS] {
    core::array::from_fn(|_| At25)
}

/// 1,000 pulses per read.
#[derive(Clone, Copy)]
struct Steady;

impl tcomp_hal::ErrorType for Steady {
    type Error = ErrorKind;
}

impl PulseCounter for Steady {
    fn read_delta(&mut self) -> Result<i32, ErrorKind> {
        Ok(1000)
    }
}

/// The MEMS IMU of `firmware/descriptions/mems6.toml`: one die thermometer, six sample sources.
static MEMS6: [ChannelConfig; 6] = crate::wiring::MEMS6;

/// `tcomp image --board firmware/descriptions/mems6.toml --serial 0x5EED --created 1763900000`
/// of six models `tcomp fit` made from `data/realdata/mems_thermal_cycle.csv` (train before
/// 3130 s; `--feature temp_imu_C --reference-value 0 --sensor mems-gyro|mems-accel --axis A
/// --unit rad/s|m/s^2`): the real tool's image of the real description and data.
static MEMS6_IMAGE: &[u8] = include_bytes!("testdata/mems6.bin");

/// A die at a fixed temperature.
struct Die(f32);

impl tcomp_hal::ErrorType for Die {
    type Error = ErrorKind;
}

impl Thermometer for Die {
    fn read_celsius(&mut self) -> Result<f32, ErrorKind> {
        Ok(self.0)
    }
}

#[test]
fn a_mems_imu_runs_its_real_models_from_the_tools_image_on_sample_sources() {
    let mut app = App::new(&MEMS6);
    let hash = Some(crate::wiring::MEMS6_HASH);
    let r = app.load_for_unit(MEMS6_IMAGE, 0x5EED, hash, 6, 1);
    assert_eq!(&r[..6], &[Ok(()); 6], "{r:?}");
    // The same image on the RLG/QMA wiring: refused as another board's, nothing loads; and by
    // its table alone when the firmware's table has no description hash.
    let mut rlg = App::new(&IMU6);
    let imu6 = Some(crate::wiring::IMU6_RLG_QMA_HASH);
    let r = rlg.load_for_unit(MEMS6_IMAGE, 0x5EED, imu6, MAX_COUNTERS, MAX_THERMOMETERS);
    let other = Err(LoadError::Table(TableError::OtherBoard));
    assert!(r[..6].iter().all(|x| *x == other), "{r:?}");
    assert_eq!(LoadError::code(&r[0]), 9);
    let r = rlg.load_for_unit(MEMS6_IMAGE, 0x5EED, None, MAX_COUNTERS, MAX_THERMOMETERS);
    assert!(
        r.iter().all(|x| matches!(x, Err(LoadError::Table(_)))),
        "{r:?}"
    );
    // A firmware for a description with this very wiring but another hash (another thermometer
    // constant, sensor or unit on some row): the wiring matches, the image is still refused.
    let mut twin = App::new(&MEMS6);
    let r = twin.load_for_unit(MEMS6_IMAGE, 0x5EED, hash.map(|h| h ^ 1), 6, 1);
    assert!(r[..6].iter().all(|x| *x == other), "{r:?}");
    assert!(
        twin.load_for_unit(MEMS6_IMAGE, 0x5EED, hash, 6, 1)[..6]
            .iter()
            .all(Result::is_ok)
    );

    let registers = [
        Ok(100),
        Ok(-200),
        Ok(0),
        Ok(1000),
        Ok(-1000),
        Err(ErrorKind::Other),
    ];
    let mut out = [Record::default(); 6];
    for _ in 0..5 {
        app.sample_sources(&mut [Die(30.0)], &registers, &mut out);
    }
    for (k, o) in out.iter().enumerate().take(5) {
        let raw = match registers[k] {
            Ok(v) => v as f32 * MEMS6[k].scale.per_pulse(),
            Err(_) => unreachable!(),
        };
        assert_eq!(o.status, status::OK, "channel {k}: {o:?}");
        assert!(o.correction.is_finite() && o.correction != 0.0, "{o:?}");
        assert_eq!(o.compensated, raw - o.correction, "channel {k}");
    }
    // The failed register read: NaN, flagged.
    assert!(out[5].compensated.is_nan());
    assert_ne!(out[5].status & status::SENSOR_ERROR, 0);
    // The correction follows the die temperature, as the fitted cubic does (a 30 °C step is
    // refused as a jump until the physics could have got there: 6 s).
    let before = out[3].correction;
    for _ in 0..2000 {
        app.sample_sources(&mut [Die(60.0)], &registers, &mut out);
    }
    assert!(
        (out[3].correction - before).abs() > 1e-4,
        "{before} {:?}",
        out[3]
    );
}
