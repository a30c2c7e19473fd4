//! `beltune commission`: the one-command self-commissioning of the built-in
//! simulated axis (or a plant file), of a drive on EtherCAT, or from data
//! recorded on a real drive (`--csv`: the stages that need the axis are
//! skipped).
//!
//! One path for the three: [`preflight::plan`] checks everything that can be
//! checked before the axis moves, the mode runs the library
//! ([`beltune::commission::commission`] or
//! [`beltune::commission::recorded::commission_recorded`]), and [`deliver`]
//! writes the result set ([`beltune::report::folder::ResultSet`]) and prints the
//! summary of the record it wrote; the library's verdict decides the exit
//! status (5 when a check fails).
//!
//! Output: progress bars and stage lines on stderr (not with `--quiet`), the
//! summary on stdout (text, or JSON with `--json`: `summary.rs`), and after a
//! safety stop a diagnostic (`diagnostic.rs`). The flags are grouped under
//! the headings of `help::COMMISSION_HEADINGS`; `--config FILE.toml`
//! supplies them from a file (`config.rs`).

pub mod preflight;

use super::summary::Summary;
use crate::exit::{ExitStatus, Failure};
use crate::progress::BarProgress;
use anyhow::Context;
use beltune::commission::recorded::commission_recorded;
use beltune::commission::{commission, CommissioningConfig};
use beltune::ident::{
    identify_from_motion, identify_recorded, read_csv_columns, EtfeConfig, FitConfig,
    MotionFrictionConfig, RecordedExcitation,
};
use beltune::record::commissioning::{AxisRecord, Origin};
use beltune::record::folder::OutputTarget;
use beltune::record::provenance::Provenance;
use beltune::report::folder::ResultSet;
use beltune::sim::{SimAxis, Truth};
use beltune_ethercat::master::BusAxis;
use preflight::{bad, Mode};
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
    /// Replace the result already in --out: its files (listed in
    /// .beltune-manifest) are replaced together; everything else in the
    /// folder (notes, tuned-* sets) is kept.
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
    #[arg(long, value_parser = clap::value_parser!(u32).range(2..=preflight::MAX_PRBS_ORDER as i64))]
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
    #[command(flatten)]
    pub closed_loop: super::identify::ClosedLoopArgs,
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
    /// EtherCAT: use distributed clocks (SYNC0) where the drive offers them.
    /// Needs a master that keeps real time (PREEMPT_RT, an isolated core,
    /// --realtime-priority): each missed SYNC0 makes the drive apply the
    /// previous torque again. Default: SM-synchronous (a drive cycle per
    /// process-data frame), which commissions within the limits on a PC.
    #[arg(long, requires = "ethercat", conflicts_with = "no_dc")]
    pub dc: bool,
    /// EtherCAT: SM-synchronous, no distributed clocks (the default; kept
    /// for scripts that say so).
    #[arg(long, requires = "ethercat")]
    pub no_dc: bool,
    /// EtherCAT: a drive profile (TOML) that maps the designed controller
    /// onto the drive's objects; the controller is then written into the
    /// drive, read back, and validated with the drive's own loops (CSP).
    /// Default: the shipped profile whose identity matches the drive (the
    /// virtual drive's), else the controller stays the host's.
    #[arg(long, value_name = "FILE", requires = "ethercat")]
    pub drive_profile: Option<PathBuf>,
    /// No progress bars or stage lines (the summary is still printed).
    #[arg(long)]
    pub quiet: bool,
    /// Print the summary as JSON on stdout (keys: see the README).
    #[arg(long)]
    pub json: bool,
    /// Also run the validation move with no and with linear feedforward
    /// before the delivered controller's, for thesis chapter 5's comparison
    /// (about 7 s more of axis time; neither move is judged or delivered).
    #[arg(long)]
    pub compare_feedforward: bool,
    /// Largest following error allowed in the closed-loop stages before the
    /// supervisor stops the axis, m (default 0.05).
    #[arg(long, value_name = "M")]
    pub following_error_max: Option<f64>,
    #[command(flatten)]
    pub limits: super::verdict::LimitArgs,
    #[command(flatten)]
    pub history: super::history::DbArgs,
    #[command(flatten)]
    pub config: super::config::ConfigArgs,
}

pub fn parse_period(s: &str) -> Result<usize, String> {
    let max = beltune::ident::csv_columns::MAX_CSV_ROWS;
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
    if n > preflight::MAX_SKIP_PERIODS {
        return Err(format!("must lie in 0..={}", preflight::MAX_SKIP_PERIODS));
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
    let plan = preflight::plan(&args)?;
    let started = Instant::now();
    // where a health check measures the stiffness near the start (stage 5c's position)
    let near = |ds: &beltune::commission::DataSheet| {
        beltune::commission::stages::identification::start_side_position_m(ds, f64::NAN)
    };
    let near_m = match &plan.mode {
        Mode::Simulated(s) => Some(near(&s.datasheet)),
        Mode::Ethercat(e) => Some(near(&e.datasheet)),
        Mode::Recorded(_) => None,
    };
    let (set, in_drive_failure) = match plan.mode {
        Mode::Simulated(s) => (run_simulated(&args, &plan.cfg, *s)?, None),
        Mode::Ethercat(e) => run_ethercat(&args, &plan.cfg, e, bus)?,
        Mode::Recorded(r) => (run_recorded(&args, &plan.cfg, r)?, None),
    };
    deliver(&set, &plan.target, &args, started, &plan.history, near_m)?;
    match in_drive_failure {
        // the result set is written; the drive's own loops missed the limits
        Some(failures) => Err(anyhow::Error::new(Failure::new(
            ExitStatus::LimitsNotMet,
            format!("the controller in the drive (CSP) misses its limits: {failures}"),
        ))),
        None => Ok(()),
    }
}

/// Write the result set, print the summary of the record it holds, and end
/// with the verdict's status: 0, or 5 when a check failed.
fn deliver(
    set: &ResultSet,
    target: &OutputTarget,
    args: &Args,
    started: Instant,
    history: &beltune::history::Location,
    near_m: Option<f64>,
) -> anyhow::Result<()> {
    let files = set.write(target)?;
    super::diagnostic::remove_stale(target)?;
    let dir = files
        .first()
        .and_then(|f| f.parent())
        .map(|d| d.display().to_string());
    let axis = args
        .history
        .axis
        .clone()
        .unwrap_or_else(|| set.record.plant.clone());
    let run = beltune::history::NewRun::of_commissioning(&axis, &set.record, dir.clone(), near_m)?;
    let id = super::history::record(history, &run).map_err(|e| {
        e.context(format!(
            "the result is in {} but the history could not record it",
            dir.clone().unwrap_or_default()
        ))
    })?;
    if !args.quiet {
        for l in crate::progress::stage_lines(
            "history",
            &format!("run {id} of `{axis}` in {}", history.display()),
        ) {
            eprintln!("{l}");
        }
    }
    let summary = Summary::of(&set.record, files, started.elapsed().as_secs_f64());
    if args.json {
        println!("{}", summary.json()?);
    } else {
        for line in summary.lines() {
            println!("{line}");
        }
    }
    let status = summary.exit_status();
    if status != ExitStatus::Success {
        let failures = set.verdict().map(|v| v.failures()).unwrap_or_default();
        return Err(anyhow::Error::new(Failure::new(
            status,
            format!(
                "the commissioning finished, but the delivered controller misses its limits: {}",
                failures.join(", ")
            ),
        )));
    }
    Ok(())
}

/// Commission the simulated axis.
fn run_simulated(
    args: &Args,
    cfg: &CommissioningConfig,
    s: preflight::Simulated,
) -> anyhow::Result<ResultSet> {
    let seed = s.sim.seed;
    let mut axis = SimAxis::new(&s.plant, s.sim)?;
    let mut progress = BarProgress::new(args.quiet);
    let run = commission(&mut axis, &s.datasheet, cfg, &mut progress)
        .map_err(|e| stopped(e, &mut progress, args))?;
    let origin = Origin {
        name: s.name.clone(),
        axis: AxisRecord::simulated(&s.name, &s.plant, s.datasheet.origin_m, seed),
        truth: Some(Truth::of_plant(&s.plant, run.identification_position_m)?),
        provenance: Provenance::of_this_process(Some(seed)),
    };
    Ok(ResultSet::of_run(&run, &origin)?)
}

/// Commission the drive on an EtherCAT bus (`--ethercat IFACE`).
fn run_ethercat(
    args: &Args,
    cfg: &CommissioningConfig,
    e: preflight::Ethercat,
    bus: Option<Bus<'_>>,
) -> anyhow::Result<(ResultSet, Option<String>)> {
    use beltune_ethercat::master::wire::RawSocket;
    use beltune_ethercat::master::{EthercatAxis, Storage};
    if let Some(bus) = bus {
        return run_on(args, cfg, e, bus);
    }
    let storage = Storage::new();
    let interface = e.interface.clone();
    let bus = Bus {
        label: format!("EtherCAT {interface}"),
        open: Box::new(|master| {
            let axis = EthercatAxis::open(&storage, master, |tx, rx| {
                RawSocket::open(&interface, tx, rx)
            })?;
            Ok(Box::new(axis) as Box<dyn BusAxis>)
        }),
    };
    run_on(args, cfg, e, bus)
}

/// Set by SIGINT/SIGTERM while a drive on a bus is commissioned.
static INTERRUPTED: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);

extern "C" fn on_signal(_: libc::c_int) {
    INTERRUPTED.store(true, std::sync::atomic::Ordering::Relaxed);
}

/// Commission the drive on `bus`; where the drive offers CSP, the delivered
/// controller then goes into the drive and the validation move is run again
/// with the drive's own loops (the failures of its verdict, if any).
fn run_on(
    args: &Args,
    cfg: &CommissioningConfig,
    e: preflight::Ethercat,
    bus: Bus<'_>,
) -> anyhow::Result<(ResultSet, Option<String>)> {
    if let Some(p) = args.realtime_priority {
        // this thread runs the bus; the computation threads it starts run normally
        beltune_ethercat::sched::set_realtime_priority(p)
            .map_err(|e| bad(format!("--realtime-priority: {e}")))?;
    }
    let label = bus.label;
    let mut axis = (bus.open)(e.master).with_context(|| label.clone())?;
    // Ctrl-C or SIGTERM: the next exchange fails, the axis is quick-stopped
    // and the bus brought down as after any failure
    axis.set_interrupt(&INTERRUPTED);
    // SAFETY: installing an async-signal-safe handler (an atomic store).
    unsafe {
        libc::signal(libc::SIGINT, on_signal as *const () as libc::sighandler_t);
        libc::signal(libc::SIGTERM, on_signal as *const () as libc::sighandler_t);
    }
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
            if id.dc { "SYNC0" } else { "SM-synchronous" },
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
    let run = commission(axis.as_axis(), &e.datasheet, cfg, &mut progress);
    // the controller into the drive, its loops validated (CSP), where a
    // profile says where it goes
    let profile = e.drive_profile.clone().or_else(|| {
        let shipped = beltune_ethercat::profile::DriveProfile::virtual_servo();
        shipped
            .matches(id.vendor_id, id.product_code)
            .then_some(shipped)
    });
    let in_drive = match (&run, &profile) {
        (Ok(r), Some(p)) if id.csp => Some(axis.validate_with_drive_loops(r, cfg, p)),
        _ => None,
    };
    // leave the drive switched off and at rest, also after a stop, then
    // bring the bus down (OP -> SAFE-OP -> PRE-OP -> INIT) so that the
    // drive's watchdog has nothing to watch and no error stays latched
    let _ = axis.stop_drive();
    let (exchanges, missed) = axis.cycle_counts();
    let jitter = axis.jitter();
    let down = axis.shut_down();
    drop(axis);
    if !args.quiet {
        let line = if down.reached {
            format!(
                "bus down: drive in AL state {}{}{}",
                match down.al_state {
                    1 => "INIT",
                    2 => "PRE-OP",
                    4 => "SAFE-OP",
                    8 => "OP",
                    _ => "?",
                },
                if down.error { ", error latched" } else { "" },
                if down.al_status_code != 0 {
                    format!(", AL status code {:#06x}", down.al_status_code)
                } else {
                    String::new()
                }
            )
        } else {
            "bus down: the drive did not answer (its watchdog removes the torque)".to_string()
        };
        for l in crate::progress::stage_lines(&label, &line) {
            eprintln!("{l}");
        }
    }
    if args.realtime_priority.is_some() {
        // the bus is closed: the report is no real-time work
        beltune_ethercat::sched::set_normal();
    }
    if !args.quiet {
        // the master's measured cycle; with SYNC0 a late exchange makes the
        // drive apply the previous torque again
        let mut line = format!(
            "{exchanges} exchanges ({})",
            if id.dc { "SYNC0" } else { "SM-synchronous" }
        );
        if let Some(j) = jitter.filter(|j| j.periods > 0) {
            line.push_str(&format!(
                ", cycle jitter rms {:.0} us, max {:.0} us, {} cycles longer than 1.5 periods",
                j.rms_s() * 1e6,
                j.max_s * 1e6,
                j.late
            ));
        }
        if id.dc {
            line.push_str(&format!(
                ", {missed} SYNC0 cycles missed by the master (host scheduling)"
            ));
        }
        for l in crate::progress::stage_lines(&label, &line) {
            eprintln!("{l}");
        }
    }
    let run = run.map_err(|e| stopped(e, &mut progress, args))?;
    let mut in_drive_failure = None;
    let line = match in_drive {
        Some(Ok(v)) => {
            if !v.verdict.limits_met() {
                in_drive_failure = Some(v.verdict.failures().join(", "));
            }
            format!(
                "{} parameters written by SDO and read back, preview {} cycles; the validation move closed by the drive (CSP): max cart error {:.3} mm, static {:.1} um; {}",
                v.parameters_written,
                v.preview_cycles,
                v.summary.max_tracking_error_m * 1e3,
                v.summary.static_error_m * 1e6,
                v.verdict.text()
            )
        }
        Some(Err(err)) => {
            in_drive_failure = Some(crate::exit::one_line(&anyhow::Error::new(err)));
            format!(
                "the controller could not be validated in the drive: {}",
                in_drive_failure.as_deref().unwrap_or("")
            )
        }
        None if !id.csp => {
            "the drive offers no CSP: the controller is the host's (controller.toml)".to_string()
        }
        None => format!(
            "no drive profile for vendor {:#010x} product {:#010x} (--drive-profile): the controller is the host's (controller.toml)",
            id.vendor_id, id.product_code
        ),
    };
    if !args.quiet {
        for l in crate::progress::stage_lines("drive loops", &line) {
            eprintln!("{l}");
        }
    }
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
    let name = format!("{label} SubDevice {} ({})", args.subdevice, id.name);
    let origin = Origin {
        name: name.clone(),
        axis: AxisRecord::Ethercat { source: name },
        truth: None,
        provenance: Provenance::of_this_process(None),
    };
    Ok((ResultSet::of_run(&run, &origin)?, in_drive_failure))
}

/// Commission from recorded data (`--csv`).
fn run_recorded(
    args: &Args,
    cfg: &CommissioningConfig,
    r: preflight::Recorded,
) -> anyhow::Result<ResultSet> {
    let id = identify_recorded(&RecordedExcitation {
        csv: &r.csv,
        time: &r.time,
        input: &r.input,
        output: &r.output,
        actual_torque: args.actual_torque.as_deref(),
        period_samples: args.period_samples,
        skip_periods: args.skip_periods.unwrap_or(1),
        etfe: EtfeConfig::default(),
        fit: FitConfig {
            theta_e: args.inertia,
            free_inertia: args.inertia.is_none(),
            i_t: args.transmission.unwrap_or(1.0),
            units: r.units,
            ..FitConfig::default()
        },
        closed_loop: super::identify::closed_loop_record(&args.closed_loop, &r.input, &r.output)?,
    })?;
    let friction = match &r.friction {
        Some((f, tq, pos)) => {
            let cols = read_csv_columns(f, &[r.time.as_str(), pos.as_str(), tq.as_str()])?;
            let column = |n: &str| {
                cols.column(n)
                    .ok_or_else(|| anyhow::anyhow!("{}: missing column `{n}`", f.display()))
            };
            Some(
                identify_from_motion(
                    column(&r.time)?,
                    column(pos)?,
                    column(tq)?,
                    &MotionFrictionConfig::default(),
                )
                .with_context(|| f.display().to_string())?,
            )
        }
        None => None,
    };
    let run = commission_recorded(id, friction, r.torque_limit, cfg).map_err(|e| {
        // a friction record in other units than the drive's torque limit
        match &r.friction {
            Some((f, ..)) => anyhow::Error::new(e).context(f.display().to_string()),
            None => anyhow::Error::new(e),
        }
    })?;
    if !args.quiet {
        for line in &run.log {
            // "stage: summary", as the stage lines of a run on the axis
            let (stage, summary) = line.split_once(": ").unwrap_or(("", line));
            for l in crate::progress::stage_lines(stage, summary) {
                eprintln!("{l}");
            }
        }
    }
    let source = r.csv.display().to_string();
    let origin = Origin {
        name: source.clone(),
        axis: AxisRecord::Recorded {
            source,
            identification: Some(run.identification.method),
        },
        truth: None,
        provenance: Provenance::of_this_process(None),
    };
    Ok(ResultSet::of_recorded(&run, &origin)?)
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
    match super::diagnostic::write(&preflight::target(args), &stop, &reason, seed) {
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
