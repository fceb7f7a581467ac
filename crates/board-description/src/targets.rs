//! The boards a calibration image can be written to, and where each keeps its models: the
//! `MODELS` region of its memory map (two slots, A then B; `tcomp_core::slots`).
//!
//! A board description (the IMU's wiring) is shared by the QEMU board of CI and the STM32F407
//! product board, so the address an image goes to is a property of the board layer, written here
//! once for the host: `tcomp image --help` and its closing line name these addresses, and the
//! firmware's tests check this table against both `memory.x` files and the firmware's slot
//! layouts (`tcomp_firmware::slots`), so the tool cannot name another address than the one the
//! firmware reads.

/// One board layer.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Target {
    /// What the board is called in help texts.
    pub name: &'static str,
    /// Where its `MODELS` region (slot A) starts in the address map.
    pub models_at: u32,
    /// Bytes per slot (a slot's header included).
    pub slot_bytes: u32,
}

impl Target {
    /// Where slot B starts.
    pub const fn slot_b_at(&self) -> u32 {
        self.models_at + self.slot_bytes
    }
}

/// The STM32F407 product board: flash sectors 10 and 11, 128 KiB each.
pub const STM32F407: Target = Target {
    name: "STM32F407 board",
    models_at: 0x080C_0000,
    slot_bytes: 128 * 1024,
};

/// QEMU's mps2-an386 (CI): the last 64 KiB of its flash-like SSRAM, two 32 KiB slots.
pub const QEMU_MPS2_AN386: Target = Target {
    name: "QEMU mps2-an386 board",
    models_at: 0x003F_0000,
    slot_bytes: 32 * 1024,
};

/// Every board, the product first.
pub const TARGETS: [Target; 2] = [STM32F407, QEMU_MPS2_AN386];

/// "0x080C0000 on the STM32F407 board, 0x003F0000 on the QEMU mps2-an386 board": where a probe writes an
/// image bare (slot A, run as generation 0), for help texts.
pub fn probe_addresses() -> String {
    TARGETS
        .iter()
        .map(|t| format!("{:#010X} on the {}", t.models_at, t.name).replace("0X", "0x"))
        .collect::<Vec<_>>()
        .join(", ")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_help_names_each_address() {
        let s = probe_addresses();
        assert_eq!(
            s,
            "0x080C0000 on the STM32F407 board, 0x003F0000 on the QEMU mps2-an386 board"
        );
    }
}
