//! The boot report: which image, made for which unit and board, and what each channel runs, sent
//! at boot and every [`REPORT_PERIODS`] samples in the frames (`tcomp_core::frame::BootReport`),
//! and over defmt by the boards, so a user can see what the unit runs without resetting it.
//!
//! Built once at boot from the load results; the loop only re-stamps and re-sends it, never on
//! the sample's own path (the instruction budget covers `App::sample_snapshot` alone).

use crate::app::{ChannelConfig, LoadError, PERIOD_S};
use crate::image::{Image, ImageError};
use crate::trust::{self, Signer};
use tcomp_core::frame::{
    BOOT_REPORT_PERIOD_S, BootReport, ChannelState, DEVELOPMENT, WATCHDOG, image_state,
};
use tcomp_core::update::Reason;

/// Samples between two reports: [`BOOT_REPORT_PERIOD_S`] at the loop's rate.
pub const REPORT_PERIODS: u32 = (BOOT_REPORT_PERIOD_S as f32 / PERIOD_S) as u32;

/// The report of a boot that runs `image` (signed by `signer`) on the unit `unit_serial`, with
/// each channel of `config` loaded as `loaded` says; `watchdog` when the boot followed a watchdog
/// reset. A development build ([`trust::DEVELOPMENT`]) says so in its flags; when no image runs
/// because the one found was refused (`refused`: unsigned, signed by an unknown key, a bad
/// signature, another unit's), the image state says why. Not inlined: a boot path keeps its frame off the model
/// decoder's stack.
#[inline(never)]
pub fn report(
    image: &[u8],
    signer: Option<Signer>,
    refused: Option<Reason>,
    unit_serial: u64,
    config: &[ChannelConfig],
    loaded: &[Result<(), LoadError>],
    watchdog: bool,
) -> BootReport {
    let mut r = BootReport::default();
    r.unit_serial = unit_serial;
    r.flags =
        if watchdog { WATCHDOG } else { 0 } | if trust::DEVELOPMENT { DEVELOPMENT } else { 0 };
    r.signer = signer.map_or(0, |s: Signer| s.report_id());
    match Image::parse(image) {
        Ok(i) => {
            r.image_version = i.version();
            if let Some(h) = i.header() {
                r.image_serial = h.serial;
                r.board_hash = h.board_hash;
                r.image_crc = h.crc;
            }
            r.image_state = match i.check_unit(unit_serial) {
                Err(_) => image_state::OTHER_UNIT,
                Ok(()) if loaded.iter().any(|l| matches!(l, Err(LoadError::Table(_)))) => {
                    image_state::TABLE
                }
                Ok(()) => image_state::OK,
            };
        }
        Err(ImageError::NoImage) => {
            r.image_state = refused.map_or(image_state::NONE, trust::image_state);
        }
        Err(_) => r.image_state = image_state::INVALID,
    }
    let mut channels = [ChannelState::default(); tcomp_core::frame::MAX_CHANNELS];
    for ((c, cfg), l) in channels.iter_mut().zip(config).zip(loaded) {
        *c = ChannelState {
            id: cfg.id,
            state: LoadError::code(l),
        };
    }
    let n = config.len().min(loaded.len()).min(channels.len());
    r.set_channels(channels.get(..n).unwrap_or(&[]));
    r
}

/// Stamps a report before it is sent again: the next data frame's sequence number, and the last
/// update since boot as the update task published it ([`crate::update::last_update`]).
pub fn stamp(report: &mut BootReport, sequence: u32) {
    report.sequence = sequence;
    let (state, reason) = crate::update::last_update();
    report.update = state;
    report.update_reason = reason;
}
