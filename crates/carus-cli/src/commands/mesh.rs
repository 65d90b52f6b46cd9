//! `carus mesh` (being built; replaced by its owner).

use super::Status;

#[derive(clap::Args)]
pub struct MeshArgs {}

pub fn run(_args: &MeshArgs) -> anyhow::Result<Status> {
    anyhow::bail!("`carus mesh` is not built yet")
}
