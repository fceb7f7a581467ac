//! Sensor-internal temperatures: first-order lags of chamber air plus self-heating.
//!
//! Why: the thermometers inside a sensor do not see the chamber air directly; each sits behind its own
//! thermal mass (a first-order lag with its own time constant), and the sensor warms itself after
//! power-on (self-heating rising as `ΔT·(1 − exp(−t/τ_sh))`). Different time constants between
//! thermometers are what create thermal gradients during ramps. The recorded thermometer value is the
//! internal temperature plus white noise, quantised to the thermometer's LSB.

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};

/// Physical parameters of one thermometer location.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ThermometerSpec {
    /// Column name, e.g. `t_coil_c`.
    pub name: String,
    /// Time constant of the lag from chamber air to this location, s.
    pub tau_s: f64,
    /// Final self-heating rise above the lagged air temperature, °C.
    pub self_heating_c: f64,
    /// Time constant of the self-heating build-up after power-on, s.
    pub self_heating_tau_s: f64,
    /// Standard deviation of thermometer white noise, °C (per internal sample).
    pub noise_c: f64,
    /// Quantisation step (LSB) of the thermometer, °C; 0 = none.
    pub lsb_c: f64,
}

impl ThermometerSpec {
    /// A thermometer with default noise (0.005 °C) and LSB (0.01 °C).
    pub fn new(name: &str, tau_s: f64, self_heating_c: f64, self_heating_tau_s: f64) -> Self {
        ThermometerSpec {
            name: name.to_string(),
            tau_s,
            self_heating_c,
            self_heating_tau_s,
            noise_c: 0.005,
            lsb_c: 0.01,
        }
    }

    /// Checks the values; errors name `prefix.<field>`.
    pub fn validate(&self, prefix: &str) -> Result<()> {
        let pos = |v: f64, f: &str| Error::positive(format!("{prefix}.{f}"), v);
        let nonneg = |v: f64, f: &str| Error::non_negative(format!("{prefix}.{f}"), v);
        pos(self.tau_s, "tau_s")?;
        pos(self.self_heating_tau_s, "self_heating_tau_s")?;
        if !self.self_heating_c.is_finite() {
            return Err(Error::invalid(
                format!("{prefix}.self_heating_c"),
                "must be finite",
            ));
        }
        nonneg(self.noise_c, "noise_c")?;
        nonneg(self.lsb_c, "lsb_c")
    }
}

/// Exact first-order lag of a piecewise-linear input (first-order hold).
///
/// For an input that moves linearly from `x0` to `x1` over `h` seconds, the lag `τ·y' = x − y` is
/// integrated exactly: `y(h) = x1 − sτ + (y0 − x0 + sτ)·e^(−h/τ)` with `s = (x1 − x0)/h`. A ramp
/// therefore settles to a lag of exactly `s·τ` behind its input, whatever the sample rate.
#[derive(Debug, Clone)]
pub struct FohLag {
    tau_s: f64,
    y: f64,
}

impl FohLag {
    /// A lag with time constant `tau_s`, starting at `y0` (soaked at the starting temperature).
    pub fn new(tau_s: f64, y0: f64) -> Self {
        FohLag { tau_s, y: y0 }
    }

    /// Current output.
    pub fn value(&self) -> f64 {
        self.y
    }

    /// Advances by `h` seconds while the input moves linearly from `x0` to `x1`; `decay` must be
    /// `exp(-h/tau_s)` (precomputed by the caller for speed).
    pub fn step(&mut self, x0: f64, x1: f64, h: f64, decay: f64) -> f64 {
        let s_tau = (x1 - x0) / h * self.tau_s;
        self.y = x1 - s_tau + (self.y - x0 + s_tau) * decay;
        self.y
    }

    /// Time constant, s.
    pub fn tau_s(&self) -> f64 {
        self.tau_s
    }
}

/// Self-heating after power-on: `ΔT·(1 − exp(−t/τ))`, evaluated recursively at a fixed step.
#[derive(Debug, Clone)]
pub struct SelfHeating {
    delta_c: f64,
    remaining: f64,
    decay: f64,
}

impl SelfHeating {
    /// Self-heating of final value `delta_c` and time constant `tau_s`, stepped every `h` seconds.
    pub fn new(delta_c: f64, tau_s: f64, h: f64) -> Self {
        SelfHeating {
            delta_c,
            remaining: 1.0,
            decay: (-h / tau_s).exp(),
        }
    }

    /// Current rise, °C.
    pub fn value(&self) -> f64 {
        self.delta_c * (1.0 - self.remaining)
    }

    /// Advances one step; returns the new rise.
    pub fn step(&mut self) -> f64 {
        self.remaining *= self.decay;
        self.value()
    }
}

/// Rounds `x` to a multiple of `lsb` (no-op for `lsb == 0`).
pub fn quantise(x: f64, lsb: f64) -> f64 {
    if lsb > 0.0 {
        (x / lsb).round() * lsb
    } else {
        x
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::expect_used)]
    use super::*;

    #[test]
    fn step_response_follows_exponential() {
        let tau = 600.0;
        let h = 1.0;
        let mut lag = FohLag::new(tau, 0.0);
        let decay = (-h / tau).exp();
        // Unit step at t = 0 (input already at 1 for the whole first step).
        for n in 1..=3000 {
            let y = lag.step(1.0, 1.0, h, decay);
            let expect = 1.0 - (-(n as f64) * h / tau).exp();
            assert!((y - expect).abs() < 1e-12, "n={n} y={y} expect={expect}");
        }
        // One time constant: 63.2 %.
        let mut lag = FohLag::new(tau, 0.0);
        let mut y = 0.0;
        for _ in 0..600 {
            y = lag.step(1.0, 1.0, h, decay);
        }
        assert!((y - 0.632_120_558_8).abs() < 1e-9);
    }

    #[test]
    fn ramp_lag_is_rate_times_tau() {
        for (h, tau) in [(1.0, 900.0), (0.01, 300.0), (10.0, 1500.0)] {
            let s = 3.0 / 60.0; // 3 °C/min in °C/s
            let mut lag = FohLag::new(tau, 0.0);
            let decay = (-h / tau).exp();
            let n = (20.0 * tau / h) as usize;
            let mut x = 0.0;
            for _ in 0..n {
                let x1 = x + s * h;
                lag.step(x, x1, h, decay);
                x = x1;
            }
            let behind = x - lag.value();
            assert!(
                (behind - s * tau).abs() < 1e-6 * s * tau,
                "h={h} behind={behind}"
            );
        }
    }

    #[test]
    fn self_heating_settles_with_its_time_constant() {
        let (dt, tau, h) = (2.0, 1200.0, 0.5);
        let mut sh = SelfHeating::new(dt, tau, h);
        let mut at_tau = 0.0;
        let n = (10.0 * tau / h) as usize;
        for i in 1..=n {
            let v = sh.step();
            if i == (tau / h) as usize {
                at_tau = v;
            }
        }
        assert!((at_tau - dt * 0.632_120_558_8).abs() < 1e-9, "{at_tau}");
        assert!((sh.value() - dt).abs() < dt * 1e-4, "{}", sh.value());
    }
}
