//! Everything `beltune commission` can check before the axis moves (or, with
//! `--csv`, before any fit starts), checked first: the mode's flags, the
//! output folder, the verdict's limits, the knobs, the plant, the data sheet
//! and its travel window, the excitation settings, the EtherCAT settings, the
//! recording's columns and the torque limit. A refusal here prints one line
//! and no stage line.

use super::Args;
use crate::exit::{ExitStatus, Failure};
use beltune::commission::{check_travel_window, CommissioningConfig, DataSheet};
use beltune::ident::csv_columns::{read_csv_header, require_columns};
use beltune::ident::ModelUnits;
use beltune::model::rigs::Plant;
use beltune::record::folder::OutputTarget;
use beltune::sim::SimConfig;
use std::path::PathBuf;

/// Largest `--prbs-order`: 2^18 - 1 bits.
pub const MAX_PRBS_ORDER: u32 = 18;
/// Largest PRBS clock period (`--prbs-clock-ms`), samples of the axis.
pub const MAX_PRBS_CLOCK: u32 = 4096;
/// Most samples in one PRBS period (`(2^n - 1) P`): 2^22, 419 s at 100 us.
pub const MAX_PRBS_PERIOD_SAMPLES: u64 = 1 << 22;
/// Largest `--skip-periods`.
pub const MAX_SKIP_PERIODS: usize = 1000;
/// The history folder without `--out`.
pub const HISTORY_ROOT: &str = "commissioning";
/// Longest network interface name Linux accepts (`IFNAMSIZ` less the NUL).
pub const MAX_INTERFACE_NAME_BYTES: usize = 15;

/// A run, checked: where its result goes, its configuration and its mode.
pub struct Plan {
    /// Where the result goes (checked to be writable as a result folder).
    pub target: OutputTarget,
    /// The commissioning's configuration (knobs, rule, limits, excitation).
    pub cfg: CommissioningConfig,
    /// What the run is made on.
    pub mode: Mode,
    /// The history database (checked, [`super::super::history::DbArgs::check`]).
    pub history: beltune::history::Location,
}

/// What a run is made on.
pub enum Mode {
    /// The simulated axis.
    Simulated(Box<Simulated>),
    /// A drive on EtherCAT (the plant gives the data sheet).
    Ethercat(Ethercat),
    /// A recording.
    Recorded(Recorded),
}

/// A simulated axis.
pub struct Simulated {
    /// The plant's name or file, as given.
    pub name: String,
    /// The plant.
    pub plant: Plant,
    /// Its data sheet.
    pub datasheet: DataSheet,
    /// The simulator's settings.
    pub sim: SimConfig,
}

/// A drive on EtherCAT.
pub struct Ethercat {
    /// The network interface.
    pub interface: String,
    /// The drive profile of `--drive-profile`, read and checked.
    pub drive_profile: Option<beltune_ethercat::profile::DriveProfile>,
    /// The data sheet (from `--plant`).
    pub datasheet: DataSheet,
    /// The master's settings.
    pub master: beltune_ethercat::master::MasterConfig,
}

/// A recording.
pub struct Recorded {
    /// The excitation record.
    pub csv: PathBuf,
    /// Its time column.
    pub time: String,
    /// Its input (torque or current) column.
    pub input: String,
    /// Its output (motor angle) column.
    pub output: String,
    /// The drive's torque limit, in the unit of the input column.
    pub torque_limit: f64,
    /// Torque or current units.
    pub units: ModelUnits,
    /// A motion record for the friction regression: (file, torque column, position column).
    pub friction: Option<(PathBuf, String, String)>,
}

/// A bad-input error (exit status 2) with one line of text.
pub fn bad(msg: impl Into<String>) -> anyhow::Error {
    anyhow::Error::new(Failure::new(ExitStatus::BadInput, msg))
}

/// Check everything before the run and say what it is.
pub fn plan(args: &Args) -> anyhow::Result<Plan> {
    check_mode_flags(args)?;
    check_inputs_outside_output(args)?;
    let target = target(args);
    target.check()?;
    let limits = args.limits.limits()?;
    let mut cfg = CommissioningConfig {
        knobs: args.knobs.knobs()?,
        design_rule: args.knobs.rule(),
        limits,
        compare_feedforward: args.compare_feedforward,
        ..CommissioningConfig::default()
    };
    if let Some(csv) = &args.csv {
        let recorded = recorded(args, csv)?;
        let history = args.history.check(&target)?;
        return Ok(Plan {
            target,
            cfg,
            mode: Mode::Recorded(recorded),
            history,
        });
    }
    let plant = load_plant(args)?;
    check_excitation(args, &plant, &mut cfg)?;
    if let Some(e) = args.following_error_max {
        if !(e.is_finite() && e > 0.0) {
            return Err(bad(format!(
                "--following-error-max must be a positive length in m, got {}",
                beltune::error::short_number(e)
            )));
        }
        cfg.following_error_max_m = e;
    }
    let start_position = args.start_position.unwrap_or(0.05);
    check_travel_window(&plant, args.travel_window)?;
    let datasheet = DataSheet::for_plant(&plant, start_position, args.travel_window);
    datasheet.validate()?;
    if let Some(interface) = &args.ethercat {
        let mode = Mode::Ethercat(ethercat(args, interface, datasheet)?);
        let history = args.history.check(&target)?;
        return Ok(Plan {
            target,
            cfg,
            mode,
            history,
        });
    }
    let plant_noise = plant.noise();
    let noise = beltune::model::MeasurementNoise {
        torque_nm: args.torque_noise.unwrap_or(plant_noise.torque_nm),
        encoder_counts: args.encoder_noise.unwrap_or(plant_noise.encoder_counts),
    };
    noise.validate()?;
    let sim = SimConfig {
        seed: args.seed.unwrap_or(1),
        noise: Some(noise),
        initial_cart_position_m: Some(start_position),
        ..SimConfig::default()
    };
    let history = args.history.check(&target)?;
    Ok(Plan {
        target,
        cfg,
        history,
        mode: Mode::Simulated(Box::new(Simulated {
            name: args.plant.clone().unwrap_or_else(|| "egc70".to_string()),
            plant,
            datasheet,
            sim,
        })),
    })
}

/// Where the result goes: `--out DIR` exactly, or the history folder.
pub fn target(args: &Args) -> OutputTarget {
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

/// Error if any flag of the other mode was given: nothing is silently ignored.
fn check_mode_flags(args: &Args) -> anyhow::Result<()> {
    let recorded_only: [(&str, bool); 14] = [
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
        ("--reference", args.closed_loop.reference.is_some()),
        ("--controller", args.closed_loop.controller.is_some()),
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
    // the EtherCAT flags apply to a bus only (a flag at its default value
    // changes nothing and is not told apart)
    let ethercat_only: [(&str, bool); 7] = match &default_args() {
        Some(d) => [
            ("--subdevice", args.subdevice != d.subdevice),
            ("--cycle-us", args.cycle_us != d.cycle_us),
            (
                "--frame-timeout-ms",
                args.frame_timeout_ms != d.frame_timeout_ms,
            ),
            ("--realtime-priority", args.realtime_priority.is_some()),
            ("--dc", args.dc),
            ("--no-dc", args.no_dc),
            ("--drive-profile", args.drive_profile.is_some()),
        ],
        None => [("", false); 7],
    };
    if args.ethercat.is_none() {
        let given: Vec<&str> = ethercat_only.iter().filter(|f| f.1).map(|f| f.0).collect();
        if !given.is_empty() {
            return Err(bad(format!(
                "{} apply only to a drive on EtherCAT (--ethercat IFACE); they would be ignored",
                given.join(", ")
            )));
        }
    } else {
        let simulation_only: [(&str, bool); 3] = [
            ("--seed", args.seed.is_some()),
            ("--torque-noise", args.torque_noise.is_some()),
            ("--encoder-noise", args.encoder_noise.is_some()),
        ];
        let given: Vec<&str> = simulation_only
            .iter()
            .filter(|f| f.1)
            .map(|f| f.0)
            .collect();
        if !given.is_empty() {
            return Err(bad(format!(
                "{} apply only to the simulated axis; a drive on EtherCAT has its own noise",
                given.join(", ")
            )));
        }
    }
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

/// The arguments of `beltune commission` without any flag: the defaults.
fn default_args() -> Option<Args> {
    use clap::{Args as _, FromArgMatches};
    let matches = Args::augment_args(clap::Command::new("commission"))
        .try_get_matches_from(["commission"])
        .ok()?;
    Args::from_arg_matches(&matches).ok()
}

/// A numeric flag that must be finite and within `lo..=hi` (`lo` exclusive when `open`).
pub fn check_flag(flag: &str, v: Option<f64>, lo: f64, hi: f64, open: bool) -> anyhow::Result<()> {
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

/// The plant of `--plant` (default egc70) with `--payload` and `--tilt`.
fn load_plant(args: &Args) -> anyhow::Result<Plant> {
    plant_with(args.plant.as_deref(), args.payload, args.tilt)
}

/// The plant `name` (default egc70) with a payload and a tilt (degrees),
/// checked (`commission` and `health`).
pub fn plant_with(
    name: Option<&str>,
    payload: Option<f64>,
    tilt: Option<f64>,
) -> anyhow::Result<Plant> {
    let name = name.unwrap_or("egc70");
    check_flag("--tilt", tilt, -90.0, 90.0, false)?;
    let mut plant = super::super::plant::resolve_plant(name, payload)?;
    if let Some(tilt) = tilt {
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

/// The excitation flags against the plant's drive, into `cfg`.
fn check_excitation(
    args: &Args,
    plant: &Plant,
    cfg: &mut CommissioningConfig,
) -> anyhow::Result<()> {
    check_flag(
        "--excitation-amplitude",
        args.excitation_amplitude,
        0.0,
        plant.info().torque_max_nm,
        true,
    )?;
    let ts_s = plant.info().ts_s;
    let clock_limit_ms = f64::from(MAX_PRBS_CLOCK) * ts_s * 1e3;
    check_flag(
        "--prbs-clock-ms",
        args.prbs_clock_ms,
        0.0,
        clock_limit_ms,
        true,
    )?;
    let ex = &mut cfg.excitation;
    ex.fixed_amplitude_nm = args.excitation_amplitude;
    if let Some(n) = args.prbs_order {
        ex.prbs_order = n;
        ex.band_from_data_sheet = false;
    }
    if let Some(ms) = args.prbs_clock_ms {
        ex.clock_period_s = ms * 1e-3;
        ex.band_from_data_sheet = false;
    }
    let order = ex.prbs_order;
    let clock = ex.clock_samples(ts_s);
    let period = ((1u64 << order) - 1) * u64::from(clock);
    if period > MAX_PRBS_PERIOD_SAMPLES {
        return Err(bad(format!(
            "--prbs-order {order} with a PRBS clock of {clock} samples makes a period of {period} \
             samples (limit {MAX_PRBS_PERIOD_SAMPLES}); lower one of them"
        )));
    }
    Ok(())
}

/// The EtherCAT settings.
fn ethercat(args: &Args, interface: &str, datasheet: DataSheet) -> anyhow::Result<Ethercat> {
    Ok(Ethercat {
        interface: interface.to_string(),
        drive_profile: match &args.drive_profile {
            Some(p) => Some(
                beltune_ethercat::profile::DriveProfile::read(p)
                    .map_err(|e| bad(format!("--drive-profile: {e}")))?,
            ),
            None => None,
        },
        datasheet,
        master: master_config(
            interface,
            args.subdevice,
            args.cycle_us,
            args.frame_timeout_ms,
            args.dc && !args.no_dc,
        )?,
    })
}

/// The master's settings of `--ethercat IFACE` and its flags, checked
/// (`commission` and `health`).
pub fn master_config(
    interface: &str,
    subdevice: usize,
    cycle_us: u32,
    frame_timeout_ms: f64,
    use_dc: bool,
) -> anyhow::Result<beltune_ethercat::master::MasterConfig> {
    use beltune_ethercat::master::MasterConfig;
    if interface.is_empty() || interface.len() > MAX_INTERFACE_NAME_BYTES {
        return Err(bad(format!(
            "--ethercat `{}`: a network interface name has 1 to {MAX_INTERFACE_NAME_BYTES} bytes",
            interface.escape_debug()
        )));
    }
    if !(frame_timeout_ms.is_finite() && (0.1..=1000.0).contains(&frame_timeout_ms)) {
        return Err(bad(format!(
            "--frame-timeout-ms {} is outside 0.1 ..= 1000",
            beltune::error::short_number(frame_timeout_ms)
        )));
    }
    Ok(MasterConfig {
        subdevice,
        cycle_s: f64::from(cycle_us) * 1e-6,
        frame_timeout_s: frame_timeout_ms * 1e-3,
        use_dc,
        ..MasterConfig::default()
    })
}

/// The recording's flags and columns (read from its header, not its data).
fn recorded(args: &Args, csv: &std::path::Path) -> anyhow::Result<Recorded> {
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
    if let Some(t) = args.torque_limit {
        super::super::util::check_torque_limit_flag("--torque-limit", t)?;
    }
    let unit = if args.current_units { "A" } else { "N m" };
    let Some(torque_limit) = args.torque_limit else {
        return Err(bad(format!(
            "--csv needs --torque-limit: the drive's torque limit in {unit} (the record's peak is not a limit)"
        )));
    };
    let time = args.time.clone().unwrap_or_else(|| "t_s".to_string());
    let header = read_csv_header(csv)?;
    let mut needed = vec![time.as_str(), input.as_str(), output.as_str()];
    if let Some(a) = &args.actual_torque {
        needed.push(a.as_str());
    }
    // a closed-loop record: its reference column and, for the indirect method, the controller
    crate::cmd::identify::closed_loop_record(&args.closed_loop, input, output)?;
    if let Some(r) = &args.closed_loop.reference {
        needed.push(r.as_str());
    }
    require_columns(csv, &header, &needed)?;
    let friction = match (
        &args.friction_csv,
        &args.friction_torque,
        &args.friction_position,
    ) {
        (Some(f), Some(tq), Some(pos)) => {
            let header = read_csv_header(f)?;
            require_columns(f, &header, &[time.as_str(), pos.as_str(), tq.as_str()])?;
            Some((f.clone(), tq.clone(), pos.clone()))
        }
        _ => None,
    };
    Ok(Recorded {
        csv: csv.to_path_buf(),
        time,
        input: input.clone(),
        output: output.clone(),
        torque_limit,
        units,
        friction,
    })
}

/// Refuse an output folder that holds one of the input files (it would be replaced).
fn check_inputs_outside_output(args: &Args) -> anyhow::Result<()> {
    let Some(out) = &args.out else { return Ok(()) };
    let Ok(out) = std::fs::canonicalize(out) else {
        return Ok(());
    };
    for input in [&args.csv, &args.friction_csv, &args.closed_loop.controller]
        .into_iter()
        .flatten()
    {
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
