//! `beltune man`: the manual page (roff, clap_mangen), with the exit statuses
//! and examples as sections of their own; `--out DIR` writes one page per
//! subcommand (`beltune.1`, `beltune-commission.1`, ...).

use super::util::write_atomic;
use crate::help::{COMMISSION_EXAMPLES, EXIT_STATUSES, ROOT_EXAMPLES};
use std::path::PathBuf;

/// Arguments of `beltune man`.
#[derive(clap::Args)]
pub struct Args {
    /// Write a page for `beltune` and for every subcommand into this folder
    /// instead of printing the page of `beltune` on stdout.
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
}

/// Text for roff: backslashes escaped, a leading `.` or `'` protected, dashes literal.
fn roff_text(s: &str) -> String {
    let s = s.replace('\\', "\\e").replace('-', "\\-");
    if s.starts_with('.') || s.starts_with('\'') {
        format!("\\&{s}")
    } else {
        s
    }
}

/// The EXIT STATUS and EXAMPLES sections.
fn extra_sections(examples: &[(&str, &str)]) -> String {
    let mut out = String::from(".SH \"EXIT STATUS\"\n");
    for (code, what) in EXIT_STATUSES {
        out.push_str(&format!(".TP\n\\fB{code}\\fR\n{}\n", roff_text(what)));
    }
    if !examples.is_empty() {
        out.push_str(".SH EXAMPLES\n");
    }
    for (cmd, what) in examples {
        out.push_str(&format!(".TP\n\\fB{}\\fR\n", roff_text(cmd)));
        if !what.is_empty() {
            out.push_str(&format!("{}\n", roff_text(what)));
        }
    }
    out
}

/// The page of `cmd` (root or subcommand of a built command tree).
pub fn page(cmd: &clap::Command, examples: &[(&str, &str)]) -> anyhow::Result<Vec<u8>> {
    // The after-help text (examples, exit statuses) is not rendered as
    // clap_mangen's EXTRA section but as proper sections of its own below.
    let man = clap_mangen::Man::new(cmd.clone());
    let mut out = Vec::new();
    man.render_title(&mut out)?;
    man.render_name_section(&mut out)?;
    man.render_synopsis_section(&mut out)?;
    man.render_description_section(&mut out)?;
    if cmd.get_arguments().any(|a| !a.is_hide_set()) {
        man.render_options_section(&mut out)?;
    }
    if cmd.get_subcommands().any(|s| !s.is_hide_set()) {
        man.render_subcommands_section(&mut out)?;
    }
    out.extend_from_slice(extra_sections(examples).as_bytes());
    if cmd.get_version().is_some() {
        man.render_version_section(&mut out)?;
    }
    Ok(out)
}

/// Print the page of `cli`, or write all pages with `--out`.
pub fn run(args: Args, cli: clap::Command) -> anyhow::Result<()> {
    let mut cli = cli.disable_help_subcommand(true);
    cli.build();
    match args.out {
        None => {
            use std::io::Write;
            std::io::stdout().write_all(&page(&cli, &ROOT_EXAMPLES)?)?;
        }
        Some(dir) => {
            std::fs::create_dir_all(&dir)
                .map_err(|e| anyhow::anyhow!("creating {}: {e}", dir.display()))?;
            let mut pages = vec![(cli.clone(), &ROOT_EXAMPLES[..])];
            let mut stack: Vec<clap::Command> = cli.get_subcommands().cloned().collect();
            while let Some(sub) = stack.pop() {
                stack.extend(sub.get_subcommands().cloned());
                let ex: &[(&str, &str)] = if sub.get_name() == "commission" {
                    &COMMISSION_EXAMPLES
                } else {
                    &[]
                };
                pages.push((sub, ex));
            }
            for (cmd, ex) in pages {
                if cmd.is_hide_set() {
                    continue;
                }
                let name = cmd.get_display_name().unwrap_or(cmd.get_name()).to_string();
                let path = dir.join(format!("{name}.1"));
                write_atomic(&path, &page(&cmd, ex)?)?;
                println!("wrote {}", path.display());
            }
        }
    }
    Ok(())
}
