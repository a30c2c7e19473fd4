//! `beltune commission`: the one-command self-commissioning of the built-in
//! simulated axis (or a plant file), with progress bars, safety supervision,
//! validation and the report; or, with `--csv`, from data recorded on a real
//! drive (the stages that need the axis are skipped).
//!
//! Output: progress bars and stage lines on stderr (not with `--quiet`), the
//! summary on stdout (text, or JSON with `--json`: `summary.rs`), and after a
//! safety stop a diagnostic file (`diagnostic.rs`). The flags are grouped
//! under the headings of `help::COMMISSION_HEADINGS`; `--config FILE.toml`
//! supplies them from a file (`config.rs`).

use super::summary::{
    ControllerSummary, IdentifiedSummary, Summary, TruthSummary, ValidationSummary,
};
use crate::exit::{ExitStatus, Failure};
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
    build_report, commissioning_json, controller_toml, recorded_outputs, write_outputs,
};
use beltune::procedure::recorded::commission_recorded;
use beltune::procedure::result::Truth;
use beltune::report::render_html;
use beltune::sim::{SimAxis, SimConfig};
use std::path::PathBuf;
use std::time::Instant;

/// Arguments of `beltune commission`.
#[derive(clap::Args)]
#[command(
    after_help = crate::help::commission_after_help(),
    args_override_self = true,
    mut_args = crate::help::with_commission_heading
)]
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
    /// PRBS clock period P_PRBS in ms (default 1.6 ms = 16 samples at 10 kHz;
    /// rounded to whole cycles of the axis).
    #[arg(long)]
    pub prbs_clock_ms: Option<f64>,
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
    /// No progress bars or stage lines (the summary is still printed).
    #[arg(long)]
    pub quiet: bool,
    /// Print the summary as JSON on stdout (keys: see the README).
    #[arg(long)]
    pub json: bool,
    /// Largest following error allowed in the closed-loop stages before the
    /// supervisor stops the axis, m (default 0.05).
    #[arg(long, value_name = "M")]
    pub following_error_max: Option<f64>,
    #[command(flatten)]
    pub limits: super::verdict::LimitArgs,
    #[command(flatten)]
    pub config: super::config::ConfigArgs,
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
    let started = Instant::now();
    let run = commission_recorded(id, friction, knobs, 2e-3)?;
    let source = csv.display().to_string();
    let (json, report) = recorded_outputs(&run, &source);
    let friction = run.friction.clone().unwrap_or_default();
    let toml = controller_toml(&run.design, &friction, args.torque_limit)?;
    let html = render_html(&report)?;
    let files = write_outputs(&args.out, &json, &toml, &html)?;
    super::diagnostic::remove_stale(&args.out)?;
    if !args.quiet {
        for line in &run.log {
            // "stage: summary", as the stage lines of a run on the axis
            let (stage, summary) = line.split_once(": ").unwrap_or(("", line));
            for l in crate::progress::stage_lines(stage, summary) {
                eprintln!("{l}");
            }
        }
    }
    let summary = Summary {
        schema: super::summary::SCHEMA,
        source,
        status: "ok",
        exit_code: ExitStatus::Success.code(),
        identified: IdentifiedSummary::of(&run.identified),
        truth: None,
        controller: ControllerSummary::of(&run.design),
        validation: None,
        verdict: None,
        axis_busy_s: None,
        computation_s: run.computation_time_s,
        wall_time_s: started.elapsed().as_secs_f64(),
        files,
        record_units: true,
    };
    print_summary(&summary, args.json)
}

/// Print the summary on stdout: text lines, or JSON.
fn print_summary(summary: &Summary, json: bool) -> anyhow::Result<()> {
    if json {
        println!("{}", summary.json()?);
    } else {
        for line in summary.lines() {
            println!("{line}");
        }
    }
    Ok(())
}

/// The error that ends a commissioning: after a safety stop, with the
/// diagnostic file written where the results would have gone (the status
/// stays that of the library error: 3).
fn stopped(e: beltune::Error, progress: &mut BarProgress, args: &Args) -> anyhow::Error {
    let stop = progress.take_safety_stop();
    let e = anyhow::Error::new(e);
    let Some(stop) = stop else {
        return e.context("commissioning stopped");
    };
    let reason = crate::exit::one_line(&e);
    match super::diagnostic::write(&args.out, &stop, &reason, Some(args.seed)) {
        Ok(files) => e.context(format!(
            "commissioning stopped in stage `{}` (diagnostic: {})",
            stop.stage,
            files[0].display()
        )),
        Err(w) => e.context(format!(
            "commissioning stopped in stage `{}` (the diagnostic could not be written: {})",
            stop.stage,
            crate::exit::one_line(&w)
        )),
    }
}

/// Run the subcommand.
pub fn run(args: Args) -> anyhow::Result<()> {
    if let Some(csv) = args.csv.clone() {
        let knobs = args.knobs.knobs()?;
        return run_recorded(&args, &csv, &knobs);
    }
    let limits = args.limits.limits()?;
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
    if let Some(p) = args.prbs_clock_ms {
        cfg.excitation.clock_period_s = p * 1e-3;
    }
    if let Some(e) = args.following_error_max {
        cfg.following_error_max_m = e;
    }
    let sim_cfg = SimConfig {
        seed: args.seed,
        initial_cart_position_m: Some(args.start_position),
        ..SimConfig::default()
    };
    let mut axis = SimAxis::new(&plant, sim_cfg)?;
    let mut progress = BarProgress::new(args.quiet);
    let started = Instant::now();
    let run = commission(&mut axis, &ds, &cfg, &mut progress)
        .map_err(|e| stopped(e, &mut progress, &args))?;
    let truth_params = plant.linearize(run.identification_position_m)?;
    let friction = plant.friction_totals();
    let truth = Truth {
        f_r_hz: truth_params.f_r_hz(),
        f_z_hz: truth_params.f_z_hz(),
        theta_e: truth_params.theta_e,
        m_c: truth_params.m_c,
        c: truth_params.c,
        dead_time_s: plant.dead_time_s(),
        viscous_nm_s_per_rad: friction.viscous_nm_s_per_rad,
        coulomb_nm: friction.coulomb_nm,
    };
    let name = args.plant.clone();
    let json = commissioning_json(&run, &name, Some(truth.clone()));
    let toml = controller_toml(&run.design, &run.friction, ds.torque_max_nm)?;
    let before = match &plant {
        Plant::Physical(p) => Some(p.linearize(run.identification_position_m)?),
        Plant::Linear(_) => None,
    };
    let report = build_report(&run, &name, before.as_ref(), Some(&truth));
    let html = render_html(&report)?;
    let files = write_outputs(&args.out, &json, &toml, &html)?;
    super::diagnostic::remove_stale(&args.out)?;
    let verdict = super::verdict::judge(&run.validation.nonlinear, &limits);
    let status = if verdict.passed {
        ExitStatus::Success
    } else {
        ExitStatus::LimitsNotMet
    };
    let failures = verdict.failures();
    let summary = Summary {
        schema: super::summary::SCHEMA,
        source: name,
        status: if verdict.passed {
            "ok"
        } else {
            "limits_not_met"
        },
        exit_code: status.code(),
        identified: IdentifiedSummary::of(&run.identified),
        truth: Some(TruthSummary::of(&truth)),
        controller: ControllerSummary::of(&run.design),
        validation: Some(ValidationSummary::of(
            &run.validation,
            cfg.validation.start_m,
            cfg.validation.target_m,
        )),
        verdict: Some(verdict),
        axis_busy_s: Some(run.experiment_time_s),
        computation_s: run.computation_time_s,
        wall_time_s: started.elapsed().as_secs_f64(),
        files,
        record_units: false,
    };
    print_summary(&summary, args.json)?;
    if status != ExitStatus::Success {
        return Err(anyhow::Error::new(Failure::new(
            status,
            format!(
                "the commissioning finished, but the validation misses its limits: {}",
                failures.join(", ")
            ),
        )));
    }
    Ok(())
}
