//! The board: clocks, pins and peripherals of the STM32F407 IMU board, configured once and returned
//! as one typed [`Devices`] struct (quartiq/stabilizer's shape). Nothing here runs per sample.
//!
//! | what | peripheral | pins | settings |
//! |---|---|---|---|
//! | clocks | RCC | 8 MHz crystal on OSC_IN/OSC_OUT (HSE) | SYSCLK 168 MHz (PLL), APB1 42 MHz, APB2 84 MHz |
//! | sample timer | TIM2 (32-bit) | — | 1 MHz tick, update every 5,000 ticks (200 Hz) |
//! | thermometers | SPI1, 12 × ADS1220 | SCK PA5, MISO PA6, MOSI PA7; CS PE0–PE11; DRDY PD0–PD11 (inputs: each conversion read once, when ready) | mode 1, ≤ 5 MHz |
//! | counter block | SPI2, FPGA | SCK PB13, MISO PB14, MOSI PB15, CS PB12 | mode 0, ≤ 10 MHz |
//! | frames out | USART1 TX | PA9 | [`BAUD`] (921,600, the description's `[link] baud`) 8N1, TXE interrupt (the application's drain) |
//! | model updates in | USART1 RX, DMA2 stream 2 channel 4 | PA10 | same link: `tcomp flash`; circular DMA into a 2 KiB ring (half/full-transfer interrupts) |
//! | watchdog | IWDG | — | 50 ms (ten periods), started by the application after the boot's erase |
//!
//! Thermometers 0–8 are the RLGs' (anode, cathode, shell of x, y, z), 9–11 the QMAs', as
//! `tcomp_firmware::app::IMU6` expects; counter-block channels 0–2 the RLGs, 3–5 the QMAs.
//! A device that does not answer at start-up is logged and left as it is: its reads fail every
//! sample and the loop flags its channels `SENSOR_ERROR`, while the other channels run.

use embedded_hal::spi::{MODE_0, MODE_1};
use embedded_hal_bus::spi::{AtomicDevice, ExclusiveDevice, NoDelay};
use embedded_hal_bus::util::AtomicCell;
use stm32f4xx_hal::dma::{StreamsTuple, Transfer, config::DmaConfig};
use stm32f4xx_hal::gpio::{AnyPin, Input, Output, PB12};
use stm32f4xx_hal::pac::{self, SPI1, SPI2, TIM2, USART1};
use stm32f4xx_hal::prelude::*;
use stm32f4xx_hal::rcc::Config;
use stm32f4xx_hal::serial::{self, Tx};
use stm32f4xx_hal::spi::Spi;
use stm32f4xx_hal::timer::CounterUs;
use stm32f4xx_hal::watchdog::IndependentWatchdog;
use tcomp_hal::OnReady;
use tcomp_hal::ads1220::{Ads1220, Config as AdcConfig, Gain, IdacCurrent, RtdThermometer};
use tcomp_hal::pulse_counter::CounterBlock;
use tcomp_hal::rtd::Rtd;

use crate::fault::{self, ResetCause};

/// Crystal frequency.
pub const HSE_HZ: u32 = 8_000_000;
/// Core clock.
pub const SYSCLK_HZ: u32 = 168_000_000;
/// Tick rate of the sample timer: the unit of the frames' timestamps.
pub const TICK_HZ: u32 = 1_000_000;
/// Sample-timer ticks per loop period (200 Hz).
pub const TICKS_PER_PERIOD: u32 = 5_000;
/// Core cycles per loop period: 168 MHz × 5 ms.
pub const CYCLES_PER_PERIOD: u32 = SYSCLK_HZ / 1_000_000 * TICKS_PER_PERIOD;
/// Thermometers on SPI1.
pub const THERMOMETERS: usize = 12;
/// Counter-block channels used.
pub const COUNTERS: usize = 6;
/// UART baud rate: the board description's `[link] baud` (`build.rs`, `tcomp_firmware::wiring`),
/// the one place it is set: USART1 runs at it, the receive ring is sized from it, and
/// `tcomp flash --board` opens the port at it.
pub const BAUD: u32 = crate::LINK_BAUD;
/// Watchdog timeout.
pub const WATCHDOG_MS: u32 = 50;
/// PT100 reference resistor on each ADS1220, Ω.
pub const R_REF_OHM: f32 = 1620.0;

/// The thermometers' shared bus.
pub type Spi1Bus = Spi<SPI1>;
/// One thermometer: an ADS1220 measuring a 4-wire PT100, sharing SPI1 (an [`AtomicCell`]: the
/// devices move into the sample task, so the bus must be `Sync`; a read while another holds it
/// fails with `Busy` instead of corrupting it — it never happens, one task reads them all).
/// Read through [`OnReady`]: each 20 SPS conversion once, when its DRDY line goes low, held in
/// between (the loop runs at 200 Hz).
pub type Thermometer =
    OnReady<RtdThermometer<AtomicDevice<'static, Spi1Bus, AnyPin<Output>, NoDelay>>, AnyPin<Input>>;
/// The counter block on SPI2.
pub type Counters = CounterBlock<ExclusiveDevice<Spi<SPI2>, PB12<Output>, NoDelay>, COUNTERS>;
/// The 200 Hz sample timer.
pub type SampleTimer = CounterUs<TIM2>;
/// The frame output.
pub type FrameTx = Tx<USART1>;
/// The model update's input: USART1 RX (PA10) by DMA2 stream 2 into a ring of [`RX_RING`] bytes.
pub type RxDma = Transfer<
    stm32f4xx_hal::dma::Stream2<pac::DMA2>,
    4,
    serial::Rx<USART1>,
    stm32f4xx_hal::dma::PeripheralToMemory,
    &'static mut [u8; RX_RING],
>;
/// Bytes of the receive ring: sized from the baud rate and the watchdog policy. At [`BAUD`] the
/// line carries 92,160 bytes a second; the update task reads the ring at least every period
/// (5 ms, 461 bytes) and is never held off for more than the policy's 20 ms without the unit
/// being reset (`application::liveness`), 1,843 bytes: 2 KiB holds that.
pub const RX_RING: usize = 2048;

/// Everything the application uses, configured.
pub struct Devices {
    /// Thermometers, in the configuration's order.
    pub thermometers: [Thermometer; THERMOMETERS],
    /// The counter block.
    pub counters: Counters,
    /// The sample timer, not started (the application starts it with the watchdog).
    pub timer: SampleTimer,
    /// The frame output.
    pub tx: FrameTx,
    /// The independent watchdog, not started yet (the application starts it, after the boot's
    /// slot erase and the model load).
    pub watchdog: IndependentWatchdog,
    /// The update input: the circular DMA, running, and its ring.
    pub rx: (RxDma, *const u8),
    /// The model slots' flash.
    pub flash: crate::flash::ModelFlash,
    /// Why the chip last reset.
    pub reset_cause: ResetCause,
    /// The fault the previous run recorded, if any.
    pub fault: Option<tcomp_firmware::fault::FaultRecord>,
}

/// What can stop the board from starting at all.
#[derive(Clone, Copy, Debug, defmt::Format)]
pub enum SetupError {
    /// The UART rejected its configuration.
    Uart,
    /// The receive ring's static was taken twice.
    Ring,
}

/// Configures the board. `spi1` is the static home of the thermometers' shared bus.
pub fn setup(
    mut core: cortex_m::Peripherals,
    dp: pac::Peripherals,
    spi1: &'static mut Option<AtomicCell<Spi1Bus>>,
) -> Result<Devices, SetupError> {
    let reset_cause = fault::reset_cause(&dp.RCC);
    let fault = fault::take();
    let mut rcc = dp.RCC.freeze(
        Config::hse(HSE_HZ.Hz())
            .sysclk(SYSCLK_HZ.Hz())
            .pclk1(42.MHz())
            .pclk2(84.MHz()),
    );
    let mut delay = core.SYST.delay(&rcc.clocks);
    // The cycle counter times the sample task's entries, so whole missed timer periods are counted
    // (TIM2's update flag can say only that at least one period was late).
    core.DCB.enable_trace();
    core.DWT.enable_cycle_counter();

    let gpioa = dp.GPIOA.split(&mut rcc);
    let gpiob = dp.GPIOB.split(&mut rcc);
    let gpiod = dp.GPIOD.split(&mut rcc);
    let gpioe = dp.GPIOE.split(&mut rcc);

    // Thermometers: SPI1, mode 1, one chip select each (high = deselected before the bus runs).
    let bus = dp.SPI1.spi(
        (Some(gpioa.pa5), Some(gpioa.pa6), Some(gpioa.pa7)),
        MODE_1,
        5.MHz(),
        &mut rcc,
    );
    let bus: &'static AtomicCell<Spi1Bus> = spi1.insert(AtomicCell::new(bus));
    let pins = thermometer_pins(gpiod, gpioe);
    let mut k = 0;
    let mut thermometers = pins.map(|(mut pin, drdy)| {
        // Thermometer k's element, from the board description (`TCOMP_BOARD`); a converter the
        // description does not use is read as a PT100 and feeds no channel.
        let rtd = crate::RTDS.get(k).copied().unwrap_or(Rtd::PT100);
        k += 1;
        pin.set_high();
        // `new_no_delay` only drives CS high, which cannot fail on this pin (`Infallible`).
        let device = match AtomicDevice::new_no_delay(bus, pin) {
            Ok(d) => d,
            Err(e) => match e {},
        };
        let adc = Ads1220::new(device, AdcConfig::rtd_4wire(IdacCurrent::Ua1000, Gain::G4));
        OnReady::new(RtdThermometer::new(adc, rtd, R_REF_OHM), drdy)
    });
    for (i, t) in thermometers.iter_mut().enumerate() {
        if let Err(e) = t.inner_mut().init(&mut delay) {
            defmt::warn!(
                "thermometer {=usize}: init failed ({}), its channels will flag SENSOR_ERROR",
                i,
                defmt::Debug2Format(&e)
            );
        }
    }

    // Counter block: SPI2, mode 0.
    let spi2 = dp.SPI2.spi(
        (Some(gpiob.pb13), Some(gpiob.pb14), Some(gpiob.pb15)),
        MODE_0,
        10.MHz(),
        &mut rcc,
    );
    let mut cs2 = gpiob.pb12.into_push_pull_output();
    cs2.set_high();
    let device = match ExclusiveDevice::new_no_delay(spi2, cs2) {
        Ok(d) => d,
        Err(e) => match e {},
    };
    let mut counters = CounterBlock::new(device);
    match counters.init() {
        Ok(info) => defmt::info!("counter block: {}", info),
        Err(e) => defmt::warn!(
            "counter block: init failed ({}), counter channels will flag SENSOR_ERROR",
            defmt::Debug2Format(&e)
        ),
    }

    // USART1: frames out (TXE interrupt, the application's drain), and model updates in
    // (`tcomp flash`) by DMA: DMA2 stream 2, channel 4, circular over the ring, half- and
    // full-transfer interrupts (the `receive` task counts them).
    let (tx, rx) = dp
        .USART1
        .serial(
            (gpioa.pa9, gpioa.pa10),
            serial::Config::default()
                .baudrate(BAUD.bps())
                .dma(serial::config::DmaConfig::Rx),
            &mut rcc,
        )
        .map_err(|_| SetupError::Uart)?
        .split();
    let ring: &'static mut [u8; RX_RING] =
        cortex_m::singleton!(: [u8; RX_RING] = [0; RX_RING]).ok_or(SetupError::Ring)?;
    let ring_ptr = ring.as_ptr();
    let streams = StreamsTuple::new(dp.DMA2, &mut rcc);
    let mut rx_dma = Transfer::init_peripheral_to_memory(
        streams.2,
        rx,
        ring,
        None,
        DmaConfig::default()
            .memory_increment(true)
            .half_transfer_interrupt(true)
            .transfer_complete_interrupt(true),
    );
    // SAFETY: the stream is configured and not enabled yet; circular mode only makes it wrap to
    // the ring's start instead of stopping (the HAL's config has no switch for it).
    unsafe {
        use stm32f4xx_hal::dma::traits::Stream as _;
        rx_dma.stream().set_circular_mode(true);
    }
    rx_dma.start(|_| {});

    // Started by the application with its watchdog, after the models are loaded.
    let timer = dp.TIM2.counter_us(&mut rcc);
    // Started by the application once the inactive model slot is erased (an erase takes 1–2 s).
    let watchdog = IndependentWatchdog::new(dp.IWDG);

    Ok(Devices {
        thermometers,
        counters,
        timer,
        tx,
        watchdog,
        rx: (rx_dma, ring_ptr),
        flash: crate::flash::ModelFlash::new(dp.FLASH),
        reset_cause,
        fault,
    })
}

/// Per thermometer: its chip select (PE0–PE11) and its converter's DRDY line (PD0–PD11).
fn thermometer_pins(
    gpiod: stm32f4xx_hal::gpio::gpiod::Parts,
    gpioe: stm32f4xx_hal::gpio::gpioe::Parts,
) -> [(AnyPin<Output>, AnyPin<Input>); THERMOMETERS] {
    [
        (
            gpioe.pe0.into_push_pull_output().erase(),
            gpiod.pd0.into_pull_up_input().erase(),
        ),
        (
            gpioe.pe1.into_push_pull_output().erase(),
            gpiod.pd1.into_pull_up_input().erase(),
        ),
        (
            gpioe.pe2.into_push_pull_output().erase(),
            gpiod.pd2.into_pull_up_input().erase(),
        ),
        (
            gpioe.pe3.into_push_pull_output().erase(),
            gpiod.pd3.into_pull_up_input().erase(),
        ),
        (
            gpioe.pe4.into_push_pull_output().erase(),
            gpiod.pd4.into_pull_up_input().erase(),
        ),
        (
            gpioe.pe5.into_push_pull_output().erase(),
            gpiod.pd5.into_pull_up_input().erase(),
        ),
        (
            gpioe.pe6.into_push_pull_output().erase(),
            gpiod.pd6.into_pull_up_input().erase(),
        ),
        (
            gpioe.pe7.into_push_pull_output().erase(),
            gpiod.pd7.into_pull_up_input().erase(),
        ),
        (
            gpioe.pe8.into_push_pull_output().erase(),
            gpiod.pd8.into_pull_up_input().erase(),
        ),
        (
            gpioe.pe9.into_push_pull_output().erase(),
            gpiod.pd9.into_pull_up_input().erase(),
        ),
        (
            gpioe.pe10.into_push_pull_output().erase(),
            gpiod.pd10.into_pull_up_input().erase(),
        ),
        (
            gpioe.pe11.into_push_pull_output().erase(),
            gpiod.pd11.into_pull_up_input().erase(),
        ),
    ]
}
