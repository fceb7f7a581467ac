//! Which timer edge a sample task serves: the sample instant belongs to the hardware timer, and the
//! task only finds out, from a free-running time base at its entry, how late it runs and whether
//! whole periods went by unserved (the interrupt held off for longer than a period, so the timer's
//! update events merged). Both boards count this the same way: the STM32F407 with the DWT cycle
//! counter (168 MHz), QEMU with a CMSDK timer (25 MHz).

/// The sample task's view of its timer edges.
#[derive(Clone, Copy, Debug)]
pub struct Edges {
    period: u32,
    next_edge: u32,
}

/// What an entry of the sample task found.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Entry {
    /// Whole timer periods that passed without a sample before this one.
    pub missed: u32,
    /// This sample is late: more than a quarter period after its edge, or after missed periods
    /// (flagged `OVERRUN`).
    pub late: bool,
}

impl Edges {
    /// Edges `period` ticks apart, the first at `first_edge` (time-base ticks, wrapping).
    pub const fn new(period: u32, first_edge: u32) -> Self {
        Self {
            period,
            next_edge: first_edge,
        }
    }

    /// The task entered at `now`: which edge it serves, how late, and how many it missed. An
    /// entry before the edge it was due for cannot happen (the timer raised it); it reads as on
    /// time, not as 2³² ticks late.
    pub fn enter(&mut self, now: u32) -> Entry {
        let period = self.period.max(1);
        let since = match now.wrapping_sub(self.next_edge) {
            s if s > u32::MAX / 2 => 0,
            s => s,
        };
        let missed = since / period;
        let late = since % period > period / 4 || missed > 0;
        self.next_edge = self
            .next_edge
            .wrapping_add(period.wrapping_mul(missed.wrapping_add(1)));
        Entry { missed, late }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn on_time_late_and_missed_edges() {
        let mut e = Edges::new(1000, 5000);
        assert_eq!(e.enter(5010), Entry::default());
        // A quarter period is jitter; more is an overrun of the previous sample.
        assert_eq!(e.enter(6250), Entry::default());
        assert_eq!(
            e.enter(7251),
            Entry {
                missed: 0,
                late: true
            }
        );
        // Two edges (8000, 9000) passed unserved: this entry serves 10,000's.
        assert_eq!(
            e.enter(10_100),
            Entry {
                missed: 2,
                late: true
            }
        );
        assert_eq!(e.enter(11_005), Entry::default());
    }

    #[test]
    fn the_time_base_wraps_and_an_early_entry_is_on_time() {
        let mut e = Edges::new(1000, u32::MAX - 500);
        assert_eq!(e.enter(u32::MAX - 490), Entry::default());
        assert_eq!(e.enter(510), Entry::default());
        // Entered 10 ticks before the edge it is due for.
        assert_eq!(e.enter(1490), Entry::default());
        assert_eq!(
            e.enter(3600),
            Entry {
                missed: 1,
                late: true
            }
        );
    }
}
