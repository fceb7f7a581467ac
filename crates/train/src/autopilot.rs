//! The autopilots' own thermal calibrations, computed from a log exactly as their tools compute
//! them, so that a PX4 or ArduPilot user gets the parameter file their firmware flies — and can see
//! beside it what that cubic leaves behind.
//!
//! PX4 (`Tools/process_sensor_caldata.py`): per `sensor_gyro`/`sensor_accel` instance k, `TMIN`
//! and `TMAX` the extreme temperatures, `TREF` their midpoint, each axis median-filtered (31
//! samples, zero-padded as `scipy.signal.medfilt`), the accelerometer's axis less its median, then
//! averaged into 2000 bins of temperature (`resampleWithDeltaX`) and fitted with a cubic in
//! `T − TREF` (`numpy.polyfit`); parameters `TC_Gk_X{0..3}_{axis}` / `TC_Ak_…` and the device id.
//! Temperatures and their differences are single precision, as the tool's numpy float32 arrays.
//!
//! ArduPilot (`Tools/scripts/tempcal_IMU.py`, the cubic version, as published in the
//! `ardupilot-methodic-configurator` package): per `IMU` instance, the calibration the log already
//! flew with (its `PARM` records: `INS_TCALn_*`, `INS_ACCn_CALTEMP`, `INS_GYRn_CALTEMP`) taken
//! out of each record, a 2 s moving average of every column, `TMIN`/`TMAX` of the averaged
//! temperature, a cubic in `T − 35` fitted to the gyro and to the accelerometer less its value at
//! `INS_ACCn_CALTEMP` (its mean when the log has none); parameters
//! `INS_TCALn_{ACC,GYR}{1..3}_{X,Y,Z}` are the coefficients of `(T−35)^p`, p = 1..3, times 1e6
//! (the constant is dropped: the offsets calibration owns it). The log's parameters are the ones
//! in force for every record (the firmware read them at boot, before logging); the script reads
//! them in file order, which on a log whose parameter burst interleaves with the first IMU
//! records stops it with a `KeyError` (`data/autopilot/README.md`). Refused: a log whose
//! `AHRS_ORIENTATION` is not 0 (the script first rotates the data into the sensor frame).

use nalgebra::{DMatrix, DVector};

/// The least-squares polynomial of degree `deg` through `(x, y)`, highest power first, as
/// `numpy.polyfit` (columns of the Vandermonde matrix scaled to unit norm, then solved by SVD).
pub fn polyfit(x: &[f64], y: &[f64], deg: usize) -> Option<Vec<f64>> {
    let n = x.len().min(y.len());
    if n <= deg {
        return None;
    }
    let mut a = DMatrix::<f64>::zeros(n, deg + 1);
    for (i, &xi) in x.iter().take(n).enumerate() {
        for j in 0..=deg {
            a[(i, j)] = xi.powi((deg - j) as i32);
        }
    }
    let scale: Vec<f64> = (0..=deg)
        .map(|j| a.column(j).norm())
        .map(|s| if s == 0.0 { 1.0 } else { s })
        .collect();
    for (j, s) in scale.iter().enumerate() {
        a.column_mut(j).scale_mut(1.0 / s);
    }
    let b = DVector::from_iterator(n, y.iter().take(n).copied());
    let svd = a.svd(true, true);
    // numpy's rcond: singular values below n·eps of the largest are dropped.
    let largest = svd.singular_values.iter().copied().fold(0.0, f64::max);
    let c = svd.solve(&b, n as f64 * f64::EPSILON * largest).ok()?;
    Some(c.iter().zip(&scale).map(|(c, s)| c / s).collect())
}

/// `scipy.signal.medfilt(v, k)`: the median of each window of `k` (odd) samples, zeros beyond
/// the ends.
pub fn medfilt(v: &[f32], k: usize) -> Vec<f32> {
    let h = k / 2;
    let mut win = Vec::with_capacity(k);
    (0..v.len())
        .map(|i| {
            win.clear();
            for j in 0..k {
                let at = (i + j).checked_sub(h);
                win.push(at.and_then(|a| v.get(a)).copied().unwrap_or(0.0));
            }
            win.sort_by(f32::total_cmp);
            win.get(h).copied().unwrap_or(0.0)
        })
        .collect()
}

/// `numpy.median` of single-precision values (the mean of the middle two of an even count, in
/// single precision).
fn median32(v: &[f32]) -> f32 {
    let mut s = v.to_vec();
    s.sort_by(f32::total_cmp);
    let n = s.len();
    match n {
        0 => f32::NAN,
        _ if n % 2 == 1 => s.get(n / 2).copied().unwrap_or(f32::NAN),
        _ => {
            let (a, b) = (s.get(n / 2 - 1).copied(), s.get(n / 2).copied());
            match (a, b) {
                (Some(a), Some(b)) => (a + b) / 2.0,
                _ => f32::NAN,
            }
        }
    }
}

/// PX4's `resampleWithDeltaX`: the mean x and y of each of 2000 equal bins of x that holds data.
fn resample(x: &[f32], y: &[f32]) -> (Vec<f64>, Vec<f64>) {
    const BINS: usize = 2000;
    let lo = x.iter().copied().fold(f32::INFINITY, f32::min);
    let hi = x.iter().copied().fold(f32::NEG_INFINITY, f32::max);
    let interval = (hi - lo) / BINS as f32;
    let (mut sx, mut sy, mut count) = (vec![0.0f64; BINS], vec![0.0f64; BINS], vec![0u32; BINS]);
    for (&xi, &yi) in x.iter().zip(y) {
        let bin = if xi < lo {
            0
        } else if xi < hi {
            (((xi - lo) / interval) as usize).min(BINS - 1)
        } else {
            BINS - 1
        };
        if let (Some(a), Some(b), Some(c)) = (sx.get_mut(bin), sy.get_mut(bin), count.get_mut(bin))
        {
            *a += f64::from(xi);
            *b += f64::from(yi);
            *c += 1;
        }
    }
    let mut out = (Vec::new(), Vec::new());
    for ((a, b), c) in sx.iter().zip(&sy).zip(&count) {
        if *c > 0 {
            out.0.push(a / f64::from(*c));
            out.1.push(b / f64::from(*c));
        }
    }
    out
}

/// One PX4 sensor instance's thermal compensation.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Px4Sensor {
    /// `G` (gyro) or `A` (accelerometer).
    pub kind: char,
    /// The instance (the topic's multi id).
    pub instance: u8,
    /// `TC_xk_ID`: the median device id.
    pub device_id: i64,
    /// `TMIN`, `TMAX`, `TREF` (°C, single precision as the tool's).
    pub tmin: f32,
    /// See `tmin`.
    pub tmax: f32,
    /// See `tmin`.
    pub tref: f32,
    /// `X0..X3` per axis (x, y, z): `coef[axis][p]` multiplies `(T − TREF)^p`.
    pub coef: [[f64; 4]; 3],
}

/// PX4's fit of one instance: `kind` `G` or `A`, temperatures, device ids and the three axes.
pub fn px4_fit(
    kind: char,
    instance: u8,
    temperature: &[f32],
    device_id: &[f64],
    axes: [&[f32]; 3],
) -> Option<Px4Sensor> {
    if temperature.first().is_none_or(|t| t.is_nan()) {
        return None;
    }
    let tmin = temperature.iter().copied().fold(f32::INFINITY, f32::min);
    let tmax = temperature
        .iter()
        .copied()
        .fold(f32::NEG_INFINITY, f32::max);
    let tref = 0.5f32 * (tmin + tmax);
    let trel: Vec<f32> = temperature.iter().map(|t| t - tref).collect();
    let mut ids = device_id.to_vec();
    ids.sort_by(f64::total_cmp);
    let id_median = match ids.len() {
        0 => 0.0,
        n if n % 2 == 1 => ids.get(n / 2).copied().unwrap_or(0.0),
        n => {
            (ids.get(n / 2 - 1).copied().unwrap_or(0.0) + ids.get(n / 2).copied().unwrap_or(0.0))
                / 2.0
        }
    };
    let mut coef = [[0.0; 4]; 3];
    for (c, axis) in coef.iter_mut().zip(axes) {
        let filtered = medfilt(axis, 31);
        let y: Vec<f32> = if kind == 'A' {
            let m = median32(&filtered);
            filtered.iter().map(|v| v - m).collect()
        } else {
            filtered
        };
        let (x, y) = resample(&trel, &y);
        let p = polyfit(&x, &y, 3)?;
        for (k, v) in p.iter().rev().enumerate() {
            if let Some(slot) = c.get_mut(k) {
                *slot = *v;
            }
        }
    }
    Some(Px4Sensor {
        kind,
        instance,
        device_id: id_median as i64,
        tmin,
        tmax,
        tref,
        coef,
    })
}

impl Px4Sensor {
    /// The parameter lines of QGroundControl's `.params` format (`1 1 NAME VALUE TYPE`, tab
    /// separated; type 6 for the id, 9 for floats), in the tool's order of keys.
    pub fn params(&self) -> Vec<String> {
        let p = format!("TC_{}{}", self.kind, self.instance);
        let mut lines = vec![
            format!("1\t1\t{p}_ID\t{}\t6", self.device_id),
            format!("1\t1\t{p}_TMIN\t{}\t9", self.tmin),
            format!("1\t1\t{p}_TMAX\t{}\t9", self.tmax),
            format!("1\t1\t{p}_TREF\t{}\t9", self.tref),
        ];
        let mut coefs = Vec::new();
        for (axis, c) in self.coef.iter().enumerate() {
            for (k, v) in c.iter().enumerate() {
                coefs.push((format!("{p}_X{k}_{axis}"), *v));
            }
        }
        // The tool sorts the gyro's keys and keeps the accelerometer's in their dict order
        // (X0..X3 of axis 0, then axis 1, …), which this order is too.
        if self.kind == 'G' {
            coefs.sort_by(|a, b| a.0.cmp(&b.0));
        }
        lines.extend(
            coefs
                .into_iter()
                .map(|(k, v)| format!("1\t1\t{k}\t{v:?}\t9")),
        );
        lines
    }

    /// The bias the firmware subtracts at temperature `t` on axis `axis` (temperature clamped to
    /// `[TMIN, TMAX]`, as PX4's `TemperatureCompensation`).
    pub fn offset(&self, axis: usize, t: f64) -> f64 {
        let dt = t.clamp(f64::from(self.tmin), f64::from(self.tmax)) - f64::from(self.tref);
        let c = self.coef.get(axis).copied().unwrap_or([0.0; 4]);
        c[0] + dt * (c[1] + dt * (c[2] + dt * c[3]))
    }
}

/// One ArduPilot IMU instance's temperature calibration (the cubic version of the tool).
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct ArduImu {
    /// The IMU instance (0-based; parameters are numbered from 1).
    pub instance: u8,
    /// `TMIN`, `TMAX` (°C).
    pub tmin: f64,
    /// See `tmin`.
    pub tmax: f64,
    /// Accelerometer polynomial per axis, highest power first (`[p3, p2, p1, p0]`).
    pub acc: [[f64; 4]; 3],
    /// Gyro polynomial per axis.
    pub gyr: [[f64; 4]; 3],
}

/// ArduPilot's reference temperature (°C).
pub const ARDU_TREF: f64 = 35.0;
/// ArduPilot's parameter scale.
pub const ARDU_SCALE: f64 = 1e6;

/// The tool's moving average over `w` samples ("valid" part: `n − w + 1` values, through a
/// cumulative sum as the tool computes it).
fn moving_average(v: &[f64], w: usize) -> Vec<f64> {
    let mut c = Vec::with_capacity(v.len());
    let mut s = 0.0;
    for x in v {
        s += x;
        c.push(s);
    }
    let shifted: Vec<f64> = (0..c.len())
        .map(|i| {
            let here = c.get(i).copied().unwrap_or(0.0);
            if i >= w {
                here - c.get(i - w).copied().unwrap_or(0.0)
            } else {
                here
            }
        })
        .collect();
    shifted
        .get(w.saturating_sub(1)..)
        .unwrap_or(&[])
        .iter()
        .map(|x| x / w as f64)
        .collect()
}

/// `numpy.poly1d(c)(x)` (Horner's rule, highest power first).
fn polyval(c: &[f64; 4], x: f64) -> f64 {
    c.iter().fold(0.0, |y, k| y * x + k)
}

/// The temperature calibration a DataFlash log flew with, from its `PARM` records as the tool
/// reads them (its `Coefficients` of the log).
#[derive(Clone, Debug)]
pub struct LogCalibration {
    /// `INS_TCALn_ENABLE` per IMU (0 when not logged).
    pub enable: [f64; 3],
    /// `INS_TCALn_TMIN` (−100 when not logged, as the tool).
    pub tmin: [f64; 3],
    /// `INS_TCALn_TMAX`.
    pub tmax: [f64; 3],
    /// Accelerometer polynomial per IMU and axis, highest power first, constant 0 (`None`: no
    /// coefficient of that axis logged).
    pub acc: [[Option<[f64; 4]>; 3]; 3],
    /// Gyro polynomial per IMU and axis.
    pub gyr: [[Option<[f64; 4]>; 3]; 3],
    /// `INS_ACCn_CALTEMP`, when logged.
    pub acc_caltemp: [Option<f64>; 3],
    /// `INS_GYRn_CALTEMP`, when logged.
    pub gyr_caltemp: [Option<f64>; 3],
    /// IMUs whose `INS_TCALn_ENABLE` changed within the log (a calibration learnt in flight): the
    /// tool stops reading them.
    pub stopped: [bool; 3],
    /// `AHRS_ORIENTATION`.
    pub orientation: f64,
}

impl LogCalibration {
    /// The calibration in `params` (name, value; file order).
    pub fn from_params(params: &[(String, f64)]) -> Self {
        let mut c = Self {
            enable: [0.0; 3],
            tmin: [-100.0; 3],
            tmax: [-100.0; 3],
            acc: [[None; 3]; 3],
            gyr: [[None; 3]; 3],
            acc_caltemp: [None; 3],
            gyr_caltemp: [None; 3],
            stopped: [false; 3],
            orientation: 0.0,
        };
        let imu = |digit: &str| -> Option<usize> {
            let d: usize = digit.parse().ok()?;
            (1..=3).contains(&d).then(|| d - 1)
        };
        for (name, value) in params {
            let v = *value;
            if name == "AHRS_ORIENTATION" {
                c.orientation = v;
            } else if let Some(rest) = name.strip_prefix("INS_TCAL") {
                let Some((d, field)) = rest.split_at_checked(1) else {
                    continue;
                };
                let Some(i) = imu(d) else { continue };
                if c.stopped.get(i).copied().unwrap_or(true) {
                    continue;
                }
                match field {
                    "_ENABLE" => {
                        let was = c.enable.get(i).copied().unwrap_or(0.0);
                        if (v == 1.0 && was == 2.0) || (v == 0.0 && was == 1.0) {
                            if let Some(s) = c.stopped.get_mut(i) {
                                *s = true;
                            }
                        } else if let Some(e) = c.enable.get_mut(i) {
                            *e = v;
                        }
                    }
                    "_TMIN" => {
                        if let Some(t) = c.tmin.get_mut(i) {
                            *t = v;
                        }
                    }
                    "_TMAX" => {
                        if let Some(t) = c.tmax.get_mut(i) {
                            *t = v;
                        }
                    }
                    _ => {
                        // `_ACC1_X` … `_GYR3_Z`
                        let b = field.as_bytes();
                        let (Some(kind), Some(&p), Some(&axis)) =
                            (field.get(1..4), b.get(4), b.get(6))
                        else {
                            continue;
                        };
                        if field.len() != 7 || b.get(5) != Some(&b'_') {
                            continue;
                        }
                        let (Some(p), Some(axis)) = (
                            (b'1'..=b'3').contains(&p).then(|| usize::from(p - b'0')),
                            [b'X', b'Y', b'Z'].iter().position(|a| *a == axis),
                        ) else {
                            continue;
                        };
                        let table = match kind {
                            "ACC" => &mut c.acc,
                            "GYR" => &mut c.gyr,
                            _ => continue,
                        };
                        if let Some(slot) = table.get_mut(i).and_then(|t| t.get_mut(axis)) {
                            let poly = slot.get_or_insert([0.0; 4]);
                            if let Some(k) = poly.get_mut(3 - p) {
                                *k = v / ARDU_SCALE;
                            }
                        }
                    }
                }
            } else {
                for (prefix, table) in [
                    ("INS_ACC", &mut c.acc_caltemp),
                    ("INS_GYR", &mut c.gyr_caltemp),
                ] {
                    let Some(rest) = name.strip_prefix(prefix) else {
                        continue;
                    };
                    let Some((d, tail)) = rest.split_at_checked(1) else {
                        continue;
                    };
                    if let (Some(i), true) = (imu(d), tail.starts_with("_CALTEMP"))
                        && !c.stopped.get(i).copied().unwrap_or(true)
                        && let Some(slot) = table.get_mut(i)
                    {
                        *slot = Some(v);
                    }
                }
            }
        }
        c
    }

    /// The correction the firmware applied to IMU `imu`'s axis at temperature `t`, calibrated
    /// at `cal` (the tool's `Coefficients.correction`: 0 when disabled or uncalibrated).
    fn correction(&self, poly: Option<[f64; 4]>, imu: usize, t: f64, cal: f64) -> f64 {
        let (Some(poly), Some(&lo), Some(&hi)) = (poly, self.tmin.get(imu), self.tmax.get(imu))
        else {
            return 0.0;
        };
        if self.enable.get(imu) != Some(&1.0) || cal < -80.0 {
            return 0.0;
        }
        let clamp = |v: f64| v.max(lo).min(hi);
        polyval(&poly, clamp(cal) - ARDU_TREF) - polyval(&poly, clamp(t) - ARDU_TREF)
    }

    /// IMU `imu`'s records with the log's calibration taken out (`acc`, `gyr` in place).
    pub fn remove(
        &self,
        imu: usize,
        temperature: &[f64],
        acc: &mut [Vec<f64>; 3],
        gyr: &mut [Vec<f64>; 3],
    ) {
        let (Some(ap), Some(gp)) = (self.acc.get(imu), self.gyr.get(imu)) else {
            return;
        };
        let acal = self
            .acc_caltemp
            .get(imu)
            .copied()
            .flatten()
            .unwrap_or(ARDU_TREF);
        let gcal = self
            .gyr_caltemp
            .get(imu)
            .copied()
            .flatten()
            .unwrap_or(ARDU_TREF);
        for (axis, (a, g)) in acc.iter_mut().zip(gyr.iter_mut()).enumerate() {
            let (pa, pg) = (
                ap.get(axis).copied().flatten(),
                gp.get(axis).copied().flatten(),
            );
            for ((va, vg), &t) in a.iter_mut().zip(g.iter_mut()).zip(temperature) {
                *va -= self.correction(pa, imu, t, acal);
                *vg -= self.correction(pg, imu, t, gcal);
            }
        }
    }
}

/// The tool's `accel_at_temp`: the (averaged) value where the temperature first rises through
/// `cal`, interpolated linearly; the first value below the first temperature, the last if never.
fn value_at_temperature(t: &[f64], v: &[f64], cal: f64) -> f64 {
    let first = v.first().copied().unwrap_or(f64::NAN);
    if t.first().is_some_and(|t0| cal < *t0) {
        return first;
    }
    for (tw, vw) in t.windows(2).zip(v.windows(2)) {
        if let ([t1, t2], [v1, v2]) = (tw, vw)
            && *t1 <= cal
            && cal <= *t2
        {
            let dt = t2 - t1;
            if dt == 0.0 {
                return *v1;
            }
            let p = (cal - t1) / dt;
            return v1 + (v2 - v1) * p;
        }
    }
    v.last().copied().unwrap_or(f64::NAN)
}

/// ArduPilot's fit of one IMU instance from its records (the log's calibration already taken
/// out, [`LogCalibration::remove`]): time (s), temperature, accelerometer and gyro axes, and the
/// accelerometer's calibration temperature when the log has one.
pub fn ardupilot_fit(
    instance: u8,
    time: &[f64],
    temperature: &[f64],
    acc: [&[f64]; 3],
    gyr: [&[f64]; 3],
    acc_caltemp: Option<f64>,
) -> Option<ArduImu> {
    let n = time.len();
    let seconds = time.last()? - time.first()?;
    let window = ((n as f64 / seconds) as usize) * 2;
    let filt = |v: &[f64]| {
        if window > 1 {
            moving_average(v, window)
        } else {
            v.to_vec()
        }
    };
    let t = filt(temperature);
    let tmin = t.iter().copied().fold(f64::INFINITY, f64::min);
    let tmax = t.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let trel: Vec<f64> = t.iter().map(|x| x - ARDU_TREF).collect();
    let mut out = ArduImu {
        instance,
        tmin,
        tmax,
        acc: [[0.0; 4]; 3],
        gyr: [[0.0; 4]; 3],
    };
    for k in 0..3 {
        let a = filt(acc.get(k)?);
        let ofs = match acc_caltemp {
            Some(cal) => value_at_temperature(&t, &a, cal),
            None => a.iter().sum::<f64>() / a.len().max(1) as f64,
        };
        let a: Vec<f64> = a.iter().map(|v| v - ofs).collect();
        let pa = polyfit(&trel, &a, 3)?;
        let pg = polyfit(&trel, &filt(gyr.get(k)?), 3)?;
        if let (Some(sa), Some(sg)) = (out.acc.get_mut(k), out.gyr.get_mut(k)) {
            sa.copy_from_slice(pa.get(..4)?);
            sg.copy_from_slice(pg.get(..4)?);
        }
    }
    Some(out)
}

impl ArduImu {
    /// The parameter lines (`NAME VALUE`), in the tool's order and rounding.
    pub fn params(&self) -> Vec<String> {
        let i = self.instance + 1;
        let mut lines = vec![
            format!("INS_TCAL{i}_ENABLE 1"),
            format!("INS_TCAL{i}_TMIN {:.1}", self.tmin),
            format!("INS_TCAL{i}_TMAX {:.1}", self.tmax),
        ];
        for (name, c) in [("ACC", &self.acc), ("GYR", &self.gyr)] {
            for p in 1..=3usize {
                for (axis, label) in ["X", "Y", "Z"].iter().enumerate() {
                    let v = c
                        .get(axis)
                        .and_then(|a| a.get(3 - p))
                        .copied()
                        .unwrap_or(0.0);
                    lines.push(format!(
                        "INS_TCAL{i}_{name}{p}_{label} {:.9}",
                        v * ARDU_SCALE
                    ));
                }
            }
        }
        lines
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    #[test]
    fn polyfit_recovers_a_cubic_and_medfilt_pads_with_zeros() {
        let x: Vec<f64> = (0..50).map(|i| f64::from(i) * 0.3 - 7.0).collect();
        let y: Vec<f64> = x
            .iter()
            .map(|x| 0.5 - 0.2 * x + 0.03 * x * x - 0.004 * x * x * x)
            .collect();
        let p = polyfit(&x, &y, 3).unwrap();
        for (a, b) in p.iter().zip([-0.004, 0.03, -0.2, 0.5]) {
            assert!((a - b).abs() < 1e-12, "{p:?}");
        }
        assert_eq!(medfilt(&[5.0], 3), [0.0]);
        assert_eq!(medfilt(&[1.0, 2.0, 3.0], 3), [1.0, 2.0, 2.0]);
        assert_eq!(moving_average(&[1.0, 2.0, 3.0, 4.0], 2), [1.5, 2.5, 3.5]);
    }
}

/// The parameters of every IMU instance of a log, in the autopilot's own file format.
#[derive(Clone, Debug, serde::Serialize)]
pub struct ParamFile {
    /// `px4` or `ardupilot`.
    pub format: &'static str,
    /// PX4 sensors (gyros, then accelerometers).
    pub px4: Vec<Px4Sensor>,
    /// ArduPilot IMUs.
    pub ardupilot: Vec<ArduImu>,
    /// Instances the tool could not fit, with why.
    pub skipped: Vec<String>,
}

impl ParamFile {
    /// The file's text.
    pub fn text(&self) -> String {
        let mut out = String::new();
        if self.format == "px4" {
            out.push_str(
                "# Sensor thermal compensation parameters\n#\n# Vehicle-Id Component-Id Name Value Type\n",
            );
            for s in self.px4.iter().filter(|s| s.kind == 'A') {
                out.extend(s.params().into_iter().map(|l| l + "\n"));
            }
            for s in self.px4.iter().filter(|s| s.kind == 'G') {
                out.extend(s.params().into_iter().map(|l| l + "\n"));
            }
        } else {
            for i in &self.ardupilot {
                out.extend(i.params().into_iter().map(|l| l + "\n"));
            }
        }
        out
    }
}

fn f32s(v: &[f64]) -> Vec<f32> {
    v.iter().map(|x| *x as f32).collect()
}

/// The autopilot's thermal calibration of every IMU instance in the log at `path`, as its tool
/// computes it (see the module doc).
pub fn from_log(path: &std::path::Path) -> Result<ParamFile, crate::TrainError> {
    let (kind, tables) = read_log(path)?;
    fit_tables(&path.display().to_string(), kind, &tables)
}

/// The log at `path`, refused when it is not an autopilot log.
fn read_log(
    path: &std::path::Path,
) -> Result<(crate::dataset::log::Kind, crate::dataset::log::Tables), crate::TrainError> {
    let not_log = || crate::DataError::LogColumn {
        file: path.display().to_string(),
        what: "not an autopilot log (.ulg or DataFlash .bin): autopilot parameters come from one"
            .into(),
    };
    Ok(crate::dataset::log::read(path)?.ok_or_else(not_log)?)
}

/// The autopilot's calibration of every IMU instance in `tables` (see [`from_log`]).
fn fit_tables(
    file: &str,
    kind: crate::dataset::log::Kind,
    tables: &crate::dataset::log::Tables,
) -> Result<ParamFile, crate::TrainError> {
    use crate::dataset::log::{self, Kind};
    let file = file.to_string();
    let mut out = ParamFile {
        format: if kind == Kind::ULog {
            "px4"
        } else {
            "ardupilot"
        },
        px4: Vec::new(),
        ardupilot: Vec::new(),
        skipped: Vec::new(),
    };
    let col = |m: &log::Message, f: &str| {
        m.fields
            .iter()
            .find(|(n, _)| n == f)
            .map(|(_, v)| v.clone())
    };
    match kind {
        Kind::ULog => {
            for (kind, topic) in [('G', "sensor_gyro"), ('A', "sensor_accel")] {
                for i in 0..4u8 {
                    let Some(m) = tables.message(topic, i) else {
                        continue;
                    };
                    let (Some(t), Some(x), Some(y), Some(z)) =
                        (col(m, "temperature"), col(m, "x"), col(m, "y"), col(m, "z"))
                    else {
                        continue;
                    };
                    let t = f32s(&t);
                    if t.first().is_none_or(|v| v.is_nan()) {
                        out.skipped.push(format!(
                            "TC_{kind}{i}: {topic}[{i}] logs no temperature (NaN): no thermal \
                             calibration (PX4's tool skips it too)"
                        ));
                        continue;
                    }
                    let (lo, hi) = t
                        .iter()
                        .fold((f32::INFINITY, f32::NEG_INFINITY), |(l, h), v| {
                            (l.min(*v), h.max(*v))
                        });
                    if lo.partial_cmp(&hi) != Some(std::cmp::Ordering::Less) {
                        out.skipped.push(format!(
                            "TC_{kind}{i}: {topic}[{i}]'s temperature never varies ({lo} °C): no cubic \
                             in temperature can be fitted (PX4's tool divides by zero here)"
                        ));
                        continue;
                    }
                    let ids = col(m, "device_id").unwrap_or_default();
                    let (x, y, z) = (f32s(&x), f32s(&y), f32s(&z));
                    match px4_fit(kind, i, &t, &ids, [&x, &y, &z]) {
                        Some(s) => out.px4.push(s),
                        None => out.skipped.push(format!("TC_{kind}{i}: the fit failed")),
                    }
                }
            }
        }
        Kind::DataFlash => {
            let cal = LogCalibration::from_params(&tables.params);
            if cal.orientation != 0.0 {
                return Err(crate::DataError::LogColumn {
                    file,
                    what: format!(
                        "AHRS_ORIENTATION is {} in the log: ArduPilot's tool first rotates the \
                         IMU data into the sensor frame, which tcomp does not do; calibrate from \
                         a log flown with AHRS_ORIENTATION 0",
                        cal.orientation
                    ),
                }
                .into());
            }
            for i in 0..3u8 {
                let Some(m) = tables.message("IMU", i) else {
                    continue;
                };
                let k = usize::from(i);
                if cal.stopped.get(k).copied().unwrap_or(false) {
                    out.skipped.push(format!(
                        "INS_TCAL{}: INS_TCAL{}_ENABLE changes within the log (a calibration \
                         learnt in flight): ArduPilot's tool reads none of IMU[{i}]'s records",
                        i + 1,
                        i + 1
                    ));
                    continue;
                }
                let names = ["T", "AccX", "AccY", "AccZ", "GyrX", "GyrY", "GyrZ"];
                let cols: Vec<Option<Vec<f64>>> = names.iter().map(|n| col(m, n)).collect();
                let [
                    Some(t),
                    Some(ax),
                    Some(ay),
                    Some(az),
                    Some(gx),
                    Some(gy),
                    Some(gz),
                ] = <[Option<Vec<f64>>; 7]>::try_from(cols).unwrap_or_default()
                else {
                    continue;
                };
                let (mut acc, mut gyr) = ([ax, ay, az], [gx, gy, gz]);
                cal.remove(k, &t, &mut acc, &mut gyr);
                let time: Vec<f64> = m.time_us.iter().map(|&u| u as f64 * 1e-6).collect();
                let acc_caltemp = cal.acc_caltemp.get(k).copied().flatten();
                let [ax, ay, az] = &acc;
                let [gx, gy, gz] = &gyr;
                match ardupilot_fit(i, &time, &t, [ax, ay, az], [gx, gy, gz], acc_caltemp) {
                    Some(s) => out.ardupilot.push(s),
                    None => out
                        .skipped
                        .push(format!("INS_TCAL{}: the fit failed", i + 1)),
                }
            }
        }
    }
    if out.px4.is_empty() && out.ardupilot.is_empty() {
        return Err(crate::DataError::LogColumn {
            file,
            what: format!(
                "no IMU instance to calibrate ({}){}",
                if kind == Kind::ULog {
                    "PX4: sensor_gyro / sensor_accel with temperature, x, y, z"
                } else {
                    "ArduPilot: IMU with T, AccX..Z, GyrX..Z"
                },
                if out.skipped.is_empty() {
                    String::new()
                } else {
                    format!("; {}", out.skipped.join("; "))
                }
            ),
        }
        .into());
    }
    Ok(out)
}

/// What the autopilot's cubic leaves on one axis over the held-out part of a log.
#[derive(Clone, Debug, serde::Serialize)]
pub struct HeldOutAxis {
    /// The axis as `--data` names it (`IMU[1].GyrZ`, `sensor_gyro[0].x`).
    pub column: String,
    /// Its instance's temperature, as `--data` names it (`IMU[1].T`).
    pub temperature: String,
    /// Held-out records.
    pub rows: usize,
    /// The held-out records' temperature range (°C).
    pub held_out_range: [f64; 2],
    /// The cubic's `[TMIN, TMAX]` (°C), fitted before the split; the firmware clamps to it.
    pub fitted_range: [f64; 2],
    /// Standard deviation of the axis over the held-out records, nothing removed.
    pub raw_std: f64,
    /// Standard deviation of what the cubic leaves there: the axis less the correction the
    /// firmware applies (ArduPilot: after the log's own calibration is taken out, as the tool
    /// does).
    pub cubic_std: f64,
    /// The axis' records over the whole log as the cubic saw them (`time_s`, the temperature
    /// and the axis; ArduPilot: the log's own calibration taken out), for fitting another model
    /// to the same signal.
    #[serde(skip)]
    pub data: crate::Dataset,
}

/// Population standard deviation (`numpy.std`): the spread a constant offset does not change.
/// Standard deviations, not RMS, because both autopilots leave the constant to another
/// calibration (ArduPilot drops it, PX4's gyro offsets are re-estimated at boot).
pub fn std(v: &[f64]) -> f64 {
    let n = v.len() as f64;
    if v.is_empty() {
        return f64::NAN;
    }
    let mean = v.iter().sum::<f64>() / n;
    (v.iter().map(|x| (x - mean) * (x - mean)).sum::<f64>() / n).sqrt()
}

/// `tables` with only the records whose timestamp is before `until_s` (the log's seconds).
fn before(tables: &crate::dataset::log::Tables, until_s: f64) -> crate::dataset::log::Tables {
    let mut t = tables.clone();
    for m in &mut t.messages {
        let n = m.time_us.partition_point(|&u| (u as f64) * 1e-6 < until_s);
        m.time_us.truncate(n);
        m.records.truncate(n);
        for (_, v) in &mut m.fields {
            v.truncate(n);
        }
    }
    t
}

/// The autopilot's own cubic fitted (by [`from_log`]'s procedure) on the records before `from_s`
/// (seconds, the log's time: `time_s`), and what it leaves on every axis over the records from
/// `from_s` on: the held-out half of the side-by-side with tcomp's model (`tcomp
/// autopilot-params --held-out-from`). Errors as [`from_log`]'s, and when no instance has
/// held-out records.
pub fn held_out(
    path: &std::path::Path,
    from_s: f64,
) -> Result<(ParamFile, Vec<HeldOutAxis>), crate::TrainError> {
    use crate::dataset::log::Kind;
    let file = path.display().to_string();
    let (kind, tables) = read_log(path)?;
    let fitted = fit_tables(&file, kind, &before(&tables, from_s))?;
    let col = |m: &crate::dataset::log::Message, f: &str| {
        m.fields
            .iter()
            .find(|(n, _)| n == f)
            .map(|(_, v)| v.clone())
    };
    let range = |t: &[f64]| {
        t.iter()
            .fold([f64::INFINITY, f64::NEG_INFINITY], |[l, h], v| {
                [l.min(*v), h.max(*v)]
            })
    };
    // One axis: its held-out rows' temperature and values, and the correction at each row.
    let axis = |m: &crate::dataset::log::Message,
                field: &str,
                tfield: &str,
                t: &[f64],
                v: &[f64],
                fitted_range: [f64; 2],
                correction: &dyn Fn(f64) -> f64|
     -> Option<HeldOutAxis> {
        let k = m.time_us.partition_point(|&u| (u as f64) * 1e-6 < from_s);
        let (th, vh) = (t.get(k..)?, v.get(k..)?);
        if th.is_empty() {
            return None;
        }
        let left: Vec<f64> = th.iter().zip(vh).map(|(t, v)| v - correction(*t)).collect();
        let label = tables.label(m);
        let (column, temperature) = (format!("{label}.{field}"), format!("{label}.{tfield}"));
        let time: Vec<f64> = m.time_us.iter().map(|&u| u as f64 * 1e-6).collect();
        let data = crate::Dataset::from_parts(
            &format!("{file}#{label}"),
            vec!["time_s".into(), temperature.clone(), column.clone()],
            vec![time, t.to_vec(), v.to_vec()],
            m.records.clone(),
        );
        Some(HeldOutAxis {
            column,
            temperature,
            rows: th.len(),
            held_out_range: range(th),
            fitted_range,
            raw_std: std(vh),
            cubic_std: std(&left),
            data,
        })
    };
    let mut out = Vec::new();
    match kind {
        Kind::ULog => {
            for s in &fitted.px4 {
                let topic = if s.kind == 'G' {
                    "sensor_gyro"
                } else {
                    "sensor_accel"
                };
                let Some(m) = tables.message(topic, s.instance) else {
                    continue;
                };
                let Some(t) = col(m, "temperature") else {
                    continue;
                };
                // the tool's single-precision temperatures
                let t: Vec<f64> = t.iter().map(|x| f64::from(*x as f32)).collect();
                for (a, field) in ["x", "y", "z"].iter().enumerate() {
                    let Some(v) = col(m, field) else { continue };
                    let fr = [f64::from(s.tmin), f64::from(s.tmax)];
                    out.extend(axis(m, field, "temperature", &t, &v, fr, &|t| {
                        s.offset(a, t)
                    }));
                }
            }
        }
        Kind::DataFlash => {
            let cal = LogCalibration::from_params(&tables.params);
            for s in &fitted.ardupilot {
                let Some(m) = tables.message("IMU", s.instance) else {
                    continue;
                };
                let names = ["T", "AccX", "AccY", "AccZ", "GyrX", "GyrY", "GyrZ"];
                let cols: Vec<Option<Vec<f64>>> = names.iter().map(|n| col(m, n)).collect();
                let Ok(
                    [
                        Some(t),
                        Some(ax),
                        Some(ay),
                        Some(az),
                        Some(gx),
                        Some(gy),
                        Some(gz),
                    ],
                ) = <[Option<Vec<f64>>; 7]>::try_from(cols)
                else {
                    continue;
                };
                let (mut acc, mut gyr) = ([ax, ay, az], [gx, gy, gz]);
                cal.remove(usize::from(s.instance), &t, &mut acc, &mut gyr);
                let fr = [s.tmin, s.tmax];
                // The firmware's correction: the cubic (constant dropped) at the clamped
                // temperature; what it adds at the calibration temperature is a constant.
                let cubic = |p: [f64; 4]| {
                    move |t: f64| {
                        polyval(&[p[0], p[1], p[2], 0.0], t.clamp(fr[0], fr[1]) - ARDU_TREF)
                    }
                };
                for (kind, values, polys) in [("Acc", &acc, &s.acc), ("Gyr", &gyr, &s.gyr)] {
                    for (a, label) in ["X", "Y", "Z"].iter().enumerate() {
                        let (Some(v), Some(p)) = (values.get(a), polys.get(a)) else {
                            continue;
                        };
                        let f = cubic(*p);
                        out.extend(axis(m, &format!("{kind}{label}"), "T", &t, v, fr, &f));
                    }
                }
            }
        }
    }
    if out.is_empty() {
        return Err(crate::DataError::LogColumn {
            file,
            what: format!(
                "no IMU record from {} s on: nothing held out to compare on (the log's IMU \
                 records end earlier)",
                crate::num::exact(from_s)
            ),
        }
        .into());
    }
    Ok((fitted, out))
}
