//! The loop's view of its own time base: is this sample's latched timestamp where the sample timer
//! says it should be?
//!
//! The counter block latches a timestamp at every edge of the sample timer. Between two samples it
//! must advance by one period, or by `1 + missed` periods when the board counted missed timer
//! periods (an overrun that swallowed whole periods). Anything else is a jump of the time base (a
//! glitch of the timestamp counter, a clock switch): the rates of that sample are computed over a
//! period that is not known, so every channel of the frame is flagged [`status::TIME_JUMP`]. The
//! check re-anchors on every sample, so a step of the time base flags one sample and a single bad
//! timestamp two (going out and coming back).
//!
//! [`status::TIME_JUMP`]: crate::app::status::TIME_JUMP

use crate::app::status;

/// Checks consecutive latched timestamps against the nominal period.
#[derive(Clone, Copy, Debug)]
pub struct TimeCheck {
    period: u64,
    tolerance: u64,
    last: Option<u64>,
}

impl TimeCheck {
    /// Timestamps in ticks, `period` ticks per sample; a deviation above `period / 8` is a jump
    /// (the latch is a hardware edge: its jitter is a tick or two, not an eighth of a period).
    pub const fn new(period: u64) -> Self {
        Self {
            period,
            tolerance: period / 8,
            last: None,
        }
    }

    /// The status bits for the sample latched at `timestamp`, `missed` timer periods after the
    /// previous sample's period (0 normally).
    pub fn check(&mut self, timestamp: u64, missed: u32) -> u16 {
        let flags = match self.last {
            Some(last) => {
                let expected = self.period.saturating_mul(u64::from(missed) + 1);
                let delta = timestamp.wrapping_sub(last);
                if delta.abs_diff(expected) > self.tolerance {
                    status::TIME_JUMP
                } else {
                    0
                }
            }
            None => 0,
        };
        self.last = Some(timestamp);
        flags
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn steady_periods_pass_and_missed_periods_are_expected() {
        let mut c = TimeCheck::new(1000);
        assert_eq!(c.check(5_000, 0), 0);
        assert_eq!(c.check(6_000, 0), 0);
        assert_eq!(c.check(6_999 + 100, 0), 0);
        // Two periods were missed: the timestamp three periods on is right.
        assert_eq!(c.check(10_099, 2), 0);
        // The same timestamp without the missed periods is a jump.
        let mut d = TimeCheck::new(1000);
        d.check(7_099, 0);
        assert_eq!(d.check(10_099, 0), status::TIME_JUMP);
    }

    #[test]
    fn a_glitch_flags_going_out_and_coming_back_a_step_only_once() {
        let mut c = TimeCheck::new(1000);
        let flags: [u16; 5] = core::array::from_fn(|n| {
            let t = 1000 * n as u64 + if n == 2 { 500 } else { 0 };
            c.check(t, 0)
        });
        assert_eq!(flags, [0, 0, status::TIME_JUMP, status::TIME_JUMP, 0]);
        let mut s = TimeCheck::new(1000);
        let flags: [u16; 5] = core::array::from_fn(|n| {
            let t = 1000 * n as u64 + if n >= 2 { 40_000 } else { 0 };
            s.check(t, 0)
        });
        assert_eq!(flags, [0, 0, status::TIME_JUMP, 0, 0]);
    }
}
