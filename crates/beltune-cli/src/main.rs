//! `beltune`: self-commissioning of belt-driven servo axes.
//!
//! Each subcommand lives in its own file under `cmd/`, with its clap `Args`
//! and a `run` function. Errors are printed as one line and exit non-zero.

use clap::{Parser, Subcommand};

mod cmd;
mod progress;

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
}

fn main() {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Plant(c) => cmd::plant::run(c),
        Command::Trajectory(a) => cmd::trajectory::run(a),
        Command::Identify(a) => cmd::identify::run(a),
        Command::Friction(a) => cmd::friction::run(a),
        Command::Design(a) => cmd::design::run(a),
        Command::Commission(a) => cmd::commission::run(a),
        Command::Serve(a) => cmd::serve::run(a),
    };
    if let Err(e) = result {
        // One line: the whole cause chain joined, no backtrace.
        let msg = e
            .chain()
            .map(|c| c.to_string())
            .collect::<Vec<_>>()
            .join(": ");
        eprintln!("error: {msg}");
        std::process::exit(1);
    }
}
