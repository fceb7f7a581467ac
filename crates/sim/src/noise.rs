//! Sensor output noise: white noise, Gauss–Markov bias instability, pulse quantisation; and the
//! statistics of the noise actually drawn.
//!
//! Why: a compensation can remove the thermal bias but never the noise, so the truth file reports the
//! noise *actually drawn* (its std at the output step and averaged over 100 s and 1000 s bins) as the
//! floor that residuals are compared to. Noise is specified in physical units: angle random walk
//! (°/√h) for gyros, velocity random walk (µg/√Hz) for accelerometers, a first-order Gauss–Markov
//! bias instability, and the weight of one output pulse (RLG and QMA output pulse counts; the count
//! over an interval depends only on the accumulated angle/velocity at its ends, so it is exact at any
//! sample rate).

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};

/// Noise of the sensor output, in the output's units (°/h for gyros, µg for accelerometers).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct NoiseSpec {
    /// White-noise density in output units · √s: the std of one sample of period `dt` is
    /// `white_density / √dt`. For gyros, `60 × ARW[°/√h]`; for accelerometers, VRW in µg/√Hz.
    pub white_density: f64,
    /// Stationary std of the Gauss–Markov bias instability, output units.
    pub bias_instability: f64,
    /// Correlation time of the bias instability, s.
    pub correlation_s: f64,
    /// Weight of one output pulse in output units · s (arc-seconds for gyros, since
    /// 1″ = 1 (°/h)·s; µg·s for accelerometers); 0 = no quantisation.
    pub pulse_weight: f64,
}

impl NoiseSpec {
    /// Gyro noise: ARW in °/√h, bias instability in °/h, correlation time in s, pulse weight in ″.
    pub fn gyro(
        arw_deg_per_sqrt_h: f64,
        bi_dph: f64,
        correlation_s: f64,
        pulse_arcsec: f64,
    ) -> Self {
        NoiseSpec {
            white_density: 60.0 * arw_deg_per_sqrt_h,
            bias_instability: bi_dph,
            correlation_s,
            pulse_weight: pulse_arcsec,
        }
    }

    /// Accelerometer noise: VRW in µg/√Hz, bias instability in µg, correlation time in s, pulse
    /// weight in µg·s.
    pub fn accel(vrw_ug_per_sqrt_hz: f64, bi_ug: f64, correlation_s: f64, pulse_ug_s: f64) -> Self {
        NoiseSpec {
            white_density: vrw_ug_per_sqrt_hz,
            bias_instability: bi_ug,
            correlation_s,
            pulse_weight: pulse_ug_s,
        }
    }

    /// Expected std of the white part of one output sample of `step_s` seconds.
    pub fn white_std(&self, step_s: f64) -> f64 {
        self.white_density / step_s.sqrt()
    }

    /// Expected std of the quantisation error of one output sample of `step_s` seconds
    /// (difference of two independent uniform phases: `q·√(1/6)/step`).
    pub fn quantisation_std(&self, step_s: f64) -> f64 {
        self.pulse_weight * (1.0f64 / 6.0).sqrt() / step_s
    }

    /// Checks the values; errors name `prefix.<field>`.
    pub fn validate(&self, prefix: &str) -> Result<()> {
        let nonneg = |v: f64, f: &str| Error::non_negative(format!("{prefix}.{f}"), v);
        nonneg(self.white_density, "white_density")?;
        nonneg(self.bias_instability, "bias_instability")?;
        nonneg(self.pulse_weight, "pulse_weight")?;
        if !(self.correlation_s.is_finite() && self.correlation_s > 0.0) {
            return Err(Error::invalid(
                format!("{prefix}.correlation_s"),
                format!("must be > 0, got {}", self.correlation_s),
            ));
        }
        Ok(())
    }
}

/// First-order Gauss–Markov process `b[n] = φ·b[n−1] + σ·√(1−φ²)·w[n]`, `φ = exp(−dt/τ)`.
#[derive(Debug, Clone)]
pub struct GaussMarkov {
    phi: f64,
    drive: f64,
    value: f64,
}

impl GaussMarkov {
    /// A process of stationary std `sigma` and correlation time `tau_s`, sampled every `dt`, starting
    /// at `initial` (draw it from N(0, σ²) for a stationary start).
    pub fn new(sigma: f64, tau_s: f64, dt: f64, initial: f64) -> Self {
        let phi = (-dt / tau_s).exp();
        GaussMarkov {
            phi,
            drive: sigma * (1.0 - phi * phi).sqrt(),
            value: initial,
        }
    }

    /// Advances with the standard-normal draw `w`; returns the new value.
    pub fn step(&mut self, w: f64) -> f64 {
        self.value = self.phi * self.value + self.drive * w;
        self.value
    }

    /// Current value.
    pub fn value(&self) -> f64 {
        self.value
    }
}

/// Pulse counter: accumulates the integral of the output and emits whole pulses.
#[derive(Debug, Clone)]
pub struct PulseCounter {
    weight: f64,
    accumulated: f64,
    counted: f64,
}

impl PulseCounter {
    /// A counter of pulse weight `weight` (output units · s), with initial phase `phase` in [0, 1).
    pub fn new(weight: f64, phase: f64) -> Self {
        PulseCounter {
            weight,
            accumulated: phase * weight,
            counted: 0.0,
        }
    }

    /// Adds the mean output `mean` over `dt` seconds; returns the quantised mean output (pulses in
    /// the interval × weight / dt). With a zero weight, returns `mean` unchanged.
    pub fn step(&mut self, mean: f64, dt: f64) -> f64 {
        if self.weight <= 0.0 {
            return mean;
        }
        self.accumulated += mean * dt;
        let total = (self.accumulated / self.weight).floor();
        let pulses = total - self.counted;
        self.counted = total;
        pulses * self.weight / dt
    }
}

/// Running mean and (population) standard deviation (Welford).
#[derive(Debug, Clone, Default)]
pub struct Running {
    n: u64,
    mean: f64,
    m2: f64,
}

impl Running {
    /// Adds a value.
    pub fn push(&mut self, x: f64) {
        self.n += 1;
        let d = x - self.mean;
        self.mean += d / self.n as f64;
        self.m2 += d * (x - self.mean);
    }

    /// Number of values.
    pub fn count(&self) -> u64 {
        self.n
    }

    /// Mean (0 when empty).
    pub fn mean(&self) -> f64 {
        self.mean
    }

    /// Population standard deviation (0 when empty).
    pub fn std(&self) -> f64 {
        if self.n == 0 {
            0.0
        } else {
            (self.m2 / self.n as f64).sqrt()
        }
    }
}

/// Std of the means of non-overlapping bins of `bin_s` seconds starting at the first sample. Only
/// complete bins count (a trailing partial bin is dropped).
#[derive(Debug, Clone)]
pub struct BinnedStd {
    bin_s: f64,
    per_bin: u64,
    t0: Option<f64>,
    current: Option<i64>,
    sum: f64,
    count: u64,
    means: Running,
}

impl BinnedStd {
    /// Bins of `bin_s` seconds over samples `step_s` apart.
    pub fn new(bin_s: f64, step_s: f64) -> Self {
        BinnedStd {
            bin_s,
            per_bin: ((bin_s / step_s) + 1e-9).floor().max(1.0) as u64,
            t0: None,
            current: None,
            sum: 0.0,
            count: 0,
            means: Running::default(),
        }
    }

    /// Adds the value `x` at time `t`.
    pub fn push(&mut self, t: f64, x: f64) {
        let t0 = *self.t0.get_or_insert(t);
        let idx = ((t - t0) / self.bin_s + 1e-9).floor() as i64;
        if self.current != Some(idx) {
            self.close();
            self.current = Some(idx);
        }
        self.sum += x;
        self.count += 1;
    }

    fn close(&mut self) {
        if self.count >= self.per_bin && self.count > 0 {
            self.means.push(self.sum / self.count as f64);
        }
        self.sum = 0.0;
        self.count = 0;
    }

    /// Finishes the last bin; returns (std of the bin means, number of complete bins).
    pub fn finish(mut self) -> (f64, u64) {
        self.close();
        (self.means.std(), self.means.count())
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::expect_used)]
    use super::*;

    #[test]
    fn pulse_counter_conserves_the_integral() {
        let mut c = PulseCounter::new(0.5, 0.3);
        let mut sum = 0.0;
        for n in 0..10_000 {
            sum += c.step(10.0 + (n as f64 * 0.1).sin(), 0.01) * 0.01;
        }
        let truth: f64 = (0..10_000)
            .map(|n| (10.0 + (n as f64 * 0.1).sin()) * 0.01)
            .sum();
        assert!((sum - truth).abs() <= 0.5 + 1e-9, "{sum} vs {truth}");
    }

    #[test]
    fn binned_std_drops_partial_bins() {
        let mut b = BinnedStd::new(10.0, 1.0);
        for n in 0..35 {
            b.push(n as f64, if n < 10 { 1.0 } else { -1.0 });
        }
        let (s, bins) = b.finish();
        assert_eq!(bins, 3);
        assert!((s - (8.0f64 / 9.0).sqrt()).abs() < 1e-12, "{s}");
    }
}
