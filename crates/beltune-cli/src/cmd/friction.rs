//! `beltune friction`: inertia, viscous and Coulomb friction and a constant
//! offset from any recorded motion (CSV with time, position and torque or
//! force), thesis 3.6 extended to arbitrary motions.

use super::util::write_atomic;
use anyhow::Context;
use beltune::ident::{
    csv_columns::check_time, identify_from_motion, read_csv_columns, MotionFrictionConfig,
};
use std::path::PathBuf;

/// Arguments of `beltune friction`.
#[derive(clap::Args)]
pub struct Args {
    /// CSV file with a header row.
    #[arg(long)]
    pub csv: PathBuf,
    /// Time column, s.
    #[arg(long)]
    pub time: String,
    /// Torque (or force) column.
    #[arg(long)]
    pub torque: String,
    /// Position column (angle in rad, or travel in m).
    #[arg(long)]
    pub position: String,
    /// Low-pass cut-off for position and torque, Hz (default: 1/50 of the sampling rate).
    #[arg(long, allow_negative_numbers = true)]
    pub cutoff_hz: Option<f64>,
    /// Samples slower than this fraction of the top speed are excluded.
    #[arg(long, default_value_t = 0.05, allow_negative_numbers = true)]
    pub min_speed_fraction: f64,
    /// Write the result here (JSON).
    #[arg(long)]
    pub json: Option<PathBuf>,
}

/// The JSON written by `--json`, in the units of the CSV.
#[derive(serde::Serialize)]
struct FrictionJson {
    inertia: f64,
    viscous: f64,
    coulomb: f64,
    offset: f64,
    relative_residual: f64,
    samples_used: usize,
    cutoff_hz: f64,
}

/// Run the subcommand.
pub fn run(args: Args) -> anyhow::Result<()> {
    if let Some(out) = &args.json {
        super::util::check_not_an_input("--json", out, &[&args.csv])?;
    }
    let cols = read_csv_columns(
        &args.csv,
        &[
            args.time.as_str(),
            args.position.as_str(),
            args.torque.as_str(),
        ],
    )?;
    check_time(&cols, &args.time, 50)?;
    beltune::ident::csv_columns::check_not_constant(&cols, &args.position)?;
    let r = identify_from_motion(
        cols.column(&args.time).expect("read"),
        cols.column(&args.position).expect("read"),
        cols.column(&args.torque).expect("read"),
        &MotionFrictionConfig {
            cutoff_hz: args.cutoff_hz,
            min_speed_fraction: args.min_speed_fraction,
        },
    )
    .map_err(|e| {
        super::util::in_flag_words(
            e.into(),
            &[
                ("cutoff_hz", "--cutoff-hz"),
                ("min_speed_fraction", "--min-speed-fraction"),
            ],
        )
    })
    .with_context(|| args.csv.display().to_string())?;
    println!(
        "inertia {:.6e}, viscous {:.6e}, coulomb {:.6e}, offset {:.6e}",
        r.inertia, r.viscous, r.coulomb, r.offset
    );
    println!(
        "relative residual {:.4}, {} samples used, cut-off {:.3} Hz",
        r.relative_residual, r.samples_used, r.cutoff_hz
    );
    if let Some(path) = &args.json {
        let json = FrictionJson {
            inertia: r.inertia,
            viscous: r.viscous,
            coulomb: r.coulomb,
            offset: r.offset,
            relative_residual: r.relative_residual,
            samples_used: r.samples_used,
            cutoff_hz: r.cutoff_hz,
        };
        let mut text = serde_json::to_string_pretty(&json)?;
        text.push('\n');
        write_atomic(path, text.as_bytes())?;
    }
    Ok(())
}
