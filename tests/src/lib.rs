//! Workspace-level end-to-end tests live in `tests/tests/`; this library holds the host side of
//! the QEMU replay ([`replay`]), which `cargo xtask qemu` runs.

pub mod replay;
