//! `beltune record`: play an exported excitation (`beltune excitation`) on a
//! simulated axis and write the recording a real drive's recorder would
//! (time, setpoint, motor angle, actual torque), so that the "another drive
//! from its recording" walk-through runs end to end without hardware:
//!
//! ```sh
//! beltune excitation --kind prbs --ts 1e-4 --amplitude 0.6 --out prbs.csv
//! beltune record --plant sim-a --excitation prbs.csv --out rec.csv
//! beltune commission --csv rec.csv --input setpoint --output angle_rad --actual-torque actual ...
//! ```
//!
//! The simulated drive sees exactly the file's setpoints, one per cycle, with
//! the position loop open; it saturates them at its torque limit as a drive
//! would. The angle is the encoder's (quantized counts times the angle per
//! count), the actual torque the drive's measured one (dead time, noise).

use crate::exit::{ExitStatus, Failure};
use beltune::axis::Axis;
use beltune::ident::csv_columns::{check_uniform_time, read_csv_columns};
use beltune::sim::{SimAxis, SimConfig};
use std::fmt::Write as _;
use std::path::PathBuf;

/// Columns of the written recording.
pub const COLUMNS: [&str; 4] = ["t_s", "setpoint", "angle_rad", "actual"];
/// Largest relative deviation of the file's time step from the simulated
/// drive's cycle time: the file must be exported at the drive's `T_s`.
const TS_TOLERANCE: f64 = 1e-6;

/// Arguments of `beltune record`.
#[derive(clap::Args)]
pub struct Args {
    /// The simulated axis: a built-in plant (egc70, sim-a, sim-b, sim-c) or a TOML file.
    #[arg(long, default_value = "egc70")]
    pub plant: String,
    /// Payload on the cart, kg (physical plants only).
    #[arg(long, allow_negative_numbers = true)]
    pub payload: Option<f64>,
    /// The excitation to play: a CSV with the columns t_s and excitation (N m), as
    /// `beltune excitation` writes it, sampled at the plant's cycle time.
    #[arg(long, value_name = "FILE.csv")]
    pub excitation: PathBuf,
    /// Seed of the simulated measurement noise.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// The recording to write (columns t_s, setpoint, angle_rad, actual).
    #[arg(long, value_name = "FILE.csv")]
    pub out: PathBuf,
}

fn bad(m: impl Into<String>) -> anyhow::Error {
    anyhow::Error::new(Failure::new(ExitStatus::BadInput, m))
}

/// The recording's CSV text for `args`.
pub fn recording(args: &Args) -> anyhow::Result<String> {
    let plant = super::plant::resolve_plant(&args.plant, args.payload)?;
    let cols = read_csv_columns(&args.excitation, &["t_s", "excitation"])?;
    let sampling = check_uniform_time(&cols, "t_s", 2, 1e-3)?;
    let u = cols.column("excitation").unwrap_or_default();
    if let Some(i) = u.iter().position(|x| !x.is_finite()) {
        return Err(bad(format!(
            "{}: row {}: the excitation is not a finite number",
            args.excitation.display(),
            beltune::ident::csv_columns::line_of_row(i)
        )));
    }
    let mut axis = SimAxis::new(
        &plant,
        SimConfig {
            seed: args.seed,
            ..SimConfig::default()
        },
    )?;
    let info = axis.info();
    if ((sampling.ts_s - info.ts_s) / info.ts_s).abs() > TS_TOLERANCE {
        return Err(bad(format!(
            "{}: sampled every {} s, the simulated drive cycles every {} s: export the \
             excitation with --ts {}",
            args.excitation.display(),
            sampling.ts_s,
            info.ts_s,
            info.ts_s
        )));
    }
    let mut out = String::with_capacity(u.len() * 48);
    out.push_str(&COLUMNS.join(","));
    out.push('\n');
    for (k, &tau) in u.iter().enumerate() {
        let setpoint = tau.clamp(-info.torque_max_nm, info.torque_max_nm);
        let m = axis.step(setpoint);
        let _ = writeln!(
            out,
            "{:?},{setpoint:?},{:?},{:?}",
            k as f64 * info.ts_s,
            m.motor_counts as f64 * info.motor_rad_per_count,
            m.torque_actual_nm
        );
    }
    Ok(out)
}

/// Run the subcommand.
pub fn run(args: Args) -> anyhow::Result<()> {
    super::util::check_not_an_input("--out", &args.out, &[&args.excitation])?;
    super::util::check_writable_file("--out", &args.out)?;
    let csv = recording(&args)?;
    super::util::write_atomic(&args.out, csv.as_bytes())?;
    println!(
        "wrote {} ({} samples on the simulated {}; columns {})",
        args.out.display(),
        csv.lines().count() - 1,
        args.plant,
        COLUMNS.join(", ")
    );
    Ok(())
}
