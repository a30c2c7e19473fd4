//! `beltune commission`: the one-command self-commissioning of the built-in
//! simulated axis (or a plant file), with progress bars, safety supervision,
//! validation and the report; or, with `--csv`, from data recorded on a real
//! drive (the stages that need the axis are skipped).

use crate::progress::BarProgress;
use anyhow::Context;
use beltune::design::DesignKnobs;
use beltune::ident::{
    identify_from_motion, identify_recorded, read_csv_columns, EtfeConfig, FitConfig,
    MotionFrictionConfig, RecordedExcitation,
};
use beltune::model::rigs::{self, Plant};
use beltune::procedure::commission::{commission, CommissioningConfig, DataSheet};
use beltune::procedure::outputs::{
    build_report, commissioning_json, controller_toml, data_files, recorded_data_files,
    recorded_outputs, write_outputs,
};
use beltune::procedure::recorded::commission_recorded;
use beltune::procedure::result::Truth;
use beltune::provenance::Provenance;
use beltune::report::render_html;
use beltune::sim::{SimAxis, SimConfig};
use std::path::PathBuf;
use std::time::Instant;

/// Arguments of `beltune commission`.
#[derive(clap::Args)]
pub struct Args {
    /// Built-in plant name (egc70, sim-a, sim-b, sim-c) or a plant TOML file.
    #[arg(long, default_value = "egc70")]
    pub plant: String,
    /// Payload on the cart, kg (egc70 only; default 11.2 kg).
    #[arg(long, allow_negative_numbers = true)]
    pub payload: Option<f64>,
    /// Tilt of the axis, degrees (0 horizontal, 90 vertical).
    #[arg(long, allow_negative_numbers = true)]
    pub tilt: Option<f64>,
    /// Seed of the simulated measurement noise.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Output folder.
    #[arg(long, default_value = "commissioning")]
    pub out: PathBuf,
    #[command(flatten)]
    pub knobs: super::knobs::KnobArgs,
    /// Travel window MIN,MAX in m (default: inside the stroke).
    #[arg(long, value_parser = parse_pair, allow_hyphen_values = true)]
    pub travel_window: Option<(f64, f64)>,
    /// Cart position at start (the homing result), m.
    #[arg(long, default_value_t = 0.05)]
    pub start_position: f64,
    /// Fixed PRBS amplitude A_PRBS in N m (values +-A/2) instead of the automatic search.
    #[arg(long)]
    pub excitation_amplitude: Option<f64>,
    /// PRBS order n_PRBS (default 9).
    #[arg(long)]
    pub prbs_order: Option<u32>,
    /// PRBS clock period P_PRBS in samples (default 16).
    #[arg(long)]
    pub prbs_clock: Option<u32>,
    /// Commission from recorded data instead of a plant: CSV of a periodic
    /// excitation (header row). Skips the stages that need the axis.
    #[arg(long, requires_all = ["input", "output"])]
    pub csv: Option<PathBuf>,
    /// Recorded data: time column, s.
    #[arg(long, default_value = "t_s")]
    pub time: String,
    /// Recorded data: desired-torque column, N m.
    #[arg(long)]
    pub input: Option<String>,
    /// Recorded data: motor-angle column, rad.
    #[arg(long)]
    pub output: Option<String>,
    /// Recorded data: actual-torque column (for the dead time).
    #[arg(long)]
    pub actual_torque: Option<String>,
    /// Recorded data: samples per excitation period (default: detected).
    #[arg(long)]
    pub period_samples: Option<usize>,
    /// Recorded data: leading periods discarded as transient.
    #[arg(long, default_value_t = 1)]
    pub skip_periods: usize,
    /// Recorded data: data-sheet Theta_e in kg m^2 (fitted when not given).
    #[arg(long)]
    pub inertia: Option<f64>,
    /// Recorded data: transmission i_t in m/rad.
    #[arg(long, default_value_t = 1.0)]
    pub transmission: f64,
    /// Recorded data: the drive's torque limit, in the unit of the input column
    /// (N m, or A for a current record), written to controller.toml.
    #[arg(long, default_value_t = 3.1)]
    pub torque_limit: f64,
    /// Recorded data: a CSV of any motion for the friction regression (same time column name).
    #[arg(long, requires_all = ["friction_torque", "friction_position"])]
    pub friction_csv: Option<PathBuf>,
    /// Friction record: torque column, N m.
    #[arg(long)]
    pub friction_torque: Option<String>,
    /// Friction record: motor-angle column, rad.
    #[arg(long)]
    pub friction_position: Option<String>,
    /// No progress bars or log lines.
    #[arg(long)]
    pub quiet: bool,
}

fn parse_pair(s: &str) -> Result<(f64, f64), String> {
    let (a, b) = s
        .split_once(',')
        .ok_or_else(|| format!("expected MIN,MAX, got `{s}`"))?;
    let a: f64 = a
        .trim()
        .parse()
        .map_err(|_| format!("`{a}` is not a number"))?;
    let b: f64 = b
        .trim()
        .parse()
        .map_err(|_| format!("`{b}` is not a number"))?;
    Ok((a, b))
}

fn load_plant(args: &Args) -> anyhow::Result<Plant> {
    let p = std::path::Path::new(&args.plant);
    let mut plant = if args.plant.ends_with(".toml") || p.exists() {
        rigs::load_toml(p)?
    } else {
        rigs::builtin(&args.plant, args.payload)?
    };
    if let (Some(tilt), Plant::Physical(pp)) = (args.tilt, &mut plant) {
        pp.tilt_rad = tilt.to_radians();
    }
    plant.validate()?;
    Ok(plant)
}

/// Commission from recorded data (`--csv`).
fn run_recorded(args: &Args, csv: &std::path::Path, knobs: &DesignKnobs) -> anyhow::Result<()> {
    let (Some(input), Some(output)) = (&args.input, &args.output) else {
        anyhow::bail!("--csv needs --input and --output column names");
    };
    let id = identify_recorded(&RecordedExcitation {
        csv,
        time: &args.time,
        input,
        output,
        actual_torque: args.actual_torque.as_deref(),
        period_samples: args.period_samples,
        skip_periods: args.skip_periods,
        etfe: EtfeConfig::default(),
        fit: FitConfig {
            theta_e: args.inertia,
            free_inertia: args.inertia.is_none(),
            i_t: args.transmission,
            ..FitConfig::default()
        },
    })?;
    let friction = match (
        &args.friction_csv,
        &args.friction_torque,
        &args.friction_position,
    ) {
        (Some(f), Some(tq), Some(pos)) => {
            let cols = read_csv_columns(f, &[args.time.as_str(), pos.as_str(), tq.as_str()])?;
            let column = |n: &str| {
                cols.column(n)
                    .ok_or_else(|| anyhow::anyhow!("{}: missing column `{n}`", f.display()))
            };
            Some(
                identify_from_motion(
                    column(&args.time)?,
                    column(pos)?,
                    column(tq)?,
                    &MotionFrictionConfig::default(),
                )
                .with_context(|| f.display().to_string())?,
            )
        }
        _ => None,
    };
    let run = commission_recorded(id, friction, knobs, 2e-3)?;
    let source = csv.display().to_string();
    let provenance = Provenance::of_this_process(None);
    let (json, report) = recorded_outputs(&run, &source, Some(&provenance))?;
    let friction = run.friction.clone().unwrap_or_default();
    let toml = controller_toml(&run.design, &friction, args.torque_limit)?;
    let html = render_html(&report)?;
    let data = recorded_data_files(&run)?;
    let mut files = write_outputs(&args.out, &json, &toml, &html)?;
    files.extend(write_data_files(&args.out, &data)?);
    if !args.quiet {
        for line in &run.log {
            eprintln!("{line}");
        }
        for f in files {
            println!("wrote {}", f.display());
        }
    }
    Ok(())
}

/// Write the data files beside the report (`frf.csv`, ...), each atomically.
pub fn write_data_files(
    dir: &std::path::Path,
    files: &[(String, String)],
) -> anyhow::Result<Vec<PathBuf>> {
    let mut out = Vec::new();
    for (name, text) in files {
        let p = dir.join(name);
        beltune::io::write_atomic(&p, text.as_bytes())?;
        out.push(p);
    }
    Ok(out)
}

/// Run the subcommand.
pub fn run(args: Args) -> anyhow::Result<()> {
    if let Some(csv) = args.csv.clone() {
        let knobs = args.knobs.knobs()?;
        return run_recorded(&args, &csv, &knobs);
    }
    let plant = load_plant(&args)?;
    let ds = DataSheet::for_plant(&plant, args.start_position, args.travel_window);
    let mut cfg = CommissioningConfig {
        knobs: args.knobs.knobs()?,
        ..CommissioningConfig::default()
    };
    cfg.excitation.fixed_amplitude_nm = args.excitation_amplitude;
    if let Some(n) = args.prbs_order {
        cfg.excitation.prbs_order = n;
    }
    if let Some(p) = args.prbs_clock {
        cfg.excitation.clock_period = p;
    }
    let sim_cfg = SimConfig {
        seed: args.seed,
        initial_cart_position_m: Some(args.start_position),
        ..SimConfig::default()
    };
    let mut axis = SimAxis::new(&plant, sim_cfg)?;
    let mut progress = BarProgress::new(args.quiet);
    let started = Instant::now();
    let run = commission(&mut axis, &ds, &cfg, &mut progress).context("commissioning stopped")?;
    let truth_params = plant.linearize(run.identification_position_m)?;
    let friction = plant.friction_totals();
    let truth = Truth {
        f_r_hz: truth_params.f_r_hz(),
        f_z_hz: truth_params.f_z_hz(),
        theta_e: truth_params.theta_e,
        m_c: truth_params.m_c,
        c: truth_params.c,
        dead_time_s: plant.dead_time_s(),
        viscous: friction.viscous_nm_s_per_rad,
        coulomb: friction.coulomb_nm,
    };
    let name = args.plant.clone();
    let json = commissioning_json(&run, &name, Some(truth.clone()));
    let toml = controller_toml(&run.design, &run.friction, ds.torque_max_nm)?;
    let before = match &plant {
        Plant::Physical(p) => Some(p.linearize(run.identification_position_m)?),
        Plant::Linear(_) => None,
    };
    let provenance = Provenance::of_this_process(Some(args.seed));
    let report = build_report(
        &run,
        &name,
        before.as_ref(),
        Some(&truth),
        Some(&provenance),
    )?;
    let html = render_html(&report)?;
    let data = data_files(&run, &report)?;
    let mut files = write_outputs(&args.out, &json, &toml, &html)?;
    files.extend(write_data_files(&args.out, &data)?);
    if !args.quiet {
        let v = &run.validation;
        println!(
            "identified: f_r {:.2} Hz (truth {:.2}), f_z {:.2} Hz (truth {:.2}), m_c {:.2} kg, c {:.1} kN/m, dead time {:.2} ms",
            run.identified.f_r_hz,
            truth.f_r_hz,
            run.identified.f_z_hz,
            truth.f_z_hz,
            run.identified.m_c,
            run.identified.c / 1e3,
            run.identified.dead_time_s * 1e3
        );
        println!(
            "controller: K_P {:.4} N m s/rad, K_I {:.3} N m/rad, K_PP {:.2} 1/s",
            run.design.k_p, run.design.k_i, run.design.k_pp
        );
        println!(
            "validation 0 -> 500 mm, max cart error: none {:.3} mm, linear {:.3} mm, nonlinear {:.3} mm (static {:.1} um)",
            v.none.max_tracking_error_m * 1e3,
            v.linear.max_tracking_error_m * 1e3,
            v.nonlinear.max_tracking_error_m * 1e3,
            v.nonlinear.static_error_m * 1e6
        );
        println!(
            "axis busy {:.1} s, computation {:.2} s, wall time {:.1} s",
            run.experiment_time_s,
            run.computation_time_s,
            started.elapsed().as_secs_f64()
        );
        for f in files {
            println!("wrote {}", f.display());
        }
    }
    Ok(())
}
