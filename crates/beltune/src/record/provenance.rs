//! Where a result comes from: the beltune version, the time it was made, the
//! command line and the seed. Every output file carries one
//! (`commissioning.json`, `controller.toml`, the report), so that a file found on
//! a machine months later can be traced to the run that wrote it.

use serde::{Deserialize, Serialize};

/// The provenance of one result. A file's `[provenance]` holds exactly these
/// keys (an unknown key is an error, not ignored).
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Provenance {
    /// The beltune version that wrote the result (the crate version).
    pub beltune_version: String,
    /// When the result was made: UTC, RFC 3339 to the second
    /// (`2026-12-01T17:15:02Z`).
    pub created_utc: String,
    /// The command line, program name first (empty for library use).
    pub command_line: Vec<String>,
    /// The seed of the random parts (simulated noise, Monte Carlo), if any.
    pub seed: Option<u64>,
}

impl Provenance {
    /// Provenance stamped now, with this crate's version.
    pub fn now(command_line: Vec<String>, seed: Option<u64>) -> Self {
        Provenance {
            beltune_version: env!("CARGO_PKG_VERSION").to_string(),
            created_utc: humantime::format_rfc3339_seconds(std::time::SystemTime::now())
                .to_string(),
            command_line,
            seed,
        }
    }

    /// Provenance of this process: its command line, now. An argument that
    /// is not UTF-8 (a path on Linux may be any bytes) is kept with its
    /// invalid bytes replaced by U+FFFD.
    pub fn of_this_process(seed: Option<u64>) -> Self {
        Provenance::now(
            std::env::args_os()
                .map(|a| a.to_string_lossy().into_owned())
                .collect(),
            seed,
        )
    }

    /// The command line as one shell-like string, arguments with spaces or
    /// quotes single-quoted.
    pub fn command_line_text(&self) -> String {
        self.command_line
            .iter()
            .map(|a| {
                if !a.is_empty()
                    && a.chars()
                        .all(|c| c.is_ascii_alphanumeric() || "-_./=,:+@%".contains(c))
                {
                    a.clone()
                } else {
                    format!("'{}'", a.replace('\'', r"'\''"))
                }
            })
            .collect::<Vec<_>>()
            .join(" ")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stamp_is_rfc3339_utc_to_the_second() {
        let p = Provenance::now(vec!["beltune".into(), "commission".into()], Some(7));
        let t = &p.created_utc;
        assert_eq!(t.len(), 20, "{t}");
        assert!(t.ends_with('Z') && t.as_bytes()[10] == b'T', "{t}");
        assert!(humantime::parse_rfc3339(t).is_ok(), "{t}");
        assert_eq!(p.beltune_version, env!("CARGO_PKG_VERSION"));
    }

    #[test]
    fn command_line_quotes_what_a_shell_would_split() {
        let p = Provenance::now(
            vec![
                "beltune".into(),
                "--out".into(),
                "my dir".into(),
                "it's".into(),
            ],
            None,
        );
        assert_eq!(p.command_line_text(), r"beltune --out 'my dir' 'it'\''s'");
    }
}
