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

/// The values completions offer for free-text arguments, by argument id: the
/// built-in plants (a plant file completes as a path in shells that fall back
/// to files), the prefilters and the one-knob presets. Only the completion
/// script sees them; parsing keeps its own checks and messages.
pub const OFFERED_VALUES: [(&str, &[&str]); 3] = [
    ("plant", beltune::model::BUILTIN_NAMES),
    ("prefilter", &["butterworth", "notch", "none"]),
    ("dynamics", &["conservative", "standard", "dynamic"]),
];

/// `cmd` and its subcommands with [`OFFERED_VALUES`] as possible values.
pub fn with_offered_values(mut cmd: clap::Command) -> clap::Command {
    for (id, values) in OFFERED_VALUES {
        if cmd.get_arguments().any(|a| a.get_id() == id) {
            cmd = cmd.mut_arg(id, |a| {
                a.value_parser(clap::builder::PossibleValuesParser::new(
                    values.iter().copied(),
                ))
            });
        }
    }
    let names: Vec<String> = cmd
        .get_subcommands()
        .map(|s| s.get_name().to_string())
        .collect();
    for n in names {
        cmd = cmd.mut_subcommand(n, with_offered_values);
    }
    cmd
}

/// Print the completion script for `cli` (the whole command tree).
pub fn run(args: Args, cli: clap::Command) -> anyhow::Result<()> {
    let mut cli = with_offered_values(cli);
    let name = cli.get_name().to_string();
    let mut out = Vec::new();
    clap_complete::generate(args.shell, &mut cli, name, &mut out);
    use std::io::Write;
    std::io::stdout().write_all(&out)?;
    Ok(())
}
