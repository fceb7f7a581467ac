//! ADS1220 driver against embedded-hal-mock SPI transaction queues.
#![allow(clippy::unwrap_used, clippy::panic, missing_docs)] // tests: a failed unwrap is a failed test

mod common;

use common::FailAt;
use embedded_hal_mock::eh1::delay::{CheckedDelay, NoopDelay, Transaction as DelayTx};
use embedded_hal_mock::eh1::spi::{Mock, Transaction as Tx};
use tcomp_hal::ads1220::{
    self, Ads1220, Config, Error, Gain, IdacCurrent, RtdThermometer, Vref, code_from_bytes,
};
use tcomp_hal::rtd::Rtd;
use tcomp_hal::{Error as _, ErrorKind, Thermometer};

/// The PT100 front end of the module docs: 1 mA, gain 4, R_ref = 1.62 kΩ.
const R_REF: f32 = 1620.0;
const R_REF_F64: f64 = 1620.0;
const GAIN: f64 = 4.0;

/// Registers of `Config::rtd_4wire(Ua1000, G4)`, by hand from the datasheet's bit fields:
/// reg0 = MUX 0000 (AIN0/AIN1) · GAIN 010 (4) · PGA_BYPASS 0          = 0000_0100 = 0x04
/// reg1 = DR 000 (20 SPS) · MODE 00 (normal) · CM 1 · TS 0 · BCS 0     = 0000_0100 = 0x04
/// reg2 = VREF 01 (REFP0/REFN0) · 50/60 01 (both) · PSW 0 · IDAC 110 (1 mA) = 0101_0110 = 0x56
/// reg3 = I1MUX 100 (AIN3) · I2MUX 000 (off) · DRDYM 0 · 0             = 1000_0000 = 0x80
const REGS: [u8; 4] = [0x04, 0x04, 0x56, 0x80];

fn config() -> Config {
    Config::rtd_4wire(IdacCurrent::Ua1000, Gain::G4)
}

fn frame(ops: Vec<Tx<u8>>) -> Vec<Tx<u8>> {
    let mut v = vec![Tx::transaction_start()];
    v.extend(ops);
    v.push(Tx::transaction_end());
    v
}

fn init_expectations(read_back: [u8; 4]) -> Vec<Tx<u8>> {
    let mut v = frame(vec![Tx::write_vec(vec![ads1220::cmd::RESET])]);
    // WREG starting at register 0, 4 bytes: 0x40 | 0 << 2 | (4 − 1) = 0x43.
    let mut wreg = vec![0x43];
    wreg.extend(REGS);
    v.extend(frame(vec![Tx::write_vec(wreg)]));
    // RREG starting at register 0, 4 bytes: 0x20 | 0 << 2 | 3 = 0x23.
    v.extend(frame(vec![
        Tx::write_vec(vec![0x23]),
        Tx::read_vec(read_back.to_vec()),
    ]));
    v
}

fn rdata(code: i32) -> Vec<Tx<u8>> {
    let b = code.to_be_bytes();
    frame(vec![
        Tx::write_vec(vec![0x10]),
        Tx::read_vec(vec![b[1], b[2], b[3]]),
    ])
}

/// The ADC code a perfect ADS1220 returns for a PT100 at `t_c`, from the CVD forward equation in
/// f64 (independent of the driver's f32 code).
fn code_for(t_c: f64) -> i32 {
    let (a, b, c) = (3.9083e-3, -5.775e-7, -4.183e-12);
    let ratio = if t_c >= 0.0 {
        1.0 + a * t_c + b * t_c * t_c
    } else {
        1.0 + a * t_c + b * t_c * t_c + c * (t_c - 100.0) * t_c.powi(3)
    };
    let ohms = 100.0 * ratio;
    (ohms * GAIN / R_REF_F64 * 8_388_608.0).round() as i32
}

fn code_for_ohms(ohms: f64) -> i32 {
    (ohms * GAIN / R_REF_F64 * 8_388_608.0).round() as i32
}

#[test]
fn register_encoding_matches_datasheet() {
    assert_eq!(config().registers(), REGS);
    assert_eq!(Config::POWER_ON.registers(), [0, 0, 0, 0]);
}

#[test]
fn init_resets_writes_verifies_and_starts() {
    let mut expectations = init_expectations(REGS);
    expectations.extend(frame(vec![Tx::write_vec(vec![ads1220::cmd::START_SYNC])]));
    let mut spi = Mock::new(&expectations);
    // The reset wait is part of the protocol: check it is asked for.
    let mut delay = CheckedDelay::new(&[DelayTx::delay_us(ads1220::RESET_WAIT_US)]);
    let mut adc = Ads1220::new(spi.clone(), config());
    adc.init(&mut delay).unwrap();
    spi.done();
    delay.done();
}

#[test]
fn read_back_mismatch_is_wrong_device() {
    // MISO stuck high: everything reads 0xFF.
    let mut spi = Mock::new(&init_expectations([0xFF; 4]));
    let mut adc = Ads1220::new(spi.clone(), config());
    let err = adc.init(&mut NoopDelay::new()).unwrap_err();
    assert_eq!(
        err,
        Error::ConfigMismatch {
            written: REGS,
            read: [0xFF; 4]
        }
    );
    assert_eq!(err.kind(), ErrorKind::WrongDevice);
    spi.done();
}

#[test]
fn invalid_config_is_rejected_before_any_bus_traffic() {
    let mut spi = Mock::new(&[]);
    let mut bad = config();
    bad.gain = Gain::G8;
    bad.pga_bypass = true; // the PGA can be bypassed at gains 1, 2, 4 only
    let mut adc = Ads1220::new(spi.clone(), bad);
    let err = adc.init(&mut NoopDelay::new()).unwrap_err();
    assert_eq!(err.kind(), ErrorKind::InvalidConfig);

    // A thermometer needs a ratiometric (external) reference and an excitation current.
    let mut internal = config();
    internal.vref = Vref::Internal;
    let mut t = RtdThermometer::new(Ads1220::new(spi.clone(), internal), Rtd::PT100, R_REF);
    assert_eq!(
        t.init(&mut NoopDelay::new()).unwrap_err().kind(),
        ErrorKind::InvalidConfig
    );
    let mut no_idac = config();
    no_idac.idac = IdacCurrent::Off;
    let mut t = RtdThermometer::new(Ads1220::new(spi.clone(), no_idac), Rtd::PT100, R_REF);
    assert_eq!(
        t.init(&mut NoopDelay::new()).unwrap_err().kind(),
        ErrorKind::InvalidConfig
    );
    let mut t = RtdThermometer::new(Ads1220::new(spi.clone(), config()), Rtd::PT100, -1.0);
    assert_eq!(
        t.init(&mut NoopDelay::new()).unwrap_err().kind(),
        ErrorKind::InvalidConfig
    );
    spi.done();
}

#[test]
fn thermometer_init_then_reads() {
    let mut expectations = init_expectations(REGS);
    expectations.extend(frame(vec![Tx::write_vec(vec![0x08])]));
    expectations.extend(rdata(code_for(25.0)));
    let mut spi = Mock::new(&expectations);
    let mut t = RtdThermometer::new(Ads1220::new(spi.clone(), config()), Rtd::PT100, R_REF);
    t.init(&mut NoopDelay::new()).unwrap();
    let c = t.read_celsius().unwrap();
    assert!((c - 25.0).abs() < 1e-3, "{c}");
    spi.done();
}

#[test]
fn rtd_reads_match_cvd_within_1_mk() {
    let temps = [
        -199.5, -150.0, -80.0, -40.0, -0.5, 0.0, 0.5, 25.0, 85.0, 200.0, 500.0, 849.5,
    ];
    let expectations: Vec<_> = temps.iter().flat_map(|&t| rdata(code_for(t))).collect();
    let mut spi = Mock::new(&expectations);
    let mut therm = RtdThermometer::new(Ads1220::new(spi.clone(), config()), Rtd::PT100, R_REF);
    for &t in &temps {
        let got = therm.read_celsius().unwrap();
        // One LSB is R_ref / (gain · 2²³) = 48 µΩ ≈ 0.13 mK here; rounding to a code costs half that.
        assert!(
            (f64::from(got) - t).abs() < 1e-3,
            "T = {t} °C, code {:#x}, read {got}",
            code_for(t)
        );
    }
    spi.done();
}

#[test]
fn generic_code_sees_the_trait_through_mut_ref() {
    fn read<T: Thermometer>(mut t: T) -> Result<f32, T::Error> {
        t.read_celsius()
    }
    let mut spi = Mock::new(&rdata(code_for(-40.0)));
    let mut therm = RtdThermometer::new(Ads1220::new(spi.clone(), config()), Rtd::PT100, R_REF);
    let c = read(&mut therm).unwrap();
    assert!((c + 40.0).abs() < 1e-3);
    spi.done();
}

#[test]
fn bus_error_maps_to_bus() {
    // Second RDATA fails on the bus; the first and third go through.
    let mut expectations = rdata(code_for(20.0));
    expectations.extend(rdata(code_for(21.0)));
    let mut mock = Mock::new(&expectations);
    let spi = FailAt::new(mock.clone(), 1);
    let mut therm = RtdThermometer::new(Ads1220::new(spi, config()), Rtd::PT100, R_REF);
    assert!((therm.read_celsius().unwrap() - 20.0).abs() < 1e-3);
    let err = therm.read_celsius().unwrap_err();
    assert_eq!(err, Error::Spi(embedded_hal::spi::ErrorKind::Other));
    assert_eq!(err.kind(), ErrorKind::Bus);
    assert!((therm.read_celsius().unwrap() - 21.0).abs() < 1e-3);
    mock.done();
}

#[test]
fn bus_error_during_init_maps_to_bus() {
    // RESET goes out, the WREG frame fails: nothing more is sent.
    let mut mock = Mock::new(&frame(vec![Tx::write_vec(vec![0x06])]));
    let mut adc = Ads1220::new(FailAt::new(mock.clone(), 1), config());
    assert_eq!(
        adc.init(&mut NoopDelay::new()).unwrap_err().kind(),
        ErrorKind::Bus
    );
    mock.done();
}

#[test]
fn full_scale_codes_are_open_circuit() {
    let mut expectations = rdata(0x7F_FFFF);
    expectations.extend(rdata(-0x80_0000));
    let mut spi = Mock::new(&expectations);
    let mut therm = RtdThermometer::new(Ads1220::new(spi.clone(), config()), Rtd::PT100, R_REF);
    let e = therm.read_celsius().unwrap_err();
    assert_eq!(e, Error::OpenCircuit { code: 0x7F_FFFF });
    assert_eq!(e.kind(), ErrorKind::OpenCircuit);
    let e = therm.read_celsius().unwrap_err();
    assert_eq!(e, Error::OpenCircuit { code: -0x80_0000 });
    assert_eq!(e.kind(), ErrorKind::OpenCircuit);
    spi.done();
}

#[test]
fn zero_negative_and_tiny_resistance_are_short_circuit() {
    // 5 Ω is below 10 % of R0: no PT100 reads that low (18.5 Ω at −200 °C).
    let codes = [0, -12, code_for_ohms(5.0)];
    let expectations: Vec<_> = codes.iter().flat_map(|&c| rdata(c)).collect();
    let mut spi = Mock::new(&expectations);
    let mut therm = RtdThermometer::new(Ads1220::new(spi.clone(), config()), Rtd::PT100, R_REF);
    for code in codes {
        let e = therm.read_celsius().unwrap_err();
        assert_eq!(e, Error::ShortCircuit { code });
        assert_eq!(e.kind(), ErrorKind::ShortCircuit);
    }
    spi.done();
}

#[test]
fn plausible_but_out_of_range_resistance_is_out_of_range() {
    // 400 Ω ≈ 880 °C (above 850 °C, R = 390.48 Ω); 15 Ω ≈ −208 °C (below 18.52 Ω).
    let mut expectations = rdata(code_for_ohms(400.0));
    expectations.extend(rdata(code_for_ohms(15.0)));
    let mut spi = Mock::new(&expectations);
    let mut therm = RtdThermometer::new(Ads1220::new(spi.clone(), config()), Rtd::PT100, R_REF);
    for expected in [400.0, 15.0] {
        match therm.read_celsius().unwrap_err() {
            e @ Error::OutOfRange { ohms } => {
                assert!((ohms - expected).abs() < 1e-3, "{ohms}");
                assert_eq!(e.kind(), ErrorKind::OutOfRange);
            }
            other => panic!("expected OutOfRange, got {other:?}"),
        }
    }
    spi.done();
}

#[test]
fn conversion_data_are_24_bit_twos_complement() {
    assert_eq!(code_from_bytes([0x00, 0x00, 0x01]), 1);
    assert_eq!(code_from_bytes([0x7F, 0xFF, 0xFF]), 8_388_607);
    assert_eq!(code_from_bytes([0x80, 0x00, 0x00]), -8_388_608);
    assert_eq!(code_from_bytes([0xFF, 0xFF, 0xFF]), -1);
    // Half scale at gain 4 and R_ref 1.62 kΩ: 2²² / 2²³ · 1620 / 4 = 202.5 Ω.
    assert_eq!(ads1220::code_to_ohms(1 << 22, 1620.0, Gain::G4), 202.5);
}

#[test]
fn single_shot_and_power_down_commands() {
    let mut expectations = frame(vec![Tx::write_vec(vec![0x08])]);
    expectations.extend(rdata(1234));
    expectations.extend(frame(vec![Tx::write_vec(vec![0x02])]));
    let mut spi = Mock::new(&expectations);
    let mut adc = Ads1220::new(spi.clone(), Config::POWER_ON);
    adc.start().unwrap();
    assert_eq!(adc.read_code().unwrap(), 1234);
    adc.power_down().unwrap();
    // `release` hands the device back; the mock's clones share one queue, checked once.
    let _spi_again = adc.release();
    spi.done();
}
