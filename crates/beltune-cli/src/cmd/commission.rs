//! `beltune commission`: the one-command self-commissioning of the built-in
//! simulated axis (or a plant file), with progress bars, safety supervision,
//! validation and the report; or, with `--csv`, from data recorded on a real
//! drive (the stages that need the axis are skipped).
//!
//! Output: progress bars and stage lines on stderr (not with `--quiet`), the
//! summary on stdout (text, or JSON with `--json`: `summary.rs`), and after a
//! safety stop a diagnostic (`diagnostic.rs`). The flags are grouped under
//! the headings of `help::COMMISSION_HEADINGS`; `--config FILE.toml`
//! supplies them from a file (`config.rs`).

use super::summary::{
    ControllerSummary, IdentifiedSummary, Summary, TruthSummary, ValidationSummary,
};
use super::verdict::Verdict;
use crate::exit::{ExitStatus, Failure};
use crate::progress::BarProgress;
use anyhow::Context;
use beltune::commission::recorded::commission_recorded;
use beltune::commission::result::Truth;
use beltune::commission::{commission, CommissioningConfig, DataSheet};
use beltune::design::DesignKnobs;
use beltune::ident::{
    identify_from_motion, identify_recorded, read_csv_columns, EtfeConfig, FitConfig, ModelUnits,
    MotionFrictionConfig, RecordedExcitation,
};
use beltune::model::rigs::Plant;
use beltune::record::folder::{
    build_report, commissioning_json, controller_toml, data_files, recorded_data_files,
    recorded_outputs,
};
use beltune::record::folder::{write_outputs_with_data, AxisRecord, OutputTarget};
use beltune::record::provenance::Provenance;
use beltune::report::render_html;
use beltune::sim::{SimAxis, SimConfig};
use beltune_ethercat::master::BusAxis;
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
    /// Built-in plant name (egc70, sim-a, sim-b, sim-c) or a plant TOML file
    /// (a built-in name always means the built-in plant; write `./egc70` for a file).
    #[arg(long)]
    pub plant: Option<String>,
    /// Payload on the cart, kg (physical plants: egc70 default 11.2 kg, or a plant file).
    #[arg(long, allow_negative_numbers = true)]
    pub payload: Option<f64>,
    /// Tilt of the axis, degrees (0 horizontal, 90 vertical; within -90..90).
    #[arg(long, allow_negative_numbers = true)]
    pub tilt: Option<f64>,
    /// Seed of the simulated measurement noise: another seed, another
    /// realization of the plant's noise (default 1).
    #[arg(long, allow_negative_numbers = true)]
    pub seed: Option<u64>,
    /// Standard deviation of the simulated actual-torque noise, N m (default:
    /// the plant's `[noise] torque_nm`; 0 for none).
    #[arg(long, value_name = "NM", allow_negative_numbers = true)]
    pub torque_noise: Option<f64>,
    /// Standard deviation of the simulated motor-encoder noise before
    /// quantization, counts (default: the plant's `[noise] encoder_counts`).
    #[arg(long, value_name = "COUNTS", allow_negative_numbers = true)]
    pub encoder_noise: Option<f64>,
    /// Output folder, written exactly (new or empty; a previous result needs
    /// --force). Without it: a new timestamped folder under commissioning/ per
    /// run, with commissioning/latest pointing at the newest.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Replace the result already in --out (the three files are replaced together).
    #[arg(long, requires = "out")]
    pub force: bool,
    #[command(flatten)]
    pub knobs: super::knobs::KnobArgs,
    /// Travel window MIN,MAX in m (default: inside the stroke).
    #[arg(long, value_parser = parse_pair, allow_hyphen_values = true)]
    pub travel_window: Option<(f64, f64)>,
    /// Cart position at start (the homing result), m (default 0.05).
    #[arg(long, allow_negative_numbers = true)]
    pub start_position: Option<f64>,
    /// Fixed PRBS amplitude A_PRBS in N m (values +-A/2) instead of the automatic search.
    #[arg(long, allow_negative_numbers = true)]
    pub excitation_amplitude: Option<f64>,
    /// PRBS order n_PRBS (default 9; 2..=18).
    #[arg(long, value_parser = clap::value_parser!(u32).range(2..=MAX_PRBS_ORDER as i64))]
    pub prbs_order: Option<u32>,
    /// PRBS clock period P_PRBS in ms (default 1.6 ms = 16 samples at 10 kHz;
    /// rounded to whole cycles of the axis).
    #[arg(long, allow_negative_numbers = true)]
    pub prbs_clock_ms: Option<f64>,
    /// Commission from recorded data instead of a plant: CSV of a periodic
    /// excitation (header row). Skips the stages that need the axis.
    #[arg(long, requires_all = ["input", "output"])]
    pub csv: Option<PathBuf>,
    /// Recorded data: time column, s (default t_s).
    #[arg(long)]
    pub time: Option<String>,
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
    #[arg(long, value_parser = parse_period)]
    pub period_samples: Option<usize>,
    /// Recorded data: leading periods discarded as transient (default 1).
    #[arg(long, value_parser = parse_skip)]
    pub skip_periods: Option<usize>,
    /// Recorded data: data-sheet Theta_e in kg m^2 (fitted when not given).
    #[arg(long, allow_negative_numbers = true)]
    pub inertia: Option<f64>,
    /// Recorded data: transmission i_t in m/rad (default 1).
    #[arg(long, allow_negative_numbers = true)]
    pub transmission: Option<f64>,
    /// Recorded data (required): the drive's torque limit, in the unit of the
    /// input column (N m, or A with --current-units), written to controller.toml.
    /// The record's peak is not a limit, so there is no default.
    #[arg(long, allow_negative_numbers = true)]
    pub torque_limit: Option<f64>,
    /// Recorded data: the input column is a motor current in A (torque constant
    /// unknown): model, gains and limits in current units (A s/rad, A).
    #[arg(long)]
    pub current_units: bool,
    /// Recorded data: a CSV of any motion for the friction regression (same time column name).
    #[arg(long, requires_all = ["friction_torque", "friction_position"])]
    pub friction_csv: Option<PathBuf>,
    /// Friction record: torque column, N m.
    #[arg(long)]
    pub friction_torque: Option<String>,
    /// Friction record: motor-angle column, rad.
    #[arg(long)]
    pub friction_position: Option<String>,
    /// Commission a drive on EtherCAT: the network interface of the bus (a
    /// CiA 402 drive in cyclic synchronous torque mode; raw sockets need root
    /// or CAP_NET_RAW). `--plant` and `--payload` then only give the data
    /// sheet (inertia, transmission, moving mass, travel, torque limit).
    #[arg(long, value_name = "IFACE", conflicts_with = "csv")]
    pub ethercat: Option<String>,
    /// EtherCAT: position of the drive on the bus (0 = the first SubDevice).
    #[arg(long, default_value_t = 0, requires = "ethercat")]
    pub subdevice: usize,
    /// EtherCAT: bus cycle (the drive's SYNC0 period), us.
    #[arg(long, default_value_t = 1000, requires = "ethercat")]
    pub cycle_us: u32,
    /// EtherCAT: how long to wait for a frame, ms (3 consecutive lost frames
    /// end the commissioning with a quick stop).
    #[arg(long, default_value_t = 10.0, requires = "ethercat")]
    pub frame_timeout_ms: f64,
    /// EtherCAT: run the bus thread under SCHED_FIFO at this priority
    /// (1-99; root or CAP_SYS_NICE), so that a busy host does not make it
    /// miss cycles (the computation threads keep normal scheduling).
    #[arg(long, value_name = "PRIO", requires = "ethercat")]
    pub realtime_priority: Option<u8>,
    /// EtherCAT: do not use distributed clocks even where the drive offers
    /// them (SM-synchronous: the drive runs a cycle per process-data frame).
    #[arg(long, requires = "ethercat")]
    pub no_dc: bool,
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

/// Largest `--prbs-order`: 2^18 - 1 bits.
pub const MAX_PRBS_ORDER: u32 = 18;
/// Largest PRBS clock period (`--prbs-clock-ms`), samples of the axis.
pub const MAX_PRBS_CLOCK: u32 = 4096;
/// Most samples in one PRBS period (`(2^n - 1) P`): 2^22, 419 s at 100 us.
pub const MAX_PRBS_PERIOD_SAMPLES: u64 = 1 << 22;
/// Largest `--skip-periods`.
pub const MAX_SKIP_PERIODS: usize = 1000;
/// Largest `--torque-limit` (N m or A).
pub const MAX_TORQUE_LIMIT: f64 = 1e4;

pub fn parse_period(s: &str) -> Result<usize, String> {
    let max = beltune::ident::record::MAX_CSV_ROWS;
    let n: usize = s
        .parse()
        .map_err(|_| format!("`{s}` is not a whole number of samples"))?;
    if !(4..=max).contains(&n) {
        return Err(format!("must lie in 4..={max} samples"));
    }
    Ok(n)
}

pub fn parse_skip(s: &str) -> Result<usize, String> {
    let n: usize = s
        .parse()
        .map_err(|_| format!("`{s}` is not a whole number of periods"))?;
    if n > MAX_SKIP_PERIODS {
        return Err(format!("must lie in 0..={MAX_SKIP_PERIODS}"));
    }
    Ok(n)
}

fn parse_pair(s: &str) -> Result<(f64, f64), String> {
    let (a, b) = s
        .split_once(',')
        .ok_or_else(|| format!("expected MIN,MAX, got `{s}`"))?;
    let num = |x: &str| -> Result<f64, String> {
        let v: f64 = x
            .trim()
            .parse()
            .map_err(|_| format!("`{}` is not a number", x.trim()))?;
        if v.is_finite() {
            Ok(v)
        } else {
            Err(format!("`{}` is not finite", x.trim()))
        }
    };
    Ok((num(a)?, num(b)?))
}

/// A bad-input error (exit status 2) with one line of text.
fn bad(msg: impl Into<String>) -> anyhow::Error {
    anyhow::Error::new(Failure::new(ExitStatus::BadInput, msg))
}

/// Error if any flag of the other mode was given: nothing is silently ignored.
fn check_mode_flags(args: &Args) -> anyhow::Result<()> {
    let recorded_only: [(&str, bool); 12] = [
        ("--time", args.time.is_some()),
        ("--input", args.input.is_some()),
        ("--output", args.output.is_some()),
        ("--actual-torque", args.actual_torque.is_some()),
        ("--period-samples", args.period_samples.is_some()),
        ("--skip-periods", args.skip_periods.is_some()),
        ("--inertia", args.inertia.is_some()),
        ("--transmission", args.transmission.is_some()),
        ("--torque-limit", args.torque_limit.is_some()),
        ("--current-units", args.current_units),
        ("--friction-csv", args.friction_csv.is_some()),
        (
            "--friction-torque/--friction-position",
            args.friction_torque.is_some() || args.friction_position.is_some(),
        ),
    ];
    let simulated_only: [(&str, bool); 14] = [
        ("--plant", args.plant.is_some()),
        ("--payload", args.payload.is_some()),
        ("--tilt", args.tilt.is_some()),
        ("--seed", args.seed.is_some()),
        ("--torque-noise", args.torque_noise.is_some()),
        ("--encoder-noise", args.encoder_noise.is_some()),
        ("--travel-window", args.travel_window.is_some()),
        ("--start-position", args.start_position.is_some()),
        (
            "--excitation-amplitude",
            args.excitation_amplitude.is_some(),
        ),
        ("--prbs-order", args.prbs_order.is_some()),
        ("--prbs-clock-ms", args.prbs_clock_ms.is_some()),
        ("--following-error-max", args.following_error_max.is_some()),
        (
            "--max-tracking-error",
            args.limits.max_tracking_error.is_some(),
        ),
        ("--max-static-error", args.limits.max_static_error.is_some()),
    ];
    let (given, mode, hint): (Vec<&str>, _, _) = if args.csv.is_some() {
        (
            simulated_only.iter().filter(|f| f.1).map(|f| f.0).collect(),
            "a plant",
            "they do not apply to recorded data (--csv)",
        )
    } else {
        (
            recorded_only.iter().filter(|f| f.1).map(|f| f.0).collect(),
            "recorded data (--csv)",
            "they would be ignored when commissioning a plant",
        )
    };
    if !given.is_empty() {
        return Err(bad(format!(
            "{} apply only to {mode}; {hint}",
            given.join(", ")
        )));
    }
    Ok(())
}

/// A numeric flag that must be finite and within `lo..=hi` (`lo` exclusive when `open`).
fn check_flag(flag: &str, v: Option<f64>, lo: f64, hi: f64, open: bool) -> anyhow::Result<()> {
    if let Some(v) = v {
        let low_ok = if open { v > lo } else { v >= lo };
        if !(v.is_finite() && low_ok && v <= hi) {
            let range = if open {
                format!("({lo}, {hi}]")
            } else {
                format!("[{lo}, {hi}]")
            };
            let v = beltune::error::short_number(v);
            return Err(bad(format!("{flag} {v} is out of range {range}")));
        }
    }
    Ok(())
}

fn load_plant(args: &Args) -> anyhow::Result<Plant> {
    let name = args.plant.as_deref().unwrap_or("egc70");
    check_flag("--tilt", args.tilt, -90.0, 90.0, false)?;
    let mut plant = super::plant::resolve_plant(name, args.payload)?;
    if let Some(tilt) = args.tilt {
        match &mut plant {
            Plant::Physical(pp) => pp.tilt_rad = tilt.to_radians(),
            Plant::Linear(_) => {
                return Err(bad(format!(
                "--tilt applies to physical plants only; `{name}` is a linear set without gravity"
            )))
            }
        }
    }
    plant.validate()?;
    Ok(plant)
}

/// Where the result goes: `--out DIR` exactly, or the history folder.
fn target(args: &Args) -> OutputTarget {
    match &args.out {
        Some(dir) => OutputTarget::Exact {
            dir: dir.clone(),
            force: args.force,
        },
        None => OutputTarget::History {
            root: PathBuf::from(HISTORY_ROOT),
        },
    }
}

/// The history folder without `--out`.
pub const HISTORY_ROOT: &str = "commissioning";

/// Refuse an output folder that holds one of the input files (it would be replaced).
fn check_inputs_outside_output(args: &Args) -> anyhow::Result<()> {
    let Some(out) = &args.out else { return Ok(()) };
    let Ok(out) = std::fs::canonicalize(out) else {
        return Ok(());
    };
    for input in [&args.csv, &args.friction_csv].into_iter().flatten() {
        if let Ok(i) = std::fs::canonicalize(input) {
            if i.starts_with(&out) {
                return Err(bad(format!(
                    "--out {} holds the input {}; the result would replace it",
                    out.display(),
                    input.display()
                )));
            }
        }
    }
    Ok(())
}

/// Commission from recorded data (`--csv`).
fn run_recorded(args: &Args, csv: &std::path::Path, knobs: &DesignKnobs) -> anyhow::Result<()> {
    let (Some(input), Some(output)) = (&args.input, &args.output) else {
        return Err(bad("--csv needs --input and --output column names"));
    };
    let units = if args.current_units {
        ModelUnits::Current
    } else {
        ModelUnits::Torque
    };
    check_flag("--inertia", args.inertia, 0.0, 1e3, true)?;
    check_flag("--transmission", args.transmission, 0.0, 1e3, true)?;
    check_flag(
        "--torque-limit",
        args.torque_limit,
        0.0,
        MAX_TORQUE_LIMIT,
        true,
    )?;
    let time = args.time.clone().unwrap_or_else(|| "t_s".to_string());
    let unit = if args.current_units { "A" } else { "N m" };
    let Some(torque_limit) = args.torque_limit else {
        return Err(bad(format!(
            "--csv needs --torque-limit: the drive's torque limit in {unit} (the record's peak is not a limit)"
        )));
    };
    let id = identify_recorded(&RecordedExcitation {
        csv,
        time: &time,
        input,
        output,
        actual_torque: args.actual_torque.as_deref(),
        period_samples: args.period_samples,
        skip_periods: args.skip_periods.unwrap_or(1),
        etfe: EtfeConfig::default(),
        fit: FitConfig {
            theta_e: args.inertia,
            free_inertia: args.inertia.is_none(),
            i_t: args.transmission.unwrap_or(1.0),
            units,
            ..FitConfig::default()
        },
    })?;
    let friction = match (
        &args.friction_csv,
        &args.friction_torque,
        &args.friction_position,
    ) {
        (Some(f), Some(tq), Some(pos)) => {
            let cols = read_csv_columns(f, &[time.as_str(), pos.as_str(), tq.as_str()])?;
            let column = |n: &str| {
                cols.column(n)
                    .ok_or_else(|| anyhow::anyhow!("{}: missing column `{n}`", f.display()))
            };
            Some(
                identify_from_motion(
                    column(&time)?,
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
    let run = commission_recorded(id, friction, knobs, args.knobs.rule(), 2e-3)?;
    let source = csv.display().to_string();
    let provenance = Provenance::of_this_process(None);
    let (json, report) = recorded_outputs(&run, &source, torque_limit, provenance.clone())?;
    let friction = run.friction.clone().unwrap_or_default();
    for (name, v) in [
        ("Coulomb friction", friction.coulomb_nm),
        ("holding torque", friction.holding_torque_nm),
    ] {
        if !(v.is_finite() && v.abs() <= torque_limit) {
            return Err(bad(format!(
                "{}: the fitted {name} {v:.4e} exceeds the torque limit {torque_limit}; \
                 check the friction record's units",
                args.friction_csv
                    .as_ref()
                    .map_or(String::from("friction"), |p| p.display().to_string())
            )));
        }
    }
    let toml = controller_toml(
        &run.design,
        &friction,
        None,
        torque_limit,
        units,
        provenance,
    )?;
    let html = render_html(&report)?;
    let data = recorded_data_files(&run)?;
    let files = write_outputs_with_data(&target(args), &json, &toml, &html, &data)?;
    super::diagnostic::remove_stale(&target(args))?;
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
/// diagnostic written next to where the results would have gone (the status
/// stays that of the library error: 3).
fn stopped(e: beltune::Error, progress: &mut BarProgress, args: &Args) -> anyhow::Error {
    let stop = progress.take_safety_stop();
    let e = anyhow::Error::new(e);
    let Some(stop) = stop else {
        return e.context("commissioning stopped");
    };
    let reason = crate::exit::one_line(&e);
    let seed = args.ethercat.is_none().then(|| args.seed.unwrap_or(1));
    match super::diagnostic::write(&target(args), &stop, &reason, seed) {
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

/// The summary of a run on an axis, its verdict against `limits` decides
/// the status (0, or 5 when the validation misses a limit).
struct AxisRun<'a> {
    source: String,
    run: &'a beltune::commission::Commissioning,
    truth: Option<&'a Truth>,
    validation_start_m: f64,
    validation_target_m: f64,
    started: Instant,
    files: Vec<PathBuf>,
}

/// Print the summary of a run on an axis and return its status as the result.
fn finish_axis_run(r: AxisRun, limits: &super::verdict::Limits, json: bool) -> anyhow::Result<()> {
    let verdict: Verdict = super::verdict::judge(&r.run.validation.nonlinear, limits);
    let status = if verdict.passed {
        ExitStatus::Success
    } else {
        ExitStatus::LimitsNotMet
    };
    let failures = verdict.failures();
    let summary = Summary {
        schema: super::summary::SCHEMA,
        source: r.source,
        status: if verdict.passed {
            "ok"
        } else {
            "limits_not_met"
        },
        exit_code: status.code(),
        identified: IdentifiedSummary::of(&r.run.identified),
        truth: r.truth.map(TruthSummary::of),
        controller: ControllerSummary::of(&r.run.design),
        validation: Some(ValidationSummary::of(
            &r.run.validation,
            r.validation_start_m,
            r.validation_target_m,
        )),
        verdict: Some(verdict),
        axis_busy_s: Some(r.run.experiment_time_s),
        computation_s: r.run.computation_time_s,
        wall_time_s: r.started.elapsed().as_secs_f64(),
        files: r.files,
        record_units: false,
    };
    print_summary(&summary, json)?;
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

/// An EtherCAT bus to commission on instead of the raw socket of
/// `--ethercat IFACE` (tests: the virtual drive in-process).
pub struct Bus<'a> {
    /// What the summary calls the bus (e.g. `EtherCAT eth0`).
    pub label: String,
    /// Open the axis with the master settings of the command line.
    #[allow(clippy::type_complexity)]
    pub open: Box<
        dyn FnOnce(
                beltune_ethercat::master::MasterConfig,
            ) -> Result<Box<dyn BusAxis + 'a>, beltune_ethercat::Error>
            + 'a,
    >,
}

/// Run the subcommand.
pub fn run(args: Args) -> anyhow::Result<()> {
    run_inner(args, None)
}

/// Run `commission --ethercat ...` on `bus` instead of the raw socket of the
/// interface (whose name is then ignored).
pub fn run_on_bus(args: Args, bus: Bus<'_>) -> anyhow::Result<()> {
    if args.ethercat.is_none() {
        return Err(bad("run_on_bus needs --ethercat".to_string()));
    }
    run_inner(args, Some(bus))
}

fn run_inner(args: Args, bus: Option<Bus<'_>>) -> anyhow::Result<()> {
    check_mode_flags(&args)?;
    check_inputs_outside_output(&args)?;
    let limits = args.limits.limits()?;
    if let Some(csv) = args.csv.clone() {
        let knobs = args.knobs.knobs()?;
        return run_recorded(&args, &csv, &knobs);
    }
    let plant = load_plant(&args)?;
    check_flag(
        "--excitation-amplitude",
        args.excitation_amplitude,
        0.0,
        plant.info().torque_max_nm,
        true,
    )?;
    let order = args.prbs_order.unwrap_or(9);
    let ts_s = plant.info().ts_s;
    let clock_limit_ms = f64::from(MAX_PRBS_CLOCK) * ts_s * 1e3;
    check_flag(
        "--prbs-clock-ms",
        args.prbs_clock_ms,
        0.0,
        clock_limit_ms,
        true,
    )?;
    let mut excitation = CommissioningConfig::default().excitation;
    if let Some(ms) = args.prbs_clock_ms {
        excitation.clock_period_s = ms * 1e-3;
    }
    let clock = excitation.clock_samples(ts_s);
    let period = ((1u64 << order) - 1) * u64::from(clock);
    if period > MAX_PRBS_PERIOD_SAMPLES {
        return Err(bad(format!(
            "--prbs-order {order} with a PRBS clock of {clock} samples makes a period of {period} \
             samples (limit {MAX_PRBS_PERIOD_SAMPLES}); lower one of them"
        )));
    }
    let start_position = args.start_position.unwrap_or(0.05);
    beltune::commission::check_travel_window(&plant, args.travel_window)?;
    let ds = DataSheet::for_plant(&plant, start_position, args.travel_window);
    let mut cfg = CommissioningConfig {
        knobs: args.knobs.knobs()?,
        design_rule: args.knobs.rule(),
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
    if let Some(bus) = bus {
        return run_ethercat(&args, bus, &ds, &cfg, &limits);
    }
    if let Some(interface) = args.ethercat.clone() {
        use beltune_ethercat::master::wire::RawSocket;
        use beltune_ethercat::master::{EthercatAxis, Storage};
        let storage = Storage::new();
        let bus = Bus {
            label: format!("EtherCAT {interface}"),
            open: Box::new(|master| {
                let axis = EthercatAxis::open(&storage, master, |tx, rx| {
                    RawSocket::open(&interface, tx, rx)
                })?;
                Ok(Box::new(axis) as Box<dyn BusAxis>)
            }),
        };
        return run_ethercat(&args, bus, &ds, &cfg, &limits);
    }
    let plant_noise = plant.noise();
    let noise = beltune::model::MeasurementNoise {
        torque_nm: args.torque_noise.unwrap_or(plant_noise.torque_nm),
        encoder_counts: args.encoder_noise.unwrap_or(plant_noise.encoder_counts),
    };
    noise.validate()?;
    let sim_cfg = SimConfig {
        seed: args.seed.unwrap_or(1),
        noise: Some(noise),
        initial_cart_position_m: Some(start_position),
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
    let name = args.plant.clone().unwrap_or_else(|| "egc70".to_string());
    let provenance = Provenance::of_this_process(Some(args.seed.unwrap_or(1)));
    let axis_record = AxisRecord::simulated(&name, &plant, start_position, args.seed.unwrap_or(1));
    let json = commissioning_json(
        &run,
        &name,
        Some(truth.clone()),
        axis_record,
        provenance.clone(),
    );
    let toml = controller_toml(
        &run.design,
        &run.friction,
        Some(&run.target_stiffness),
        ds.torque_max_nm,
        ModelUnits::Torque,
        provenance,
    )?;
    let before = match &plant {
        Plant::Physical(p) => Some(p.linearize(run.identification_position_m)?),
        Plant::Linear(_) => None,
    };
    let report = build_report(
        &run,
        &name,
        before.as_ref(),
        Some(&truth),
        Some(&json.provenance),
    )?;
    let html = render_html(&report)?;
    let data = data_files(&run, &report)?;
    let files = write_outputs_with_data(&target(&args), &json, &toml, &html, &data)?;
    super::diagnostic::remove_stale(&target(&args))?;
    finish_axis_run(
        AxisRun {
            source: name,
            run: &run,
            truth: Some(&truth),
            validation_start_m: cfg.validation.start_m,
            validation_target_m: cfg.validation.target_m,
            started,
            files,
        },
        &limits,
        args.json,
    )
}

/// Commission the drive on an EtherCAT bus (`--ethercat IFACE`).
fn run_ethercat(
    args: &Args,
    bus: Bus<'_>,
    ds: &DataSheet,
    cfg: &CommissioningConfig,
    limits: &super::verdict::Limits,
) -> anyhow::Result<()> {
    use beltune_ethercat::master::MasterConfig;
    if !(args.frame_timeout_ms.is_finite() && (0.1..=1000.0).contains(&args.frame_timeout_ms)) {
        return Err(anyhow::Error::new(crate::exit::Failure::new(
            crate::exit::ExitStatus::BadInput,
            format!(
                "--frame-timeout-ms {} is outside 0.1 ..= 1000",
                args.frame_timeout_ms
            ),
        )));
    }
    if let Some(p) = args.realtime_priority {
        // this thread runs the bus; the computation threads it starts run normally
        beltune_ethercat::sched::set_realtime_priority(p)
            .map_err(|e| bad(format!("--realtime-priority: {e}")))?;
    }
    let master = MasterConfig {
        subdevice: args.subdevice,
        cycle_s: f64::from(args.cycle_us) * 1e-6,
        frame_timeout_s: args.frame_timeout_ms * 1e-3,
        use_dc: !args.no_dc,
        ..MasterConfig::default()
    };
    let label = bus.label;
    let mut axis = (bus.open)(master).with_context(|| label.clone())?;
    let id = axis.identity().clone();
    let sc = axis.scaling();
    if !args.quiet {
        let line = format!(
            "SubDevice {} of {}: {} (vendor {:#010x}, product {:#010x}, rev {:#010x}, serial {}), {}; rated torque {:.3} N m, limit {:.3} N m, {} increments per {} rev{}",
            args.subdevice,
            id.subdevices,
            id.name,
            id.vendor_id,
            id.product_code,
            id.revision,
            id.serial,
            if id.dc { "SYNC0" } else { "no distributed clocks" },
            sc.rated_torque_nm,
            sc.torque_limit_nm(),
            sc.encoder_increments,
            sc.motor_revolutions,
            if sc.load_m_per_inc.is_some() { ", load-side encoder" } else { "" }
        );
        for l in crate::progress::stage_lines(&label, &line) {
            eprintln!("{l}");
        }
    }
    let mut progress = BarProgress::new(args.quiet);
    let started = Instant::now();
    let run = commission(axis.as_axis(), ds, cfg, &mut progress);
    // leave the drive switched off and at rest, also after a stop
    let _ = axis.stop_drive();
    let (exchanges, missed) = axis.cycle_counts();
    drop(axis);
    if args.realtime_priority.is_some() {
        // the bus is closed: the report is no real-time work
        beltune_ethercat::sched::set_normal();
    }
    if !args.quiet && id.dc {
        // a late exchange makes the drive apply the previous torque again
        let line = format!(
            "{exchanges} exchanges, {missed} SYNC0 cycles missed by the master (host scheduling)"
        );
        for l in crate::progress::stage_lines(&label, &line) {
            eprintln!("{l}");
        }
    }
    let run = run.map_err(|e| stopped(e, &mut progress, args))?;
    let name = format!("{label} SubDevice {} ({})", args.subdevice, id.name);
    let provenance = Provenance::of_this_process(None);
    let axis_record = AxisRecord::Ethercat {
        source: name.clone(),
    };
    let json = commissioning_json(&run, &name, None, axis_record, provenance.clone());
    let toml = controller_toml(
        &run.design,
        &run.friction,
        Some(&run.target_stiffness),
        ds.torque_max_nm,
        ModelUnits::Torque,
        provenance,
    )?;
    let report = build_report(&run, &name, None, None, Some(&json.provenance))?;
    let html = render_html(&report)?;
    let data = data_files(&run, &report)?;
    let files = write_outputs_with_data(&target(args), &json, &toml, &html, &data)?;
    super::diagnostic::remove_stale(&target(args))?;
    if !args.quiet {
        let note = if sc.load_m_per_inc.is_some() {
            "the cart errors are measured by the load-side encoder"
        } else {
            "the drive has no load-side encoder: the cart errors are motor-side"
        };
        for l in crate::progress::stage_lines("EtherCAT", note) {
            eprintln!("{l}");
        }
    }
    finish_axis_run(
        AxisRun {
            source: name,
            run: &run,
            truth: None,
            validation_start_m: cfg.validation.start_m,
            validation_target_m: cfg.validation.target_m,
            started,
            files,
        },
        limits,
        args.json,
    )
}
