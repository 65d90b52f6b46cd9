//! `carus measure` (being built; replaced by its owner).

use super::Status;

#[derive(clap::Args)]
pub struct MeasureArgs {}

pub fn run(_args: &MeasureArgs) -> anyhow::Result<Status> {
    anyhow::bail!("`carus measure` is not built yet")
}
