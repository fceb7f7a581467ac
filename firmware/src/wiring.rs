//! The channel tables of the board descriptions, generated at build time from
//! `firmware/descriptions/*.toml` by `build.rs` with the same reader `tcomp image --board` uses.
//!
//! Why generated, not read from the image at run time: a unit with no valid image (erased, corrupt,
//! made for another unit) must still know its wiring to output its raw values, flagged `NO_MODEL`;
//! and a table compiled into flash costs no RAM, where one built at boot from the image would need
//! room in the `App` for every channel's names and inputs. The image carries the same rows and the
//! description's hash, and the boot checks the image's table against the table compiled here
//! (`image::check_table`), so a calibration made for another wiring runs no model. One firmware
//! source serves every IMU design: the board binary is built for its description (see the board
//! crate's README), the QEMU replay picks among them by the vector's configuration.
//!
//! Each description `NAME.toml` gives `NAME` (upper case, `-` → `_`): `[ChannelConfig; N]`, and
//! `NAME_HASH`: its board hash.

use crate::app::ChannelConfig;
use tcomp_hal::scale::ChannelScale;

include!(concat!(env!("OUT_DIR"), "/wiring.rs"));

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::expect_used)]

    extern crate std;
    use super::*;
    use crate::app::{QMA_UG_PER_HZ, RLG_ARCSEC_PER_PULSE};
    use std::format;
    use std::vec::Vec;
    use tcomp_board_description::Board;
    use tcomp_core::image::{Image, Source};

    fn description(stem: &str) -> Board {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("descriptions")
            .join(format!("{stem}.toml"));
        Board::load(&path).unwrap()
    }

    /// Every generated table says what its TOML says, row by row (the reader is the one
    /// `tcomp image --board` uses), and its hash is the description's.
    #[test]
    fn generated_tables_are_the_descriptions() {
        let tables: [(&str, &[ChannelConfig], u64); 4] = [
            ("imu6-rlg-qma", &IMU6_RLG_QMA, IMU6_RLG_QMA_HASH),
            ("ifog3", &IFOG3, IFOG3_HASH),
            ("mems6", &MEMS6, MEMS6_HASH),
            ("ifog1", &IFOG1, IFOG1_HASH),
        ];
        for (stem, table, hash) in tables {
            let board = description(stem);
            assert_eq!(board.hash(), hash, "{stem}");
            let rows = board.channel_rows();
            assert_eq!(rows.len(), table.len(), "{stem}");
            for (row, cfg) in rows.iter().zip(table) {
                assert_eq!((row.id, row.name), (cfg.id, cfg.name), "{stem}");
                let (Source::Counter(n) | Source::Sample(n)) = row.source;
                assert_eq!(n, cfg.counter, "{stem} {}", row.name);
                assert_eq!(row.scale, cfg.scale.per_pulse(), "{stem} {}", row.name);
                let inputs: Vec<(&str, u8)> = row
                    .inputs()
                    .iter()
                    .map(|i| (i.name, i.thermometer))
                    .collect();
                assert_eq!(inputs, cfg.thermometers, "{stem} {}", row.name);
            }
        }
    }

    /// The replay vectors' pulse weights are the description's scales.
    #[test]
    fn imu6_scales_are_the_replay_constants() {
        for cfg in &IMU6_RLG_QMA[..3] {
            assert_eq!(cfg.scale.per_pulse(), RLG_ARCSEC_PER_PULSE);
        }
        for cfg in &IMU6_RLG_QMA[3..] {
            assert_eq!(cfg.scale.per_pulse(), QMA_UG_PER_HZ);
        }
    }

    /// The real tool's image of `mems6.toml` carries the hash compiled here.
    #[test]
    fn the_mems_image_names_the_compiled_description() {
        let image = Image::parse(include_bytes!("testdata/mems6.bin")).unwrap();
        assert_eq!(image.header().unwrap().board_hash, MEMS6_HASH);
    }
}
