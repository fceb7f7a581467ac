//! The QEMU board's side of the application: `setup` (the reset cause, the model slots, the replay
//! vector), the replay sensors as the sample task's I/O with the run's bookkeeping (every record
//! compared with the host's, bit for bit), the injected faults, and the end of a run in `idle`.
//!
//! A watchdog reset is survived like on a board: the watchdog's early-warning NMI writes a fault
//! record into no-init RAM, the second expiry resets, and the next boot reads the record (the reset
//! cause), resumes the vector after the hung sample with a fresh loop, and flags its first frame
//! `WATCHDOG_RESET`. The run's counters live in no-init RAM too, so the summary covers both boots.
//!
//! The sample task's cost is counted in instructions with SysTick: QEMU runs with `-icount shift=3`
//! (8 ns of virtual time per instruction) and SysTick ticks at 25 MHz, so one tick is
//! [`INSTRUCTIONS_PER_TICK`] = 5 instructions.

use core::mem::MaybeUninit;
use core::sync::atomic::{AtomicBool, AtomicU8, Ordering};
use cortex_m::peripheral::{NVIC, SYST};
use cortex_m_rt::{ExceptionFrame, exception};
use heapless::spsc::{Consumer, Producer, Queue};
use tcomp_board_qemu::device::{self, Interrupt};
use tcomp_board_qemu::drivers::{self, RamFlash, TimeBase, Timer, Uart, Watchdog};
use tcomp_core::frame::BootReport;
use tcomp_firmware::app::{ChannelConfig, IFOG1, IMU6, Record};
use tcomp_firmware::application::{
    self, Boot, CONFIRM_STATE, CONFIRMED, Devices, Period, ReceiveIrq, STATS, Stats, Task,
    Timestamp, UPDATE_COMMITTED, UPDATE_STATE,
};
use tcomp_firmware::fault::{FaultKind, FaultRecord};
use tcomp_firmware::replay::{
    self, CONFIG_IFOG1, CONFIG_IMU6, HANG, HOLD_FOR_UPDATE, MISS, STALL, TICK_HZ, TICKS_PER_PERIOD,
    UNIT_SERIAL, Vector,
};
use tcomp_firmware::slots::{QEMU_LAYOUT, Source, boot, choose};
use tcomp_firmware::trust::Trust;
use tcomp_firmware::{HASH_START, fold_hash};

/// Instructions per SysTick tick under `-icount shift=3` (40 ns per tick, 8 ns per instruction).
const INSTRUCTIONS_PER_TICK: u32 = 5;
/// Timer ticks per loop period: 25 MHz / 200 Hz.
const PERIOD: u32 = TICKS_PER_PERIOD as u32;
/// Watchdog ticks to its early warning: three and a half periods (a sample may be late, or even
/// miss the next timer edge, which is counted and flagged, but a loop that has not fed it for
/// three periods hangs, or has stopped feeding it because a task is stuck); the reset follows
/// after as many again. Not a whole number of periods, so the reset falls between two samples.
const WATCHDOG_TICKS: u32 = 3 * PERIOD + PERIOD / 2;
/// Below the stack pointer at entry, this much stack is painted to measure the peak use.
const PAINT_BYTES: usize = 32 * 1024;
const PAINT: u32 = 0xA5A5_5A5A;
/// Marks a valid [`Run`] in no-init RAM.
const RUN_MAGIC: u32 = 0x52E9_1A7C;
/// Marks the reset after a committed update (in [`Run::update_reset`]).
const UPDATE_RESET: u32 = 0x0B5E_7A11;
/// Periods the loop holds past a [`HOLD_FOR_UPDATE`] vector's end waiting for an update to
/// commit: 600 s of guest time (QEMU runs it in about a minute and a half of wall time), far
/// longer than a 6-channel update takes (about 3 s of guest time) however slowly the host sends.
const HOLD_LIMIT: u64 = 120_000;
/// Bytes of the receive ring (the QEMU board's stand-in for the STM32F407's DMA ring): 2 KiB,
/// 22 ms of a 921,600-baud line, longer than the update task is ever held off without the
/// watchdog policy resetting the unit (`application::liveness`).
const RX_RING: usize = 2048;

/// The sample task's I/O.
pub type SampleIo = ReplayIo;
/// The drain's transmitter.
pub type SerialTx = drivers::UartTx;
/// The receive interrupt's state.
pub type Receive = UartReceive;
/// The update task's receive source.
pub type Rx = Consumer<'static, u8>;
/// The model flash.
pub type Flash = RamFlash;

/// The previous run's fault, if any (no-init RAM: survives the watchdog reset).
#[unsafe(link_section = ".uninit.tcomp.fault")]
static mut FAULT: MaybeUninit<FaultRecord> = MaybeUninit::uninit();
/// The run's counters (no-init RAM: they cover every boot of one QEMU run).
#[unsafe(link_section = ".uninit.tcomp.run")]
static mut RUN: MaybeUninit<Run> = MaybeUninit::uninit();
/// Set by the sample task after the vector's last sample: `idle` ends the run.
static DONE: AtomicBool = AtomicBool::new(false);
/// This boot follows the reset that activates an update.
static AFTER_UPDATE: AtomicBool = AtomicBool::new(false);
/// The task the sample task found stuck (its code), for the watchdog's fault record.
static STUCK: AtomicU8 = AtomicU8::new(0);
/// The painted stack window.
static mut PAINTED: (usize, usize) = (0, 0);

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
    /// Sum of per-sample instruction counts: at most 10⁴ samples of ~10⁴ instructions.
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
    /// The sample of the worst instruction count.
    instr_max_at: u32,
    /// [`UPDATE_RESET`] when this boot follows the reset that activates an update.
    update_reset: u32,
    /// The worst sample task (entry to the watchdog feed), instructions.
    task_max: u32,
    /// Sample periods that preempted the drain, and the update task.
    drain_preempted: u32,
    update_preempted: u32,
    /// Frames dropped whole (queue full).
    dropped: u32,
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
        update_reset: 0,
        task_max: 0,
        drain_preempted: 0,
        update_preempted: 0,
        dropped: 0,
    };
}

/// The run's counters. The sample task writes them; `setup` (before any task runs) and `idle`
/// (after the sample timer is masked) read them.
fn run() -> &'static mut Run {
    let ptr: *mut MaybeUninit<Run> = &raw mut RUN;
    // SAFETY: `setup` writes a valid record (`Run::NEW` or the resumed one) before any task runs;
    // afterwards the sample task is its only user while the timer runs, and `idle` reads it only
    // after masking the timer; every bit pattern of the `repr(C)` integer record is valid.
    unsafe { (*ptr).assume_init_mut() }
}

/// The bytes between two linker symbols.
///
/// # Safety
/// The range must be mapped, and nothing may write it while the returned slice lives.
unsafe fn region(start: *const u8, end: *const u8) -> &'static [u8] {
    let len = (end as usize).saturating_sub(start as usize);
    // SAFETY: the caller's contract.
    unsafe { core::slice::from_raw_parts(start, len) }
}

/// Paints the stack below the current frame.
fn paint_stack() {
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
    // SAFETY: written once here, before any task runs; read by `idle` at the end.
    unsafe { PAINTED = (bottom, top) };
}

/// Stack bytes used at the peak: from the top of the stack to the lowest overwritten paint.
fn stack_peak() -> u32 {
    // SAFETY: written by `paint_stack` before any task ran.
    let (bottom, top) = unsafe { PAINTED };
    let mut p = bottom;
    // SAFETY: the window `paint_stack` wrote, word aligned.
    while p < top && unsafe { core::ptr::read_volatile(p as *const u32) } == PAINT {
        p += 4;
    }
    let stack_top = (&raw const _stack_start) as usize;
    stack_top.saturating_sub(p) as u32
}

/// The reset cause: the previous boot's fault record, read once and cleared.
fn take_fault() -> Option<FaultRecord> {
    let ptr: *mut MaybeUninit<FaultRecord> = &raw mut FAULT;
    // SAFETY: only `setup` (before any interrupt is enabled) and the fault handlers (which never
    // return to it) touch FAULT; every bit pattern of the `repr(C)` integer record is valid.
    let slot = unsafe { &mut *ptr };
    // SAFETY: see above.
    let record = unsafe { slot.assume_init_read() };
    slot.write(FaultRecord::CLEAR);
    record.valid().map(|_| record)
}

fn record_fault(record: FaultRecord) {
    let ptr: *mut MaybeUninit<FaultRecord> = &raw mut FAULT;
    // SAFETY: a fault handler writes the record and resets or hangs; nothing else runs after it.
    unsafe { (*ptr).write(record) };
}

/// Configures the board for the application: the reset cause and the run record, the model slots
/// (the boot's erase of the slot an update will write, before the watchdog starts), the replay
/// vector and the channel table it names.
pub fn setup(
    core: cortex_m::Peripherals,
    _device: device::Peripherals,
) -> Devices<ReplayIo, drivers::UartTx, UartReceive, Rx, RamFlash> {
    paint_stack();
    let fault = take_fault();
    let ptr: *mut MaybeUninit<Run> = &raw mut RUN;
    // SAFETY: no task runs yet; every bit pattern of the `repr(C)` integer record is valid. Read
    // field by field: this frame lies under the model decoder's at the boot's stack peak.
    let (magic, update_reset, next) = unsafe {
        let p = (*ptr).as_ptr();
        ((*p).magic, (*p).update_reset, (*p).next)
    };
    let after_update = magic == RUN_MAGIC && update_reset == UPDATE_RESET;
    AFTER_UPDATE.store(after_update, Ordering::Release);
    let mut watchdog_reset = false;
    match fault.and_then(|f| f.valid()) {
        _ if after_update => {
            // SAFETY: as above.
            unsafe { (*ptr).write(Run::NEW) };
        }
        Some(FaultKind::Watchdog) if magic == RUN_MAGIC => {
            let stuck = fault.map_or(0, |f| f.line_or_pc());
            defmt::println!(
                "reset cause: watchdog (stuck task {=u32}); resuming at sample {=u32}",
                stuck,
                next
            );
            watchdog_reset = true;
            run().watchdog_resets += 1;
        }
        Some(kind) => {
            defmt::error!("the previous run ended in {}", kind);
            drivers::exit(false)
        }
        None => {
            // SAFETY: as above.
            unsafe { (*ptr).write(Run::NEW) };
        }
    }
    // SAFETY: the linker symbols bound the MODELS region of `memory.x` (mapped RAM under QEMU).
    let mut flash = unsafe {
        RamFlash::new(
            &raw const __models_start,
            (&raw const __models_end as usize).saturating_sub(&raw const __models_start as usize),
        )
    };
    // The slots' boot work, before the watchdog and the loop start: each candidate's signature
    // verified before a slot is chosen, a new image's trial begun, a failed trial rolled back, the
    // slot an update writes erased unless the old image is needed. Counted (SysTick, 5
    // instructions a tick under `-icount shift=3`): the verifier's cost at boot.
    let counter = drivers::InstructionCounter::new(core.SYST);
    let v0 = counter.now();
    let choice = match boot(&mut flash, &QEMU_LAYOUT, |b| trust().check(b)) {
        Ok(c) => c,
        Err(_) => choose(&mut flash, &QEMU_LAYOUT, |b| trust().check(b)),
    };
    let v1 = counter.now();
    defmt::println!(
        "BOOT-VERIFY instructions={=u32} source={} signer={}",
        counter.ticks_between(v0, v1) * INSTRUCTIONS_PER_TICK,
        choice.source,
        choice.signer
    );
    let image = match choice.image {
        // SAFETY: the active slot's payload: an update writes only the other slot, and the
        // board's erase at boot touched only that one, so nothing writes these bytes while the
        // loop's models borrow them.
        Some((offset, len)) => unsafe { flash.map_static(offset, len) },
        None => &[],
    };
    // SAFETY: the replay region is QEMU RAM filled by the loader before reset; nothing writes it.
    let bytes = unsafe { region(&raw const __replay_start, &raw const __replay_end) };
    let vector = match Vector::parse(bytes) {
        Ok(v) => v,
        Err(e) => {
            defmt::error!("no replay vector at 0x2100_0000: {}", e);
            drivers::exit(false)
        }
    };
    let config: &'static [ChannelConfig] = match vector.config {
        CONFIG_IMU6 if vector.channels == IMU6.len() => &IMU6,
        CONFIG_IFOG1 if vector.channels == IFOG1.len() => &IFOG1,
        _ => {
            defmt::error!("unknown configuration {=u16}", vector.config);
            drivers::exit(false)
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
    let first = u64::from(run().next);
    let ring: &'static mut Queue<u8, RX_RING> = match cortex_m::singleton!(: Queue<u8, RX_RING> = Queue::new())
    {
        Some(q) => q,
        None => drivers::exit(false),
    };
    let (producer, consumer) = ring.split();
    let uart = Uart::uart0();
    uart.enable_rx_interrupt();
    Devices {
        sample: ReplayIo {
            board: vector.board_at(first as usize),
            vector,
            timer: Timer::timer0(),
            time: TimeBase::start(),
            watchdog: None,
            _syst: counter,
            after_update: after_update.then_some(choice.source),
            held: 0,
        },
        tx: drivers::UartTx::uart0(),
        receive: UartReceive { ring: producer },
        rx: consumer,
        flash,
        boot: Boot {
            unit: UNIT_SERIAL,
            config,
            board_hash: replay::board_hash(vector.config),
            counters: vector.counters,
            thermometers: vector.thermometers,
            image,
            signer: choice.signer,
            refused: choice.refused,
            keys: keys(),
            active: choice.active,
            layout: QEMU_LAYOUT,
            trial: choice.trial,
            watchdog_reset,
            first_period: first,
            ticks_per_latch: TICKS_PER_PERIOD,
        },
    }
}

/// UART 0's receive interrupt: every waiting byte into the receive ring (a DMA channel's job on
/// the STM32F407). QEMU holds further bytes back until the one-byte buffer is read, so none is
/// lost here; a full ring counts its losses.
pub struct UartReceive {
    ring: Producer<'static, u8>,
}

impl ReceiveIrq for UartReceive {
    fn on_interrupt(&mut self) {
        let port = Uart::handle0();
        port.clear_rx_interrupt();
        while let Some(byte) = port.read() {
            if self.ring.enqueue(byte).is_err() {
                drivers::count_rx_lost();
            }
        }
    }
}

/// The replay sensors and the QEMU board's timer, time base and watchdog.
pub struct ReplayIo {
    vector: Vector<'static>,
    board: replay::Board,
    timer: Timer,
    time: TimeBase,
    watchdog: Option<Watchdog>,
    _syst: drivers::InstructionCounter,
    /// This boot follows the reset that activates an update: what the boot chose.
    after_update: Option<Source>,
    /// The last period served past the vector's end while holding for an update (0: none).
    held: u64,
}

impl ReplayIo {
    /// The vector's last record, served again past its end while an update is under way.
    fn hold(&mut self, number: u64) -> bool {
        let waiting = self.vector.flags & HOLD_FOR_UPDATE != 0
            && self.after_update.is_none()
            && UPDATE_STATE.load(Ordering::Acquire) != UPDATE_COMMITTED;
        let last = self.vector.samples as u64 - 1;
        if !waiting || number - last > HOLD_LIMIT {
            return false;
        }
        self.held = number;
        self.vector.load(last as usize, &mut self.board);
        true
    }
}

impl application::SampleIo for ReplayIo {
    type Thermometer = replay::ReplayThermometer;
    type Counters = replay::ReplayBlock;

    fn ticks_per_period(&self) -> u32 {
        PERIOD
    }

    fn start(&mut self) -> u32 {
        self.watchdog = Some(Watchdog::start(WATCHDOG_TICKS));
        let t = self.time.now();
        self.timer.start(PERIOD, true);
        t.wrapping_add(PERIOD)
    }

    fn clear_timer(&mut self) {
        self.timer.clear();
    }

    fn now(&self) -> u32 {
        self.time.now()
    }

    fn cost_start() -> u32 {
        SYST::get_current()
    }

    fn cost_since(start: u32) -> u32 {
        (start.wrapping_sub(SYST::get_current()) & 0x00FF_FFFF) * INSTRUCTIONS_PER_TICK
    }

    fn sensors(
        &mut self,
        number: u64,
    ) -> Option<(&mut [replay::ReplayThermometer], &mut replay::ReplayBlock)> {
        if number >= self.vector.samples as u64 {
            if !self.hold(number) {
                self.timer.stop();
                DONE.store(true, Ordering::Release);
                return None;
            }
        } else {
            self.vector.load(number as usize, &mut self.board);
        }
        Some(self.board.snapshot())
    }

    fn timestamp(&self, number: u64) -> Timestamp {
        let last = self.vector.samples.saturating_sub(1) as u64;
        let ticks = if number > last {
            // Held past the end: the periods count on from the last latch.
            self.vector.timestamp(last as usize) + (number - last) * TICKS_PER_PERIOD
        } else {
            self.vector.timestamp(number as usize)
        };
        Timestamp {
            ticks,
            hz: TICK_HZ,
            latched: true,
        }
    }

    fn feed_watchdog(&mut self) {
        if let Some(w) = &self.watchdog {
            w.feed();
        }
    }

    /// Each record of the vector compared with the host's, bit for bit (before the board's bits,
    /// as the host's loop computed them), folded into the run's hash, and the run's counters.
    fn observe(&mut self, period: &Period, records: &[Record]) {
        let n = period.index();
        if n >= self.vector.samples || self.after_update.is_some() {
            // Past the vector, or the boot after an update: the new models' outputs are not the
            // host's (computed for the image before the update).
            return;
        }
        let r = run();
        for (c, rec) in records.iter().enumerate() {
            let expected = self.vector.expected(n, c);
            if rec.compensated.to_bits() != expected.compensated.to_bits()
                || rec.status != expected.status
            {
                r.mismatches += 1;
            }
            r.hash = fold_hash(r.hash, rec);
            if rec.status | period.flags != 0 {
                r.flagged += 1;
            }
        }
        r.instr_sum = r.instr_sum.saturating_add(period.cost);
        // The sample after missed periods carries every filter across the gap (more work, once,
        // after an overrun): counted apart, with its own budget.
        if period.entry.missed > 0 {
            r.instr_max_gap = r.instr_max_gap.max(period.cost);
        } else if period.cost > r.instr_max {
            r.instr_max = period.cost;
            r.instr_max_at = n as u32;
        }
        r.late += u32::from(period.entry.late);
        r.missed += period.entry.missed;
        r.samples += 1;
        r.next = n as u32 + 1;
    }

    /// The vector's injected overruns and hangs of the sample task.
    fn after(&mut self, period: &Period) {
        let n = period.index();
        if n >= self.vector.samples {
            return;
        }
        let injected = self.vector.board_faults(n);
        let entry = self.time.now();
        if injected & HANG != 0 {
            // The loop hangs: only the watchdog gets the board out of here.
            #[allow(clippy::empty_loop)]
            loop {}
        }
        if injected & STALL != 0 {
            // This sample overruns its period by half a period: the next one is late.
            while self.time.now().wrapping_sub(entry) < PERIOD + PERIOD / 2 {}
        }
        if injected & MISS != 0 {
            // This sample overruns past the next timer edge: that period is missed entirely.
            while self.time.now().wrapping_sub(entry) < 2 * PERIOD + PERIOD / 2 {}
        }
    }

    fn stuck(&mut self, task: Task) {
        STUCK.store(task.code(), Ordering::Relaxed);
    }

    /// The boot after an update's reset: what the application loaded from the image the boot
    /// chose. The run goes on (the vector again, not compared) so the trial can be confirmed.
    fn booted(&mut self, report: &BootReport) {
        let Some(source) = self.after_update else {
            return;
        };
        let channels = report.channels();
        let loaded = channels.iter().filter(|c| c.state == 0).count();
        defmt::println!(
            "UPDATE-BOOT source={} models_loaded={=usize} channels={=usize}",
            source,
            loaded,
            channels.len()
        );
    }

    fn reset(&mut self) -> ! {
        defmt::println!("reset requested: the boot erases the update slot");
        cortex_m::peripheral::SCB::sys_reset()
    }
}

/// `idle`: spins until the sample task has served the vector's last sample, then ends the run.
/// A board would sleep here (WFI). Under `-icount …,sleep=off` QEMU 7.2 delivers only every second
/// CMSDK timer interrupt across a WFI (measured: two timer periods between interrupts with WFI, one
/// when the CPU does not sleep), so it spins; the run is made short by a coarser `-icount` shift.
///
/// Like the STM32F407's `idle`, it measures the stack's peak now and then (every 2¹⁶ spins, a
/// few times a second of guest time) into [`STATS`], which the periodic boot report carries.
pub fn idle() -> ! {
    let mut spins: u32 = 0;
    while !DONE.load(Ordering::Acquire) {
        spins = spins.wrapping_add(1);
        if spins.is_multiple_of(1 << 16) {
            STATS.stack_peak.fetch_max(stack_peak(), Ordering::Relaxed);
        } else {
            cortex_m::asm::nop();
        }
    }
    finish()
}

/// Stops the loop, measures the stack and prints the summary; after a committed update, resets
/// to run the new image.
fn finish() -> ! {
    NVIC::mask(Interrupt::TIMER0);
    Watchdog::stop_any();
    let r = run();
    r.stack_peak = r.stack_peak.max(stack_peak());
    r.task_max = r.task_max.max(Stats::get(&STATS.worst_task));
    r.drain_preempted += Stats::get(&STATS.drain_preempted);
    r.update_preempted += Stats::get(&STATS.update_preempted);
    r.dropped += Stats::get(&STATS.dropped_frames);
    let timed = r.samples.max(1);
    defmt::println!(
        "REPLAY-SUMMARY samples={=u32} mismatches={=u32} flagged={=u32} hash={=u32} instructions_mean={=u32} instructions_max={=u32} instructions_max_at={=u32} instructions_max_after_gap={=u32} task_max={=u32} late={=u32} missed={=u32} watchdog_resets={=u32} stack_bytes={=u32} drain_preempted={=u32} update_preempted={=u32} dropped_frames={=u32} rx_lost={=u32}",
        r.samples,
        r.mismatches,
        r.flagged,
        r.hash,
        r.instr_sum / timed,
        r.instr_max,
        r.instr_max_at,
        r.instr_max_gap,
        r.task_max,
        r.late,
        r.missed,
        r.watchdog_resets,
        r.stack_peak,
        r.drain_preempted,
        r.update_preempted,
        r.dropped,
        drivers::rx_lost(),
    );
    if AFTER_UPDATE.load(Ordering::Acquire) {
        // The boot after an update: ends on whether the trial was confirmed.
        let confirmed = CONFIRM_STATE.load(Ordering::Acquire) == CONFIRMED;
        // SAFETY: as below: nothing writes the region any more.
        let mut flash = unsafe { models_flash() };
        let now = choose(&mut flash, &QEMU_LAYOUT, |b| trust().check(b)).source;
        let state = match choose(&mut flash, &QEMU_LAYOUT, |b| trust().check(b)).active {
            Some(a) => tcomp_core::slots::trial(&mut flash, &QEMU_LAYOUT, a.slot).ok(),
            None => None,
        };
        defmt::println!(
            "UPDATE-TRIAL source={} confirmed={=bool} slot_state={}",
            now,
            confirmed,
            state
        );
        drivers::exit(confirmed && state == Some(tcomp_core::slots::Trial::Confirmed))
    }
    let ok = r.mismatches == 0 && r.samples > 0;
    if ok && UPDATE_STATE.load(Ordering::Acquire) == UPDATE_COMMITTED {
        // What the next boot will run, read from the slots as the boot reads them.
        // SAFETY: every task that writes the region is stopped (the update task's last request
        // was the commit, and nothing runs but this).
        let mut flash = unsafe { models_flash() };
        let next = choose(&mut flash, &QEMU_LAYOUT, |b| trust().check(b)).source;
        defmt::println!("UPDATE-COMMITTED {}: resetting to run it", next);
        r.update_reset = UPDATE_RESET;
        cortex_m::peripheral::SCB::sys_reset();
    }
    drivers::exit(ok)
}

/// The unit's key store: the `KEYS` region of `memory.x` (QEMU has no OTP: its loader puts the
/// key block there as a factory programs the STM32F407's OTP blocks 1–4).
fn keys() -> &'static [u8] {
    // SAFETY: the linker symbols bound the KEYS region (mapped RAM under QEMU, filled by the
    // loader before reset); nothing in the firmware writes it.
    unsafe { region(&raw const __keys_start, &raw const __keys_end) }
}

/// The unit's trust: the replay board's serial and its key store (`tcomp_firmware::trust`).
fn trust() -> Trust<'static> {
    Trust::new(UNIT_SERIAL, keys())
}

/// The `MODELS` region as a flash.
///
/// # Safety
/// As [`RamFlash::new`]: no reference may be alive over a part the returned flash writes.
unsafe fn models_flash() -> RamFlash {
    // SAFETY: the linker symbols bound the MODELS region of `memory.x` (mapped RAM under QEMU);
    // the caller's contract.
    unsafe {
        RamFlash::new(
            &raw const __models_start,
            (&raw const __models_end as usize).saturating_sub(&raw const __models_start as usize),
        )
    }
}

/// The watchdog's early warning: the loop has not fed it for three and a half periods (it hangs,
/// or a task is stuck and the sample task stopped feeding it). Records the cause and the stuck
/// task, if any; the watchdog's second expiry resets the board.
#[exception]
unsafe fn NonMaskableInt() {
    record_fault(FaultRecord::watchdog(
        u32::from(STUCK.load(Ordering::Relaxed)),
        0,
    ));
}

#[exception]
unsafe fn HardFault(frame: &ExceptionFrame) -> ! {
    record_fault(FaultRecord::hard_fault(frame.pc(), frame.lr()));
    defmt::error!("HardFault at pc={=u32:#x}", frame.pc());
    drivers::exit(false)
}

#[panic_handler]
fn panic(info: &core::panic::PanicInfo) -> ! {
    let (file, line) = info.location().map_or(("?", 0), |l| (l.file(), l.line()));
    record_fault(FaultRecord::panic(file, line));
    defmt::error!("panic at {=str}:{=u32}", file, line);
    drivers::exit(false)
}
