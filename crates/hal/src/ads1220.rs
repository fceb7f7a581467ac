//! TI ADS1220 24-bit delta-sigma ADC, measuring a platinum RTD ratiometrically.
//!
//! Why this part: four inputs, a PGA, two matched programmable current sources (IDACs) and an
//! external reference input make it a one-chip RTD front end; with simultaneous 50/60 Hz rejection
//! at 20 SPS it resolves a PT100 to well under 1 mK, far better than the compensation model needs.
//!
//! # Interface (datasheet SBAS501)
//! SPI mode 1 (CPOL = 0, CPHA = 1), MSB first, ≤ 10 MHz (fewer for long cables). Commands, one byte
//! each, opening a chip-select frame:
//!
//! | command     | byte                     | followed by                              |
//! |-------------|--------------------------|------------------------------------------|
//! | RESET       | `0x06`                   | wait ≥ 50 µs + 32·t_CLK before the next   |
//! | START/SYNC  | `0x08`                   | —                                        |
//! | POWERDOWN   | `0x02`                   | —                                        |
//! | RDATA       | `0x10`                   | 24 bits of conversion data read          |
//! | RREG        | `0x20 \| rr<<2 \| (n−1)` | n register bytes read                    |
//! | WREG        | `0x40 \| rr<<2 \| (n−1)` | n register bytes written                 |
//!
//! Configuration registers (all reset to `0x00`):
//!
//! | reg | bits 7..0                                                                         |
//! |-----|-----------------------------------------------------------------------------------|
//! | 0   | MUX\[3:0\] · GAIN\[2:0\] · PGA_BYPASS                                                 |
//! | 1   | DR\[2:0\] · MODE\[1:0\] · CM · TS · BCS                                               |
//! | 2   | VREF\[1:0\] · 50/60\[1:0\] · PSW · IDAC\[2:0\]                                          |
//! | 3   | I1MUX\[2:0\] · I2MUX\[2:0\] · DRDYM · 0                                               |
//!
//! Conversion data are 24-bit two's complement: `code = V_in · gain / V_ref · 2²³`, clipped at
//! `0x7FFFFF` (+full scale) and `0x800000` (−full scale).
//!
//! # Ratiometric RTD measurement
//! The IDAC current `I` flows through the RTD and then through a precision reference resistor
//! `R_ref` between REFP0 and REFN0, so `V_in = I·R_rtd` and `V_ref = I·R_ref`; the current cancels:
//!
//! ```text
//! R_rtd = code / 2²³ · R_ref / gain
//! ```
//!
//! and only `R_ref`'s tolerance and drift matter. The default wiring
//! ([`Config::rtd_4wire`]) is a 4-wire RTD: IDAC1 on AIN3 drives the force lead, AIN0/AIN1 sense
//! across the element (lead resistance drops out), the return lead goes to REFP0 through `R_ref` to
//! ground at REFN0. A PT100 with `R_ref` = 1.62 kΩ, 1 mA and gain 4 spans 0…405 Ω, covering
//! 850 °C (390.5 Ω); a PT1000 uses 100 µA and 16.2 kΩ.
//!
//! # Faults
//! A broken element or lead stops the current: the reference collapses and the inputs float, and
//! the converter sits at a full-scale code (`0x7FFFFF` or `0x800000`) → [`ErrorKind::OpenCircuit`].
//! (The 10 µA burn-out sources, `burnout_current`, make this deterministic at the cost of a 10 µA
//! error current; enable them for a diagnostic conversion only.) A shorted element reads zero,
//! negative, or below 10 % of R0 — lower than any platinum RTD reaches at −200 °C — →
//! [`ErrorKind::ShortCircuit`]. Anything else outside −200…850 °C is [`ErrorKind::OutOfRange`].

use core::fmt;

use embedded_hal::delay::DelayNs;
use embedded_hal::spi::{Operation, SpiDevice};

use crate::error::{self, ErrorKind, ErrorType};
use crate::rtd::Rtd;
use crate::thermometer::Thermometer;

/// Command bytes.
pub mod cmd {
    /// Reset the device to its power-on state.
    pub const RESET: u8 = 0x06;
    /// Start or restart conversions.
    pub const START_SYNC: u8 = 0x08;
    /// Enter power-down mode.
    pub const POWERDOWN: u8 = 0x02;
    /// Read conversion data.
    pub const RDATA: u8 = 0x10;
    /// Read registers: `RREG | reg << 2 | (count − 1)`.
    pub const RREG: u8 = 0x20;
    /// Write registers: `WREG | reg << 2 | (count − 1)`.
    pub const WREG: u8 = 0x40;
}

/// Wait after RESET: the datasheet asks for 50 µs + 32 t_CLK (7.8 µs at the internal 4.096 MHz).
pub const RESET_WAIT_US: u32 = 100;

/// Positive full-scale code.
pub const CODE_MAX: i32 = 0x7F_FFFF;
/// Negative full-scale code.
pub const CODE_MIN: i32 = -0x80_0000;
/// 2²³, the code of `V_in = V_ref / gain`.
pub const FULL_SCALE: f32 = 8_388_608.0;

/// Input multiplexer (register 0, MUX\[3:0\]): positive and negative input.
#[derive(Debug, Copy, Clone, Eq, PartialEq)]
#[repr(u8)]
#[allow(missing_docs)]
pub enum Mux {
    Ain0Ain1 = 0b0000,
    Ain0Ain2 = 0b0001,
    Ain0Ain3 = 0b0010,
    Ain1Ain2 = 0b0011,
    Ain1Ain3 = 0b0100,
    Ain2Ain3 = 0b0101,
    Ain1Ain0 = 0b0110,
    Ain3Ain2 = 0b0111,
    Ain0Avss = 0b1000,
    Ain1Avss = 0b1001,
    Ain2Avss = 0b1010,
    Ain3Avss = 0b1011,
    /// (V(REFPx) − V(REFNx)) / 4 monitor.
    RefMonitor = 0b1100,
    /// (AVDD − AVSS) / 4 monitor.
    SupplyMonitor = 0b1101,
    /// Inputs shorted to (AVDD + AVSS) / 2, for offset calibration.
    Shorted = 0b1110,
}

impl Mux {
    const fn single_ended_or_monitor(self) -> bool {
        (self as u8) >= 0b1000
    }
}

/// PGA gain (register 0, GAIN\[2:0\]).
#[derive(Debug, Copy, Clone, Eq, PartialEq)]
#[repr(u8)]
#[allow(missing_docs)]
pub enum Gain {
    G1 = 0,
    G2 = 1,
    G4 = 2,
    G8 = 3,
    G16 = 4,
    G32 = 5,
    G64 = 6,
    G128 = 7,
}

impl Gain {
    /// The gain as a number (1…128).
    pub const fn factor(self) -> u8 {
        1 << (self as u8)
    }
}

/// Data rate (register 1, DR\[2:0\]), named by the normal-mode rate; duty-cycle mode divides by 4,
/// turbo mode doubles it.
#[derive(Debug, Copy, Clone, Eq, PartialEq)]
#[repr(u8)]
#[allow(missing_docs)]
pub enum DataRate {
    Sps20 = 0,
    Sps45 = 1,
    Sps90 = 2,
    Sps175 = 3,
    Sps330 = 4,
    Sps600 = 5,
    Sps1000 = 6,
}

/// Operating mode (register 1, MODE\[1:0\]).
#[derive(Debug, Copy, Clone, Eq, PartialEq)]
#[repr(u8)]
pub enum OperatingMode {
    /// Normal mode, 256 kHz modulator.
    Normal = 0,
    /// Duty-cycle mode: a quarter of the rate, lower power.
    DutyCycle = 1,
    /// Turbo mode: 512 kHz modulator, twice the rate.
    Turbo = 2,
}

/// Conversion mode (register 1, CM).
#[derive(Debug, Copy, Clone, Eq, PartialEq)]
pub enum ConversionMode {
    /// One conversion per START/SYNC.
    SingleShot,
    /// Convert continuously after one START/SYNC; RDATA returns the latest result.
    Continuous,
}

/// Reference selection (register 2, VREF\[1:0\]).
#[derive(Debug, Copy, Clone, Eq, PartialEq)]
#[repr(u8)]
pub enum Vref {
    /// Internal 2.048 V reference.
    Internal = 0,
    /// External reference on REFP0/REFN0 (ratiometric with a reference resistor).
    RefP0RefN0 = 1,
    /// External reference on AIN0/REFP1 and AIN3/REFN1.
    RefP1RefN1 = 2,
    /// Analog supply AVDD − AVSS.
    Supply = 3,
}

impl Vref {
    const fn external(self) -> bool {
        matches!(self, Self::RefP0RefN0 | Self::RefP1RefN1)
    }
}

/// FIR filter for line-frequency rejection (register 2, 50/60\[1:0\]); effective only at 20 SPS in
/// normal mode (5 SPS in duty-cycle mode).
#[derive(Debug, Copy, Clone, Eq, PartialEq)]
#[repr(u8)]
pub enum LineRejection {
    /// No 50/60 Hz rejection.
    Off = 0,
    /// Simultaneous 50 Hz and 60 Hz rejection.
    Both = 1,
    /// 50 Hz rejection only.
    Hz50 = 2,
    /// 60 Hz rejection only.
    Hz60 = 3,
}

/// Excitation current of both IDACs (register 2, IDAC\[2:0\]).
#[derive(Debug, Copy, Clone, Eq, PartialEq)]
#[repr(u8)]
#[allow(missing_docs)]
pub enum IdacCurrent {
    Off = 0,
    Ua10 = 1,
    Ua50 = 2,
    Ua100 = 3,
    Ua250 = 4,
    Ua500 = 5,
    Ua1000 = 6,
    Ua1500 = 7,
}

/// Pin an IDAC is routed to (register 3, I1MUX\[2:0\] / I2MUX\[2:0\]).
#[derive(Debug, Copy, Clone, Eq, PartialEq)]
#[repr(u8)]
#[allow(missing_docs)]
pub enum IdacRoute {
    Disabled = 0,
    Ain0Refp1 = 1,
    Ain1 = 2,
    Ain2 = 3,
    Ain3Refn1 = 4,
    Refp0 = 5,
    Refn0 = 6,
}

/// A complete device configuration: the four configuration registers, field by field.
#[derive(Debug, Copy, Clone, Eq, PartialEq)]
pub struct Config {
    /// Input multiplexer.
    pub mux: Mux,
    /// PGA gain.
    pub gain: Gain,
    /// Bypass the PGA (allowed for gains 1, 2 and 4 only).
    pub pga_bypass: bool,
    /// Data rate.
    pub data_rate: DataRate,
    /// Operating mode.
    pub mode: OperatingMode,
    /// Single-shot or continuous conversion.
    pub conversion: ConversionMode,
    /// Internal temperature sensor mode (replaces the input; 14-bit result).
    pub temperature_sensor: bool,
    /// 10 µA burn-out current sources on the inputs (open-circuit diagnosis).
    pub burnout_current: bool,
    /// Voltage reference.
    pub vref: Vref,
    /// 50/60 Hz rejection.
    pub line_rejection: LineRejection,
    /// Low-side power switch closed automatically during conversions.
    pub low_side_switch: bool,
    /// IDAC current.
    pub idac: IdacCurrent,
    /// Routing of IDAC1.
    pub idac1: IdacRoute,
    /// Routing of IDAC2.
    pub idac2: IdacRoute,
    /// Also signal data-ready on DOUT/DRDY.
    pub drdy_on_dout: bool,
}

impl Default for Config {
    /// The power-on state (all registers zero).
    fn default() -> Self {
        Self::POWER_ON
    }
}

impl Config {
    /// The power-on state: all four registers `0x00`.
    pub const POWER_ON: Config = Config {
        mux: Mux::Ain0Ain1,
        gain: Gain::G1,
        pga_bypass: false,
        data_rate: DataRate::Sps20,
        mode: OperatingMode::Normal,
        conversion: ConversionMode::SingleShot,
        temperature_sensor: false,
        burnout_current: false,
        vref: Vref::Internal,
        line_rejection: LineRejection::Off,
        low_side_switch: false,
        idac: IdacCurrent::Off,
        idac1: IdacRoute::Disabled,
        idac2: IdacRoute::Disabled,
        drdy_on_dout: false,
    };

    /// A 4-wire RTD (see the module docs): AIN0/AIN1 sense, IDAC1 on AIN3 forces `idac`, reference
    /// REFP0/REFN0 across `R_ref`, `gain`, 20 SPS continuous with simultaneous 50/60 Hz rejection.
    ///
    /// PT100: `rtd_4wire(IdacCurrent::Ua1000, Gain::G4)` with `R_ref` = 1.62 kΩ;
    /// PT1000: `rtd_4wire(IdacCurrent::Ua100, Gain::G4)` with `R_ref` = 16.2 kΩ.
    pub const fn rtd_4wire(idac: IdacCurrent, gain: Gain) -> Config {
        Config {
            mux: Mux::Ain0Ain1,
            gain,
            pga_bypass: false,
            data_rate: DataRate::Sps20,
            mode: OperatingMode::Normal,
            conversion: ConversionMode::Continuous,
            temperature_sensor: false,
            burnout_current: false,
            vref: Vref::RefP0RefN0,
            line_rejection: LineRejection::Both,
            low_side_switch: false,
            idac,
            idac1: IdacRoute::Ain3Refn1,
            idac2: IdacRoute::Disabled,
            drdy_on_dout: false,
        }
    }

    /// The four register values.
    pub const fn registers(&self) -> [u8; 4] {
        let r0 = (self.mux as u8) << 4 | (self.gain as u8) << 1 | self.pga_bypass as u8;
        let cm = matches!(self.conversion, ConversionMode::Continuous) as u8;
        let r1 = (self.data_rate as u8) << 5
            | (self.mode as u8) << 3
            | cm << 2
            | (self.temperature_sensor as u8) << 1
            | self.burnout_current as u8;
        let r2 = (self.vref as u8) << 6
            | (self.line_rejection as u8) << 4
            | (self.low_side_switch as u8) << 3
            | self.idac as u8;
        let r3 = (self.idac1 as u8) << 5 | (self.idac2 as u8) << 2 | (self.drdy_on_dout as u8) << 1;
        [r0, r1, r2, r3]
    }

    /// Check the combination against the datasheet's rules.
    ///
    /// The PGA can be bypassed only at gains 1, 2 and 4, and single-ended inputs and the monitors
    /// run with the PGA bypassed, so they too allow gains 1, 2 and 4 only.
    pub const fn validate(&self) -> Result<(), ErrorKind> {
        let low_gain = (self.gain as u8) <= (Gain::G4 as u8);
        if (self.pga_bypass || self.mux.single_ended_or_monitor()) && !low_gain {
            return Err(ErrorKind::InvalidConfig);
        }
        Ok(())
    }
}

/// ADS1220 driver error.
#[derive(Debug, Copy, Clone, PartialEq)]
pub enum Error<E> {
    /// The SPI transfer failed.
    Spi(E),
    /// The configuration is not supported by the part (see [`Config::validate`]) or by the RTD
    /// measurement (no external reference, no excitation, a non-positive reference resistor).
    InvalidConfig,
    /// The registers did not read back as written.
    ConfigMismatch {
        /// What was written.
        written: [u8; 4],
        /// What was read back.
        read: [u8; 4],
    },
    /// A full-scale code: the RTD or a lead is open.
    OpenCircuit {
        /// The code read.
        code: i32,
    },
    /// Zero, negative, or implausibly low resistance: the RTD is shorted.
    ShortCircuit {
        /// The code read.
        code: i32,
    },
    /// A plausible resistance outside the sensor's −200…850 °C.
    OutOfRange {
        /// The resistance measured (Ω).
        ohms: f32,
    },
}

impl<E: fmt::Debug> error::Error for Error<E> {
    fn kind(&self) -> ErrorKind {
        match self {
            Self::Spi(_) => ErrorKind::Bus,
            Self::InvalidConfig => ErrorKind::InvalidConfig,
            Self::ConfigMismatch { .. } => ErrorKind::WrongDevice,
            Self::OpenCircuit { .. } => ErrorKind::OpenCircuit,
            Self::ShortCircuit { .. } => ErrorKind::ShortCircuit,
            Self::OutOfRange { .. } => ErrorKind::OutOfRange,
        }
    }
}

impl<E: fmt::Debug> fmt::Display for Error<E> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Spi(e) => write!(f, "ADS1220: SPI error {e:?}"),
            Self::InvalidConfig => f.write_str("ADS1220: unsupported configuration"),
            Self::ConfigMismatch { written, read } => {
                write!(
                    f,
                    "ADS1220: wrote registers {written:02x?}, read back {read:02x?}"
                )
            }
            Self::OpenCircuit { code } => write!(f, "ADS1220: open circuit (code {code:#x})"),
            Self::ShortCircuit { code } => write!(f, "ADS1220: short circuit (code {code})"),
            Self::OutOfRange { ohms } => write!(f, "ADS1220: {ohms} Ω out of the RTD's range"),
        }
    }
}

impl<E: fmt::Debug> core::error::Error for Error<E> {}

/// Sign-extend a 24-bit two's-complement conversion result.
pub const fn code_from_bytes(bytes: [u8; 3]) -> i32 {
    // Place the 24 bits at the top of an i32, then shift arithmetically back down.
    let [hi, mid, lo] = bytes;
    i32::from_be_bytes([hi, mid, lo, 0]) >> 8
}

/// The ADS1220 on an SPI device (mode 1, its own chip select).
#[derive(Debug)]
pub struct Ads1220<SPI> {
    spi: SPI,
    config: Config,
}

impl<SPI: SpiDevice> Ads1220<SPI> {
    /// Wrap the device; no bus traffic until [`init`](Self::init).
    pub const fn new(spi: SPI, config: Config) -> Self {
        Self { spi, config }
    }

    /// The configuration the driver writes.
    pub const fn config(&self) -> &Config {
        &self.config
    }

    /// Give the SPI device back.
    pub fn release(self) -> SPI {
        self.spi
    }

    /// Reset the device, write the configuration, verify it by reading it back, and start
    /// conversions if the configuration is continuous.
    pub fn init<D: DelayNs>(&mut self, delay: &mut D) -> Result<(), Error<SPI::Error>> {
        self.config.validate().map_err(|_| Error::InvalidConfig)?;
        self.reset()?;
        delay.delay_us(RESET_WAIT_US);
        self.configure(self.config)
    }

    /// Send RESET (the caller waits [`RESET_WAIT_US`] before the next command).
    pub fn reset(&mut self) -> Result<(), Error<SPI::Error>> {
        self.command(cmd::RESET)
    }

    /// Send START/SYNC: start a single-shot conversion, or (re)start continuous conversions.
    pub fn start(&mut self) -> Result<(), Error<SPI::Error>> {
        self.command(cmd::START_SYNC)
    }

    /// Send POWERDOWN.
    pub fn power_down(&mut self) -> Result<(), Error<SPI::Error>> {
        self.command(cmd::POWERDOWN)
    }

    /// Write `config`, read it back and compare, then start conversions if it is continuous.
    ///
    /// Used by [`init`](Self::init), and to switch the input (e.g. between two RTDs on one ADC).
    pub fn configure(&mut self, config: Config) -> Result<(), Error<SPI::Error>> {
        config.validate().map_err(|_| Error::InvalidConfig)?;
        let written = config.registers();
        self.write_registers(written)?;
        let read = self.read_registers()?;
        if read != written {
            return Err(Error::ConfigMismatch { written, read });
        }
        self.config = config;
        if config.conversion == ConversionMode::Continuous {
            self.start()?;
        }
        Ok(())
    }

    /// Write all four configuration registers (WREG from register 0, four bytes).
    pub fn write_registers(&mut self, regs: [u8; 4]) -> Result<(), Error<SPI::Error>> {
        let [r0, r1, r2, r3] = regs;
        let frame = [cmd::WREG | 3, r0, r1, r2, r3];
        self.spi.write(&frame).map_err(Error::Spi)
    }

    /// Read all four configuration registers (RREG from register 0, four bytes).
    pub fn read_registers(&mut self) -> Result<[u8; 4], Error<SPI::Error>> {
        let mut regs = [0u8; 4];
        self.spi
            .transaction(&mut [
                Operation::Write(&[cmd::RREG | 3]),
                Operation::Read(&mut regs),
            ])
            .map_err(Error::Spi)?;
        Ok(regs)
    }

    /// Read the latest conversion result (RDATA), sign-extended.
    ///
    /// In continuous mode this is the most recent completed conversion; in single-shot mode, the
    /// one started by the last [`start`](Self::start) once it has completed (watch DRDY, or wait a
    /// conversion time).
    pub fn read_code(&mut self) -> Result<i32, Error<SPI::Error>> {
        let mut data = [0u8; 3];
        self.spi
            .transaction(&mut [Operation::Write(&[cmd::RDATA]), Operation::Read(&mut data)])
            .map_err(Error::Spi)?;
        Ok(code_from_bytes(data))
    }

    fn command(&mut self, command: u8) -> Result<(), Error<SPI::Error>> {
        self.spi.write(&[command]).map_err(Error::Spi)
    }
}

/// Resistance of a ratiometric measurement: `code / 2²³ · R_ref / gain`.
pub fn code_to_ohms(code: i32, r_ref_ohm: f32, gain: Gain) -> f32 {
    code as f32 * (r_ref_ohm / (FULL_SCALE * gain.factor() as f32))
}

/// A platinum RTD thermometer on an ADS1220: the [`Thermometer`] the firmware reads.
///
/// Each read is one RDATA frame (4 bytes) and returns the latest completed conversion: with the
/// continuous configuration of [`Config::rtd_4wire`] (20 SPS) a 200 Hz loop sees each conversion
/// about ten times, as a staircase. In single-shot mode, call `adc().start()` and wait a conversion
/// time (or DRDY) before reading.
#[derive(Debug)]
pub struct RtdThermometer<SPI> {
    adc: Ads1220<SPI>,
    rtd: Rtd,
    r_ref_ohm: f32,
}

impl<SPI: SpiDevice> RtdThermometer<SPI> {
    /// An `rtd` measured by `adc` against a reference resistor of `r_ref_ohm`.
    pub const fn new(adc: Ads1220<SPI>, rtd: Rtd, r_ref_ohm: f32) -> Self {
        Self {
            adc,
            rtd,
            r_ref_ohm,
        }
    }

    /// Check that the configuration is a ratiometric RTD measurement (external reference,
    /// excitation current on, temperature-sensor mode off, positive `R_ref`), then
    /// [`Ads1220::init`].
    pub fn init<D: DelayNs>(&mut self, delay: &mut D) -> Result<(), Error<SPI::Error>> {
        let c = self.adc.config();
        let ratiometric = c.vref.external()
            && c.idac != IdacCurrent::Off
            && (c.idac1 != IdacRoute::Disabled || c.idac2 != IdacRoute::Disabled)
            && !c.temperature_sensor;
        if !ratiometric || !crate::is_positive(self.r_ref_ohm) {
            return Err(Error::InvalidConfig);
        }
        self.adc.init(delay)
    }

    /// The ADC, e.g. to start a single-shot conversion.
    pub fn adc(&mut self) -> &mut Ads1220<SPI> {
        &mut self.adc
    }

    /// The RTD model.
    pub const fn rtd(&self) -> &Rtd {
        &self.rtd
    }

    /// Give the ADC back.
    pub fn release(self) -> Ads1220<SPI> {
        self.adc
    }

    /// Read the RTD's resistance (Ω), with the open- and short-circuit checks of the module docs.
    pub fn read_ohms(&mut self) -> Result<f32, Error<SPI::Error>> {
        let code = self.adc.read_code()?;
        if code >= CODE_MAX || code <= CODE_MIN {
            return Err(Error::OpenCircuit { code });
        }
        let ohms = code_to_ohms(code, self.r_ref_ohm, self.adc.config().gain);
        if code <= 0 || ohms < 0.1 * self.rtd.r0() {
            return Err(Error::ShortCircuit { code });
        }
        Ok(ohms)
    }
}

impl<SPI: SpiDevice> ErrorType for RtdThermometer<SPI> {
    type Error = Error<SPI::Error>;
}

impl<SPI: SpiDevice> Thermometer for RtdThermometer<SPI> {
    fn read_celsius(&mut self) -> Result<f32, Self::Error> {
        let ohms = self.read_ohms()?;
        self.rtd
            .temperature(ohms)
            .map_err(|_| Error::OutOfRange { ohms })
    }
}
