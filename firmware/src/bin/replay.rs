//! The compensation loop at 200 Hz on QEMU's mps2-an386, fed by the replay board.
//!
//! Reads the model-blob image from the `MODELS` flash region and the test vector from `mps.ram`
//! (both loaded by QEMU's generic loader, so a new image or vector needs no rebuild), then runs the
//! configuration the vector names: on every SysTick tick (200 Hz) it latches one recorded sample,
//! runs [`App::sample`] (sensor reads through the HAL traits, every channel's compensator), and
//! compares each output bit for bit with the host's. SysTick doubles as the instruction counter
//! (`-icount shift=0`: one tick = 40 instructions). Logs go out with defmt over semihosting; the
//! verdict is QEMU's exit code.
#![no_std]
#![no_main]

use core::sync::atomic::{AtomicBool, Ordering};
use cortex_m::peripheral::SYST;
use cortex_m::peripheral::syst::SystClkSource;
use cortex_m_rt::{ExceptionFrame, entry, exception};
use defmt_semihosting as _;
use tcomp_firmware::app::{App, ChannelConfig, IFOG1, IMU6, MAX_CHANNELS, Record};
use tcomp_firmware::replay::{CONFIG_IFOG1, CONFIG_IMU6, Vector};
use tcomp_firmware::{HASH_START, INSTRUCTIONS_PER_TICK, exit, fold_hash};

/// SysTick ticks per loop period: 25 MHz / 200 Hz.
const TICKS_PER_PERIOD: u32 = 125_000;
/// Below the stack pointer at entry, this much stack is painted to measure the peak use.
const PAINT_BYTES: usize = 32 * 1024;
const PAINT: u32 = 0xA5A5_5A5A;

static TICK: AtomicBool = AtomicBool::new(false);

unsafe extern "C" {
    static __models_start: u8;
    static __models_end: u8;
    static __replay_start: u8;
    static __replay_end: u8;
    static _stack_start: u8;
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

struct Summary {
    samples: u32,
    mismatches: u32,
    flagged: u32,
    hash: u32,
    /// Sum of per-sample counts: at most 10⁴ samples of ~10⁴ instructions, far below 2³².
    instr_sum: u32,
    instr_max: u32,
    overruns: u32,
}

fn run(config: &'static [ChannelConfig], image: &[u8], v: &Vector) -> Summary {
    let mut app = App::new(config);
    let loaded = app.load(image);
    for (cfg, r) in config.iter().zip(loaded.iter()) {
        match r {
            Ok(()) => defmt::info!("channel {=str}: model loaded", cfg.name),
            Err(e) => defmt::warn!(
                "channel {=str}: no model ({}), raw passed through",
                cfg.name,
                e
            ),
        }
    }
    let mut board = v.board();
    let mut buf = [Record::default(); MAX_CHANNELS];
    let out = buf.get_mut(..config.len()).unwrap_or(&mut []);
    let mut last_status = [0u16; MAX_CHANNELS];
    let mut s = Summary {
        samples: 0,
        mismatches: 0,
        flagged: 0,
        hash: HASH_START,
        instr_sum: 0,
        instr_max: 0,
        overruns: 0,
    };
    TICK.store(false, Ordering::Relaxed);
    for n in 0..v.samples {
        while !TICK.swap(false, Ordering::Acquire) {
            cortex_m::asm::wfi();
        }
        v.load(n, &mut board);
        let (thermometers, counters) = board.sensors();
        let t0 = SYST::get_current();
        app.sample(thermometers, counters, out);
        let t1 = SYST::get_current();
        if t1 > t0 {
            s.overruns += 1; // SysTick reloaded mid-sample: the sample overran its period
        } else {
            let instr = (t0 - t1) * INSTRUCTIONS_PER_TICK;
            s.instr_sum = s.instr_sum.saturating_add(instr);
            s.instr_max = s.instr_max.max(instr);
        }
        for (k, (rec, last)) in out.iter().zip(last_status.iter_mut()).enumerate() {
            let expected = v.expected(n, k);
            if rec.compensated.to_bits() != expected.compensated.to_bits()
                || rec.status != expected.status
            {
                if s.mismatches == 0 {
                    defmt::error!(
                        "MISMATCH sample {=usize} channel {=usize}: firmware {=u32:#010x} status {=u16:#x}, host {=u32:#010x} status {=u16:#x}",
                        n,
                        k,
                        rec.compensated.to_bits(),
                        rec.status,
                        expected.compensated.to_bits(),
                        expected.status
                    );
                }
                s.mismatches += 1;
            }
            if rec.status != 0 {
                s.flagged += 1;
            }
            if rec.status != *last {
                let name = config.get(k).map_or("?", |c| c.name);
                defmt::info!(
                    "sample {=usize} {=str}: status {=u16:#x} -> {=u16:#x} (output {=f32})",
                    n,
                    name,
                    *last,
                    rec.status,
                    rec.compensated
                );
                *last = rec.status;
            }
            s.hash = fold_hash(s.hash, rec);
        }
        s.samples += 1;
    }
    s
}

#[entry]
fn main() -> ! {
    let (paint_bottom, paint_top) = paint_stack();
    let Some(cp) = cortex_m::Peripherals::take() else {
        exit(false)
    };
    let image = region(&raw const __models_start, &raw const __models_end);
    let vector = region(&raw const __replay_start, &raw const __replay_end);
    let v = match Vector::parse(vector) {
        Ok(v) => v,
        Err(e) => {
            defmt::error!("no replay vector at 0x2100_0000: {}", e);
            exit(false)
        }
    };
    defmt::info!(
        "replay: configuration {=u16}, {=usize} samples, {=usize} thermometers, {=usize} counters",
        v.config,
        v.samples,
        v.thermometers,
        v.counters
    );

    let mut syst = cp.SYST;
    syst.set_clock_source(SystClkSource::Core);
    syst.set_reload(TICKS_PER_PERIOD - 1);
    syst.clear_current();
    syst.enable_interrupt();
    syst.enable_counter();

    let s = match v.config {
        CONFIG_IMU6 if v.channels == IMU6.len() => run(&IMU6, image, &v),
        CONFIG_IFOG1 if v.channels == IFOG1.len() => run(&IFOG1, image, &v),
        _ => {
            defmt::error!("unknown configuration {=u16}", v.config);
            exit(false)
        }
    };
    syst.disable_interrupt();
    let peak = stack_peak(paint_bottom, paint_top);
    let stack_top = (&raw const _stack_start) as usize;
    let timed = s.samples.saturating_sub(s.overruns).max(1);
    defmt::println!(
        "REPLAY-SUMMARY config={=u16} samples={=u32} mismatches={=u32} flagged={=u32} hash={=u32} instructions_mean={=u32} instructions_max={=u32} overruns={=u32} stack_bytes={=usize}",
        v.config,
        s.samples,
        s.mismatches,
        s.flagged,
        s.hash,
        s.instr_sum / timed,
        s.instr_max,
        s.overruns,
        stack_top.saturating_sub(peak)
    );
    exit(s.mismatches == 0 && s.samples > 0 && s.overruns == 0)
}

#[exception]
fn SysTick() {
    TICK.store(true, Ordering::Release);
}

#[exception]
unsafe fn HardFault(frame: &ExceptionFrame) -> ! {
    defmt::error!("HardFault at pc={=u32:#x}", frame.pc());
    exit(false)
}

#[panic_handler]
fn panic(_info: &core::panic::PanicInfo) -> ! {
    defmt::error!("panic");
    exit(false)
}
