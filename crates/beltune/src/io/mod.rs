//! File input and output that never leaves half a file behind, never replaces
//! a special file, and never reads without bound.
//!
//! - [`write_atomic`]: a regular file (or a new one) is replaced atomically
//!   through a uniquely named temporary in the same folder; a device, a FIFO or
//!   a symlink's target is written through instead of being replaced.
//! - [`read_capped`] / [`read_to_string_capped`]: only regular files, at most
//!   a given size ([`MAX_TEXT_BYTES`] for TOML/JSON, [`MAX_CSV_BYTES`] for CSV).
//! - [`write_folder_atomic`] ([`set`]): a result set replaced as a whole,
//!   keeping everything in the folder that beltune did not write.
//! - [`clean_stale_temporaries`]: removes temporaries left by a killed process
//!   (and puts back what a killed set replacement had carried aside).

mod set;
pub use set::{users_entries, write_folder_atomic, MANIFEST_FILE};

use crate::{Error, Result};
use std::io::{Read, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

/// Largest TOML or JSON file read (plant, model, commissioning), bytes (4 MiB).
pub const MAX_TEXT_BYTES: u64 = 4 << 20;
/// Largest CSV file read, bytes (512 MiB; after decompression for `.csv.gz`).
pub const MAX_CSV_BYTES: u64 = 512 << 20;

/// Marker inside every temporary name: `.NAME.tmp-PID-N`.
const TMP_MARK: &str = ".tmp-";

static COUNTER: AtomicU64 = AtomicU64::new(0);

/// A name for a temporary sibling of `name`, unique within the machine: the
/// process id, a per-process counter and the clock.
pub fn temporary_name(name: &str) -> String {
    let n = COUNTER.fetch_add(1, Ordering::Relaxed);
    let nanos = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.subsec_nanos());
    format!(".{name}{TMP_MARK}{}-{n}-{nanos}", std::process::id())
}

fn parent_of(path: &Path) -> PathBuf {
    match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    }
}

/// Write `contents` to `path` atomically: a temporary file in the same
/// directory (a unique name, so concurrent writers never share one) is
/// written, flushed to disk and renamed over `path`. A readers sees the old
/// file or the new one, never a partial or empty one.
///
/// A symlink is followed (its target is replaced, the link stays); a device,
/// FIFO or socket is written through (opened and written, never replaced);
/// a directory is an error.
pub fn write_atomic(path: &Path, contents: &[u8]) -> Result<()> {
    let io = |source| Error::Io {
        path: path.to_path_buf(),
        source,
    };
    // Follow symlinks to the file that is really meant.
    let target = match std::fs::symlink_metadata(path) {
        Ok(m) if m.file_type().is_symlink() => match std::fs::canonicalize(path) {
            Ok(t) => t,
            // A dangling link: create its target.
            Err(_) => {
                let link = std::fs::read_link(path).map_err(io)?;
                parent_of(path).join(link)
            }
        },
        _ => path.to_path_buf(),
    };
    match std::fs::metadata(&target) {
        Ok(m) if m.is_dir() => {
            return Err(io(std::io::Error::new(
                std::io::ErrorKind::IsADirectory,
                "is a directory",
            )))
        }
        Ok(m) if !m.is_file() => {
            // Device, FIFO, socket: write through.
            let mut f = std::fs::OpenOptions::new()
                .write(true)
                .open(&target)
                .map_err(io)?;
            return f.write_all(contents).and_then(|()| f.flush()).map_err(io);
        }
        _ => {}
    }
    let dir = parent_of(&target);
    let name = target
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "out".into());
    let tmp = dir.join(temporary_name(&name));
    let result = (|| {
        let mut f = std::fs::OpenOptions::new()
            .write(true)
            .create_new(true)
            .open(&tmp)?;
        // Keep the permissions of the file being replaced.
        if let Ok(m) = std::fs::metadata(&target) {
            let _ = f.set_permissions(m.permissions());
        }
        f.write_all(contents)?;
        f.sync_all()?;
        std::fs::rename(&tmp, &target)?;
        sync_dir(&dir);
        Ok(())
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result.map_err(io)
}

/// Flush a directory's entries (a rename) to disk; best effort.
pub fn sync_dir(dir: &Path) {
    if let Ok(d) = std::fs::File::open(dir) {
        let _ = d.sync_all();
    }
}

fn too_big(path: &Path, limit: u64) -> Error {
    Error::Parse {
        path: path.display().to_string(),
        message: format!("file is larger than the limit of {} bytes", limit),
    }
}

/// Refuse anything but a regular file (a FIFO would block, a device such as
/// `/dev/zero` never ends) and a file larger than `limit` bytes.
pub fn check_readable_file(path: &Path, limit: u64) -> Result<()> {
    // A missing or unreadable file stays an I/O error (exit status 1).
    let m = std::fs::metadata(path).map_err(|source| Error::Io {
        path: path.to_path_buf(),
        source,
    })?;
    if m.is_dir() {
        return Err(Error::Parse {
            path: path.display().to_string(),
            message: "is a directory, not a file".into(),
        });
    }
    if !m.is_file() {
        return Err(Error::Parse {
            path: path.display().to_string(),
            message: "is not a regular file (a device, FIFO or socket); give a file".into(),
        });
    }
    if m.len() > limit {
        return Err(too_big(path, limit));
    }
    Ok(())
}

/// An I/O error's text, once (the error is not kept as a source, so that
/// the one-line message does not repeat it).
pub fn describe(e: &std::io::Error) -> String {
    e.to_string()
}

/// A reader of at most `limit` bytes: reading more is an error naming `path`.
pub struct CappedReader<R> {
    inner: R,
    left: u64,
    limit: u64,
}

impl<R: Read> CappedReader<R> {
    /// Cap `inner` at `limit` bytes.
    pub fn new(inner: R, limit: u64) -> Self {
        CappedReader {
            inner,
            left: limit,
            limit,
        }
    }
}

impl<R: Read> Read for CappedReader<R> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        if self.left == 0 {
            // One more byte means the limit was exceeded.
            let mut probe = [0u8; 1];
            return match self.inner.read(&mut probe)? {
                0 => Ok(0),
                _ => Err(std::io::Error::new(
                    std::io::ErrorKind::InvalidData,
                    format!("more than the limit of {} bytes", self.limit),
                )),
            };
        }
        let n = buf.len().min(self.left.min(usize::MAX as u64) as usize);
        let got = self.inner.read(&mut buf[..n])?;
        self.left -= got as u64;
        Ok(got)
    }
}

/// The bytes of the regular file `path`, at most `limit` bytes
/// ([`Error::Parse`] naming the file otherwise).
pub fn read_capped(path: &Path, limit: u64) -> Result<Vec<u8>> {
    check_readable_file(path, limit)?;
    let f = std::fs::File::open(path).map_err(|source| Error::Io {
        path: path.to_path_buf(),
        source,
    })?;
    let mut out = Vec::new();
    CappedReader::new(f, limit)
        .read_to_end(&mut out)
        .map_err(|e| Error::Parse {
            path: path.display().to_string(),
            message: format!("cannot open: {}", describe(&e)),
        })?;
    Ok(out)
}

/// The text of the regular file `path` (UTF-8), at most `limit` bytes.
pub fn read_to_string_capped(path: &Path, limit: u64) -> Result<String> {
    let bytes = read_capped(path, limit)?;
    String::from_utf8(bytes).map_err(|e| Error::Parse {
        path: path.display().to_string(),
        message: format!("not UTF-8 text (byte {})", e.utf8_error().valid_up_to()),
    })
}

/// `true` if the process `pid` still runs (Linux: `/proc/PID`; elsewhere
/// every process is assumed alive and only age counts).
fn process_alive(pid: u32) -> bool {
    let proc = Path::new("/proc");
    if !proc.join("self").exists() {
        return true;
    }
    pid == std::process::id() || proc.join(pid.to_string()).exists()
}

/// The process id in a temporary name `.NAME.tmp-PID-...`.
fn temporary_pid(name: &str) -> Option<u32> {
    if !name.starts_with('.') {
        return None;
    }
    // Exactly our pattern `PID-N-NANOS` (three numbers), so that a user's
    // own `.x.tmp-...` file is never taken for one of ours.
    let rest = &name[name.rfind(TMP_MARK)? + TMP_MARK.len()..];
    let parts: Vec<&str> = rest.split('-').collect();
    if parts.len() != 3
        || !parts
            .iter()
            .all(|p| !p.is_empty() && p.bytes().all(|b| b.is_ascii_digit()))
    {
        return None;
    }
    parts[0].parse().ok()
}

/// Remove temporaries (`.NAME.tmp-PID-...`, files or folders) in `dir` whose
/// process no longer runs, or older than a day. A temporary folder holding
/// entries a killed [`write_folder_atomic`] carried aside has them moved back
/// into `dir/NAME` first, and is kept if that fails. Best effort: returns
/// what was removed.
pub fn clean_stale_temporaries(dir: &Path) -> Vec<PathBuf> {
    let mut removed = Vec::new();
    let Ok(entries) = std::fs::read_dir(dir) else {
        return removed;
    };
    for e in entries.flatten() {
        let name = e.file_name().to_string_lossy().into_owned();
        let Some(pid) = temporary_pid(&name) else {
            continue;
        };
        let old = e
            .metadata()
            .ok()
            .and_then(|m| m.modified().ok())
            .and_then(|t| t.elapsed().ok())
            .is_some_and(|age| age.as_secs() > 24 * 3600);
        if process_alive(pid) && !old {
            continue;
        }
        let p = e.path();
        // a replacement killed while it held the user's entries: put them
        // back first, and keep the temporary if that fails
        if e.file_type().is_ok_and(|t| t.is_dir()) {
            let back = match set::folder_of_temporary(dir, &e.file_name()) {
                Some(folder) => set::carried_back(&p, &folder),
                None => !p.join(set::CARRIED_FILE).exists(),
            };
            if !back {
                continue;
            }
        }
        let gone = match e.file_type() {
            Ok(t) if t.is_dir() => std::fs::remove_dir_all(&p),
            _ => std::fs::remove_file(&p),
        };
        if gone.is_ok() {
            removed.push(p);
        }
    }
    removed
}

#[cfg(test)]
mod tests {
    use super::*;

    fn temp(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("beltune-io-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    #[test]
    fn writes_and_replaces_without_leftovers() {
        let dir = temp("replace");
        let p = dir.join("a.json");
        write_atomic(&p, b"one").unwrap();
        write_atomic(&p, b"two").unwrap();
        assert_eq!(std::fs::read(&p).unwrap(), b"two");
        let names: Vec<_> = std::fs::read_dir(&dir).unwrap().collect();
        assert_eq!(names.len(), 1, "temporary file left behind");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn missing_directory_is_an_error_not_a_panic() {
        let p = Path::new("/nonexistent-beltune-dir/x.json");
        assert!(matches!(write_atomic(p, b"x"), Err(Error::Io { .. })));
    }

    #[test]
    fn concurrent_writers_use_distinct_temporaries() {
        // 8 threads x 50 writes of the same file; a reader never sees an
        // empty or foreign file, no write fails, nothing is left behind.
        let dir = temp("concurrent");
        let p = dir.join("c.toml");
        write_atomic(&p, b"x = 0\n").unwrap();
        let stop = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
        let reader = {
            let (p, stop) = (p.clone(), stop.clone());
            std::thread::spawn(move || {
                let mut looks = 0;
                while !stop.load(Ordering::Relaxed) {
                    let text = std::fs::read_to_string(&p).unwrap();
                    assert!(text.starts_with("x = ") && text.ends_with('\n'), "{text:?}");
                    looks += 1;
                }
                looks
            })
        };
        let writers: Vec<_> = (0..8)
            .map(|w| {
                let p = p.clone();
                std::thread::spawn(move || {
                    for k in 0..50 {
                        write_atomic(&p, format!("x = {}\n", w * 1000 + k).as_bytes()).unwrap();
                    }
                })
            })
            .collect();
        for w in writers {
            w.join().unwrap();
        }
        stop.store(true, Ordering::Relaxed);
        assert!(reader.join().unwrap() > 0);
        assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 1);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn special_files_are_written_through_not_replaced() {
        let dir = temp("special");
        // A symlink stays a symlink; its target gets the contents.
        let target = dir.join("target.csv");
        std::fs::write(&target, b"old").unwrap();
        let link = dir.join("link.csv");
        std::os::unix::fs::symlink(&target, &link).unwrap();
        write_atomic(&link, b"new").unwrap();
        assert!(std::fs::symlink_metadata(&link)
            .unwrap()
            .file_type()
            .is_symlink());
        assert_eq!(std::fs::read(&target).unwrap(), b"new");
        // A character device stays a device.
        let null = Path::new("/dev/null");
        write_atomic(null, b"discarded").unwrap();
        assert!(!std::fs::metadata(null).unwrap().is_file());
        // A directory is an error.
        assert!(write_atomic(&dir, b"x").is_err());
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn reads_refuse_devices_fifos_and_oversized_files() {
        let e = read_capped(Path::new("/dev/zero"), MAX_TEXT_BYTES).unwrap_err();
        assert!(e.to_string().contains("not a regular file"), "{e}");
        let dir = temp("read");
        let big = dir.join("big.toml");
        std::fs::write(&big, vec![b'#'; 2000]).unwrap();
        let e = read_capped(&big, 1000).unwrap_err();
        assert!(e.to_string().contains("limit of 1000 bytes"), "{e}");
        assert_eq!(read_capped(&big, 2000).unwrap().len(), 2000);
        let e = read_capped(&dir, 1000).unwrap_err();
        assert!(e.to_string().contains("directory"), "{e}");
        // A reader capped below its stream's length fails instead of growing.
        let mut s = Vec::new();
        let r = CappedReader::new(std::io::repeat(0), 100).read_to_end(&mut s);
        assert!(r.is_err() && s.len() == 100);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn stale_temporaries_of_dead_processes_are_removed() {
        let dir = temp("stale");
        // pid 0 never names a user process.
        let dead = dir.join(".report.html.tmp-0-1-2");
        std::fs::write(&dead, b"x").unwrap();
        let live = dir.join(temporary_name("controller.toml"));
        std::fs::write(&live, b"x").unwrap();
        let keep = dir.join("controller.toml");
        std::fs::write(&keep, b"x").unwrap();
        let users = dir.join(".notes.tmp-0");
        std::fs::write(&users, b"x").unwrap();
        let removed = clean_stale_temporaries(&dir);
        assert_eq!(removed, vec![dead.clone()]);
        assert!(live.exists() && keep.exists() && users.exists() && !dead.exists());
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
