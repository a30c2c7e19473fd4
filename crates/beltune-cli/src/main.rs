//! `beltune`: self-commissioning of belt-driven servo axes.
//!
//! Each subcommand lives in its own file under `cmd/` of the `beltune_cli`
//! library, with its clap `Args` and a `run` function. Errors are printed as
//! one line and exit with the status of their kind (`beltune_cli::exit`).

use beltune_cli::{cmd, exit, help, term};
use clap::{CommandFactory, FromArgMatches, Parser, Subcommand};

#[derive(Parser)]
#[command(
    name = "beltune",
    version,
    about = "Self-commissioning of belt-driven servo axes",
    long_about = "Self-commissioning of belt-driven servo axes: excite the axis, identify a \
                  two-mass model, design the cascaded controller with resonance filter and \
                  feedforward, and prove it with a move (`beltune commission`).",
    after_help = help::root_after_help(),
    max_term_width = term::WIDTH
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

// Parsed once per run: the size of the largest variant does not matter.
#[allow(clippy::large_enum_variant)]
#[derive(Subcommand)]
enum Command {
    /// Show a plant's parameters and derived quantities (resonance, antiresonance, ...).
    #[command(subcommand)]
    Plant(cmd::plant::PlantCommand),
    /// Plan a jerk-limited time-optimal move and print its duration and phases.
    #[command(
        override_usage = "beltune trajectory [OPTIONS] --start <START> --target <TARGET>\n       \
                                --v-max <V_MAX> --a-max <A_MAX> --j-max <J_MAX>"
    )]
    Trajectory(cmd::trajectory::Args),
    /// Identify a two-mass model from a recorded excitation (CSV).
    Identify(cmd::identify::Args),
    /// Identify inertia and friction from a recorded motion (CSV).
    Friction(cmd::friction::Args),
    /// Design the cascaded controller from an identified model.
    Design(cmd::design::Args),
    /// Commission an axis end to end: identify, design, validate, report.
    Commission(cmd::commission::Args),
    /// Check the health of a commissioned axis against its commissioning (a few seconds).
    Health(cmd::health::Args),
    /// Vibration benchmark of a commissioned axis: fixed, Klipper's shaper, model-based shaping.
    Vibration(cmd::vibration::Args),
    /// The runs of the history database, their trends and limits.
    History(cmd::history::Args),
    /// Serve the interactive tuning page.
    Serve(cmd::serve::Args),
    /// Robustness study: commission N seeded random axes and print the table.
    Montecarlo(cmd::montecarlo::Args),
    /// Compare two commissioning folders: FRFs, fits, loops, moves, parameter changes.
    Compare(cmd::compare::Args),
    /// Export a controller.toml as firmware source (Rust module or C header).
    Export(cmd::export::Args),
    /// Write an excitation signal (PRBS, chirp, multisine) to play on another drive.
    Excitation(cmd::excitation::Args),
    /// Play an excitation on a simulated axis and write the drive's recording (CSV).
    Record(cmd::record::Args),
    /// Answer as a virtual CiA 402 servo drive (EtherCAT SubDevice) on a network interface.
    VirtualDrive(cmd::virtual_drive::Args),
    /// Print the shell completion script (bash, zsh, fish, elvish, powershell).
    Completions(cmd::completions::Args),
    /// Print the manual page (roff), or write one per subcommand with --out.
    Man(cmd::man::Args),
}

/// A command that prints to a pipe whose reader went away (`beltune ... | head`)
/// ends quietly with the conventional SIGPIPE status, as `cat` does, instead of
/// panicking in `println!`. Rust starts programs with SIGPIPE ignored; this
/// restores the default action. Not for `serve`: a client that closes its
/// connection must not end the server.
fn die_quietly_on_closed_stdout() {
    // SAFETY: `signal` with a valid signal number and `SIG_DFL` has no
    // preconditions; it runs before any other thread exists.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
}

fn main() {
    // `--config FILE.toml` puts the file's flags on the command line first.
    let argv = match cmd::config::expand(std::env::args_os().collect(), &Cli::command()) {
        Ok(a) => a,
        Err(e) => fail(&e),
    };
    let cli =
        Cli::from_arg_matches(&Cli::command().get_matches_from(argv)).unwrap_or_else(|e| e.exit());
    if !matches!(cli.command, Command::Serve(_)) {
        die_quietly_on_closed_stdout();
    }
    let result = match cli.command {
        Command::Plant(c) => cmd::plant::run(c),
        Command::Trajectory(a) => cmd::trajectory::run(a),
        Command::Identify(a) => cmd::identify::run(a),
        Command::Friction(a) => cmd::friction::run(a),
        Command::Design(a) => cmd::design::run(a),
        Command::Commission(a) => cmd::commission::run(a),
        Command::Health(a) => cmd::health::run(a),
        Command::Vibration(a) => cmd::vibration::run(a),
        Command::History(a) => cmd::history::run(a),
        Command::Serve(a) => cmd::serve::run(a),
        Command::Montecarlo(a) => cmd::montecarlo::run(a),
        Command::Compare(a) => cmd::compare::run(a),
        Command::Export(a) => cmd::export::run(a),
        Command::Excitation(a) => cmd::excitation::run(a),
        Command::Record(a) => cmd::record::run(a),
        Command::VirtualDrive(a) => cmd::virtual_drive::run(a),
        Command::Completions(a) => cmd::completions::run(a, Cli::command()),
        Command::Man(a) => cmd::man::run(a, Cli::command()),
    };
    if let Err(e) = result {
        fail(&e);
    }
}

/// One line on stderr (the whole cause chain joined, numbers without float
/// noise, no backtrace), then exit with the status of the error's kind.
fn fail(e: &anyhow::Error) -> ! {
    eprintln!("error: {}", term::tidy_numbers(&exit::one_line(e)));
    std::process::exit(exit::status_of(e).code());
}
