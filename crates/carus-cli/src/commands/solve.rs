//! `carus solve` (being built; replaced by its owner).

use super::Status;

#[derive(clap::Args)]
pub struct SolveArgs {}

pub fn run(_args: &SolveArgs) -> anyhow::Result<Status> {
    anyhow::bail!("`carus solve` is not built yet")
}
