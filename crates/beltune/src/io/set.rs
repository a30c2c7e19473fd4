//! A set of files replaced as a whole inside a folder that may hold other
//! things too.
//!
//! beltune writes a result (or a diagnostic) as one set: all files appear
//! together or not at all. The folder it goes into may also hold what a user
//! put there (notes, the tuning page's saved `tuned-*` sets, a `.git`): those
//! are never touched. What beltune wrote is listed in the set's manifest
//! ([`MANIFEST_FILE`]); a folder written before manifests existed is read with
//! the caller's list of the names it writes.
//!
//! The replacement, under an exclusive lock on the parent folder (concurrent
//! writers of one folder take turns):
//!
//! 1. the new set and its manifest are written into a temporary sibling
//!    folder and flushed;
//! 2. the entries of the old folder that are not beltune's are listed in a
//!    journal ([`CARRIED_FILE`]) inside the temporary and moved into it;
//! 3. the temporary is exchanged with the old folder (Linux
//!    `renameat2(RENAME_EXCHANGE)`): anyone looking sees the old set or the new
//!    one, each beside the user's entries;
//! 4. the journal is removed and the old set deleted.
//!
//! A process killed between 2 and 3 leaves the user's entries in the
//! temporary with the journal beside them; the next writer in that folder
//! ([`super::clean_stale_temporaries`]) moves them back before it removes the
//! temporary, and keeps the temporary if it cannot.

use super::{parent_of, sync_dir, temporary_name};
use crate::{Error, Result};
use std::collections::BTreeSet;
use std::ffi::{OsStr, OsString};
use std::io::Write;
use std::os::unix::ffi::{OsStrExt, OsStringExt};
use std::path::{Path, PathBuf};

/// The names of the files of the set, one per line, after a header line.
pub const MANIFEST_FILE: &str = ".beltune-manifest";
/// The user's entries carried aside during a replacement (NUL-separated
/// names); exists only while a replacement runs.
pub(super) const CARRIED_FILE: &str = ".beltune-carried";
const MANIFEST_HEADER: &str =
    "# files written by beltune as one set; the others in this folder are kept";

/// Replace the set of files in `dir` by `files` (name, contents), all
/// together or none; returns the files' paths. Everything in `dir` that is
/// not beltune's (not in its manifest or, without one, not in
/// `legacy_names`) is kept. An entry of the user's that bears the name of a
/// new file is an error, and nothing is changed. A symlinked `dir` has its
/// target replaced.
///
/// The caller decides whether replacing an existing set is allowed.
pub fn write_folder_atomic(
    dir: &Path,
    files: &[(&str, &[u8])],
    legacy_names: &[&str],
) -> Result<Vec<PathBuf>> {
    let io = |p: &Path| {
        let p = p.to_path_buf();
        move |source| Error::Io { path: p, source }
    };
    for (name, _) in files {
        if name.is_empty()
            || name.contains(['/', '\n', '\0'])
            || [MANIFEST_FILE, CARRIED_FILE, ".", ".."].contains(name)
        {
            return Err(Error::Parse {
                path: dir.join(name).display().to_string(),
                message: "not a file name of a result set".into(),
            });
        }
    }
    let dir = match std::fs::symlink_metadata(dir) {
        Ok(m) if m.file_type().is_symlink() => std::fs::canonicalize(dir).map_err(io(dir))?,
        _ => dir.to_path_buf(),
    };
    let parent = parent_of(&dir);
    std::fs::create_dir_all(&parent).map_err(io(&parent))?;
    let name = dir
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .ok_or_else(|| Error::Parse {
            path: dir.display().to_string(),
            message: "not a folder name".into(),
        })?;
    // one writer at a time per parent folder: held until the end of this call
    let lock = std::fs::File::open(&parent).map_err(io(&parent))?;
    lock_exclusive(&lock).map_err(io(&parent))?;
    super::clean_stale_temporaries(&parent);

    let new_names: BTreeSet<&str> = files.iter().map(|(n, _)| *n).collect();
    let kept = match std::fs::read_dir(&dir) {
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Vec::new(),
        Err(e) => return Err(io(&dir)(e)),
        Ok(_) => users_entries(&dir, legacy_names)?,
    };
    if let Some(clash) = kept.iter().find(|k| {
        k.to_str()
            .is_some_and(|k| new_names.contains(k) || k == MANIFEST_FILE)
    }) {
        return Err(Error::Parse {
            path: dir.join(clash).display().to_string(),
            message: "is not beltune's (not in the result's manifest) and the new result \
                      has a file of this name; move it away first"
                .into(),
        });
    }

    let tmp = parent.join(temporary_name(&name));
    let result = (|| -> Result<()> {
        std::fs::create_dir(&tmp).map_err(io(&tmp))?;
        for (file, bytes) in files {
            write_synced(&tmp.join(file), bytes)?;
        }
        write_synced(&tmp.join(MANIFEST_FILE), manifest_text(files).as_bytes())?;
        if !kept.is_empty() {
            let mut journal = Vec::new();
            for k in &kept {
                journal.extend_from_slice(k.as_bytes());
                journal.push(0);
            }
            write_synced(&tmp.join(CARRIED_FILE), &journal)?;
        }
        sync_dir(&tmp);
        if std::fs::symlink_metadata(&dir).is_err() {
            // new: a plain rename puts the whole set in place
            return std::fs::rename(&tmp, &dir).map_err(io(&dir));
        }
        // a journal left in the folder by a replacement killed after its
        // exchange lists entries that are all back: stale
        let _ = std::fs::remove_file(dir.join(CARRIED_FILE));
        if let Err(e) = carry(&dir, &tmp, &kept) {
            let _ = carry(&tmp, &dir, &kept);
            return Err(e);
        }
        if let Err(e) = exchange(&tmp, &dir) {
            let _ = carry(&tmp, &dir, &kept);
            return Err(io(&dir)(e));
        }
        // `dir` holds the new set and the user's entries; `tmp` the old set
        let _ = std::fs::remove_file(dir.join(CARRIED_FILE));
        Ok(())
    })();
    // the temporary now holds the old set, or the new one after a failure
    // with the user's entries carried back; it stays where it cannot be
    // emptied of theirs
    if carried_back(&tmp, &dir) {
        let _ = std::fs::remove_dir_all(&tmp);
    }
    result?;
    sync_dir(&parent);
    drop(lock);
    Ok(files.iter().map(|(f, _)| dir.join(f)).collect())
}

/// Everything in `dir` that beltune did not write: not in its manifest (or,
/// without a readable one, not in `legacy_names`), and every entry that is
/// not a regular file; sorted.
pub fn users_entries(dir: &Path, legacy_names: &[&str]) -> Result<Vec<OsString>> {
    let owned: BTreeSet<OsString> = match read_manifest(dir) {
        Some(names) => names,
        None => legacy_names.iter().map(OsString::from).collect(),
    };
    let entries = std::fs::read_dir(dir).map_err(|source| Error::Io {
        path: dir.to_path_buf(),
        source,
    })?;
    let mut kept = Vec::new();
    for e in entries.flatten() {
        let n = e.file_name();
        let ours = n == MANIFEST_FILE
            || n == CARRIED_FILE
            || (owned.contains(&n) && e.file_type().is_ok_and(|t| t.is_file()));
        if !ours {
            kept.push(n);
        }
    }
    kept.sort();
    Ok(kept)
}

/// The names a manifest lists, `None` where there is none (or not ours).
fn read_manifest(dir: &Path) -> Option<BTreeSet<OsString>> {
    let p = dir.join(MANIFEST_FILE);
    if !std::fs::symlink_metadata(&p).is_ok_and(|m| m.is_file()) {
        return None;
    }
    let text = super::read_to_string_capped(&p, 1 << 16).ok()?;
    let mut lines = text.lines();
    if lines.next()? != MANIFEST_HEADER {
        return None;
    }
    Some(
        lines
            .filter(|l| !l.is_empty())
            .map(OsString::from)
            .collect(),
    )
}

fn manifest_text(files: &[(&str, &[u8])]) -> String {
    let mut text = format!("{MANIFEST_HEADER}\n");
    for (name, _) in files {
        text.push_str(name);
        text.push('\n');
    }
    text
}

fn write_synced(p: &Path, bytes: &[u8]) -> Result<()> {
    let io = |source| Error::Io {
        path: p.to_path_buf(),
        source,
    };
    let mut f = std::fs::File::create(p).map_err(io)?;
    f.write_all(bytes).map_err(io)?;
    f.sync_all().map_err(io)
}

/// Move the entries `names` from `from` into `to` (those present in `from`
/// and absent from `to`).
fn carry(from: &Path, to: &Path, names: &[OsString]) -> Result<()> {
    for n in names {
        let (a, b) = (from.join(n), to.join(n));
        if std::fs::symlink_metadata(&a).is_ok() && std::fs::symlink_metadata(&b).is_err() {
            std::fs::rename(&a, &b).map_err(|source| Error::Io { path: a, source })?;
        }
    }
    sync_dir(from);
    sync_dir(to);
    Ok(())
}

/// Move the entries a temporary's journal lists back into `dir`; `true` when
/// none is left in the temporary (it may then be removed).
pub(super) fn carried_back(tmp: &Path, dir: &Path) -> bool {
    let Ok(journal) = std::fs::read(tmp.join(CARRIED_FILE)) else {
        return true;
    };
    let names: Vec<OsString> = journal
        .split(|b| *b == 0)
        .filter(|n| !n.is_empty())
        .map(|n| OsStr::from_bytes(n).to_os_string())
        .collect();
    if std::fs::symlink_metadata(dir).is_ok_and(|m| m.is_dir()) {
        let _ = carry(tmp, dir, &names);
    }
    names
        .iter()
        .all(|n| std::fs::symlink_metadata(tmp.join(n)).is_err())
}

/// The folder a temporary `.NAME.tmp-...` in `parent` stands for.
pub(super) fn folder_of_temporary(parent: &Path, temporary: &OsStr) -> Option<PathBuf> {
    let bytes = temporary.as_bytes();
    let mark = super::TMP_MARK.as_bytes();
    let end = bytes.windows(mark.len()).rposition(|w| w == mark)?;
    let name = bytes.get(1..end).filter(|n| !n.is_empty())?;
    Some(parent.join(OsString::from_vec(name.to_vec())))
}

/// Block until this process holds the exclusive `flock` of `file` (released
/// when the file is closed). `File::lock` would do it from Rust 1.89 on; the
/// workspace supports 1.85.
fn lock_exclusive(file: &std::fs::File) -> std::io::Result<()> {
    use std::os::fd::AsRawFd;
    loop {
        // SAFETY: a valid open descriptor; flock has no other preconditions.
        if unsafe { libc::flock(file.as_raw_fd(), libc::LOCK_EX) } == 0 {
            return Ok(());
        }
        let e = std::io::Error::last_os_error();
        if e.kind() != std::io::ErrorKind::Interrupted {
            return Err(e);
        }
    }
}

/// Swap two paths atomically; where the system cannot, move `b` aside, move
/// `a` to `b` and the old `b` to `a` (a short window without `b`).
fn exchange(a: &Path, b: &Path) -> std::io::Result<()> {
    #[cfg(target_os = "linux")]
    {
        let ca = std::ffi::CString::new(a.as_os_str().as_bytes())?;
        let cb = std::ffi::CString::new(b.as_os_str().as_bytes())?;
        // SAFETY: two valid NUL-terminated paths; renameat2 has no other
        // preconditions.
        let r = unsafe {
            libc::renameat2(
                libc::AT_FDCWD,
                ca.as_ptr(),
                libc::AT_FDCWD,
                cb.as_ptr(),
                libc::RENAME_EXCHANGE,
            )
        };
        if r == 0 {
            return Ok(());
        }
        let e = std::io::Error::last_os_error();
        if !matches!(e.raw_os_error(), Some(libc::EINVAL) | Some(libc::ENOSYS)) {
            return Err(e);
        }
    }
    let aside = parent_of(b).join(temporary_name("old"));
    std::fs::rename(b, &aside)?;
    if let Err(e) = std::fs::rename(a, b) {
        let _ = std::fs::rename(&aside, b);
        return Err(e);
    }
    std::fs::rename(&aside, a)
}

#[cfg(test)]
mod tests;
