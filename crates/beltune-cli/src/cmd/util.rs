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

/// Whether `a` and `b` name the same file: the same path as written (before
/// either exists), or the same file once resolved.
pub fn same_file(a: &Path, b: &Path) -> bool {
    let absolute = |p: &Path| std::path::absolute(p).ok();
    match (std::fs::canonicalize(a), std::fs::canonicalize(b)) {
        (Ok(x), Ok(y)) => x == y,
        _ => absolute(a).is_some_and(|x| Some(x) == absolute(b)),
    }
}

/// Error (bad input, exit status 2) if the output `out` names the same file
/// as one of `inputs`: writing it would destroy the input.
pub fn check_not_an_input(flag: &str, out: &Path, inputs: &[&Path]) -> anyhow::Result<()> {
    for input in inputs {
        if same_file(out, input) {
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

/// A drive's torque limit given as `flag` (N m, or A for a current record):
/// the library's plausibility range
/// ([`beltune::model::params::check_torque_limit`]), or one line naming the flag.
pub fn check_torque_limit_flag(flag: &str, torque_limit: f64) -> anyhow::Result<()> {
    use beltune::model::params::bounds;
    beltune::model::params::check_torque_limit(flag, torque_limit).map_err(|_| {
        anyhow::Error::new(crate::exit::Failure::new(
            crate::exit::ExitStatus::BadInput,
            format!(
                "{flag} {} is out of range [{}, {}]",
                beltune::error::short_number(torque_limit),
                beltune::error::short_number(bounds::TORQUE_LIMIT_MIN_NM),
                beltune::error::short_number(bounds::TORQUE_MAX_NM)
            ),
        ))
    })
}

/// Error (bad input) unless `path` can take an output file: not a folder,
/// in a folder that exists. Checked before the work that produces the file.
pub fn check_writable_file(flag: &str, path: &Path) -> anyhow::Result<()> {
    let bad = |why: String| {
        anyhow::Error::new(crate::exit::Failure::new(
            crate::exit::ExitStatus::BadInput,
            format!("{flag} {}: {why}", path.display()),
        ))
    };
    if path.is_dir() {
        return Err(bad("is a folder; name a file".into()));
    }
    let parent = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    if !parent.is_dir() {
        return Err(bad(format!(
            "the folder {} does not exist",
            parent.display()
        )));
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
