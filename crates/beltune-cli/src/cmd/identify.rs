//! `beltune identify` (being written).

/// Arguments of `beltune identify`.
#[derive(clap::Args)]
pub struct Args {}

/// Run the subcommand.
pub fn run(_args: Args) -> anyhow::Result<()> {
    anyhow::bail!("`beltune identify` is not available yet")
}
