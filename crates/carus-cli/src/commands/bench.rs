//! `carus bench` (being built; replaced by its owner).

use super::Status;

#[derive(clap::Subcommand)]
pub enum BenchCommand {
    /// Time the TLED solver.
    Tled,
}

pub fn run(_cmd: &BenchCommand) -> anyhow::Result<Status> {
    anyhow::bail!("`carus bench` is not built yet")
}
