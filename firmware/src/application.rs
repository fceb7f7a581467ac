//! The application, once for every board: its tasks and their priorities, the frame queue and its
//! drain, the update task, the watchdog policy and the per-period sequence. A board binary only
//! binds it to its device (the [`application!`](crate::application!) macro: an RTIC 2 app) and
//! supplies its `setup` and drivers; so the QEMU board that CI runs and the STM32F407 that ships
//! run the same program, down to the task structure.
//!
//! | task | bound to | priority | does |
//! |---|---|---|---|
//! | `receive` | the board's receive interrupt | 4 (highest) | the board's: QEMU moves the received byte into the receive ring; the STM32F407's DMA fills the ring by itself and this only clears its flags. Above the sample task, so no byte waits behind a sample |
//! | `sample` | the sample timer | 3 | one period ([`sample::SampleTask::period`]): which edge (late, missed), the sensors, `App::sample_snapshot`, the board's bits, the frame into the queue, the boot report every 10 s, the watchdog fed only while every task is alive ([`liveness`]); then pends `drain` and `update` |
//! | `drain` | the transmitter's interrupt | 2 | the frame queue into the transmitter while it takes bytes ([`serial`]) |
//! | `update` | a free interrupt, pended | 1 | the receive ring through the update protocol into the inactive model slot; replies into the frame queue |
//! | `idle` | — | 0 | the board's (`wfi`; QEMU ends its run here) |
//!
//! The sample task preempts the drain and the update task (counted: [`Stats`]); the frame queue
//! is the one resource they share with it, locked for a whole-frame enqueue. Everything here but
//! the macro builds and is tested on the host.

pub mod liveness;
pub mod ring;
pub mod sample;
pub mod serial;
pub mod tasks;
pub mod timing;

use core::sync::atomic::{AtomicBool, AtomicU8, AtomicU32, Ordering};
pub use liveness::{Heartbeat, Task};
pub use ring::{RingReader, RingWriter};
pub use sample::{Period, SampleIo, SampleTask, Timestamp};
pub use serial::{
    ReceiveIrq, RxSource, SerialTx, TX_QUEUE, TxConsumer, TxProducer, TxQueue, enqueue_whole,
};
pub use tasks::{
    Boot, Devices, Drain, ModelFlash, Parts, UPDATE_COMMITTED, UPDATE_IDLE, UPDATE_RECEIVING,
    Update, init,
};

/// The drain's heartbeat ([`liveness`]).
pub static DRAIN_BEAT: Heartbeat = Heartbeat::new();
/// The update task's heartbeat.
pub static UPDATE_BEAT: Heartbeat = Heartbeat::new();
/// Set while the drain runs (the sample task counts the times it preempts it).
pub static DRAIN_ACTIVE: AtomicBool = AtomicBool::new(false);
/// Set while the update task runs.
pub static UPDATE_ACTIVE: AtomicBool = AtomicBool::new(false);
/// The update task's state ([`UPDATE_IDLE`], [`UPDATE_RECEIVING`], [`UPDATE_COMMITTED`]).
pub static UPDATE_STATE: AtomicU8 = AtomicU8::new(UPDATE_IDLE);
/// The run's counters.
pub static STATS: Stats = Stats::new();
/// A reset the update task asked for (an update needs a slot erased, which only the boot does):
/// 0 none, [`RESET_REQUESTED`], then [`RESET_DRAINED`] once the drain has sent every queued byte
/// (the reply that says so); the sample task resets the unit at its next period.
pub static RESET_STATE: AtomicU8 = AtomicU8::new(0);
/// See [`RESET_STATE`].
pub const RESET_REQUESTED: u8 = 1;
/// See [`RESET_STATE`].
pub const RESET_DRAINED: u8 = 2;
/// The trial boot's confirm: 0 not due, [`CONFIRM_DUE`] (the sample task: the loop has run
/// correctly for [`CONFIRM_PERIODS`]), then [`CONFIRMED`] or [`CONFIRM_FAILED`] (the update task,
/// which owns the flash, programmed the confirm word).
pub static CONFIRM_STATE: AtomicU8 = AtomicU8::new(0);
/// See [`CONFIRM_STATE`].
pub const CONFIRM_DUE: u8 = 1;
/// See [`CONFIRM_STATE`].
pub const CONFIRMED: u8 = 2;
/// See [`CONFIRM_STATE`].
pub const CONFIRM_FAILED: u8 = 3;
/// Periods a trial boot must run with every task alive (the watchdog fed each period) before its
/// image is confirmed: 10 s at 200 Hz, one boot-report period. Long enough to catch an image that
/// does not load, a crash or hang the new models cause in the first samples, a boot loop; the old
/// image is kept until then.
pub const CONFIRM_PERIODS: u32 = crate::boot::REPORT_PERIODS;

/// What the tasks count, for the boards' reports (the QEMU run's summary, the boot report).
#[derive(Debug)]
pub struct Stats {
    /// The worst cost of `App::sample_snapshot` over ordinary periods, and over periods after
    /// missed ones (which carry every filter across the gap).
    pub worst_snapshot: AtomicU32,
    /// See `worst_snapshot`.
    pub worst_snapshot_after_gap: AtomicU32,
    /// The sum of the snapshot costs, and the periods summed (for the mean).
    pub snapshot_sum: AtomicU32,
    /// See `snapshot_sum`.
    pub snapshots: AtomicU32,
    /// The worst cost of the whole sample task (entry to the watchdog feed).
    pub worst_task: AtomicU32,
    /// Samples taken late, and timer periods missed.
    pub late: AtomicU32,
    /// See `late`.
    pub missed: AtomicU32,
    /// Frames and replies dropped whole because the queue was full.
    pub dropped_frames: AtomicU32,
    /// See `dropped_frames`.
    pub dropped_replies: AtomicU32,
    /// Received bytes lost before the update task read them.
    pub rx_lost: AtomicU32,
    /// The stack's peak use, bytes, as the board measures it (its paint).
    pub stack_peak: AtomicU32,
    /// Sample periods that began while the drain, or the update task, was running.
    pub drain_preempted: AtomicU32,
    /// See `drain_preempted`.
    pub update_preempted: AtomicU32,
}

impl Stats {
    const fn new() -> Self {
        Self {
            worst_snapshot: AtomicU32::new(0),
            worst_snapshot_after_gap: AtomicU32::new(0),
            snapshot_sum: AtomicU32::new(0),
            snapshots: AtomicU32::new(0),
            worst_task: AtomicU32::new(0),
            late: AtomicU32::new(0),
            missed: AtomicU32::new(0),
            dropped_frames: AtomicU32::new(0),
            dropped_replies: AtomicU32::new(0),
            rx_lost: AtomicU32::new(0),
            stack_peak: AtomicU32::new(0),
            drain_preempted: AtomicU32::new(0),
            update_preempted: AtomicU32::new(0),
        }
    }

    fn record_cost(&self, cost: u32, after_gap: bool) {
        let worst = if after_gap {
            &self.worst_snapshot_after_gap
        } else {
            &self.worst_snapshot
        };
        worst.fetch_max(cost, Ordering::Relaxed);
        self.snapshot_sum.fetch_add(cost, Ordering::Relaxed);
        self.snapshots.fetch_add(1, Ordering::Relaxed);
    }

    fn record_task_cost(&self, cost: u32) {
        self.worst_task.fetch_max(cost, Ordering::Relaxed);
    }

    /// A counter's value.
    pub fn get(counter: &AtomicU32) -> u32 {
        counter.load(Ordering::Relaxed)
    }
}

/// Binds the application to a board: an RTIC 2 app on `device` (its `Interrupt` enum and
/// `NVIC_PRIO_BITS`), with the board module `board` supplying `setup(core, device) -> Devices`,
/// `idle() -> !`, and the types `SampleIo`, `SerialTx`, `Receive`, `Rx`, `Flash`; `sample`,
/// `drain`, `receive` name the interrupts of the sample timer, the transmitter and the receive
/// path, `update` a free interrupt for the update task. The tasks, their priorities and their
/// resources are written here once (see the module doc).
#[macro_export]
macro_rules! application {
    (
        device: $($device:ident)::+,
        board: $($board:ident)::+,
        sample: $sample:ident,
        drain: $drain:ident,
        receive: $receive:ident,
        update: $update:ident $(,)?
    ) => {
        #[rtic::app(device = $($device)::+, peripherals = true)]
        mod app {
            use $($board)::+ as board;
            use $crate::application as a;
            use $($device)::+::Interrupt;

            #[shared]
            struct Shared {
                /// The frame queue's producer: the sample task's frames, the update task's
                /// replies, each enqueued whole.
                queue: a::TxProducer,
            }

            #[local]
            struct Local {
                sample: a::SampleTask<board::SampleIo>,
                drain: a::Drain<board::SerialTx>,
                receive: board::Receive,
                update: a::Update<board::Rx, board::Flash>,
            }

            #[init(local = [
                tx_queue: a::TxQueue = a::TxQueue::new(),
                // The loop's state (about 11 KB) lives in this static from the start: never
                // built on the stack and moved.
                app_state: $crate::app::App<'static> = $crate::app::App::new(&[]),
            ])]
            fn init(cx: init::Context) -> (Shared, Local) {
                let devices = board::setup(cx.core, cx.device);
                let (mut producer, consumer) = cx.local.tx_queue.split();
                let parts = a::init(devices, cx.local.app_state, consumer, &mut |bytes| {
                    a::enqueue_whole(&mut producer, bytes)
                });
                rtic::pend(Interrupt::$drain);
                (
                    Shared { queue: producer },
                    Local {
                        sample: parts.sample,
                        drain: parts.drain,
                        receive: parts.receive,
                        update: parts.update,
                    },
                )
            }

            #[idle]
            fn idle(_: idle::Context) -> ! {
                board::idle()
            }

            /// The board's receive path, above everything (see `application`).
            #[task(binds = $receive, priority = 4, local = [receive])]
            fn receive(cx: receive::Context) {
                a::ReceiveIrq::on_interrupt(cx.local.receive);
                rtic::pend(Interrupt::$update);
            }

            /// One loop period, on the sample timer.
            #[task(binds = $sample, priority = 3, local = [sample], shared = [queue])]
            fn sample(mut cx: sample::Context) {
                let queue = &mut cx.shared.queue;
                cx.local
                    .sample
                    .period(&mut |bytes| queue.lock(|p| a::enqueue_whole(p, bytes)));
                rtic::pend(Interrupt::$drain);
                rtic::pend(Interrupt::$update);
            }

            /// The frame queue into the transmitter.
            #[task(binds = $drain, priority = 2, local = [drain])]
            fn drain(cx: drain::Context) {
                cx.local.drain.run();
            }

            /// The update protocol over the receive ring.
            #[task(binds = $update, priority = 1, local = [update], shared = [queue])]
            fn update(mut cx: update::Context) {
                let queue = &mut cx.shared.queue;
                cx.local
                    .update
                    .run(&mut |bytes| queue.lock(|p| a::enqueue_whole(p, bytes)));
                rtic::pend(Interrupt::$drain);
            }
        }
    };
}
