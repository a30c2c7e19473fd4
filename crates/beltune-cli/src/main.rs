//! `beltune`: self-commissioning of belt-driven servo axes.
//!
//! Each subcommand lives in its own file under `cmd/` of the `beltune_cli`
//! library, with its clap `Args` and a `run` function. Errors are printed as
//! one line and exit with the status of their kind (`beltune_cli::exit`).

use beltune_cli::{cmd, exit};
use clap::{Parser, Subcommand};

#[derive(Parser)]
#[command(
    name = "beltune",
    version,
    about = "Self-commissioning of belt-driven servo axes"
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
    Trajectory(cmd::trajectory::Args),
    /// Identify a two-mass model from a recorded excitation (CSV).
    Identify(cmd::identify::Args),
    /// Identify inertia and friction from a recorded motion (CSV).
    Friction(cmd::friction::Args),
    /// Design the cascaded controller from an identified model.
    Design(cmd::design::Args),
    /// Commission an axis end to end: identify, design, validate, report.
    Commission(cmd::commission::Args),
    /// Serve the interactive tuning page.
    Serve(cmd::serve::Args),
    /// Compare two commissioning folders: FRFs, fits, loops, moves, parameter changes.
    Compare(cmd::compare::Args),
    /// Export a controller.toml as firmware source (Rust module or C header).
    Export(cmd::export::Args),
    /// Write an excitation signal (PRBS, chirp, multisine) to play on another drive.
    Excitation(cmd::excitation::Args),
    /// Answer as a virtual CiA 402 servo drive (EtherCAT SubDevice) on a network interface.
    VirtualDrive(cmd::virtual_drive::Args),
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
    let cli = Cli::parse();
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
        Command::Serve(a) => cmd::serve::run(a),
        Command::Compare(a) => cmd::compare::run(a),
        Command::Export(a) => cmd::export::run(a),
        Command::Excitation(a) => cmd::excitation::run(a),
        Command::VirtualDrive(a) => cmd::virtual_drive::run(a),
    };
    if let Err(e) = result {
        // One line: the whole cause chain joined, no backtrace.
        eprintln!("error: {}", exit::one_line(&e));
        std::process::exit(exit::status_of(&e).code());
    }
}
