//! The model image in flash: the format and its reader are `tcomp-core`'s ([`tcomp_core::image`]),
//! the one definition `tcomp image` writes with; this module only says where the firmware finds it.
//!
//! The image is written on the host by `tcomp image --model CH=FILE.tcm …` and placed at the start
//! of the `MODELS` flash region (`0x003F_0000`, 64 KiB, see `memory.x`) by a flashing tool, without
//! rebuilding the firmware. [`Image::parse`] is given the whole region: the table says where each
//! blob lies, and the bytes past the image (erased flash) are never read. A corrupt blob disables
//! its channel only (which then runs with `NO_MODEL`, raw passed through); erased flash (`0xFF…`)
//! or an empty region (zeros) reads as [`ImageError::NoImage`].

pub use tcomp_core::image::{
    ENTRY_LEN, HEADER_LEN, Image, ImageError, MAGIC, MAX_ENTRIES, VERSION,
};
