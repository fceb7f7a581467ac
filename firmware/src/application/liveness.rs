//! The watchdog policy: fed by the sample task only while every task is known to be alive.
//!
//! The sample task runs on the hardware timer at the highest application priority, so a stuck
//! lower task never stops it: feeding the watchdog from it alone would keep a unit running whose
//! frames no longer leave (a stuck drain) or which no longer hears an update (a stuck receive). So
//! the sample task pends the drain and the update task every period, each of them counts a
//! [`Heartbeat`] whenever it runs, and the sample task feeds the watchdog only while each count has
//! moved within the last [`STALE_PERIODS`] periods. A task that stops running for longer resets
//! the unit through the watchdog like a hung sample task does.
//!
//! Why [`STALE_PERIODS`] = 4 (20 ms at 200 Hz): longer than any legitimate hold-off of the lowest
//! task (the update task, below the sample task, the drain and the receive interrupt; its longest
//! own step is programming one chunk, ≤ 64 words × 100 µs worst case on the STM32F407, 6.4 ms),
//! and short enough that the receive ring (sized from it and the baud rate, see
//! `application::RX_RING`) cannot overflow before the unit resets.

use core::sync::atomic::{AtomicU32, Ordering};

/// Periods without a heartbeat after which a task counts as stuck.
pub const STALE_PERIODS: u16 = 4;

/// A task's run counter, counted by the task, read by the sample task.
#[derive(Debug)]
pub struct Heartbeat(AtomicU32);

impl Heartbeat {
    /// Never run.
    pub const fn new() -> Self {
        Self(AtomicU32::new(0))
    }

    /// The task ran.
    pub fn beat(&self) {
        self.0.fetch_add(1, Ordering::Release);
    }

    /// Runs so far (wrapping).
    pub fn count(&self) -> u32 {
        self.0.load(Ordering::Acquire)
    }
}

impl Default for Heartbeat {
    fn default() -> Self {
        Self::new()
    }
}

/// The tasks the sample task watches.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(target_os = "none", derive(defmt::Format))]
pub enum Task {
    /// The frame queue's drain.
    Drain,
    /// The update task (the receive ring's consumer).
    Update,
}

impl Task {
    /// A one-byte code for the fault record (1 drain, 2 update).
    pub const fn code(self) -> u8 {
        match self {
            Self::Drain => 1,
            Self::Update => 2,
        }
    }
}

/// One watched heartbeat: its last count and the periods since it moved.
#[derive(Clone, Copy, Debug, Default)]
struct Watch {
    last: u32,
    age: u16,
}

impl Watch {
    fn see(&mut self, count: u32) -> bool {
        if count == self.last {
            self.age = self.age.saturating_add(1);
        } else {
            self.last = count;
            self.age = 0;
        }
        self.age <= STALE_PERIODS
    }
}

/// The sample task's watch over the drain's and the update task's heartbeats.
#[derive(Clone, Copy, Debug, Default)]
pub struct Liveness {
    drain: Watch,
    update: Watch,
}

impl Liveness {
    /// Nothing seen yet.
    pub const fn new() -> Self {
        Self {
            drain: Watch { last: 0, age: 0 },
            update: Watch { last: 0, age: 0 },
        }
    }

    /// One period: the heartbeats' counts now. `Ok` while both moved within [`STALE_PERIODS`]
    /// periods (then the watchdog may be fed); otherwise the first stuck task.
    pub fn check(&mut self, drain: u32, update: u32) -> Result<(), Task> {
        let drain_ok = self.drain.see(drain);
        let update_ok = self.update.see(update);
        match (drain_ok, update_ok) {
            (true, true) => Ok(()),
            (false, _) => Err(Task::Drain),
            (true, false) => Err(Task::Update),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fed_while_both_tasks_beat_and_not_once_one_stops() {
        let mut l = Liveness::new();
        let (mut d, mut u) = (0, 0);
        for _ in 0..100 {
            d += 1;
            u += 3;
            assert_eq!(l.check(d, u), Ok(()));
        }
        // The update task stops: still fed for STALE_PERIODS periods, then never again.
        for k in 1..=u32::from(STALE_PERIODS) + 3 {
            d += 1;
            let r = l.check(d, u);
            if k <= u32::from(STALE_PERIODS) {
                assert_eq!(r, Ok(()), "period {k}");
            } else {
                assert_eq!(r, Err(Task::Update), "period {k}");
            }
        }
        // A stuck drain is named first.
        for _ in 0..=STALE_PERIODS {
            let _ = l.check(d, u);
        }
        assert_eq!(l.check(d, u), Err(Task::Drain));
        // Both beat again: fed again.
        assert_eq!(l.check(d + 1, u + 1), Ok(()));
    }

    #[test]
    fn a_heartbeat_counts_and_wraps() {
        let h = Heartbeat::new();
        h.beat();
        h.beat();
        assert_eq!(h.count(), 2);
        let w = Heartbeat(AtomicU32::new(u32::MAX));
        w.beat();
        assert_eq!(w.count(), 0);
        let mut l = Liveness::new();
        assert_eq!(l.check(u32::MAX, u32::MAX), Ok(()));
        assert_eq!(l.check(0, 0), Ok(()));
    }
}
