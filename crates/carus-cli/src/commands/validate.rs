//! `carus validate` (being built; replaced by its owner).

use super::Status;

#[derive(clap::Args)]
pub struct ValidateArgs {}

pub fn run(_args: &ValidateArgs) -> anyhow::Result<Status> {
    anyhow::bail!("`carus validate` is not built yet")
}
