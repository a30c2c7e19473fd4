//! `beltune completions SHELL`: the shell completion script (clap_complete)
//! on stdout.

use clap_complete::Shell;

/// Arguments of `beltune completions`.
#[derive(clap::Args)]
pub struct Args {
    /// The shell: bash, zsh, fish, elvish or powershell.
    #[arg(value_enum)]
    pub shell: Shell,
}

/// Print the completion script for `cli` (the whole command tree).
pub fn run(args: Args, mut cli: clap::Command) -> anyhow::Result<()> {
    let name = cli.get_name().to_string();
    let mut out = Vec::new();
    clap_complete::generate(args.shell, &mut cli, name, &mut out);
    use std::io::Write;
    std::io::stdout().write_all(&out)?;
    Ok(())
}
