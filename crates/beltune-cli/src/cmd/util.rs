//! Helpers shared by the subcommands.

use anyhow::Context;
use std::path::Path;

/// Write `contents` to `path` atomically: write a temporary file in the same
/// directory, then rename it over the target. A crash leaves either the old
/// file or the new one, never half a file.
pub fn write_atomic(path: &Path, contents: &[u8]) -> anyhow::Result<()> {
    // Temporaries a killed earlier run left beside the file go first.
    if let Some(dir) = path.parent() {
        let dir = if dir.as_os_str().is_empty() {
            Path::new(".")
        } else {
            dir
        };
        beltune::io::clean_stale_temporaries(dir);
    }
    beltune::io::write_atomic(path, contents).with_context(|| format!("writing {}", path.display()))
}

/// Error (bad input, exit status 2) if the output `out` names the same file
/// as one of `inputs`: writing it would destroy the input.
pub fn check_not_an_input(flag: &str, out: &Path, inputs: &[&Path]) -> anyhow::Result<()> {
    let Ok(o) = std::fs::canonicalize(out) else {
        return Ok(()); // does not exist yet: cannot be an input
    };
    for input in inputs {
        if std::fs::canonicalize(input).is_ok_and(|i| i == o) {
            return Err(anyhow::Error::new(crate::exit::Failure::new(
                crate::exit::ExitStatus::BadInput,
                format!(
                    "{flag} {} is the input file {}; it would be overwritten",
                    out.display(),
                    input.display()
                ),
            )));
        }
    }
    Ok(())
}

/// The command-line flags of the design knobs, by the library's parameter names.
pub const KNOB_FLAGS: [(&str, &str); 5] = [
    ("pm_velocity_deg", "--pm-velocity"),
    ("pm_position_deg", "--pm-position"),
    ("resonance_suppression_db", "--resonance-suppression-db"),
    ("filter_attenuation_db", "--filter-attenuation-db"),
    ("dynamics", "--dynamics"),
];

/// A library error about a parameter the user gave as a flag, in the words
/// of the command line: `--pm-velocity 200: the velocity phase margin must
/// lie in (0, 180) degrees` instead of the library's field name (issue 13
/// item 14). `flags` maps the library's parameter names to the flags; any
/// other error is returned unchanged.
pub fn in_flag_words(e: anyhow::Error, flags: &[(&str, &str)]) -> anyhow::Error {
    for cause in e.chain() {
        if let Some(beltune::Error::InvalidParameter {
            name,
            value,
            reason,
        }) = cause.downcast_ref::<beltune::Error>()
        {
            if let Some((_, flag)) = flags.iter().find(|(n, _)| n == name) {
                return anyhow::Error::new(crate::exit::Failure::new(
                    crate::exit::ExitStatus::BadInput,
                    format!("{flag} {}: {reason}", beltune::error::short_number(*value)),
                ));
            }
        }
    }
    e
}
