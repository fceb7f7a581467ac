//! The core's streaming operators in f64 under the names the effects use.
//!
//! Why this module still exists: the effects compute their bias with `lag`, `rate` and `hyst`
//! exactly as the core's feature programs define them, and since the language is defined once in
//! `tcomp-core` ([`tcomp_core::lang`], evaluated by [`tcomp_core::eval`]) these are the core's own
//! filters, monomorphised in f64. Only aliases remain here, so the effects compile unchanged while
//! they are split into modules; they can import `tcomp_core::eval` directly and this module go.

/// Default window of `rate(x)` in seconds (the core's).
pub const RATE_WINDOW_S: f64 = tcomp_core::lang::DEFAULT_RATE_WINDOW_S as f64;

/// `lag(x, tau_s)` in f64: the core's filter.
pub type Lag = tcomp_core::eval::Lag<f64>;
/// `rate(x, window_s)` in f64 (units per minute): the core's filter.
pub type Rate = tcomp_core::eval::Rate<f64>;
/// `hyst(x, threshold)` in f64: the core's filter.
pub type Hyst = tcomp_core::eval::Hyst<f64>;

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
