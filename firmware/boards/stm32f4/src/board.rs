//! The STM32F407 board's side of the application: `setup` (the part configured, the model slots
//! chosen and the update slot erased before the watchdog starts), the sample task's I/O (TIM2, the
//! DWT cycle counter, the ADS1220s and the counter block, the IWDG), the drain's transmitter
//! (USART1, TXE interrupt), and the receive path (DMA2 stream 2 into a ring, its half/full
//! interrupts counted for the ring's reader).

use core::sync::atomic::{AtomicU32, Ordering};
use cortex_m::peripheral::DWT;
use stm32f4xx_hal::dma::DmaFlag;
use stm32f4xx_hal::pac;
use stm32f4xx_hal::prelude::*;
use stm32f4xx_hal::serial::TxISR;
use stm32f4xx_hal::serial::TxListen;
use stm32f4xx_hal::timer::{Event, Flag};
use stm32f4xx_hal::watchdog::IndependentWatchdog;
use stm32f4xx_hal::{ClearFlags, ReadFlags};
use tcomp_firmware::application::{
    self, Boot, Devices, ReceiveIrq, RingReader, RingWriter, Task, Timestamp,
};
use tcomp_firmware::slots::{STM32F4_LAYOUT, boot, choose};

use crate::flash::ModelFlash;
use crate::setup::{self, CYCLES_PER_PERIOD, RX_RING, TICK_HZ, TICKS_PER_PERIOD};

/// The sample task's I/O.
pub type SampleIo = Stm32Io;
/// The drain's transmitter.
pub type SerialTx = UartTx;
/// The receive interrupt's state.
pub type Receive = DmaIrq;
/// The update task's receive source.
pub type Rx = RingReader<DmaRing>;
/// The model flash.
pub type Flash = ModelFlash;

/// Half rings the receive DMA completed (its half- and full-transfer interrupts).
static HALVES: AtomicU32 = AtomicU32::new(0);

/// Configures the board: the part (`setup::setup`), the reset cause and fault record, the unit
/// serial, the model slots (the boot's erase of the slot an update will write, before the
/// watchdog starts: it stalls every flash fetch for 1–2 s).
pub fn setup(
    core: cortex_m::Peripherals,
    dp: pac::Peripherals,
) -> Devices<Stm32Io, UartTx, DmaIrq, Rx, ModelFlash> {
    paint_stack();
    let d = match setup::setup(core, dp, spi1_home()) {
        Ok(d) => d,
        Err(e) => {
            defmt::error!("setup failed: {}", e);
            // Nothing can run; reset (the watchdog is not started yet).
            cortex_m::peripheral::SCB::sys_reset();
        }
    };
    defmt::info!("reset cause: {}", d.reset_cause);
    if let Some((f, kind)) = d.fault.and_then(|f| Some((f, f.valid()?))) {
        defmt::error!(
            "previous run ended in {} at {=str}:{=u32} (lr {=u32:#010x}; for a HardFault the \
             number is the PC)",
            kind,
            f.file(),
            f.line_or_pc(),
            f.lr()
        );
    }
    let mut flash = d.flash;
    let (kib, holds) = flash.part();
    if !holds {
        defmt::error!(
            "this part has {=u16} KiB of flash: the model slots (sectors 10, 11) need 1024 KiB; no models, no updates",
            kib
        );
    }
    // The slots' boot work, before the watchdog starts (an erase stalls every flash fetch for
    // 1–2 s): each candidate's signature verified against the OTP keys before a slot is chosen
    // (a slot refused is never put on trial), a new image's trial begun, a failed trial rolled back, the slot an update writes
    // erased unless the old image is still the rollback.
    let trust = crate::trust();
    let choice = match boot(&mut flash, &STM32F4_LAYOUT, |b| trust.check(b)) {
        Ok(c) => c,
        Err(e) => {
            defmt::warn!(
                "model slots: boot work failed ({}); running what they hold",
                e
            );
            choose(&mut flash, &STM32F4_LAYOUT, |b| trust.check(b))
        }
    };
    defmt::info!("models: {}", choice);
    let image = match choice.image {
        // SAFETY: the active slot's payload: an update writes only the other slot, and the boot's
        // erase touched only that one.
        Some((offset, len)) => unsafe { flash.map_static(offset, len) },
        None => &[],
    };
    let watchdog_reset = matches!(
        d.reset_cause,
        crate::fault::ResetCause::WindowWatchdog | crate::fault::ResetCause::IndependentWatchdog
    );
    let (dma, ring) = d.rx;
    Devices {
        sample: Stm32Io {
            thermometers: d.thermometers,
            counters: d.counters,
            timer: d.timer,
            watchdog: d.watchdog,
            periods: 0,
        },
        tx: UartTx(d.tx),
        receive: DmaIrq(dma),
        rx: RingReader::new(DmaRing(ring)),
        flash,
        boot: Boot {
            unit: crate::unit_serial(),
            config: crate::CONFIG,
            board_hash: Some(crate::CONFIG_HASH),
            counters: tcomp_firmware::app::MAX_COUNTERS,
            thermometers: setup::THERMOMETERS,
            image,
            signer: choice.signer,
            refused: choice.refused,
            keys: crate::otp_keys(),
            active: choice.active,
            layout: STM32F4_LAYOUT,
            trial: choice.trial,
            watchdog_reset,
            first_period: 0,
            ticks_per_latch: u64::from(TICKS_PER_PERIOD),
        },
    }
}

/// The thermometers' shared bus's static home.
fn spi1_home() -> &'static mut Option<embedded_hal_bus::util::AtomicCell<setup::Spi1Bus>> {
    match cortex_m::singleton!(: Option<embedded_hal_bus::util::AtomicCell<setup::Spi1Bus>> = None)
    {
        Some(home) => home,
        None => cortex_m::peripheral::SCB::sys_reset(),
    }
}

/// The stack's paint, and the window painted at boot (below `setup`'s frame to the CCM's bottom).
const PAINT: u32 = 0xA5A5_5A5A;
static PAINTED_BOTTOM: AtomicU32 = AtomicU32::new(0);
static PAINTED_TOP: AtomicU32 = AtomicU32::new(0);

unsafe extern "C" {
    static _stack_start: u8;
    static _stack_end: u8;
}

/// Paints the CCM stack from 256 bytes below the current frame down to its bottom, so that the
/// peak use can be read while the unit runs (`stack_peak`).
fn paint_stack() {
    let sp = cortex_m::register::msp::read() as usize;
    let bottom = (&raw const _stack_end) as usize;
    let top = sp.saturating_sub(256) & !3;
    let mut p = bottom;
    while p < top {
        // SAFETY: [bottom, top) is the CCM stack region below the live frame (memory.x:
        // `_stack_end` = 0x1000_0000), which nothing else uses; word aligned.
        unsafe { core::ptr::write_volatile(p as *mut u32, PAINT) };
        p += 4;
    }
    PAINTED_BOTTOM.store(bottom as u32, Ordering::Relaxed);
    PAINTED_TOP.store(top as u32, Ordering::Relaxed);
}

/// The stack's peak use so far, bytes: from its top to the lowest word whose paint was
/// overwritten (scanning up from the bottom: a frame need not write every word it reserves).
fn stack_peak() -> u32 {
    let (bottom, top) = (
        PAINTED_BOTTOM.load(Ordering::Relaxed) as usize,
        PAINTED_TOP.load(Ordering::Relaxed) as usize,
    );
    let mut p = bottom;
    // SAFETY: the window `paint_stack` wrote, word aligned, in the CCM.
    while p < top && unsafe { core::ptr::read_volatile(p as *const u32) } == PAINT {
        p += 4;
    }
    ((&raw const _stack_start) as usize).saturating_sub(p) as u32
}

/// `idle`: sleeps until the next interrupt; once a second (at the lowest priority, about 60,000
/// cycles) measures the stack's peak, and every 10 s logs it with the sample task's worst cost.
pub fn idle() -> ! {
    let mut wakes: u32 = 0;
    loop {
        cortex_m::asm::wfi();
        wakes = wakes.wrapping_add(1);
        if wakes.is_multiple_of(200) {
            let peak = stack_peak();
            application::STATS
                .stack_peak
                .fetch_max(peak, Ordering::Relaxed);
            if wakes.is_multiple_of(2000) {
                defmt::info!(
                    "status: sample task worst {=u32} cycles (of {=u32} a period), stack peak {=u32} B of {=u32}",
                    application::Stats::get(&application::STATS.worst_task),
                    CYCLES_PER_PERIOD,
                    peak,
                    ((&raw const _stack_start) as usize - (&raw const _stack_end) as usize) as u32
                );
            }
        }
    }
}

/// TIM2, the DWT cycle counter, the sensors, the IWDG.
pub struct Stm32Io {
    thermometers: [setup::Thermometer; setup::THERMOMETERS],
    counters: setup::Counters,
    timer: setup::SampleTimer,
    watchdog: IndependentWatchdog,
    /// Periods since the timer started (the frames' timestamps count them).
    periods: u64,
}

impl application::SampleIo for Stm32Io {
    type Thermometer = setup::Thermometer;
    type Counters = setup::Counters;

    fn ticks_per_period(&self) -> u32 {
        CYCLES_PER_PERIOD
    }

    fn start(&mut self) -> u32 {
        self.watchdog.start(setup::WATCHDOG_MS.millis());
        let t = DWT::cycle_count();
        if self.timer.start(TICKS_PER_PERIOD.micros()).is_err() {
            defmt::error!("the sample timer refused its period");
        }
        self.timer.listen(Event::Update);
        t.wrapping_add(CYCLES_PER_PERIOD)
    }

    fn clear_timer(&mut self) {
        self.timer.clear_flags(Flag::Update);
    }

    fn now(&self) -> u32 {
        DWT::cycle_count()
    }

    fn cost_start() -> u32 {
        DWT::cycle_count()
    }

    fn cost_since(start: u32) -> u32 {
        DWT::cycle_count().wrapping_sub(start)
    }

    fn sensors(
        &mut self,
        number: u64,
    ) -> Option<(&mut [setup::Thermometer], &mut setup::Counters)> {
        self.periods = number;
        Some((&mut self.thermometers, &mut self.counters))
    }

    fn timestamp(&self, number: u64) -> Timestamp {
        Timestamp {
            ticks: number.wrapping_mul(u64::from(TICKS_PER_PERIOD)),
            hz: TICK_HZ,
            latched: false,
        }
    }

    fn feed_watchdog(&mut self) {
        self.watchdog.feed();
    }

    fn stuck(&mut self, task: Task) {
        defmt::error!("{} stopped: the watchdog is no longer fed", task);
    }

    fn reset(&mut self) -> ! {
        cortex_m::peripheral::SCB::sys_reset()
    }
}

/// USART1's transmitter for the drain: TXE says it takes a byte; its interrupt is on while bytes
/// wait in the frame queue.
pub struct UartTx(setup::FrameTx);

impl application::SerialTx for UartTx {
    fn ready(&mut self) -> bool {
        self.0.is_tx_empty()
    }

    fn write(&mut self, byte: u8) {
        let _ = self.0.write(byte);
    }

    fn listen(&mut self, on: bool) {
        if on {
            self.0.listen();
        } else {
            self.0.unlisten();
        }
    }
}

/// DMA2 stream 2's interrupt: counts the half rings written (the ring reader's clock).
pub struct DmaIrq(setup::RxDma);

impl ReceiveIrq for DmaIrq {
    fn on_interrupt(&mut self) {
        let flags = self.0.flags();
        let mut halves = 0;
        if flags.contains(DmaFlag::HalfTransfer) {
            halves += 1;
        }
        if flags.contains(DmaFlag::TransferComplete) {
            halves += 1;
        }
        self.0.clear_flags(flags);
        HALVES.fetch_add(halves, Ordering::Release);
    }
}

/// The receive ring as the DMA writes it.
pub struct DmaRing(*const u8);

// SAFETY: the ring is a static the DMA writes and only the update task reads.
unsafe impl Send for DmaRing {}

impl RingWriter for DmaRing {
    fn ring_len(&self) -> usize {
        RX_RING
    }

    fn halves(&self) -> u32 {
        HALVES.load(Ordering::Acquire)
    }

    fn position(&self) -> usize {
        // SAFETY: a read of DMA2 stream 2's NDTR (remaining transfers), which has no side effect.
        let remaining = unsafe { (*pac::DMA2::ptr()).st(2).ndtr().read().ndt().bits() };
        RX_RING.saturating_sub(usize::from(remaining)) % RX_RING
    }

    fn byte(&self, index: usize) -> u8 {
        // SAFETY: `index < RX_RING` (the reader's contract) inside the ring's static; a volatile
        // read of a byte the DMA wrote before the position the reader got.
        unsafe { core::ptr::read_volatile(self.0.add(index % RX_RING)) }
    }
}
