//! Where a result goes and how it is written: a new timestamped folder per
//! run under a history folder (with `latest` pointing at the newest), or
//! exactly one folder. Every file of a result is written as one set: all
//! appear together or not at all, so a failed or killed run leaves the old
//! set or the new one, never a mix. The target is checked before any work
//! starts ([`OutputTarget::check`]).

use crate::{Error, Result};
use std::path::{Path, PathBuf};

/// Name of the symlink to the newest run in a history folder.
pub const LATEST_LINK: &str = "latest";

/// Where a commissioning run writes its result.
#[derive(Clone, Debug, PartialEq)]
pub enum OutputTarget {
    /// A new timestamped folder `root/YYYY-MM-DDTHHMMSSZ` per run, with the
    /// symlink `root/latest` pointing at the newest.
    History {
        /// The history folder (`commissioning` by default).
        root: PathBuf,
    },
    /// Exactly this folder: new or empty; one holding a result (a
    /// `commissioning.json`) only with `force`, and then the result's files
    /// are replaced as a set while everything else in the folder (the user's
    /// notes, the tuning page's `tuned-*` sets) is kept
    /// ([`crate::io::write_folder_atomic`]). A folder with other files and no
    /// result is refused.
    Exact {
        /// The folder.
        dir: PathBuf,
        /// Replace an existing result.
        force: bool,
    },
}

impl OutputTarget {
    /// Whether the result can go there, checked before any work starts (the
    /// axis does not move for a result that could not be written): `Exact`
    /// must be new or empty, or hold a result and `force` be given; `History`
    /// must be a folder (or creatable) whose `latest` is a symlink if present.
    /// The write checks again.
    pub fn check(&self) -> Result<()> {
        match self {
            OutputTarget::Exact { dir, force } => check_exact_target(dir, *force),
            OutputTarget::History { root } => {
                if std::fs::symlink_metadata(root).is_ok_and(|m| !m.is_dir()) {
                    return Err(Error::Parse {
                        path: root.display().to_string(),
                        message: "is not a folder; the runs are kept in a folder of this name"
                            .into(),
                    });
                }
                check_latest_link(root)
            }
        }
    }

    /// Write `files` (name, contents) as one set; returns their paths. All
    /// appear together or not at all ([`crate::io::write_folder_atomic`]).
    /// Nothing non-finite is written: an `inf` or `nan` in `controller.toml`
    /// is an error.
    pub fn write(&self, files: &[(String, Vec<u8>)]) -> Result<Vec<PathBuf>> {
        if let Some((name, text)) = files.iter().find(|(n, _)| n == super::CONTROLLER_FILE) {
            check_finite_text(name, &String::from_utf8_lossy(text))?;
        }
        let files: Vec<(&str, &[u8])> = files
            .iter()
            .map(|(n, t)| (n.as_str(), t.as_slice()))
            .collect();
        match self {
            OutputTarget::Exact { dir, force } => {
                check_exact_target(dir, *force)?;
                write_set(dir, &files)
            }
            OutputTarget::History { root } => {
                std::fs::create_dir_all(root).map_err(|source| Error::Io {
                    path: root.clone(),
                    source,
                })?;
                crate::io::clean_stale_temporaries(root);
                let stamp = humantime::format_rfc3339_seconds(std::time::SystemTime::now())
                    .to_string()
                    .replace(':', "");
                let mut name = stamp.clone();
                let mut k = 1;
                while std::fs::symlink_metadata(root.join(&name)).is_ok() {
                    k += 1;
                    name = format!("{stamp}-{k}");
                }
                let written = write_set(&root.join(&name), &files)?;
                point_latest(root, &name)?;
                Ok(written)
            }
        }
    }
}

fn write_set(dir: &Path, files: &[(&str, &[u8])]) -> Result<Vec<PathBuf>> {
    crate::io::write_folder_atomic(dir, files, &super::RESULT_FILE_NAMES)
}

/// `--out DIR` without `--force` must be new or empty; with it, a folder that
/// holds a result. A folder with other contents is refused either way.
fn check_exact_target(dir: &Path, force: bool) -> Result<()> {
    let err = |message: String| Error::Parse {
        path: dir.display().to_string(),
        message,
    };
    let entries: Vec<String> = match std::fs::read_dir(dir) {
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(()),
        Err(e) => {
            return Err(err(format!(
                "cannot use as output folder: {}",
                crate::io::describe(&e)
            )))
        }
        Ok(d) => d
            .flatten()
            .map(|e| e.file_name().to_string_lossy().into_owned())
            .collect(),
    };
    if entries.is_empty() {
        return Ok(());
    }
    if !entries.iter().any(|e| e == super::COMMISSIONING_FILE) {
        return Err(err(
            "the output folder is not empty and holds no commissioning result; \
             choose a new or empty folder"
                .into(),
        ));
    }
    if !force {
        return Err(err(
            "the output folder already holds a commissioning result; pass --force to \
             replace it, or leave out --out to keep every run under commissioning/"
                .into(),
        ));
    }
    // the user's entries stay; one under a result file's name would be replaced
    let users = crate::io::users_entries(dir, &super::RESULT_FILE_NAMES)?;
    if let Some(clash) = users.iter().find(|u| {
        u.to_str()
            .is_some_and(|u| super::RESULT_FILE_NAMES.contains(&u))
    }) {
        return Err(Error::Parse {
            path: dir.join(clash).display().to_string(),
            message: "is not beltune's (not in the result's manifest) but bears the name of a \
                      result file; move it away first"
                .into(),
        });
    }
    Ok(())
}

/// Point `root/latest` at `name`: a new symlink renamed over the old one.
fn point_latest(root: &Path, name: &str) -> Result<()> {
    check_latest_link(root)?;
    let link = root.join(LATEST_LINK);
    let tmp = root.join(crate::io::temporary_name(LATEST_LINK));
    let io = |source| Error::Io {
        path: link.clone(),
        source,
    };
    std::os::unix::fs::symlink(name, &tmp).map_err(io)?;
    std::fs::rename(&tmp, &link).map_err(|e| {
        let _ = std::fs::remove_file(&tmp);
        io(e)
    })?;
    crate::io::sync_dir(root);
    Ok(())
}

/// `root/latest` is absent or a symlink (anything else would be replaced).
fn check_latest_link(root: &Path) -> Result<()> {
    let link = root.join(LATEST_LINK);
    if std::fs::symlink_metadata(&link).is_ok_and(|m| !m.file_type().is_symlink()) {
        return Err(Error::Parse {
            path: link.display().to_string(),
            message: "is not a symlink; remove it so that it can point at the newest run".into(),
        });
    }
    Ok(())
}

/// Nothing non-finite reaches a file: `inf`/`nan` in a TOML text is an error.
fn check_finite_text(name: &str, text: &str) -> Result<()> {
    let bad = text.lines().find(|l| {
        let v = l.split_once('=').map_or("", |(_, v)| v);
        v.split(|c: char| !(c.is_ascii_alphanumeric() || c == '.'))
            .any(|w| matches!(w, "inf" | "nan" | "NaN"))
    });
    match bad {
        Some(line) => Err(Error::Report {
            reason: format!(
                "{name}: refusing to write a non-finite value: `{}`",
                line.trim()
            ),
        }),
        None => Ok(()),
    }
}

#[cfg(test)]
mod output_tests {
    use super::*;

    const JSON: &str = "{}";

    /// The three files of a result with `toml` as its controller.
    fn set(toml: &str, html: &str) -> Vec<(String, Vec<u8>)> {
        vec![
            ("commissioning.json".into(), JSON.into()),
            ("controller.toml".into(), toml.into()),
            ("report.html".into(), html.into()),
        ]
    }

    fn temp(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("beltune-out-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    #[test]
    fn history_keeps_every_run_and_latest_points_at_the_newest() {
        let root = temp("history").join("commissioning");
        let target = OutputTarget::History { root: root.clone() };
        let a = target.write(&set("a = 1\n", "<p>1</p>")).unwrap();
        let b = target.write(&set("a = 2\n", "<p>2</p>")).unwrap();
        assert_ne!(a[0].parent(), b[0].parent());
        assert_eq!(std::fs::read_to_string(&a[1]).unwrap(), "a = 1\n");
        let latest = root.join(LATEST_LINK);
        assert_eq!(
            std::fs::read_to_string(latest.join("controller.toml")).unwrap(),
            "a = 2\n"
        );
        // Two runs and the link, no temporaries.
        assert_eq!(std::fs::read_dir(&root).unwrap().count(), 3);
        std::fs::remove_dir_all(root.parent().unwrap()).unwrap();
    }

    #[test]
    fn exact_output_needs_force_over_a_result_and_refuses_foreign_folders() {
        let dir = temp("exact");
        let out = dir.join("out");
        let exact = |force| OutputTarget::Exact {
            dir: out.clone(),
            force,
        };
        exact(false).write(&set("a = 1\n", "")).unwrap();
        let e = exact(false).write(&set("a = 2\n", "")).unwrap_err();
        assert!(e.to_string().contains("--force"), "{e}");
        exact(true).write(&set("a = 2\n", "")).unwrap();
        assert_eq!(
            std::fs::read_to_string(out.join("controller.toml")).unwrap(),
            "a = 2\n"
        );
        let foreign = dir.join("foreign");
        std::fs::create_dir_all(&foreign).unwrap();
        std::fs::write(foreign.join("notes.txt"), "mine").unwrap();
        let target = OutputTarget::Exact {
            dir: foreign.clone(),
            force: true,
        };
        let e = target.write(&set("a = 1\n", "")).unwrap_err();
        assert!(e.to_string().contains("not empty"), "{e}");
        assert!(foreign.join("notes.txt").exists());
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn a_non_finite_controller_is_never_written() {
        let dir = temp("finite");
        let out = dir.join("out");
        for bad in [
            "k_p = inf\n",
            "k_p = -inf\n",
            "k_p = nan\n",
            "sos = [1.0, nan]\n",
        ] {
            let e = OutputTarget::Exact {
                dir: out.clone(),
                force: false,
            }
            .write(&set(bad, ""))
            .unwrap_err();
            assert!(e.to_string().contains("non-finite"), "{bad}: {e}");
        }
        assert!(!out.exists());
        OutputTarget::Exact {
            dir: out.clone(),
            force: false,
        }
        .write(&set("kind = \"notch\"\nk = 1e300\n", ""))
        .unwrap();
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
