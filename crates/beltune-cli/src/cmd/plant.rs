//! `beltune plant ...` (being written).

/// `beltune plant` subcommands.
#[derive(clap::Subcommand)]
pub enum PlantCommand {
    /// Print the parameters and derived quantities of a plant.
    Show(ShowArgs),
}

/// Arguments of `beltune plant show`.
#[derive(clap::Args)]
pub struct ShowArgs {}

/// Run the subcommand.
pub fn run(cmd: PlantCommand) -> anyhow::Result<()> {
    match cmd {
        PlantCommand::Show(_) => anyhow::bail!("`beltune plant show` is not available yet"),
    }
}
