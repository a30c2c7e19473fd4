//! `beltune friction` (being written).

/// Arguments of `beltune friction`.
#[derive(clap::Args)]
pub struct Args {}

/// Run the subcommand.
pub fn run(_args: Args) -> anyhow::Result<()> {
    anyhow::bail!("`beltune friction` is not available yet")
}
