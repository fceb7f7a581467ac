//! The product's loop on QEMU's mps2-an386, fed by the replay board.
//!
//! Structured as the STM32F407 board binary is: the loop runs in the sample timer's interrupt
//! (CMSDK timer 0, IRQ 8, 200 Hz from the 25 MHz clock; `main` only sleeps), the loop's state is a
//! `static` (the `App` with its six decoded models, never on the stack), each sample's output
//! leaves over UART 0 as one of the core's binary frames, and the watchdog is fed once per sample.
//! The sensors are the replay board's: the vector (loaded into `mps.ram` by QEMU's loader) says
//! what the front ends latched at each timer edge, and which faults to inject, including those of
//! the board itself — a sample that overruns its period, one that overruns past the next timer
//! edge (a whole missed period: the board skips that edge's vector record, and the next sample's
//! counts and latched interval cover both periods), a glitch of the latched timestamp, and a hang
//! that the watchdog must end. The counters are read as one latched snapshot per sample, and the
//! rates divided by the interval between the vector's latched timestamps. Semihosting only ends the run and carries the boot messages and
//! the summary line (defmt): nothing is logged in the loop.
//!
//! A watchdog reset is survived like on a board: the watchdog's early-warning NMI writes a fault
//! record into no-init RAM, the second expiry resets, and the next boot reads the record (the reset
//! cause), resumes the vector after the hung sample with a fresh loop, and flags its first frame
//! `WATCHDOG_RESET`. The run's counters live in no-init RAM too, so the summary covers both boots.
//!
//! SysTick counts instructions around `App::sample_snapshot`: QEMU runs it with `-icount shift=3` (8 ns of
//! virtual time per instruction, a 125 MIPS core) and SysTick ticks at 25 MHz, so one tick is
//! [`INSTRUCTIONS_PER_TICK`] = 5 instructions.
#![no_std]
#![no_main]

mod sample_loop;
mod update_task;

use sample_loop::{Loop, send_report};
use update_task::{Updater, install_update, on_receive, start_update};

use core::cell::RefCell;
use core::mem::MaybeUninit;
use core::sync::atomic::{AtomicBool, AtomicU8, Ordering};
use cortex_m::interrupt::{InterruptNumber, Mutex};
use cortex_m::peripheral::NVIC;
use cortex_m_rt::{ExceptionFrame, entry, exception};
use defmt_semihosting as _;
use tcomp_core::frame::BootReport;
use tcomp_core::frame::MAX_FRAME_LEN;
use tcomp_core::slots::SlotId;
use tcomp_firmware::app::{
    App, ChannelConfig, IFOG1, IMU6, LoadError, MAX_CHANNELS, Record, status,
};
use tcomp_firmware::boot::REPORT_PERIODS;
use tcomp_firmware::fault::{FaultKind, FaultRecord};
use tcomp_firmware::replay::{
    Board, CONFIG_IFOG1, CONFIG_IMU6, HANG, HOLD_FOR_UPDATE, MISS, STALL, TICK_HZ,
    TICKS_PER_PERIOD, UNIT_SERIAL, Vector,
};
use tcomp_firmware::slots::{Choice, QEMU_LAYOUT, Source, choose};
use tcomp_firmware::timing::TimeCheck;
use tcomp_firmware::trust::Trust;
use tcomp_firmware::update::serial_text;
use tcomp_firmware::{
    HASH_START, InstructionCounter, RamFlash, TIMER0_IRQ, TimeBase, Timer, UART0_RX_IRQ, Uart,
    Watchdog, exit, fold_hash,
};

/// Instructions per SysTick tick under `-icount shift=3` (40 ns per tick, 8 ns per instruction).
const INSTRUCTIONS_PER_TICK: u32 = 5;
/// Timer ticks per loop period: 25 MHz / 200 Hz.
const PERIOD: u32 = TICKS_PER_PERIOD as u32;
/// Watchdog ticks to its early warning (three periods: a sample may be late, or even miss the
/// next timer edge, which is counted and flagged, but a loop that has not run for three periods
/// hangs); the reset follows after as many again.
const WATCHDOG_TICKS: u32 = 3 * PERIOD;
/// Below the stack pointer at entry, this much stack is painted to measure the peak use.
const PAINT_BYTES: usize = 32 * 1024;
const PAINT: u32 = 0xA5A5_5A5A;
/// Marks a valid [`Run`] in no-init RAM.
const RUN_MAGIC: u32 = 0x52E9_1A7C;
/// Marks the reset after a committed update (in [`Run::update_reset`]).
const UPDATE_RESET: u32 = 0x0B5E_7A11;
/// The unit's serial number in the update protocol's INFO reply. A board reads its own; QEMU's
/// has none, so this names the board.
const SERIAL: [u8; 18] = serial_text(UNIT_SERIAL);

/// The loop's state: about 11 KB, in `.data`, never on the stack.
static mut APP: App<'static> = App::new(&IMU6);
/// The previous run's fault, if any (no-init RAM: survives the watchdog reset).
#[unsafe(link_section = ".uninit.tcomp.fault")]
static mut FAULT: MaybeUninit<FaultRecord> = MaybeUninit::uninit();
/// The run's counters (no-init RAM: they cover every boot of one QEMU run).
#[unsafe(link_section = ".uninit.tcomp.run")]
static mut RUN: MaybeUninit<Run> = MaybeUninit::uninit();
/// Everything the sample interrupt owns, handed over by `main` before the timer starts.
static LOOP: Mutex<RefCell<Option<Loop>>> = Mutex::new(RefCell::new(None));
/// The update task and the flash it writes, owned by UART 0's receive interrupt once `main` has set
/// it (about 400 B: one protocol frame of receive buffer and the receiver's state).
static mut UPDATE: Option<Updater> = None;
/// The boot report, written once by `load_models` and re-sent by the loop every
/// [`REPORT_PERIODS`]. A static rather than a value `main` hands on, so no copy of it lies in
/// `main`'s frame under the model decoder's (the boot's stack peak).
static mut REPORT: BootReport = BootReport::EMPTY;
/// Set by the sample interrupt after the vector's last sample.
static DONE: AtomicBool = AtomicBool::new(false);
/// The update task's state as the loop sees it ([`COMMITTED`] once an update has committed),
/// published by the receive interrupt.
static UPDATE_STATE: AtomicU8 = AtomicU8::new(0);
/// [`UPDATE_STATE`]: an update has committed.
const COMMITTED: u8 = 2;
/// Periods the loop holds past a [`HOLD_FOR_UPDATE`] vector's end waiting for an update to
/// commit: 600 s of guest time (QEMU runs it in about a minute and a half of wall time), far
/// longer than a 6-channel update takes (about 3 s of guest time) however slowly the host sends.
const HOLD_LIMIT: usize = 120_000;

unsafe extern "C" {
    static __models_start: u8;
    static __models_end: u8;
    static __replay_start: u8;
    static __replay_end: u8;
    static __keys_start: u8;
    static __keys_end: u8;
    static _stack_start: u8;
}

/// The run's counters, in no-init RAM (every bit pattern valid; [`RUN_MAGIC`] marks one written).
#[repr(C)]
#[derive(Clone, Copy)]
struct Run {
    magic: u32,
    /// The next sample of the vector.
    next: u32,
    samples: u32,
    mismatches: u32,
    flagged: u32,
    hash: u32,
    /// Sum of per-sample counts: at most 10⁴ samples of ~10⁴ instructions, far below 2³².
    instr_sum: u32,
    /// Worst count over the ordinary samples, and over the samples after missed periods.
    instr_max: u32,
    instr_max_gap: u32,
    /// Samples taken late (after a period overran) and timer periods missed entirely.
    late: u32,
    missed: u32,
    /// Boots after a watchdog reset.
    watchdog_resets: u32,
    stack_peak: u32,
    /// The sample of the worst instruction count, and the SysTick ticks (25 MHz) between the
    /// first two timer interrupts: the period as measured by the core's own clock (125,000).
    instr_max_at: u32,
    period_ticks: u32,
    /// [`UPDATE_RESET`] when this boot follows the reset that activates an update.
    update_reset: u32,
}

impl Run {
    const NEW: Self = Self {
        magic: RUN_MAGIC,
        next: 0,
        samples: 0,
        mismatches: 0,
        flagged: 0,
        hash: HASH_START,
        instr_sum: 0,
        instr_max: 0,
        instr_max_gap: 0,
        late: 0,
        missed: 0,
        watchdog_resets: 0,
        stack_peak: 0,
        instr_max_at: 0,
        period_ticks: 0,
        update_reset: 0,
    };
}

/// The sample timer's IRQ line, for the NVIC.
#[derive(Clone, Copy)]
struct Irq(u16);

// SAFETY: `number` returns a valid IRQ number of this device (timer 0's line, 8).
unsafe impl InterruptNumber for Irq {
    fn number(self) -> u16 {
        self.0
    }
}

/// Decodes the models (the boot's stack peak: the decoder's frame lies on top of this one's).
#[inline(never)]
fn load(
    app: &mut App<'static>,
    image: &'static [u8],
    vector: &Vector<'static>,
) -> [Result<(), LoadError>; MAX_CHANNELS] {
    app.load_for_unit(
        image,
        UNIT_SERIAL,
        tcomp_firmware::replay::board_hash(vector.config),
        vector.counters,
        vector.thermometers,
    )
}

/// The unit's trust: the replay board's serial and the keys of the `KEYS` region (QEMU has no
/// OTP: the loader puts the key store there as a factory would program OTP blocks 1–4).
fn trust() -> Trust<'static> {
    Trust::new(
        UNIT_SERIAL,
        region(&raw const __keys_start, &raw const __keys_end),
    )
}

/// Writes the boot report into [`REPORT`] and logs it. Not inlined: its temporaries are not on
/// the stack while the models are decoded.
#[inline(never)]
fn write_report(
    report: &mut BootReport,
    choice: &Choice<'static>,
    config: &'static [ChannelConfig],
    loaded: &[Result<(), LoadError>; MAX_CHANNELS],
    watchdog: bool,
    next: u32,
) {
    *report = tcomp_firmware::boot::report(choice, UNIT_SERIAL, config, loaded, watchdog);
    report.sequence = next;
    defmt::info!(
        "boot report: unit {=u64:#x}, image v{=u16} for unit {=u64:#x} (state {=u8}), board {=u64:#018x}, crc {=u32:#010x}",
        report.unit_serial,
        report.image_version,
        report.image_serial,
        report.image_state,
        report.board_hash,
        report.image_crc
    );
    for (cfg, r) in config.iter().zip(loaded.iter()) {
        if let Err(e) = r {
            defmt::warn!(
                "channel {=str}: no model ({}), raw passed through",
                cfg.name,
                e
            );
        }
    }
}

/// The boot report's static, for `main` to fill and hand to the loop.
fn boot_report() -> &'static mut BootReport {
    let report: *mut BootReport = &raw mut REPORT;
    // SAFETY: `main` calls this once per boot, before the sample interrupt (REPORT's only other
    // user, through the reference returned here) is enabled.
    unsafe { &mut *report }
}

/// The bytes between two linker symbols.
fn region(start: *const u8, end: *const u8) -> &'static [u8] {
    let len = (end as usize).saturating_sub(start as usize);
    // SAFETY: the symbols bound a memory region of `memory.x` that nothing writes while the firmware
    // runs (flash, or QEMU RAM filled by the loader before reset); it is readable for its whole length.
    unsafe { core::slice::from_raw_parts(start, len) }
}

/// Paints the stack below the current frame, returning the painted window.
fn paint_stack() -> (usize, usize) {
    let sp = cortex_m::register::msp::read() as usize;
    let top = sp - 256;
    let bottom = top - PAINT_BYTES;
    let mut p = bottom;
    while p < top {
        // SAFETY: [bottom, top) lies in RAM below the live stack frame (4 MiB of RAM, the stack at
        // its top, statics at its bottom), so nothing live is overwritten.
        unsafe { core::ptr::write_volatile(p as *mut u32, PAINT) };
        p += 4;
    }
    (bottom, top)
}

/// Lowest address whose paint was overwritten: the peak of stack use.
fn stack_peak(bottom: usize, top: usize) -> usize {
    let mut p = bottom;
    // SAFETY: the same window `paint_stack` wrote, word aligned.
    while p < top && unsafe { core::ptr::read_volatile(p as *const u32) } == PAINT {
        p += 4;
    }
    p
}

/// The reset cause: the previous boot's fault record, read once and cleared.
fn take_fault() -> Option<FaultRecord> {
    // SAFETY: only `main` (before any interrupt is enabled) and the fault handlers (which never
    // return to it) touch FAULT; every bit pattern is a valid `FaultRecord`.
    let ptr: *mut MaybeUninit<FaultRecord> = &raw mut FAULT;
    // SAFETY: see above.
    let slot = unsafe { &mut *ptr };
    // SAFETY: every bit pattern of the `repr(C)` integer record is valid (see `fault.rs`).
    let record = unsafe { slot.assume_init_read() };
    slot.write(FaultRecord::CLEAR);
    record.valid().map(|_| record)
}

fn record_fault(record: FaultRecord) {
    // SAFETY: a fault handler writes the record and resets or hangs; nothing else runs after it.
    let ptr: *mut MaybeUninit<FaultRecord> = &raw mut FAULT;
    // SAFETY: as above.
    unsafe { (*ptr).write(record) };
}

#[entry]
fn main() -> ! {
    let (paint_bottom, paint_top) = paint_stack();
    let Some(cp) = cortex_m::Peripherals::take() else {
        exit(false)
    };
    let fault = take_fault();
    // SAFETY: `main` runs once per boot and takes the only references to RUN and APP before the
    // sample interrupt, their only other user, is enabled.
    let (run, app): (*mut MaybeUninit<Run>, *mut App<'static>) = (&raw mut RUN, &raw mut APP);
    // SAFETY: as above.
    let (run, app) = unsafe { (&mut *run, &mut *app) };
    // SAFETY: every bit pattern of the `repr(C)` integer struct is valid. Read field by field, not
    // copied whole: `main`'s frame lies under the model decoder's at the boot's stack peak.
    let (magic, update_reset, next) = unsafe {
        let p = run.as_ptr();
        ((*p).magic, (*p).update_reset, (*p).next)
    };
    let after_update = magic == RUN_MAGIC && update_reset == UPDATE_RESET;
    let mut boot_flags = 0;
    let run = match fault.and_then(|f| f.valid()) {
        _ if after_update => run.write(Run::NEW),
        Some(FaultKind::Watchdog) if magic == RUN_MAGIC => {
            defmt::println!("reset cause: watchdog; resuming at sample {=u32}", next);
            boot_flags = status::WATCHDOG_RESET;
            // SAFETY: as above; the previous run's record is resumed in place.
            let resumed = unsafe { run.assume_init_mut() };
            resumed.watchdog_resets += 1;
            resumed
        }
        Some(kind) => {
            defmt::error!("the previous run ended in {}", kind);
            exit(false)
        }
        None => run.write(Run::NEW),
    };
    let models = region(&raw const __models_start, &raw const __models_end);
    // SAFETY: MODELS is mapped RAM under QEMU; the update writes only the inactive slot, and the
    // loop's models borrow only the active one (`choice.image`).
    let mut flash = unsafe { RamFlash::new(models.as_ptr(), models.len()) };
    // The boot's choice verifies each candidate's signature: counted (SysTick, 5 instructions a
    // tick under `-icount shift=3`) for the verifier's cost at boot.
    let counter = InstructionCounter::new(cp.SYST);
    let v0 = counter.now();
    let choice = choose(&mut flash, &QEMU_LAYOUT, models, |b| trust().check(b));
    let v1 = counter.now();
    defmt::println!(
        "BOOT-VERIFY instructions={=u32} source={} signer={}",
        counter.ticks_between(v0, v1) * INSTRUCTIONS_PER_TICK,
        choice.source,
        choice.signer
    );
    let (image, source) = (choice.image, choice.source);
    if after_update {
        update_boot(app, image, source);
    }
    // Into its static now, so the slot choice is not kept in `main`'s frame under the model
    // decoder's (the boot's stack peak).
    install_update(flash, choice.active);
    let bytes = region(&raw const __replay_start, &raw const __replay_end);
    let vector = match Vector::parse(bytes) {
        Ok(v) => v,
        Err(e) => {
            defmt::error!("no replay vector at 0x2100_0000: {}", e);
            exit(false)
        }
    };
    let config: &'static [ChannelConfig] = match vector.config {
        CONFIG_IMU6 if vector.channels == IMU6.len() => &IMU6,
        CONFIG_IFOG1 if vector.channels == IFOG1.len() => &IFOG1,
        _ => {
            defmt::error!("unknown configuration {=u16}", vector.config);
            exit(false)
        }
    };
    defmt::info!("models: {}", choice.source);
    defmt::info!(
        "replay: configuration {=u16}, {=usize} samples, {=usize} thermometers, {=usize} counters",
        vector.config,
        vector.samples,
        vector.thermometers,
        vector.counters
    );
    app.reset(config);
    // Two calls, not one function: only `load`'s small frame lies under the decoder's.
    let loaded = load(app, image, &vector);
    let report = boot_report();
    write_report(report, &choice, config, &loaded, boot_flags != 0, run.next);

    let port = start_update(cp.NVIC);
    start_loop(app, run, vector, config, counter, boot_flags, report);
    // A byte already waiting raises the interrupt at once.
    port.enable_rx_interrupt();
    // SAFETY: UPDATE is set; the handler (DefaultHandler, IRQ 0) is its only user from here on.
    unsafe { NVIC::unmask(Irq(UART0_RX_IRQ as u16)) };
    // A board would sleep here (WFI). Under `-icount …,sleep=off` QEMU 7.2 delivers only every
    // second CMSDK timer interrupt across a WFI (measured: two timer periods between interrupts
    // with WFI, one when the CPU does not sleep; the timer's own INTSTATUS, polled, sets every
    // period), so `main` spins; the run is made short by a coarser `-icount` shift instead.
    while !DONE.load(Ordering::Acquire) {
        cortex_m::asm::nop();
    }
    NVIC::mask(Irq(UART0_RX_IRQ as u16));
    let update: *mut Option<Updater> = &raw mut UPDATE;
    // SAFETY: the UART interrupt, UPDATE's only other user, is masked.
    let committed = unsafe { (*update).as_ref() }.and_then(|u| u.task.committed());
    finish(paint_bottom, paint_top, committed)
}

/// Starts the sample timer and hands the loop's state to the interrupt. Not inlined: the `Loop`
/// is built in this frame, which is gone before the interrupt runs on top of `main`'s.
#[inline(never)]
fn start_loop(
    app: &'static mut App<'static>,
    run: &'static mut Run,
    vector: Vector<'static>,
    config: &'static [ChannelConfig],
    counter: InstructionCounter,
    boot_flags: u16,
    report: &'static mut BootReport,
) {
    let timer = Timer::timer0();
    let time = TimeBase::start();
    let board = vector.board_at(run.next as usize);
    let watchdog = Watchdog::start(WATCHDOG_TICKS);
    let t_start = time.now();
    timer.start(PERIOD, true);
    let state = Loop {
        app,
        run,
        vector,
        board,
        config,
        uart: Uart::uart0(),
        timer,
        time,
        watchdog,
        counter,
        check: TimeCheck::new(TICKS_PER_PERIOD),
        next_edge: t_start.wrapping_add(PERIOD),
        edges: 0,
        last_entry: 0,
        boot_flags,
        report,
        held: 0,
    };
    send_report(&state.uart, state.report);
    cortex_m::interrupt::free(|cs| *LOOP.borrow(cs).borrow_mut() = Some(state));
    // SAFETY: the handler (DefaultHandler, IRQ 8) only takes LOOP inside a critical section.
    unsafe { NVIC::unmask(Irq(TIMER0_IRQ as u16)) };
}

/// Stops the loop, measures the stack and prints the summary; after a committed update, resets
/// to run the new image. Not inlined, like `start_loop`.
#[inline(never)]
fn finish(paint_bottom: usize, paint_top: usize, committed: Option<(SlotId, u32)>) -> ! {
    NVIC::mask(Irq(TIMER0_IRQ as u16));
    let Some(state) = cortex_m::interrupt::free(|cs| LOOP.borrow(cs).borrow_mut().take()) else {
        exit(false)
    };
    state.watchdog.stop();
    let config = state.vector.config;
    let r = state.run;
    let peak = stack_peak(paint_bottom, paint_top);
    let stack_top = (&raw const _stack_start) as usize;
    r.stack_peak = r.stack_peak.max(stack_top.saturating_sub(peak) as u32);
    let timed = r.samples.max(1);
    defmt::println!(
        "REPLAY-SUMMARY config={=u16} samples={=u32} mismatches={=u32} flagged={=u32} hash={=u32} instructions_mean={=u32} instructions_max={=u32} instructions_max_at={=u32} instructions_max_after_gap={=u32} period_ticks={=u32} late={=u32} missed={=u32} watchdog_resets={=u32} stack_bytes={=u32}",
        config,
        r.samples,
        r.mismatches,
        r.flagged,
        r.hash,
        r.instr_sum / timed,
        r.instr_max,
        r.instr_max_at,
        r.instr_max_gap,
        r.period_ticks,
        r.late,
        r.missed,
        r.watchdog_resets,
        r.stack_peak
    );
    let ok = r.mismatches == 0 && r.samples > 0;
    if let (true, Some((slot, generation))) = (ok, committed) {
        defmt::println!(
            "UPDATE-COMMITTED slot={} generation={=u32}: resetting to run it",
            slot,
            generation
        );
        r.update_reset = UPDATE_RESET;
        cortex_m::peripheral::SCB::sys_reset();
    }
    exit(ok)
}

/// The boot after an update's reset: loads the models the boot chose, reports them and ends the
/// run (the replay vector was played by the boot before).
fn update_boot(app: &mut App<'static>, image: &'static [u8], source: Source) -> ! {
    app.reset(&IMU6);
    let loaded = app
        .load(image)
        .iter()
        .take(IMU6.len())
        .filter(|r| r.is_ok())
        .count();
    defmt::println!(
        "UPDATE-BOOT source={} models_loaded={=usize} channels={=usize}",
        source,
        loaded,
        IMU6.len()
    );
    exit(matches!(source, Source::Slot(..)))
}

#[exception]
unsafe fn DefaultHandler(irqn: i16) {
    if irqn == TIMER0_IRQ {
        cortex_m::interrupt::free(|cs| {
            if let Some(l) = LOOP.borrow(cs).borrow_mut().as_mut() {
                l.tick();
            }
        });
    } else if irqn == UART0_RX_IRQ {
        on_receive();
    }
}

/// The watchdog's early warning: the loop has not fed it for three periods. Records the cause (the
/// handler gets no exception frame from cortex-m-rt, so no PC); the watchdog's second expiry resets
/// the board.
#[exception]
unsafe fn NonMaskableInt() {
    record_fault(FaultRecord::watchdog(0, 0));
}

#[exception]
unsafe fn HardFault(frame: &ExceptionFrame) -> ! {
    record_fault(FaultRecord::hard_fault(frame.pc(), frame.lr()));
    defmt::error!("HardFault at pc={=u32:#x}", frame.pc());
    exit(false)
}

#[panic_handler]
fn panic(info: &core::panic::PanicInfo) -> ! {
    let (file, line) = info.location().map_or(("?", 0), |l| (l.file(), l.line()));
    record_fault(FaultRecord::panic(file, line));
    defmt::error!("panic at {=str}:{=u32}", file, line);
    exit(false)
}
