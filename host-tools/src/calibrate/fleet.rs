//! Several units (filled in below).
use super::spec::{CalSpec, ChannelPlan};
use crate::cmd::calibrate::Args;
use std::path::Path;
use tcomp_board_description::Board;

/// Runs every unit of `dir`.
pub fn run(
    _args: &Args,
    _spec: &CalSpec,
    _plans: &[ChannelPlan],
    _board: Option<&Board>,
    _dir: &Path,
) -> anyhow::Result<()> {
    anyhow::bail!("--units is not implemented yet")
}
