//! The sample task's work, once for every board: one timer period served — which edge (late,
//! missed), the sensors read through the board, [`App::sample_snapshot`], the board's bits on the
//! records, the frame into the queue (the boot report before it when due), the watchdog fed only
//! while every task is alive.

use super::liveness::{Liveness, Task};
use super::timing::{Edges, Entry};
use super::{
    CONFIRM_DUE, CONFIRM_PERIODS, CONFIRM_STATE, DRAIN_BEAT, RESET_DRAINED, RESET_STATE, STATS,
    Stats, UPDATE_BEAT,
};
use crate::app::{App, MAX_CHANNELS, Record, status};
use crate::boot::REPORT_PERIODS;
use crate::timing::TimeCheck;
use core::sync::atomic::Ordering;
use tcomp_core::frame::{BootReport, MAX_FRAME_LEN};
use tcomp_hal::{CounterSnapshot, Thermometer};

/// A frame's timestamp: ticks of `hz`, and whether the sensors' hardware latched it (then the
/// loop checks it against the period, [`TimeCheck`]) or the task computed it from the periods.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Timestamp {
    /// Ticks.
    pub ticks: u64,
    /// Tick rate.
    pub hz: u32,
    /// Latched by the sensors' hardware at the timer edge.
    pub latched: bool,
}

/// What one period of the sample task was, for a board's bookkeeping.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Period {
    /// The period's number since the loop started counting (the frame's sequence number).
    pub number: u64,
    /// Whole periods missed before it, and whether it ran late.
    pub entry: Entry,
    /// What [`App::sample_snapshot`] cost ([`SampleIo::cost_since`]'s unit).
    pub cost: u32,
    /// The board's bits on every record of the frame (`OVERRUN`, `TIME_JUMP`, the boot's).
    pub flags: u16,
}

impl Period {
    /// The replay vector's record of this period (its number).
    pub fn index(&self) -> usize {
        self.number as usize
    }
}

/// What the sample task needs from a board: its sample timer, time base, sensors and watchdog.
/// Owned by the sample task alone.
pub trait SampleIo {
    /// A thermometer.
    type Thermometer: Thermometer;
    /// The counter block.
    type Counters: CounterSnapshot;

    /// Time-base ticks per loop period.
    fn ticks_per_period(&self) -> u32;
    /// Starts the watchdog and the sample timer; returns the time base at the first edge.
    fn start(&mut self) -> u32;
    /// Acknowledges the sample timer's interrupt.
    fn clear_timer(&mut self);
    /// The free-running time base (ticks, wrapping).
    fn now(&self) -> u32;
    /// A cost counter's reading (the STM32F407: core cycles; QEMU: instructions).
    fn cost_start() -> u32;
    /// What passed on the cost counter since `start`.
    fn cost_since(start: u32) -> u32;
    /// The sensors as the hardware latched them at period `number`'s edge; `None` when there are
    /// no more (the end of QEMU's replay vector).
    fn sensors(&mut self, number: u64) -> Option<(&mut [Self::Thermometer], &mut Self::Counters)>;
    /// Period `number`'s timestamp.
    fn timestamp(&self, number: u64) -> Timestamp;
    /// Feeds the watchdog.
    fn feed_watchdog(&mut self);
    /// The board's look at a period's records, before the board's bits (the replay board compares
    /// them with the host's); nothing by default.
    fn observe(&mut self, _period: &Period, _records: &[Record]) {}
    /// The end of the period's work (the replay board injects its overruns and hangs here);
    /// nothing by default.
    fn after(&mut self, _period: &Period) {}
    /// A task stopped: the watchdog is no longer fed (a board records why); nothing by default.
    fn stuck(&mut self, _task: Task) {}
    /// The boot is done: `report` says what it loaded (QEMU's run after an update ends here).
    fn booted(&mut self, _report: &BootReport) {}
    /// Resets the unit (the update task asked for the boot's erase).
    fn reset(&mut self) -> !;
}

/// The sample task's state.
pub struct SampleTask<S: SampleIo> {
    app: &'static mut App<'static>,
    io: S,
    edges: Edges,
    check: TimeCheck,
    liveness: Liveness,
    /// The next period's number.
    next: u64,
    /// Bits for the next frame only (the boot's: `FIRST_SAMPLE`, `WATCHDOG_RESET`).
    boot_flags: u16,
    report: BootReport,
    /// On trial: periods in a row with every task alive, until the confirm is due.
    trial: Option<u32>,
}

impl<S: SampleIo> SampleTask<S> {
    /// The task for `app` (models loaded) on `io`, counting periods from `first` and flagging
    /// the first frame with `boot_flags`; `report` is re-sent every [`REPORT_PERIODS`]. Starts
    /// the board's watchdog and timer.
    pub fn start(
        app: &'static mut App<'static>,
        mut io: S,
        first: u64,
        boot_flags: u16,
        report: BootReport,
        ticks_per_latch: u64,
        trial: bool,
    ) -> Self {
        io.booted(&report);
        let first_edge = io.start();
        let period = io.ticks_per_period();
        Self {
            app,
            io,
            edges: Edges::new(period, first_edge),
            check: TimeCheck::new(ticks_per_latch),
            liveness: Liveness::new(),
            next: first,
            boot_flags,
            report,
            trial: trial.then_some(0),
        }
    }

    /// The board's side, for its own bookkeeping.
    pub fn io(&mut self) -> &mut S {
        &mut self.io
    }

    /// One timer period. `enqueue` puts bytes into the frame queue whole or not at all (false).
    pub fn period(&mut self, enqueue: &mut dyn FnMut(&[u8]) -> bool) {
        let task_start = S::cost_start();
        self.io.clear_timer();
        if RESET_STATE.load(Ordering::Acquire) == RESET_DRAINED {
            self.io.reset();
        }
        if super::DRAIN_ACTIVE.load(Ordering::Relaxed) {
            STATS.drain_preempted.fetch_add(1, Ordering::Relaxed);
        }
        if super::UPDATE_ACTIVE.load(Ordering::Relaxed) {
            STATS.update_preempted.fetch_add(1, Ordering::Relaxed);
        }
        let entry = self.edges.enter(self.io.now());
        let number = self.next.wrapping_add(u64::from(entry.missed));
        self.next = number.wrapping_add(1);
        if entry.missed > 0 {
            // The counters kept counting: the next rates cover every missed period.
            self.app
                .skip_periods(u16::try_from(entry.missed).unwrap_or(u16::MAX));
            STATS.missed.fetch_add(entry.missed, Ordering::Relaxed);
        }
        if entry.late {
            STATS.late.fetch_add(1, Ordering::Relaxed);
        }
        let mut records = [Record::default(); MAX_CHANNELS];
        let k = self.app.config().len().min(MAX_CHANNELS);
        let records = records.get_mut(..k).unwrap_or(&mut []);
        let Some((thermometers, counters)) = self.io.sensors(number) else {
            return;
        };
        let start = S::cost_start();
        self.app.sample_snapshot(thermometers, counters, records);
        let cost = S::cost_since(start);
        STATS.record_cost(cost, entry.missed > 0);
        let time = self.io.timestamp(number);
        let mut flags = core::mem::take(&mut self.boot_flags);
        if time.latched {
            flags |= self.check.check(time.ticks, entry.missed);
        }
        if entry.late {
            flags |= status::OVERRUN;
        }
        let period = Period {
            number,
            entry,
            cost,
            flags,
        };
        self.io.observe(&period, records);
        for r in records.iter_mut() {
            r.status |= flags;
        }
        let frame = self.app.frame(number as u32, time.ticks, time.hz, records);
        let mut bytes = [0u8; MAX_FRAME_LEN];
        if let Ok(len) = frame.encode(&mut bytes)
            && !enqueue(bytes.get(..len).unwrap_or(&[]))
        {
            STATS.dropped_frames.fetch_add(1, Ordering::Relaxed);
        }
        let next = number.wrapping_add(1);
        // Every 10 s, and at once when an update has ended (its outcome is then on the link
        // while the host still listens).
        if (next % u64::from(REPORT_PERIODS)) == 0 || crate::update::take_report_due() {
            self.send_report(next as u32, enqueue);
        }
        match self.liveness.check(DRAIN_BEAT.count(), UPDATE_BEAT.count()) {
            Ok(()) => {
                self.io.feed_watchdog();
                if let Some(n) = self.trial.as_mut() {
                    *n += 1;
                    if *n >= CONFIRM_PERIODS {
                        CONFIRM_STATE.store(CONFIRM_DUE, Ordering::Release);
                        self.trial = None;
                    }
                }
            }
            Err(task) => {
                self.io.stuck(task);
                if let Some(n) = self.trial.as_mut() {
                    *n = 0;
                }
            }
        }
        STATS.record_task_cost(S::cost_since(task_start));
        self.io.after(&period);
    }

    /// Sends the boot report, stamped with the sequence number of the next data frame and the last
    /// update's outcome ([`crate::boot::stamp`]), and with the unit's status as [`STATS`] holds
    /// it: the stack's peak (the board's paint, measured in its `idle`) and the sample task's
    /// worst cost. Not inlined, so its buffer is not in the sample task's frame.
    #[inline(never)]
    pub fn send_report(&mut self, sequence: u32, enqueue: &mut dyn FnMut(&[u8]) -> bool) {
        crate::boot::stamp(&mut self.report, sequence);
        self.report.stack_peak = Stats::get(&STATS.stack_peak);
        self.report.worst_task = Stats::get(&STATS.worst_task);
        let mut bytes = [0u8; MAX_FRAME_LEN];
        if let Some(len) = self.report.encode(&mut bytes)
            && !enqueue(bytes.get(..len).unwrap_or(&[]))
        {
            STATS.dropped_frames.fetch_add(1, Ordering::Relaxed);
        }
    }
}
