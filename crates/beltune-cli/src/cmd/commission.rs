//! `beltune commission` (being written).

/// Arguments of `beltune commission`.
#[derive(clap::Args)]
pub struct Args {}

/// Run the subcommand.
pub fn run(_args: Args) -> anyhow::Result<()> {
    anyhow::bail!("`beltune commission` is not available yet")
}
