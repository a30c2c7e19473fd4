//! `beltune design` (being written).

/// Arguments of `beltune design`.
#[derive(clap::Args)]
pub struct Args {}

/// Run the subcommand.
pub fn run(_args: Args) -> anyhow::Result<()> {
    anyhow::bail!("`beltune design` is not available yet")
}
