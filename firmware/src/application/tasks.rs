//! The drain and the update task, and the boot that builds every task's state from a board's
//! [`Devices`].

use super::sample::{SampleIo, SampleTask};
use super::serial::{self, RxSource, SerialTx, TxConsumer};
use super::{
    CONFIRM_DUE, CONFIRM_FAILED, CONFIRM_STATE, CONFIRMED, DRAIN_ACTIVE, DRAIN_BEAT, RESET_DRAINED,
    RESET_REQUESTED, RESET_STATE, STATS, UPDATE_ACTIVE, UPDATE_BEAT, UPDATE_STATE,
};
use crate::app::{App, ChannelConfig, LoadError, MAX_CHANNELS, status};
use crate::slots::{MappedFlash, RunTime, confirm};
use crate::trust::{Signer, Trust};
use crate::update::{MAX_REPLY, UpdateTask, serial_text};
use core::sync::atomic::Ordering;
use embedded_storage::nor_flash::NorFlash;
use tcomp_core::frame::BootReport;
use tcomp_core::slots::{Active, Layout, SlotId};
use tcomp_core::update::Reason;

/// A board's model flash: the `MODELS` region (offsets from its start), programmable, and mapped.
pub trait ModelFlash: NorFlash + MappedFlash {}

impl<F: NorFlash + MappedFlash> ModelFlash for F {}

/// What the boot found, from the board's setup.
#[derive(Clone, Copy, Debug)]
pub struct Boot {
    /// The unit's serial number.
    pub unit: u64,
    /// The channel table the loop runs.
    pub config: &'static [ChannelConfig],
    /// Its board description's hash (`None`: a table made without one).
    pub board_hash: Option<u64>,
    /// The board's counter (or sample) channels and thermometers.
    pub counters: usize,
    /// See `counters`.
    pub thermometers: usize,
    /// The running image's bytes (the active slot's payload; empty without one). Never written
    /// while the unit runs: an update writes only the other slot.
    pub image: &'static [u8],
    /// Who vouches for the running image (`None` without one).
    pub signer: Option<Signer>,
    /// Why the last image the boot considered was refused by the trust check, if one was.
    pub refused: Option<Reason>,
    /// The unit's key store (`crate::trust`): the board's OTP blocks, or QEMU's `KEYS` region.
    /// An update is checked against it at COMMIT, as the boot checked the running image.
    pub keys: &'static [u8],
    /// The slot the update receiver must treat as active.
    pub active: Option<Active>,
    /// The model slots.
    pub layout: Layout,
    /// The running image is on trial (a newly committed slot's first boot): confirmed once the
    /// loop has run correctly for [`CONFIRM_PERIODS`], rolled back by the next boot otherwise.
    pub trial: bool,
    /// The boot followed a watchdog reset.
    pub watchdog_reset: bool,
    /// The first period's number (the frames' sequence numbers count on from it).
    pub first_period: u64,
    /// Time-base ticks per period of the latched timestamps ([`crate::timing::TimeCheck`]).
    pub ticks_per_latch: u64,
}

/// A board's devices, configured by its `setup`, one part per task.
pub struct Devices<S, Tx, R, Rx, F> {
    /// The sample task's: timer, time base, sensors, watchdog.
    pub sample: S,
    /// The drain's transmitter.
    pub tx: Tx,
    /// The receive interrupt's state.
    pub receive: R,
    /// The update task's receive source.
    pub rx: Rx,
    /// The model slots' flash.
    pub flash: F,
    /// What the boot found.
    pub boot: Boot,
}

/// The drain: the frame queue into the transmitter, on the transmitter's interrupt and whenever
/// the sample or update task pends it.
pub struct Drain<Tx: SerialTx> {
    queue: TxConsumer,
    tx: Tx,
}

impl<Tx: SerialTx> Drain<Tx> {
    /// Runs once (the interrupt's body).
    pub fn run(&mut self) {
        DRAIN_ACTIVE.store(true, Ordering::Relaxed);
        DRAIN_BEAT.beat();
        let left = serial::drain(&mut self.queue, &mut self.tx);
        // A reset the update task asked for waits until its reply has left.
        if !left && RESET_STATE.load(Ordering::Acquire) == RESET_REQUESTED {
            RESET_STATE.store(RESET_DRAINED, Ordering::Release);
        }
        DRAIN_ACTIVE.store(false, Ordering::Relaxed);
    }

    /// The transmitter (a board's injected faults reach it through here).
    pub fn tx(&mut self) -> &mut Tx {
        &mut self.tx
    }
}

/// [`UPDATE_STATE`]: no update under way.
pub const UPDATE_IDLE: u8 = 0;
/// [`UPDATE_STATE`]: an image is being received.
pub const UPDATE_RECEIVING: u8 = 1;
/// [`UPDATE_STATE`]: an update has committed (it runs from the next boot).
pub const UPDATE_COMMITTED: u8 = 2;

/// The update task: received bytes through the update protocol, the inactive slot written, the
/// replies into the frame queue.
pub struct Update<Rx: RxSource, F: ModelFlash> {
    rx: Rx,
    flash: RunTime<F>,
    task: UpdateTask,
    serial: [u8; 18],
    trust: Trust<'static>,
    layout: Layout,
    /// The slot on trial, until it is confirmed.
    trial: Option<SlotId>,
}

impl<Rx: RxSource, F: ModelFlash> Update<Rx, F> {
    /// Runs once: every byte waiting is fed to the receiver; each reply goes into the queue whole
    /// (or is dropped whole: the host repeats its request).
    pub fn run(&mut self, enqueue: &mut dyn FnMut(&[u8]) -> bool) {
        UPDATE_ACTIVE.store(true, Ordering::Relaxed);
        UPDATE_BEAT.beat();
        if let Some(slot) = self.trial
            && CONFIRM_STATE.load(Ordering::Acquire) == CONFIRM_DUE
        {
            // The trial boot has run correctly: one word program, never an erase.
            let done = confirm(self.flash.inner(), &self.layout, slot).is_ok();
            CONFIRM_STATE.store(
                if done { CONFIRMED } else { CONFIRM_FAILED },
                Ordering::Release,
            );
            self.trial = None;
        }
        let trust = self.trust;
        let mut reply = [0u8; MAX_REPLY];
        while let Some(byte) = self.rx.pop() {
            // The new image must pass the unit's trust check (it reads, it is made for this
            // unit, it is signed by a provisioned key, and nothing follows its signature) before
            // the commit word is written: a refused image is never committed, the unit keeps its
            // models and the RESULT says why.
            let validate = |f: &mut RunTime<F>, off: u32, len: u32| {
                f.mapped(off, len)
                    .map_or(Err(Reason::Flash), |b| trust.check_payload(b).map(|_| ()))
            };
            if let Some(n) =
                self.task
                    .push(byte, &mut self.flash, &self.serial, validate, &mut reply)
                && !enqueue(reply.get(..n).unwrap_or(&[]))
            {
                STATS.dropped_replies.fetch_add(1, Ordering::Relaxed);
            }
        }
        STATS.rx_lost.store(self.rx.lost(), Ordering::Relaxed);
        if self.flash.erase_requested().is_some() {
            // The update needs a slot erased that the boot left written: the boot erases it
            // (before the watchdog starts), so the unit resets once its reply has left, and the
            // host's next BEGIN finds the slot blank.
            let _ = RESET_STATE.compare_exchange(
                0,
                RESET_REQUESTED,
                Ordering::AcqRel,
                Ordering::Relaxed,
            );
        }
        let state = match (self.task.committed(), self.task.is_receiving()) {
            (Some(_), _) => UPDATE_COMMITTED,
            (None, true) => UPDATE_RECEIVING,
            (None, false) => UPDATE_IDLE,
        };
        UPDATE_STATE.store(state, Ordering::Release);
        UPDATE_ACTIVE.store(false, Ordering::Relaxed);
    }

    /// The receiver's flash (a board's injected faults reach it through here).
    pub fn flash(&mut self) -> &mut F {
        self.flash.inner()
    }

    /// The update task's state (what was committed).
    pub fn task(&self) -> &UpdateTask {
        &self.task
    }
}

/// Every task's state, built by [`init`].
pub struct Parts<S: SampleIo, Tx: SerialTx, R, Rx: RxSource, F: ModelFlash> {
    /// The sample task's.
    pub sample: SampleTask<S>,
    /// The drain's.
    pub drain: Drain<Tx>,
    /// The receive interrupt's.
    pub receive: R,
    /// The update task's.
    pub update: Update<Rx, F>,
}

/// The boot, once for every board: loads the models of the image the board chose into `app`,
/// builds the boot report and puts it into the frame queue (the first thing a unit sends), then
/// starts the watchdog and the sample timer. `enqueue` is the frame queue's producer.
pub fn init<S: SampleIo, Tx: SerialTx, R, Rx: RxSource, F: ModelFlash>(
    devices: Devices<S, Tx, R, Rx, F>,
    app: &'static mut App<'static>,
    queue: TxConsumer,
    enqueue: &mut dyn FnMut(&[u8]) -> bool,
) -> Parts<S, Tx, R, Rx, F> {
    let Devices {
        sample,
        tx,
        receive,
        rx,
        flash,
        boot,
    } = devices;
    app.reset(boot.config);
    let loaded = load(app, &boot);
    let report = report(&boot, &loaded);
    if boot.trial && !proves(&loaded[..boot.config.len().min(MAX_CHANNELS)]) {
        // A new image on trial that does not load: roll it back now (the boot after the reset
        // runs the old one) rather than run without the models it replaced.
        RESET_STATE.store(RESET_REQUESTED, Ordering::Release);
    }
    // The first frame of a boot is flagged: its filters start from nothing, its counts cover the
    // interval since the counters were last read (by the previous run, or never).
    let mut boot_flags = status::FIRST_SAMPLE;
    if boot.watchdog_reset {
        boot_flags |= status::WATCHDOG_RESET;
    }
    let mut sample = SampleTask::start(
        app,
        sample,
        boot.first_period,
        boot_flags,
        report,
        boot.ticks_per_latch,
        boot.trial,
    );
    sample.send_report(boot.first_period as u32, enqueue);
    Parts {
        sample,
        drain: Drain { queue, tx },
        receive,
        update: Update {
            rx,
            flash: RunTime::new(flash),
            task: UpdateTask::new(boot.layout, boot.active),
            serial: serial_text(boot.unit),
            trust: Trust::new(boot.unit, boot.keys),
            layout: boot.layout,
            trial: boot.trial.then_some(boot.active.map(|a| a.slot)).flatten(),
        },
    }
}

/// Whether a trial image's load proves it: every channel loaded, or has no model in the image
/// (a channel the image leaves out runs raw, as it did before). A channel refused for any other
/// reason (a corrupt blob, another board's table, a blob for another channel) fails the trial.
fn proves(loaded: &[Result<(), LoadError>]) -> bool {
    loaded.iter().all(|l| {
        matches!(
            l,
            Ok(()) | Err(LoadError::Image(crate::image::ImageError::Missing))
        )
    })
}

/// Decodes the models (the boot's stack peak: the decoder's frame lies on top of this one's).
#[inline(never)]
fn load(app: &mut App<'static>, boot: &Boot) -> [Result<(), LoadError>; MAX_CHANNELS] {
    app.load_for_unit(
        boot.image,
        boot.unit,
        boot.board_hash,
        boot.counters,
        boot.thermometers,
    )
}

/// The boot report, logged over defmt on the target. Not inlined: its temporaries are not on
/// the stack while the models are decoded.
#[inline(never)]
fn report(boot: &Boot, loaded: &[Result<(), LoadError>; MAX_CHANNELS]) -> BootReport {
    let report = crate::boot::report(
        boot.image,
        boot.signer,
        boot.refused,
        boot.unit,
        boot.config,
        loaded,
        boot.watchdog_reset,
    );
    #[cfg(target_os = "none")]
    {
        defmt::info!(
            "boot report: unit {=u64:#x}, image v{=u16} for unit {=u64:#x} (state {=u8}), board {=u64:#018x}, crc {=u32:#010x}",
            report.unit_serial,
            report.image_version,
            report.image_serial,
            report.image_state,
            report.board_hash,
            report.image_crc
        );
        for (cfg, r) in boot.config.iter().zip(loaded.iter()) {
            if let Err(e) = r {
                defmt::warn!(
                    "channel {=str}: no model ({}), raw passed through",
                    cfg.name,
                    e
                );
            }
        }
    }
    report
}
