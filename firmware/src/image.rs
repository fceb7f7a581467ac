//! The model image in flash: the format and its reader are `tcomp-core`'s ([`tcomp_core::image`]),
//! the one definition `tcomp image` writes with; this module only says where the firmware finds it.
//!
//! The image is written on the host by `tcomp image --board FILE --serial N --model CH=FILE.tcm …`
//! and placed at the start
//! of the `MODELS` flash region (`0x003F_0000`, 64 KiB, see `memory.x`) by a flashing tool, without
//! rebuilding the firmware. [`Image::parse`] is given the whole region: the table says where each
//! blob lies, and the bytes past the image (erased flash) are never read. A corrupt blob disables
//! its channel only (which then runs with `NO_MODEL`, raw passed through); erased flash (`0xFF…`)
//! or an empty region (zeros) reads as [`ImageError::NoImage`].

//!
//! A version-2 image carries the board's channel table and the unit serial it was made for. The
//! firmware checks, before any model runs: the serial ([`check_unit`]); the board hash against
//! the one of the description its table was generated from ([`check_board`]); the table against
//! its own capacities and wiring ([`check_table`]); and each blob against its row (`App::load`).
//! Any failure is a status the boot report names, never a panic.

pub use tcomp_core::image::{
    ChannelRow, ENTRY_LEN, HEADER_LEN, Image, ImageError, MAGIC, MAX_ENTRIES, Source, VERSION,
    VERSION_2,
};

use crate::app::{ChannelConfig, MAX_CHANNELS, MAX_COUNTERS, MAX_THERMOMETERS};

/// Whether `image` may run on the unit whose serial is `unit_serial` (see
/// [`Image::check_unit`]); the boot path calls it, and an update can call it before it commits a
/// new image. A version-1 image names no unit and passes.
pub fn check_unit(image: &[u8], unit_serial: u64) -> Result<(), ImageError> {
    Image::parse(image)?.check_unit(unit_serial)
}

/// Why an image's channel table cannot run on this firmware and board.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(target_os = "none", derive(defmt::Format))]
pub enum TableError {
    /// More channels than [`MAX_CHANNELS`], or thermometers than [`MAX_THERMOMETERS`].
    Capacity,
    /// Channel `id`'s row names a counter or sample source the board does not have.
    Source(u16),
    /// Channel `id`'s row reads a thermometer on a converter the board does not have.
    Thermometer(u16),
    /// Channel `id`'s row is wired differently from the board's channel configuration (another
    /// counter, or an input on another thermometer), or the board has no channel `id`.
    Wiring(u16),
    /// The image was made for another board description than the one this firmware was built
    /// for (its board hash differs): another thermometer type or constant, sensor or unit on some
    /// row, even where the wiring would match.
    OtherBoard,
}

/// Checks a version-2 image's board hash against `expected`, the hash of the description the
/// firmware's channel table was generated from (`wiring::NAME_HASH`); `None` (a table not made
/// from a description) and a version-1 image pass.
pub fn check_board(image: &Image<'_>, expected: Option<u64>) -> Result<(), TableError> {
    match (image.header(), expected) {
        (Some(h), Some(e)) if h.board_hash != e => Err(TableError::OtherBoard),
        _ => Ok(()),
    }
}

/// Checks a version-2 image's channel table against the firmware's capacities, the board's
/// hardware (`counters` counter or sample channels, `thermometers` converters) and the board's
/// channel configuration `config` (each row's source and each input's thermometer must be the
/// configuration's: the image was made for this wiring). A version-1 image has no table: `Ok`.
/// Not inlined: its rows stay off the model decoder's stack.
#[inline(never)]
pub fn check_table(
    image: &Image<'_>,
    config: &[ChannelConfig],
    counters: usize,
    thermometers: usize,
) -> Result<(), TableError> {
    if image.n_channels() > MAX_CHANNELS || image.n_thermometers() > MAX_THERMOMETERS {
        return Err(TableError::Capacity);
    }
    for row in (0..image.n_channels()).filter_map(|i| image.channel(i)) {
        let id = row.id;
        let index = match row.source {
            Source::Counter(n) | Source::Sample(n) => usize::from(n),
        };
        if index >= counters.min(MAX_COUNTERS) {
            return Err(TableError::Source(id));
        }
        let cfg = config
            .iter()
            .find(|c| c.id == id)
            .ok_or(TableError::Wiring(id))?;
        if usize::from(cfg.counter) != index {
            return Err(TableError::Wiring(id));
        }
        for input in row.inputs() {
            let t = image
                .thermometer(usize::from(input.thermometer))
                .ok_or(TableError::Thermometer(id))?;
            if usize::from(t.adc) >= thermometers {
                return Err(TableError::Thermometer(id));
            }
            let wired = cfg
                .thermometers
                .iter()
                .any(|&(name, index)| name == input.name && index == input.thermometer);
            if !wired {
                return Err(TableError::Wiring(id));
            }
        }
    }
    Ok(())
}
