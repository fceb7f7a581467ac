//! Streaming operators of the core's feature-expression language, mirrored in f64.
//!
//! Why: the truth file promises that each effect is *exactly* (up to noise) the listed expressions
//! evaluated over the file's columns. The simulator therefore computes every effect from the recorded
//! columns with these operators, sample by sample at the file's step, exactly as the core's feature
//! programs do. This is a private mirror so the simulator does not depend on the core yet; the
//! definitions below are the contract and are those documented in `tcomp-core`'s `program` module
//! (evaluated here in f64 rather than f32):
//!
//! - `lag(x, tau)`: `L[0] = x[0]`, `L[n] = L[n-1] + (1 - exp(-dt/tau)) * (x[n] - L[n-1])`.
//! - `rate(x, w)` (units per minute, `w` defaults to 60 s): two cascaded lags with `τ = w/2`,
//!   `L1 = lag(x, τ)`, `L2 = lag(L1, τ)`, `rate[n] = 60·(L1[n] − L2[n])·(e^(dt/τ) − 1)/dt`,
//!   `rate[0] = 0`. A ramp of slope `s` per minute gives exactly `s` once the transient has decayed.
//! - `hyst(x, th)`: state `0` at start; `+1` when `x > th`, `-1` when `x < -th`, otherwise held.
//!
//! `dt` is the sample period of the file (its step).

/// Default window of `rate(x)` in seconds.
pub const RATE_WINDOW_S: f64 = 60.0;

/// Human-readable definitions of the operators, copied into the truth file.
pub fn definitions() -> Vec<(String, String)> {
    [
        (
            "lag(x, tau_s)",
            "L[0] = x[0]; L[n] = L[n-1] + (1 - exp(-dt/tau_s)) * (x[n] - L[n-1])",
        ),
        (
            "rate(x, window_s = 60)",
            "tau = window_s/2; L1 = lag(x, tau); L2 = lag(L1, tau); rate[0] = 0; rate[n] = 60 * (L1[n] - L2[n]) * (exp(dt/tau) - 1) / dt  (units per minute)",
        ),
        (
            "hyst(x, th)",
            "s[-1] = 0; s[n] = +1 if x[n] > th, -1 if x[n] < -th, else s[n-1]",
        ),
        ("mean(a, b, ...)", "arithmetic mean of the arguments"),
        ("sq(x)", "x * x"),
        ("abs(x)", "|x|"),
        ("clamp(x, lo, hi)", "min(max(x, lo), hi)"),
    ]
    .into_iter()
    .map(|(a, b)| (a.to_string(), b.to_string()))
    .collect()
}

/// Discrete first-order lag, as the core defines it.
#[derive(Debug, Clone)]
pub struct Lag {
    tau_s: f64,
    y: Option<f64>,
}

impl Lag {
    /// A lag with time constant `tau_s` seconds.
    pub fn new(tau_s: f64) -> Self {
        Lag { tau_s, y: None }
    }

    /// Feeds `x` after a sample period of `dt` seconds; returns the lagged value.
    pub fn step(&mut self, x: f64, dt: f64) -> f64 {
        let y = match self.y {
            None => x,
            Some(prev) => prev + (1.0 - (-dt / self.tau_s).exp()) * (x - prev),
        };
        self.y = Some(y);
        y
    }
}

/// Rate of change in units per minute, as the core defines it: two cascaded lags with
/// `τ = window/2` (`L1` of `x`, `L2` of `L1`) and `rate = 60·(L1 − L2)·(e^(dt/τ) − 1)/dt`, kept in
/// difference form (`e1 = x − L1`, `e2 = L1 − L2`) like the core. `rate[0] = 0`.
#[derive(Debug, Clone)]
pub struct Rate {
    tau_s: f64,
    prev: Option<f64>,
    e1: f64,
    e2: f64,
}

impl Rate {
    /// A rate estimator with the given window in seconds.
    pub fn new(window_s: f64) -> Self {
        Rate {
            tau_s: 0.5 * window_s,
            prev: None,
            e1: 0.0,
            e2: 0.0,
        }
    }

    /// Feeds `x` after a sample period of `dt` seconds; returns the rate per minute.
    pub fn step(&mut self, x: f64, dt: f64) -> f64 {
        let Some(prev) = self.prev else {
            self.prev = Some(x);
            self.e1 = 0.0;
            self.e2 = 0.0;
            return 0.0;
        };
        let h = dt / self.tau_s;
        let decay = (-h).exp();
        let dx = x - prev;
        let e1 = (self.e1 + dx) * decay;
        let dl1 = dx - (e1 - self.e1);
        self.e2 = (self.e2 + dl1) * decay;
        self.e1 = e1;
        self.prev = Some(x);
        self.e2 * 60.0 * h.exp_m1() / dt
    }
}

/// Heating/cooling hysteresis state, as the core defines it.
#[derive(Debug, Clone)]
pub struct Hyst {
    threshold: f64,
    state: f64,
}

impl Hyst {
    /// A hysteresis detector with the given threshold.
    pub fn new(threshold: f64) -> Self {
        Hyst {
            threshold,
            state: 0.0,
        }
    }

    /// Feeds `x`; returns +1, -1 or 0.
    pub fn step(&mut self, x: f64) -> f64 {
        if x > self.threshold {
            self.state = 1.0;
        } else if x < -self.threshold {
            self.state = -1.0;
        }
        self.state
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::expect_used)]
    use super::*;

    #[test]
    fn rate_of_a_ramp_is_exact_after_transient() {
        let mut r = Rate::new(60.0);
        let mut last = 0.0;
        for n in 0..2000 {
            last = r.step(20.0 + 0.05 * n as f64, 1.0); // 3 °C/min
        }
        assert!((last - 3.0).abs() < 1e-9, "{last}");
    }

    #[test]
    fn hysteresis_holds_state() {
        let mut h = Hyst::new(0.5);
        let out: Vec<f64> = [0.0, 0.6, 0.1, -0.4, -0.6, 0.2]
            .iter()
            .map(|&x| h.step(x))
            .collect();
        assert_eq!(out, vec![0.0, 1.0, 1.0, 1.0, -1.0, -1.0]);
    }
}
