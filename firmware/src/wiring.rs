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

/// The facts about the link and the model region that three places state — the board
/// description, the firmware's slot layouts and memory maps, the READMEs and `tcomp`'s help —
/// checked against each other.
#[cfg(test)]
mod facts {
    #![allow(clippy::unwrap_used, clippy::expect_used)]

    extern crate std;
    use crate::slots::{QEMU_LAYOUT, STM32F4_LAYOUT};
    use std::path::Path;
    use std::string::String;
    use tcomp_board_description::Board;
    use tcomp_board_description::targets::{QEMU_MPS2_AN386, STM32F407};

    fn read(rel: &str) -> String {
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join(rel)).unwrap()
    }

    /// `ORIGIN = 0x…` of the `MODELS` line of a `memory.x`.
    fn models_origin(memory_x: &str) -> u32 {
        let line = memory_x
            .lines()
            .find(|l| l.trim_start().starts_with("MODELS"))
            .unwrap();
        let hex = line.split("ORIGIN = 0x").nth(1).unwrap();
        u32::from_str_radix(hex.split(',').next().unwrap().trim(), 16).unwrap()
    }

    #[test]
    fn the_generated_baud_is_the_descriptions() {
        let board = Board::load(
            &Path::new(env!("CARGO_MANIFEST_DIR")).join("descriptions/imu6-rlg-qma.toml"),
        )
        .unwrap();
        assert_eq!(board.baud, Some(super::IMU6_RLG_QMA_BAUD));
        assert_eq!(super::IMU6_RLG_QMA_BAUD, 921_600);
    }

    /// The board README's flash command takes the baud from the description, and the rate it
    /// states is the description's.
    #[test]
    fn the_board_readme_agrees_with_the_description() {
        let readme = read("boards/stm32f4/README.md");
        assert!(
            readme.contains("tcomp flash --board firmware/descriptions/imu6-rlg-qma.toml"),
            "the README's update command must name the description"
        );
        assert!(readme.contains("921,600 baud"));
        assert!(!readme.contains("115,200") && !readme.contains("115200"));
        let setup = read("boards/stm32f4/src/setup.rs");
        assert!(setup.contains("pub const BAUD: u32 = crate::LINK_BAUD;"));
    }

    /// `tcomp`'s table of targets (help texts) is the firmware's: memory maps and slot layouts.
    #[test]
    fn the_tools_targets_are_the_firmwares() {
        assert_eq!(
            models_origin(&read("boards/qemu/memory.x")),
            QEMU_MPS2_AN386.models_at
        );
        assert_eq!(models_origin(&read("../memory.x")), STM32F407.models_at);
        for (layout, target) in [(QEMU_LAYOUT, QEMU_MPS2_AN386), (STM32F4_LAYOUT, STM32F407)] {
            assert_eq!((layout.a, layout.size), (0, target.slot_bytes));
            assert_eq!(layout.b, target.slot_bytes);
        }
    }
}
