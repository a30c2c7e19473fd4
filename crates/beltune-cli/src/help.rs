//! Texts of `--help` and the man page: the exit statuses, examples, and the
//! headings that group the flags of `beltune commission`.

use crate::exit::ExitStatus;

/// The status of a command killed by SIGPIPE, as a shell reports it (128 + 13).
pub const SIGPIPE_STATUS: i32 = 141;

/// Every exit status of `beltune` with its meaning (README and man page say the same).
pub const EXIT_STATUSES: [(i32, &str); 7] = [
    (ExitStatus::Success as i32, "success"),
    (
        ExitStatus::Error as i32,
        "any other error (a file cannot be written, an internal failure)",
    ),
    (
        ExitStatus::BadInput as i32,
        "bad input: a bad flag or value, a malformed file, data that cannot be fitted",
    ),
    (
        ExitStatus::SafetyStop as i32,
        "safety stop: the supervisor stopped the axis (safety-stop.json), or the axis failed",
    ),
    (
        ExitStatus::Infeasible as i32,
        "infeasible: no controller meets the design, or the axis cannot do the move",
    ),
    (
        ExitStatus::LimitsNotMet as i32,
        "finished, but the validation misses its limits (1 mm / 100 um by default)",
    ),
    (
        SIGPIPE_STATUS,
        "the reader of stdout went away (SIGPIPE, e.g. `beltune ... | head`)",
    ),
];

/// Examples of the whole command, with what each does.
pub const ROOT_EXAMPLES: [(&str, &str); 7] = [
    (
        "beltune commission",
        "commission the built-in EGC-70 rig (11.2 kg payload)",
    ),
    (
        "beltune commission --payload 0 --out run0",
        "the empty cart, results in run0/",
    ),
    (
        "beltune plant template > axis.toml",
        "an annotated plant file to edit",
    ),
    (
        "beltune commission --plant axis.toml --json",
        "commission it, summary as JSON",
    ),
    (
        "beltune serve",
        "the interactive tuning page on http://127.0.0.1:8080",
    ),
    (
        "beltune completions bash > ~/.local/share/bash-completion/completions/beltune",
        "",
    ),
    ("beltune man | man -l -", "this manual"),
];

/// Examples of `beltune commission`.
pub const COMMISSION_EXAMPLES: [(&str, &str); 5] = [
    (
        "beltune commission",
        "the built-in EGC-70 rig, results in commissioning/",
    ),
    (
        "beltune commission --plant sim-a --dynamics dynamic",
        "a linear set, a faster design",
    ),
    (
        "beltune commission --config axis.toml --seed 2",
        "flags from a file; the command line overrides it",
    ),
    (
        "beltune commission --quiet --json | jq .verdict",
        "only the summary, as JSON",
    ),
    (
        "beltune commission --csv rec.csv --input iq_A --output phi_rad",
        "from a recording",
    ),
];

/// The `Examples:` block of a help text.
fn examples(list: &[(&str, &str)]) -> String {
    let mut out = String::from("Examples:\n");
    for (cmd, what) in list {
        out.push_str(&format!("  {cmd}\n"));
        if !what.is_empty() {
            out.push_str(&format!("      {what}\n"));
        }
    }
    out
}

/// The `Exit status:` block of a help text.
pub fn exit_status_text() -> String {
    let mut out = String::from("Exit status:\n");
    for (code, what) in EXIT_STATUSES {
        out.push_str(&format!("  {code:<4} {what}\n"));
    }
    out
}

/// After the help of `beltune`: examples and the exit statuses.
pub fn root_after_help() -> String {
    format!(
        "{}\n{}",
        examples(&ROOT_EXAMPLES),
        exit_status_text().trim_end()
    )
}

/// After the help of `beltune commission`.
pub fn commission_after_help() -> String {
    format!(
        "{}\n{}",
        examples(&COMMISSION_EXAMPLES),
        exit_status_text().trim_end()
    )
}

/// Headings of the flags of `beltune commission`, in the order they show,
/// with the ids (field names) of their flags. A new flag needs an entry here
/// (a test checks that every flag has one).
pub const COMMISSION_HEADINGS: [(&str, &[&str]); 8] = [
    (
        "Plant",
        &[
            "plant",
            "payload",
            "tilt",
            "seed",
            "torque_noise",
            "encoder_noise",
            "start_position",
        ],
    ),
    ("Safety", &["travel_window", "following_error_max"]),
    (
        "EtherCAT drive",
        &[
            "ethercat",
            "subdevice",
            "cycle_us",
            "frame_timeout_ms",
            "realtime_priority",
            "dc",
            "no_dc",
            "drive_profile",
        ],
    ),
    (
        "Design",
        &[
            "prefilter",
            "pm_velocity",
            "pm_position",
            "resonance_suppression_db",
            "filter_attenuation_db",
            "dynamics",
            "thesis_design",
        ],
    ),
    (
        "Excitation",
        &["excitation_amplitude", "prbs_order", "prbs_clock_ms"],
    ),
    (
        "Validation limits",
        &[
            "max_tracking_error",
            "max_static_error",
            "compare_feedforward",
        ],
    ),
    (
        "Recorded data (--csv)",
        &[
            "csv",
            "time",
            "input",
            "output",
            "actual_torque",
            "period_samples",
            "skip_periods",
            "inertia",
            "transmission",
            "torque_limit",
            "friction_csv",
            "friction_torque",
            "friction_position",
            "current_units",
            "reference",
            "reference_kind",
            "method",
            "controller",
        ],
    ),
    (
        "Output",
        &["config", "out", "force", "quiet", "json", "db", "axis"],
    ),
];

/// The heading of a `beltune commission` flag.
pub fn commission_heading(id: &str) -> Option<&'static str> {
    COMMISSION_HEADINGS
        .iter()
        .find(|(_, ids)| ids.contains(&id))
        .map(|(h, _)| *h)
}

/// Put a `beltune commission` flag under its heading (for `Command::mut_args`).
pub fn with_commission_heading(arg: clap::Arg) -> clap::Arg {
    match commission_heading(arg.get_id().as_str()) {
        Some(h) => arg.help_heading(h),
        None => arg,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_status_of_exit_rs_is_listed_once() {
        let codes: Vec<i32> = EXIT_STATUSES.iter().map(|(c, _)| *c).collect();
        assert_eq!(codes, [0, 1, 2, 3, 4, 5, 141]);
        for s in [
            ExitStatus::Success,
            ExitStatus::Error,
            ExitStatus::BadInput,
            ExitStatus::SafetyStop,
            ExitStatus::Infeasible,
            ExitStatus::LimitsNotMet,
        ] {
            assert!(codes.contains(&s.code()), "{s}");
        }
    }

    /// Every flag of `beltune commission` sits under a heading of
    /// [`COMMISSION_HEADINGS`] (a new flag needs an entry there), and every
    /// entry there is a flag.
    #[test]
    fn every_commission_flag_has_a_heading() {
        use clap::Args as _;
        let mut cmd = crate::cmd::commission::Args::augment_args(clap::Command::new("commission"));
        cmd.build();
        let ids: Vec<String> = cmd
            .get_arguments()
            .map(|a| a.get_id().to_string())
            .filter(|id| id != "help")
            .collect();
        for a in cmd.get_arguments().filter(|a| a.get_id() != "help") {
            assert!(
                a.get_help_heading().is_some(),
                "--{} has no heading in help::COMMISSION_HEADINGS",
                a.get_long().unwrap_or_default()
            );
        }
        for (heading, listed) in COMMISSION_HEADINGS {
            for id in listed {
                assert!(ids.iter().any(|i| i == id), "{heading}: `{id}` is no flag");
            }
        }
    }

    #[test]
    fn help_blocks_fit_100_columns() {
        for text in [root_after_help(), commission_after_help()] {
            for line in text.lines() {
                assert!(line.chars().count() <= crate::term::WIDTH, "{line}");
            }
        }
    }
}
