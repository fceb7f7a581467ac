//! Loading the models of a calibration image into the loop: each blob decoded in place into its
//! channel's slot, checked against the image's row for its channel and wired to the channel's
//! thermometers; a channel that fails runs with `NO_MODEL` and says why ([`LoadError`]).

use super::{App, FwModel, MAX_CHANNELS, MAX_COUNTERS, MAX_THERMOMETERS};
use crate::image::{Image, ImageError, TableError, check_board, check_table};
use tcomp_core::BlobError;

/// Why a channel has no model.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(target_os = "none", derive(defmt::Format))]
pub enum LoadError {
    /// The image, or this channel's entry in it (an image made for another unit included).
    Image(ImageError),
    /// The blob was rejected by `Model::decode`.
    Blob(BlobError),
    /// The model reads an input column this channel has no thermometer for.
    Unwired,
    /// The image's channel table cannot run on this board (see [`crate::image::check_table`]).
    Table(TableError),
    /// The image's table has no row for this channel.
    NotInTable,
    /// The blob's sensor kind, axis, unit or inputs are not its row's: an entry that points at
    /// another channel's (valid) blob.
    WrongChannel,
}

impl LoadError {
    /// A one-byte code for the boot report: 0 loaded, then one per reason.
    pub fn code(r: &Result<(), LoadError>) -> u8 {
        match r {
            Ok(()) => 0,
            Err(Self::Image(ImageError::Missing)) => 1,
            Err(Self::Image(ImageError::OtherUnit)) => 2,
            Err(Self::Image(_)) => 3,
            Err(Self::Blob(_)) => 4,
            Err(Self::Unwired) => 5,
            Err(Self::Table(TableError::OtherBoard)) => 9,
            Err(Self::Table(_)) => 6,
            Err(Self::NotInTable) => 7,
            Err(Self::WrongChannel) => 8,
        }
    }
}

impl<'a> App<'a> {
    /// Loads every channel's model from the image bytes; returns each channel's outcome. A channel
    /// that fails keeps running without a model. No unit check: see [`App::load_for_unit`].
    pub fn load(&mut self, image: &'a [u8]) -> [Result<(), LoadError>; MAX_CHANNELS] {
        self.load_checked(Image::parse(image), None, MAX_COUNTERS, MAX_THERMOMETERS)
    }

    /// [`App::load`] for the unit with serial `unit_serial` on a board with `counters` counter (or
    /// sample) channels and `thermometers` converters, built for the board description whose hash
    /// is `board_hash` (`wiring::NAME_HASH`; `None` for a table not made from a description): an
    /// image made for another unit or another board description, or whose channel table the
    /// board cannot run, loads no model at all (every channel says why).
    pub fn load_for_unit(
        &mut self,
        image: &'a [u8],
        unit_serial: u64,
        board_hash: Option<u64>,
        counters: usize,
        thermometers: usize,
    ) -> [Result<(), LoadError>; MAX_CHANNELS] {
        let image = Image::parse(image).and_then(|i| i.check_unit(unit_serial).map(|()| i));
        self.load_checked(image, board_hash, counters, thermometers)
    }

    fn load_checked(
        &mut self,
        image: Result<Image<'a>, ImageError>,
        board_hash: Option<u64>,
        counters: usize,
        thermometers: usize,
    ) -> [Result<(), LoadError>; MAX_CHANNELS] {
        let table = match &image {
            Ok(i) => check_board(i, board_hash)
                .and_then(|()| check_table(i, self.config, counters, thermometers)),
            Err(_) => Ok(()),
        };
        core::array::from_fn(|k| {
            let loaded = match table {
                Err(e) if k < self.config.len() => Err(LoadError::Table(e)),
                _ => self.load_channel(k, image),
            };
            if let (Err(_), Some(m)) = (&loaded, self.models.get_mut(k)) {
                *m = None;
            }
            loaded
        })
    }

    /// Decodes channel `k`'s blob straight into its slot of the loop (no `Model` moved around
    /// after decoding), then wires its inputs. On error the caller clears the slot.
    fn load_channel(
        &mut self,
        k: usize,
        image: Result<Image<'a>, ImageError>,
    ) -> Result<(), LoadError> {
        let cfg = self.config.get(k).ok_or(LoadError::Unwired)?;
        let blob = image
            .and_then(|i| i.blob(cfg.id))
            .map_err(LoadError::Image)?;
        let slot = self.models.get_mut(k).ok_or(LoadError::Unwired)?;
        decode_into(slot, blob).map_err(LoadError::Blob)?;
        let model = slot.as_ref().ok_or(LoadError::Unwired)?;
        // After the decode, so the row is not on the stack under the decoder's frame.
        if let Ok(i) = image {
            bound_to_row(&i, cfg.id, model)?;
        }
        let map = self.input_map.get_mut(k).ok_or(LoadError::Unwired)?;
        for (slot, name) in map.iter_mut().zip(model.program.inputs.iter()) {
            let (_, t) = cfg
                .thermometers
                .iter()
                .find(|(n, _)| n == name)
                .ok_or(LoadError::Unwired)?;
            if usize::from(*t) >= MAX_THERMOMETERS {
                return Err(LoadError::Unwired);
            }
            *slot = *t;
        }
        if let Some(n) = self.n_inputs.get_mut(k) {
            *n = model.program.inputs.len() as u8;
        }
        if let Some(c) = self.channels.get_mut(k) {
            c.reset();
            c.prepare(model);
        }
        Ok(())
    }
}

/// Whether `model` belongs on channel `id`'s row of a version-2 `image` (a version-1 image has
/// no rows: yes). Not inlined: the row is on the stack only for this check.
#[inline(never)]
fn bound_to_row(image: &Image<'_>, id: u16, model: &FwModel<'_>) -> Result<(), LoadError> {
    if image.version() < crate::image::VERSION_2 {
        return Ok(());
    }
    let row = image.channel_by_id(id).ok_or(LoadError::NotInTable)?;
    row.accepts(&model.meta, model.program.inputs.iter().map(|s| &**s))
        .map_err(|_| LoadError::WrongChannel)
}

/// Decodes `blob` into `slot` in place ([`Model::decode_into`]). Not inlined, so the decoder's
/// frame is on the stack once, while the caller's stays small.
#[inline(never)]
fn decode_into<'a>(slot: &mut Option<FwModel<'a>>, blob: &'a [u8]) -> Result<(), BlobError> {
    FwModel::decode_into(blob, slot)
}
