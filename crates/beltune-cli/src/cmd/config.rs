//! `--config FILE.toml`: the flags of a subcommand from a file.
//!
//! The file is flat TOML whose keys are the subcommand's long flags without
//! the dashes (`payload = 5.0`, `travel-window = [0.0, 0.5]`, `quiet = true`;
//! `_` may stand for `-`). Its flags are put on the command line right after
//! the subcommand, before those the user typed: clap then parses one command
//! line, so every check and default is the usual one, and a flag typed on
//! the command line overrides the file (`args_override_self`). A key that is
//! not a flag of the subcommand, a table, or a value of the wrong type is an
//! error (exit status 2) naming the file and the key.

use crate::exit::{ExitStatus, Failure};
use clap::{ArgAction, Command};
use std::ffi::OsString;
use std::path::{Path, PathBuf};

/// The `--config` flag.
#[derive(clap::Args, Clone, Debug)]
pub struct ConfigArgs {
    /// Read flags from a TOML file (keys are the long flags without dashes,
    /// e.g. `payload = 5.0`, `travel-window = [0.0, 0.5]`); flags given on
    /// the command line override it.
    #[arg(long, value_name = "FILE.toml")]
    pub config: Option<PathBuf>,
}

fn bad(msg: String) -> anyhow::Error {
    anyhow::Error::new(Failure::new(ExitStatus::BadInput, msg))
}

/// The path given with `--config` (`--config F` or `--config=F`) in `args`,
/// if any.
fn config_path(args: &[OsString]) -> anyhow::Result<Option<PathBuf>> {
    let mut found = None;
    let mut it = args.iter();
    while let Some(a) = it.next() {
        let Some(s) = a.to_str() else { continue };
        if s == "--" {
            break;
        }
        if s == "--config" {
            let Some(p) = it.next() else {
                return Err(bad("--config needs a file".into()));
            };
            found = Some(PathBuf::from(p));
        } else if let Some(p) = s.strip_prefix("--config=") {
            found = Some(PathBuf::from(p));
        }
    }
    Ok(found)
}

/// The command line with the flags of a `--config` file inserted after the
/// subcommand. `argv` is the whole command line (program name first); `cli`
/// the whole command tree. Unchanged when the subcommand has no `--config`
/// flag or none is given.
pub fn expand(argv: Vec<OsString>, cli: &Command) -> anyhow::Result<Vec<OsString>> {
    let Some(sub_name) = argv.get(1).and_then(|s| s.to_str()) else {
        return Ok(argv);
    };
    let Some(sub) = cli.find_subcommand(sub_name) else {
        return Ok(argv);
    };
    if !sub.get_arguments().any(|a| a.get_id() == "config") {
        return Ok(argv);
    }
    let Some(path) = config_path(&argv[2..])? else {
        return Ok(argv);
    };
    let file_args = file_flags(&path, sub)?;
    check_values(&path, cli, sub_name, &file_args)?;
    let mut out = argv[..2].to_vec();
    out.extend(file_args.into_iter().map(OsString::from));
    out.extend(argv[2..].iter().cloned());
    Ok(out)
}

/// The flags a config file stands for (sorted by key: order does not matter,
/// a key appears once).
pub fn file_flags(path: &Path, sub: &Command) -> anyhow::Result<Vec<String>> {
    let file = path.display();
    // a regular file of at most MAX_TEXT_BYTES: `/dev/zero` or a FIFO is refused at once
    let text = beltune::io::read_to_string_capped(path, beltune::io::MAX_TEXT_BYTES)
        .map_err(|e| bad(format!("{file}: cannot read the config file: {e}")))?;
    let table: toml::Table = text.parse().map_err(|e: toml::de::Error| {
        let line = e
            .span()
            .map(|s| text[..s.start.min(text.len())].matches('\n').count() + 1);
        bad(format!(
            "{file}: {}{}",
            e.message(),
            line.map(|l| format!(" (line {l})")).unwrap_or_default()
        ))
    })?;
    let known = || {
        let mut names: Vec<&str> = sub
            .get_arguments()
            .filter_map(|a| a.get_long())
            .filter(|l| !matches!(*l, "config" | "help" | "version"))
            .collect();
        names.sort_unstable();
        names.join(", ")
    };
    let mut args = Vec::new();
    for (key, value) in &table {
        let long = key.replace('_', "-");
        let arg = sub
            .get_arguments()
            .find(|a| a.get_long() == Some(long.as_str()))
            .filter(|_| !matches!(long.as_str(), "config" | "help" | "version"))
            .ok_or_else(|| {
                bad(format!(
                    "{file}: unknown key `{key}` (keys are the flags of `beltune {}`: {})",
                    sub.get_name(),
                    known()
                ))
            })?;
        let flag = format!("--{long}");
        let is_switch = matches!(arg.get_action(), ArgAction::SetTrue);
        let wrong = |what: &str| bad(format!("{file}: `{key}` {what}"));
        match value {
            toml::Value::Boolean(b) if is_switch => {
                if *b {
                    args.push(flag);
                }
            }
            _ if is_switch => return Err(wrong("is a switch: true or false")),
            toml::Value::Boolean(_) => return Err(wrong("needs a value, not true/false")),
            toml::Value::String(s) => args.extend([flag, s.clone()]),
            toml::Value::Integer(i) => args.extend([flag, i.to_string()]),
            toml::Value::Float(f) => args.extend([flag, crate::term::tidy(*f)]),
            toml::Value::Array(items) => {
                let parts = items
                    .iter()
                    .map(|v| match v {
                        toml::Value::Integer(i) => Ok(i.to_string()),
                        toml::Value::Float(f) => Ok(crate::term::tidy(*f)),
                        toml::Value::String(s) => Ok(s.clone()),
                        _ => Err(wrong("lists numbers or strings only")),
                    })
                    .collect::<anyhow::Result<Vec<_>>>()?;
                args.extend([flag, parts.join(",")]);
            }
            toml::Value::Table(_) => {
                return Err(wrong("is a table; the file is flat (one key per flag)"))
            }
            toml::Value::Datetime(_) => return Err(wrong("is a date; expected a flag's value")),
        }
    }
    Ok(args)
}

/// Parse the file's flags alone, so that a bad value is reported as the
/// file's (a flag the command line must add, as `--input` with `--csv`, is
/// not missing yet).
fn check_values(path: &Path, cli: &Command, sub: &str, file_args: &[String]) -> anyhow::Result<()> {
    let mut line = vec!["beltune".to_string(), sub.to_string()];
    line.extend(file_args.iter().cloned());
    match cli.clone().try_get_matches_from(line) {
        Ok(_) => Ok(()),
        Err(e) if e.kind() == clap::error::ErrorKind::MissingRequiredArgument => Ok(()),
        Err(e) => {
            let text = e.render().to_string();
            let first = text
                .lines()
                .next()
                .unwrap_or("")
                .trim_start_matches("error: ")
                .to_string();
            Err(bad(format!("{}: {first}", path.display())))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cmd() -> Command {
        Command::new("beltune").subcommand(
            Command::new("commission")
                .args_override_self(true)
                .arg(clap::Arg::new("config").long("config"))
                .arg(clap::Arg::new("payload").long("payload"))
                .arg(clap::Arg::new("travel_window").long("travel-window"))
                .arg(
                    clap::Arg::new("quiet")
                        .long("quiet")
                        .action(ArgAction::SetTrue),
                ),
        )
    }

    fn file(name: &str, text: &str) -> PathBuf {
        let p =
            std::env::temp_dir().join(format!("beltune-config-{name}-{}.toml", std::process::id()));
        std::fs::write(&p, text).unwrap();
        p
    }

    fn argv(items: &[&str]) -> Vec<OsString> {
        items.iter().map(OsString::from).collect()
    }

    #[test]
    fn file_flags_go_before_the_typed_ones() {
        let p = file(
            "order",
            "payload = 5.0\ntravel_window = [0, 0.5]\nquiet = true\n",
        );
        let out = expand(
            argv(&[
                "beltune",
                "commission",
                "--config",
                p.to_str().unwrap(),
                "--payload",
                "7",
            ]),
            &cmd(),
        )
        .unwrap();
        let out: Vec<_> = out.iter().map(|s| s.to_str().unwrap()).collect();
        assert_eq!(
            &out[..8],
            [
                "beltune",
                "commission",
                "--payload",
                "5",
                "--quiet",
                "--travel-window",
                "0,0.5",
                "--config"
            ]
        );
        assert_eq!(&out[9..], ["--payload", "7"]);
        let m = cmd().get_matches_from(&out);
        let (_, sub) = m.subcommand().unwrap();
        assert_eq!(sub.get_one::<String>("payload").unwrap(), "7");
        std::fs::remove_file(p).unwrap();
    }

    #[test]
    fn unknown_keys_tables_and_wrong_types_are_bad_input() {
        for (text, needle) in [
            ("paylod = 5.0", "unknown key `paylod`"),
            ("config = \"x.toml\"", "unknown key `config`"),
            ("[payload]\nx = 5.0", "is a table"),
            ("quiet = 1", "is a switch"),
            ("payload = true", "needs a value"),
            ("payload = ", "line 1"),
        ] {
            let p = file("bad", text);
            let e = expand(
                argv(&["beltune", "commission", "--config", p.to_str().unwrap()]),
                &cmd(),
            )
            .unwrap_err();
            assert_eq!(crate::exit::status_of(&e), ExitStatus::BadInput);
            let msg = crate::exit::one_line(&e);
            assert!(
                msg.contains(needle) && msg.contains(p.to_str().unwrap()),
                "{msg}"
            );
            std::fs::remove_file(p).unwrap();
        }
        // A missing file too.
        let e = expand(
            argv(&["beltune", "commission", "--config", "/nonexistent/x.toml"]),
            &cmd(),
        )
        .unwrap_err();
        assert_eq!(crate::exit::status_of(&e), ExitStatus::BadInput);
    }

    #[test]
    fn without_config_the_command_line_is_unchanged() {
        let a = argv(&["beltune", "commission", "--payload", "3"]);
        assert_eq!(expand(a.clone(), &cmd()).unwrap(), a);
        let a = argv(&["beltune", "plant", "show"]);
        assert_eq!(expand(a.clone(), &cmd()).unwrap(), a);
    }
}
