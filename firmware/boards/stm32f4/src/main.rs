//! The compensation loop on an STM32F407 IMU board, as an RTIC 2 application.
//!
//! * `sample` — bound to TIM2's update interrupt (200 Hz), the highest priority: latches the counter
//!   block's snapshot, reads the thermometers, runs [`App::sample_snapshot`] (the very loop the
//!   host tests and the QEMU replay run), encodes one [`Frame`] into the UART queue, feeds the
//!   watchdog and counts overruns (TIM2's update flag set again before the work is done); the
//!   next frame, the late one, carries `OVERRUN` on every channel. Whole missed periods (the
//!   interrupt held off for more than one period, so TIM2's update events merged) are counted from
//!   the DWT cycle counter and passed to [`App::skip_periods`], so the next rates cover every period
//!   the counters counted, and the frame's timestamp skips them.
//! * `uart` — bound to USART1 at a lower priority: drains the queue one byte per TXE interrupt.
//!   A frame that does not fit in the queue is dropped whole; its sequence number is still used, so
//!   the host sees the gap.
//!
//! Logs go out with defmt over RTT (read by `probe-rs run`; without a probe they cost a buffer
//! write). A panic or HardFault is recorded in no-init RAM and resets the chip ([`fault`]); the
//! next boot reports it.
#![no_std]
#![no_main]

mod fault;
mod setup;

include!(concat!(env!("OUT_DIR"), "/board_config.rs"));

use defmt_rtt as _;

unsafe extern "C" {
    static __models_start: u8;
    static __models_end: u8;
}

/// The model slots' region of `memory.x` (flash sectors 10 and 11: slot A, slot B).
fn models_region() -> &'static [u8] {
    let start = core::ptr::addr_of!(__models_start);
    let end = core::ptr::addr_of!(__models_end);
    let len = (end as usize).saturating_sub(start as usize);
    // SAFETY: the linker symbols bound flash sectors 10–11, which are always readable; the update
    // task writes only the inactive slot, which no running model borrows from; erased flash reads
    // 0xFF, which the slot and image readers reject.
    unsafe { core::slice::from_raw_parts(start, len) }
}

/// The image to run: the newest committed slot that validates and passes the unit's trust check
/// (made for this unit, signed by a key of [`otp_keys`]), else a bare image a probe wrote at slot
/// A that passes it, else none (`tcomp_firmware::slots`). Runs before the watchdog starts: each
/// candidate's signature is verified here.
fn models_choice() -> tcomp_firmware::slots::Choice<'static> {
    let trust = trust();
    let choice = tcomp_firmware::slots::choose_mapped(
        &tcomp_firmware::slots::STM32F4_LAYOUT,
        models_region(),
        |b| trust.check(b),
    );
    defmt::info!("models: {} signed by {}", choice.source, choice.signer);
    choice
}

/// OTP blocks 1–4 (`0x1FFF_7820`, 128 bytes): the Ed25519 public keys this unit trusts, one per
/// 32-byte block, programmed at the factory (see README.md, "Signed images"); an unprogrammed
/// block (all 0xFF) or a revoked one (all 0x00) holds no key.
const OTP_KEYS: usize = 0x1FFF_7820;
/// Bytes of the key store: four keys, for rotation.
const OTP_KEYS_LEN: usize = 4 * 32;

/// The key store in OTP.
fn otp_keys() -> &'static [u8] {
    // SAFETY: the OTP area is always mapped and readable on the STM32F405/407, and nothing in
    // the firmware programs it; 128 bytes from block 1 lie inside its 512 bytes.
    unsafe { core::slice::from_raw_parts(OTP_KEYS as *const u8, OTP_KEYS_LEN) }
}

/// The unit's trust: its serial and its keys (`tcomp_firmware::trust`).
fn trust() -> tcomp_firmware::trust::Trust<'static> {
    tcomp_firmware::trust::Trust::new(unit_serial(), otp_keys())
}

/// Offset of the `MODELS` region (sector 10) from the start of the part's flash, as the HAL's
/// `NorFlash` counts.
const MODELS_OFFSET: u32 = 0x000C_0000;

/// Start of the STM32F4's one-time-programmable area (RM0090 §3.8: 512 bytes in 16 blocks of
/// 32 bytes, and a lock byte per block at 0x1FFF_7A00). Block 0's first 8 bytes hold the unit
/// serial, programmed once at manufacturing and then locked: unlike the factory's 96-bit device
/// id (0x1FFF_7A10), it is the number on the unit's label, which `tcomp image --serial` takes; and
/// OTP survives every firmware and image update, so an image cannot be moved to another unit by
/// reflashing it.
const OTP_SERIAL: usize = 0x1FFF_7800;

/// The unit's serial (little-endian u64 at [`OTP_SERIAL`]); all ones on a unit whose OTP was never
/// programmed, which no image names, so such a unit runs every channel with `NO_MODEL` and its
/// boot report says "image made for another unit".
pub fn unit_serial() -> u64 {
    let mut b = [0u8; 8];
    for (i, byte) in b.iter_mut().enumerate() {
        // SAFETY: the OTP area is always mapped and readable on the STM32F405/407; reading it has
        // no side effect.
        *byte = unsafe { core::ptr::read_volatile((OTP_SERIAL + i) as *const u8) };
    }
    u64::from_le_bytes(b)
}

/// Bytes the UART queue holds (511 usable): six 84-byte six-channel frames. At 921,600
/// baud one frame takes 0.9 ms, so the queue never fills unless the line is stalled.
const TX_QUEUE: usize = 512;

#[rtic::app(device = stm32f4xx_hal::pac, peripherals = true)]
mod app {
    use crate::CONFIG;
    use embedded_hal_bus::util::AtomicCell;
    use heapless::spsc::{Consumer, Producer, Queue};
    use stm32f4xx_hal::flash::{FlashExt, LockedFlash};
    use stm32f4xx_hal::pac::Interrupt;
    use stm32f4xx_hal::prelude::*;
    use stm32f4xx_hal::serial::RxISR;
    use stm32f4xx_hal::serial::{TxISR, TxListen};
    use stm32f4xx_hal::timer::Flag;
    use tcomp_core::frame::{BootReport, MAX_FRAME_LEN};
    use tcomp_core::slots::Active;
    use tcomp_core::update::Reason;
    use tcomp_firmware::app::{App, MAX_CHANNELS, Record, status};
    use tcomp_firmware::boot::REPORT_PERIODS;
    use tcomp_firmware::slots::{STM32F4_LAYOUT, Windowed, erase_inactive};
    use tcomp_firmware::update::{MAX_REPLY, UpdateTask, serial_text};

    use crate::setup::{
        self, CYCLES_PER_PERIOD, Counters, FrameTx, SampleTimer, Spi1Bus, TICK_HZ,
        TICKS_PER_PERIOD, UpdateRx,
    };
    use stm32f4xx_hal::watchdog::IndependentWatchdog;

    #[shared]
    struct Shared {
        /// The UART queue: the sample task's frames and the update task's replies, each
        /// enqueued whole.
        producer: Producer<'static, u8>,
    }

    #[local]
    struct Local {
        app: &'static mut App<'static>,
        thermometers: [setup::Thermometer; setup::THERMOMETERS],
        counters: Counters,
        timer: SampleTimer,
        watchdog: IndependentWatchdog,
        consumer: Consumer<'static, u8>,
        tx: FrameTx,
        rx: UpdateRx,
        flash: LockedFlash,
        update: UpdateTask,
        /// The unit's serial as the update protocol's HELLO answer spells it.
        serial: [u8; 18],
        unit: u64,
        /// What this boot loaded: sent first, then every `REPORT_PERIODS` periods.
        report: BootReport,
    }

    #[init(local = [
        // The loop's state (about 11 KB) lives in this static from the start (`App::new` is const):
        // never built on the stack and moved.
        app_state: App<'static> = App::new(CONFIG),
        queue: Queue<u8, { crate::TX_QUEUE }> = Queue::new(),
        spi1: Option<AtomicCell<Spi1Bus>> = None,
    ])]
    fn init(cx: init::Context) -> (Shared, Local) {
        let devices = match setup::setup(cx.core, cx.device, cx.local.spi1) {
            Ok(d) => d,
            Err(e) => {
                defmt::error!("setup failed: {}", e);
                // Nothing can run; the reset cause on the next boot says the watchdog was never fed
                // only if it was started, so reset explicitly.
                cortex_m::peripheral::SCB::sys_reset();
            }
        };
        defmt::info!("reset cause: {}", devices.reset_cause);
        if let Some((f, kind)) = devices.fault.and_then(|f| Some((f, f.valid()?))) {
            defmt::error!(
                "previous run ended in {} at {=str}:{=u32} (lr {=u32:#010x}; for a HardFault the \
                 number is the PC)",
                kind,
                f.file(),
                f.line_or_pc(),
                f.lr()
            );
        }
        let app = cx.local.app_state;
        let unit = crate::unit_serial();
        let choice = crate::models_choice();
        let image = choice.image;
        let mut flash = devices.flash;
        prepare_update_slot(&mut flash, choice.active);
        let mut iwdg = devices.watchdog;
        iwdg.start(setup::WATCHDOG_MS.millis());
        let loaded = app.load_for_unit(
            image,
            unit,
            Some(crate::CONFIG_HASH),
            tcomp_firmware::app::MAX_COUNTERS,
            crate::setup::THERMOMETERS,
        );
        let watchdog = matches!(
            devices.reset_cause,
            crate::fault::ResetCause::WindowWatchdog
                | crate::fault::ResetCause::IndependentWatchdog
        );
        let report = tcomp_firmware::boot::report(&choice, unit, CONFIG, &loaded, watchdog);
        defmt::info!(
            "boot report: unit {=u64:#x}, image v{=u16} for unit {=u64:#x} (state {=u8}), board {=u64:#018x}, crc {=u32:#010x}",
            report.unit_serial,
            report.image_version,
            report.image_serial,
            report.image_state,
            report.board_hash,
            report.image_crc
        );
        for (cfg, r) in CONFIG.iter().zip(loaded.iter()) {
            match r {
                Ok(()) => defmt::info!("channel {=str}: model loaded", cfg.name),
                Err(e) => defmt::warn!(
                    "channel {=str}: no model ({}), raw passed through",
                    cfg.name,
                    e
                ),
            }
        }
        let (producer, consumer) = cx.local.queue.split();
        (
            Shared { producer },
            Local {
                app,
                thermometers: devices.thermometers,
                counters: devices.counters,
                timer: devices.timer,
                watchdog: iwdg,
                consumer,
                tx: devices.tx,
                rx: devices.rx,
                flash,
                update: UpdateTask::new(STM32F4_LAYOUT, choice.active),
                serial: serial_text(unit),
                unit,
                report,
            },
        )
    }

    #[idle]
    fn idle(_: idle::Context) -> ! {
        loop {
            cortex_m::asm::wfi();
        }
    }

    /// One loop period, on TIM2's update.
    #[task(binds = TIM2, priority = 2, shared = [producer], local = [
        app, thermometers, counters, timer, watchdog, report,
        sequence: u32 = 0, periods: u64 = 0, overruns: u32 = 0, dropped: u32 = 0, late: bool = false,
        missed: u32 = 0, last_cycles: Option<u32> = None,
    ])]
    fn sample(mut cx: sample::Context) {
        let l = cx.local;
        l.timer.clear_flags(Flag::Update);
        *l.periods += 1;
        // Whole periods missed since the last entry (the interrupt held off for more than a period:
        // TIM2's update events merged), counted from the cycle counter: the counters kept counting,
        // so the loop is told to compute the next rates over all of them, never one period's.
        let now = cortex_m::peripheral::DWT::cycle_count();
        if let Some(last) = l.last_cycles.replace(now) {
            let elapsed = now.wrapping_sub(last);
            let periods = elapsed.saturating_add(CYCLES_PER_PERIOD / 2) / CYCLES_PER_PERIOD;
            if periods >= 2 {
                let skipped = periods - 1;
                l.app
                    .skip_periods(u16::try_from(skipped).unwrap_or(u16::MAX));
                *l.periods += u64::from(skipped);
                *l.missed = l.missed.wrapping_add(skipped);
                *l.late = true;
                defmt::warn!(
                    "{=u32} timer periods missed ({=u32} in all)",
                    skipped,
                    *l.missed
                );
            }
        }

        let mut records = [Record::default(); MAX_CHANNELS];
        l.app
            .sample_snapshot(l.thermometers, l.counters, &mut records);

        if *l.late {
            // The previous period overran: this sample was taken late.
            for r in &mut records {
                r.status |= status::OVERRUN;
            }
        }
        if l.sequence.is_multiple_of(REPORT_PERIODS) || tcomp_firmware::update::take_report_due() {
            // At boot and every 10 s, before the data frame it announces (never on the loop's
            // timed path: the sample is done).
            tcomp_firmware::boot::stamp(l.report, *l.sequence);
            let mut buf = [0u8; MAX_FRAME_LEN];
            if let Some(len) = l.report.encode(&mut buf) {
                cx.shared
                    .producer
                    .lock(|p| enqueue_whole(p, buf.get(..len).unwrap_or(&[])));
            }
        }
        let frame = l.app.frame(
            *l.sequence,
            l.periods.wrapping_mul(u64::from(TICKS_PER_PERIOD)),
            TICK_HZ,
            &records,
        );
        *l.sequence = l.sequence.wrapping_add(1);
        let mut buf = [0u8; MAX_FRAME_LEN];
        if let Ok(len) = frame.encode(&mut buf) {
            let sent = cx
                .shared
                .producer
                .lock(|p| enqueue_whole(p, buf.get(..len).unwrap_or(&[])));
            if sent {
                rtic::pend(Interrupt::USART1);
            } else {
                *l.dropped = l.dropped.wrapping_add(1);
            }
        }

        l.watchdog.feed();
        *l.late = l.timer.flags().contains(Flag::Update);
        if *l.late {
            *l.overruns = l.overruns.wrapping_add(1);
            defmt::warn!(
                "overrun {=u32}: a period took longer than 5 ms",
                *l.overruns
            );
        }
    }

    /// USART1, below the sample task: every received byte through the update task (which writes
    /// only the inactive slot, already erased at boot, so the loop never waits for an erase), its
    /// replies queued whole between frames; then drains the queue, one byte per TXE.
    #[task(binds = USART1, priority = 1, shared = [producer], local = [
        tx, rx, consumer, flash, update, serial, unit,
    ])]
    fn uart(mut cx: uart::Context) {
        let l = cx.local;
        while l.rx.is_rx_not_empty() {
            let Ok(byte) = l.rx.read() else {
                continue;
            };
            let mut reply = [0u8; MAX_REPLY];
            let mut window = Windowed {
                flash: l.flash.unlocked(),
                base: crate::MODELS_OFFSET,
                mapped: crate::models_region(),
            };
            let trust = tcomp_firmware::trust::Trust::new(*l.unit, crate::otp_keys());
            let validate = |w: &mut Windowed<'_, _>, off: u32, len: u32| {
                let at = off as usize;
                w.mapped
                    .get(at..at.saturating_add(len as usize))
                    .map_or(Err(Reason::Flash), |b| trust.check_payload(b).map(|_| ()))
            };
            if let Some(n) = l
                .update
                .push(byte, &mut window, &l.serial[..], validate, &mut reply)
            {
                // A reply that does not fit is dropped whole: the host repeats its request.
                cx.shared
                    .producer
                    .lock(|p| enqueue_whole(p, reply.get(..n).unwrap_or(&[])));
            }
        }
        let tx = l.tx;
        while tx.is_tx_empty() {
            match l.consumer.dequeue() {
                Some(b) => {
                    let _ = tx.write(b);
                }
                None => {
                    tx.unlisten();
                    return;
                }
            }
        }
        tx.listen();
    }

    /// Enqueues `bytes` whole or not at all (a frame or a reply is never split or cut).
    fn enqueue_whole(p: &mut Producer<'static, u8>, bytes: &[u8]) -> bool {
        if p.capacity() - p.len() < bytes.len() {
            return false;
        }
        for &b in bytes {
            let _ = p.enqueue(b);
        }
        true
    }

    /// Erases the slot the next update will write unless it is blank, before the loop and the
    /// watchdog start: a sector erase stalls every flash fetch of this single-bank part for 1–2 s,
    /// which only the boot can afford. After it an update only programs words.
    fn prepare_update_slot(flash: &mut LockedFlash, active: Option<Active>) {
        let mut window = Windowed {
            flash: flash.unlocked(),
            base: crate::MODELS_OFFSET,
            mapped: crate::models_region(),
        };
        match erase_inactive(&mut window, &STM32F4_LAYOUT, active, crate::models_region()) {
            Ok(true) => defmt::info!("model update slot erased"),
            Ok(false) => {}
            Err(e) => defmt::warn!(
                "model update slot: erase failed ({}), an update will erase it",
                defmt::Debug2Format(&e)
            ),
        }
    }
}
