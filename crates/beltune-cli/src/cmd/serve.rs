//! `beltune serve` (being written).

/// Arguments of `beltune serve`.
#[derive(clap::Args)]
pub struct Args {}

/// Run the subcommand.
pub fn run(_args: Args) -> anyhow::Result<()> {
    anyhow::bail!("`beltune serve` is not available yet")
}
