//! `beltune trajectory` (being written).

/// Arguments of `beltune trajectory`.
#[derive(clap::Args)]
pub struct Args {}

/// Run the subcommand.
pub fn run(_args: Args) -> anyhow::Result<()> {
    anyhow::bail!("`beltune trajectory` is not available yet")
}
