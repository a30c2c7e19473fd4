//! Helpers shared by the subcommands.

use anyhow::Context;
use std::path::Path;

/// Write `contents` to `path` atomically: write a temporary file in the same
/// directory, then rename it over the target. A crash leaves either the old
/// file or the new one, never half a file.
pub fn write_atomic(path: &Path, contents: &[u8]) -> anyhow::Result<()> {
    beltune::io::write_atomic(path, contents).with_context(|| format!("writing {}", path.display()))
}
