//! `beltune health --baseline DIR`: the health of a commissioned axis (the
//! simulated one, a drive on EtherCAT, or a recording), each quantity
//! against the baseline commissioning (`beltune::health`). Thin: the flags
//! are checked before the axis moves (with `commission`'s checks), one
//! library call runs the check, the result folder (`health.json`,
//! `report.html`) is written and the run recorded in the history; the
//! summary goes to stdout (`--json`: as JSON). Exit status as `commission`:
//! 5 when a quantity asks for action.

use super::commission::preflight::{bad, check_flag, master_config, plant_with};
use super::history::{record, DbArgs};
use crate::exit::{ExitStatus, Failure};
use crate::progress::BarProgress;
use beltune::commission::{check_travel_window, DataSheet};
use beltune::health::{
    health_check, health_of_recording, Baseline, HealthCheck, HealthConfig, Limit, Quantity, Status,
};
use beltune::history::NewRun;
use beltune::model::{Plant, Wear};
use beltune::record::commissioning::AxisRecord;
use beltune::record::folder::OutputTarget;
use beltune::record::health::HealthRecord;
use beltune::record::provenance::Provenance;
use beltune::report::health::HealthSet;
use beltune::sim::{SimAxis, SimConfig};
use std::path::PathBuf;

/// The folder of the health results without `--out`.
pub const HEALTH_ROOT: &str = "health";

/// Arguments of `beltune health`.
#[derive(clap::Args)]
pub struct Args {
    /// The commissioning to compare with: its result folder (e.g.
    /// `commissioning/latest`).
    #[arg(long, value_name = "DIR")]
    pub baseline: PathBuf,
    /// Simulated axis: built-in plant name or plant TOML file (default egc70).
    #[arg(long)]
    pub plant: Option<String>,
    /// Simulated axis: payload on the cart, kg.
    #[arg(long, allow_negative_numbers = true)]
    pub payload: Option<f64>,
    /// Simulated axis: tilt, degrees.
    #[arg(long, allow_negative_numbers = true)]
    pub tilt: Option<f64>,
    /// Simulated axis: seed of the measurement noise (default 1).
    #[arg(long)]
    pub seed: Option<u64>,
    /// Simulated axis: actual-torque noise, N m.
    #[arg(long, value_name = "NM", allow_negative_numbers = true)]
    pub torque_noise: Option<f64>,
    /// Simulated axis: encoder noise, counts.
    #[arg(long, value_name = "COUNTS", allow_negative_numbers = true)]
    pub encoder_noise: Option<f64>,
    /// Simulated axis: cart position at start, m (default 0.05).
    #[arg(long, allow_negative_numbers = true)]
    pub start_position: Option<f64>,
    /// Simulated ageing: belt tension loss as the fraction of belt stiffness lost (0..0.9).
    #[arg(long, value_name = "FRACTION", allow_negative_numbers = true)]
    pub belt_stiffness_loss: Option<f64>,
    /// Simulated ageing: friction growth, every friction coefficient times 1 + this.
    #[arg(long, value_name = "FRACTION", allow_negative_numbers = true)]
    pub friction_growth: Option<f64>,
    /// Simulated ageing: a slack span: the belt's pretension, N.
    #[arg(long, value_name = "N", allow_negative_numbers = true)]
    pub belt_pretension: Option<f64>,
    /// Simulated ageing: a worn guide: extra Coulomb friction of the cart, N.
    #[arg(long, value_name = "N", allow_negative_numbers = true)]
    pub guide_wear: Option<f64>,
    /// From a recording instead of an axis: CSV of a periodic excitation.
    #[arg(long, requires_all = ["input", "output"], conflicts_with = "ethercat")]
    pub csv: Option<PathBuf>,
    /// Recording: time column, s (default t_s).
    #[arg(long)]
    pub time: Option<String>,
    /// Recording: desired-torque column, N m.
    #[arg(long)]
    pub input: Option<String>,
    /// Recording: motor-angle column, rad.
    #[arg(long)]
    pub output: Option<String>,
    /// Recording: samples per period (default: detected).
    #[arg(long, value_parser = super::commission::parse_period)]
    pub period_samples: Option<usize>,
    /// Recording: leading periods discarded (default 1).
    #[arg(long, value_parser = super::commission::parse_skip)]
    pub skip_periods: Option<usize>,
    /// Recording: a CSV of any motion for the friction (same time column).
    #[arg(long, requires_all = ["friction_torque", "friction_position"])]
    pub friction_csv: Option<PathBuf>,
    /// Friction record: torque column, N m.
    #[arg(long)]
    pub friction_torque: Option<String>,
    /// Friction record: motor-angle column, rad.
    #[arg(long)]
    pub friction_position: Option<String>,
    /// A drive on EtherCAT: the network interface (`--plant` gives the data sheet).
    #[arg(long, value_name = "IFACE")]
    pub ethercat: Option<String>,
    /// EtherCAT: position of the drive on the bus.
    #[arg(long, default_value_t = 0, requires = "ethercat")]
    pub subdevice: usize,
    /// EtherCAT: bus cycle, us.
    #[arg(long, default_value_t = 1000, requires = "ethercat")]
    pub cycle_us: u32,
    /// EtherCAT: how long to wait for a frame, ms.
    #[arg(long, default_value_t = 10.0, requires = "ethercat")]
    pub frame_timeout_ms: f64,
    /// EtherCAT: use distributed clocks (SYNC0) where the drive offers them
    /// (as `commission --dc`). Default: SM-synchronous.
    #[arg(long, requires = "ethercat", conflicts_with = "no_dc")]
    pub dc: bool,
    /// EtherCAT: SM-synchronous, no distributed clocks (the default; kept
    /// for scripts that say so).
    #[arg(long, requires = "ethercat")]
    pub no_dc: bool,
    /// A limit QUANTITY=LOWER,UPPER (fractions of the baseline, or N m for
    /// holding_torque; `-` for none), e.g. `stiffness_far=-0.08,0.25`; repeatable.
    #[arg(long = "limit", value_name = "QUANTITY=LOWER,UPPER")]
    pub limits: Vec<String>,
    /// Output folder (new or empty). Without it: a new timestamped folder
    /// under health/ per run, health/latest pointing at the newest.
    #[arg(long)]
    pub out: Option<PathBuf>,
    #[command(flatten)]
    pub db: DbArgs,
    /// No progress bars or stage lines.
    #[arg(long)]
    pub quiet: bool,
    /// Print the summary as JSON.
    #[arg(long)]
    pub json: bool,
}

/// The limits of `--limit` over the defaults.
fn limits(args: &Args) -> anyhow::Result<beltune::health::HealthLimits> {
    let mut l = beltune::health::HealthLimits::default();
    for spec in &args.limits {
        let err = || {
            bad(format!(
                "--limit `{spec}`: expected QUANTITY=LOWER,UPPER with QUANTITY one of {}",
                Quantity::ALL.map(|q| q.key()).join(", ")
            ))
        };
        let (name, bounds) = spec.split_once('=').ok_or_else(err)?;
        let q = Quantity::from_key(name.trim()).ok_or_else(err)?;
        let (lo, hi) = bounds.split_once(',').ok_or_else(err)?;
        let num = |s: &str| -> anyhow::Result<Option<f64>> {
            let s = s.trim();
            if s == "-" {
                return Ok(None);
            }
            s.parse::<f64>().map(Some).map_err(|_| err())
        };
        let relative = l.of(q).relative;
        l.set(
            q,
            Limit {
                lower: num(lo)?,
                upper: num(hi)?,
                relative,
            },
        );
    }
    l.validate()?;
    Ok(l)
}

/// The simulated plant with the ageing flags.
fn simulated_plant(args: &Args) -> anyhow::Result<Plant> {
    let mut plant = plant_with(args.plant.as_deref(), args.payload, args.tilt)?;
    let ageing = [
        args.belt_stiffness_loss,
        args.friction_growth,
        args.belt_pretension,
        args.guide_wear,
    ];
    if ageing.iter().any(Option::is_some) {
        let Plant::Physical(p) = &mut plant else {
            return Err(bad(
                "the ageing flags apply to physical plants (a linear set has no belt to age)",
            ));
        };
        p.wear = Wear {
            belt_stiffness_loss: args
                .belt_stiffness_loss
                .unwrap_or(p.wear.belt_stiffness_loss),
            friction_growth: args.friction_growth.unwrap_or(p.wear.friction_growth),
            belt_pretension_n: args.belt_pretension.or(p.wear.belt_pretension_n),
            guide_wear_n: args.guide_wear.unwrap_or(p.wear.guide_wear_n),
            ..p.wear
        };
        plant.validate()?;
    }
    Ok(plant)
}

/// Error if a flag of another mode was given.
fn check_mode_flags(args: &Args) -> anyhow::Result<()> {
    let simulated: [(&str, bool); 11] = [
        ("--payload", args.payload.is_some()),
        ("--tilt", args.tilt.is_some()),
        ("--seed", args.seed.is_some()),
        ("--torque-noise", args.torque_noise.is_some()),
        ("--encoder-noise", args.encoder_noise.is_some()),
        ("--start-position", args.start_position.is_some()),
        ("--belt-stiffness-loss", args.belt_stiffness_loss.is_some()),
        ("--friction-growth", args.friction_growth.is_some()),
        ("--belt-pretension", args.belt_pretension.is_some()),
        ("--guide-wear", args.guide_wear.is_some()),
        ("--plant", args.plant.is_some() && args.csv.is_some()),
    ];
    let recorded: [(&str, bool); 6] = [
        ("--time", args.time.is_some()),
        ("--input", args.input.is_some()),
        ("--output", args.output.is_some()),
        ("--period-samples", args.period_samples.is_some()),
        ("--skip-periods", args.skip_periods.is_some()),
        ("--friction-csv", args.friction_csv.is_some()),
    ];
    let (given, mode): (Vec<&str>, &str) = if args.csv.is_some() {
        (
            simulated.iter().filter(|f| f.1).map(|f| f.0).collect(),
            "a simulated axis",
        )
    } else {
        let mut g: Vec<&str> = recorded.iter().filter(|f| f.1).map(|f| f.0).collect();
        if args.ethercat.is_some() {
            g.extend(
                simulated
                    .iter()
                    // the data sheet and the homing result apply to a drive too
                    .filter(|f| {
                        f.1 && !["--payload", "--tilt", "--plant", "--start-position"]
                            .contains(&f.0)
                    })
                    .map(|f| f.0),
            );
        }
        (g, "another mode")
    };
    if !given.is_empty() {
        return Err(bad(format!("{} apply only to {mode}", given.join(", "))));
    }
    Ok(())
}

/// What the check runs on, checked.
enum Mode {
    Simulated {
        plant: Box<Plant>,
        datasheet: DataSheet,
        sim: SimConfig,
    },
    Ethercat {
        datasheet: DataSheet,
        master: beltune_ethercat::master::MasterConfig,
        interface: String,
    },
    Recorded,
}

/// Run the subcommand.
pub fn run(args: Args) -> anyhow::Result<()> {
    // ---- everything checked before the axis moves ----
    check_mode_flags(&args)?;
    let target = match &args.out {
        Some(dir) => OutputTarget::Exact {
            dir: dir.clone(),
            force: false,
        },
        None => OutputTarget::History {
            root: PathBuf::from(HEALTH_ROOT),
        },
    };
    target.check()?;
    let cfg = HealthConfig {
        limits: limits(&args)?,
        ..HealthConfig::default()
    };
    if !args
        .baseline
        .join(beltune::record::COMMISSIONING_FILE)
        .is_file()
    {
        return Err(bad(format!(
            "--baseline {}: no {} there (the result folder of a `beltune commission`)",
            args.baseline.display(),
            beltune::record::COMMISSIONING_FILE
        )));
    }
    let baseline = Baseline::read(&args.baseline)?;
    let mode = if args.csv.is_some() {
        Mode::Recorded
    } else {
        let start = args.start_position.unwrap_or(0.05);
        let plant = simulated_plant(&args)?;
        check_travel_window(&plant, None)?;
        let datasheet = DataSheet::for_plant(&plant, start, None);
        datasheet.validate()?;
        match &args.ethercat {
            Some(iface) => Mode::Ethercat {
                datasheet,
                master: master_config(
                    iface,
                    args.subdevice,
                    args.cycle_us,
                    args.frame_timeout_ms,
                    args.dc && !args.no_dc,
                )?,
                interface: iface.clone(),
            },
            None => {
                check_flag("--torque-noise", args.torque_noise, 0.0, 10.0, false)?;
                check_flag("--encoder-noise", args.encoder_noise, 0.0, 1e3, false)?;
                let noise = beltune::model::MeasurementNoise {
                    torque_nm: args.torque_noise.unwrap_or(plant.noise().torque_nm),
                    encoder_counts: args.encoder_noise.unwrap_or(plant.noise().encoder_counts),
                };
                Mode::Simulated {
                    sim: SimConfig {
                        seed: args.seed.unwrap_or(1),
                        noise: Some(noise),
                        initial_cart_position_m: Some(start),
                        ..SimConfig::default()
                    },
                    plant: Box::new(plant),
                    datasheet,
                }
            }
        }
    };
    let db = args.db.check(&target)?;
    let axis_name = args
        .db
        .axis
        .clone()
        .unwrap_or_else(|| baseline.plant.clone());

    // ---- the check ----
    let mut progress = BarProgress::new(args.quiet);
    let (check, axis_record) = match mode {
        Mode::Simulated {
            plant,
            datasheet,
            sim,
        } => {
            let seed = sim.seed;
            let mut axis = SimAxis::new(&plant, sim)?;
            let check = health_check(&mut axis, &datasheet, &baseline, &cfg, &mut progress)?;
            let name = args.plant.clone().unwrap_or_else(|| "egc70".into());
            (
                check,
                AxisRecord::simulated(&name, &plant, datasheet.origin_m, seed),
            )
        }
        Mode::Ethercat {
            datasheet,
            master,
            interface,
        } => {
            use beltune_ethercat::master::wire::RawSocket;
            use beltune_ethercat::master::{BusAxis, EthercatAxis, Storage};
            let storage = Storage::new();
            let mut axis = EthercatAxis::open(&storage, master, |tx, rx| {
                RawSocket::open(&interface, tx, rx)
            })?;
            let check = health_check(axis.as_axis(), &datasheet, &baseline, &cfg, &mut progress);
            let _ = axis.stop_drive();
            let source = format!("EtherCAT {interface} SubDevice {}", args.subdevice);
            (check?, AxisRecord::Ethercat { source })
        }
        Mode::Recorded => recorded(&args, &baseline, &cfg)?,
    };
    // ---- the result folder and the history ----
    let record_ = HealthRecord {
        schema_version: beltune::record::SCHEMA_VERSION,
        provenance: Provenance::of_this_process(args.seed),
        axis: axis_name.clone(),
        axis_record,
        baseline_dir: args.baseline.display().to_string(),
        baseline_created_utc: baseline.created_utc.clone(),
        recommendations: check.recommendations(),
        check,
    };
    let set = HealthSet::of(record_);
    let files = set.write(&target)?;
    let dir = files
        .first()
        .and_then(|f| f.parent())
        .map(|d| d.display().to_string());
    let run = NewRun::of_health(
        &axis_name,
        &set.record.check,
        set.record.to_json_text()?,
        dir,
        args.baseline.display().to_string(),
    );
    let run_id = record(&db, &run).map_err(|e| {
        e.context(format!(
            "the result is in {} but the history could not record it",
            files
                .first()
                .and_then(|f| f.parent())
                .map(|d| d.display().to_string())
                .unwrap_or_default()
        ))
    })?;
    print_summary(&set.record, &files, &db.display(), run_id, args.json)?;
    if set.record.check.status == Status::Act {
        return Err(anyhow::Error::new(Failure::new(
            ExitStatus::LimitsNotMet,
            format!(
                "the health check finished: act: {}",
                set.record
                    .recommendations
                    .first()
                    .cloned()
                    .unwrap_or_default()
            ),
        )));
    }
    Ok(())
}

/// The check of a recording (`--csv`).
fn recorded(
    args: &Args,
    baseline: &Baseline,
    cfg: &HealthConfig,
) -> anyhow::Result<(HealthCheck, AxisRecord)> {
    use beltune::ident::{
        identify_from_motion, identify_recorded, read_csv_columns, EtfeConfig, FitConfig,
        MotionFrictionConfig, RecordedExcitation,
    };
    let csv = args.csv.as_ref().ok_or_else(|| bad("--csv"))?;
    let (Some(input), Some(output)) = (&args.input, &args.output) else {
        return Err(bad("--csv needs --input and --output column names"));
    };
    let time = args.time.clone().unwrap_or_else(|| "t_s".to_string());
    let id = identify_recorded(&RecordedExcitation {
        csv,
        time: &time,
        input,
        output,
        actual_torque: None,
        period_samples: args.period_samples,
        skip_periods: args.skip_periods.unwrap_or(1),
        etfe: EtfeConfig::default(),
        fit: FitConfig {
            theta_e: Some(baseline.model.theta_e),
            i_t: baseline.model.i_t,
            ..FitConfig::default()
        },
        closed_loop: None,
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
            Some(identify_from_motion(
                column(&time)?,
                column(pos)?,
                column(tq)?,
                &MotionFrictionConfig::default(),
            )?)
        }
        _ => None,
    };
    let duration = id.rows as f64 * id.ts_s;
    let check = health_of_recording(&id.fit, friction.as_ref(), duration, baseline, &cfg.limits)?;
    Ok((
        check,
        AxisRecord::Recorded {
            source: csv.display().to_string(),
            identification: Some(id.method),
        },
    ))
}

/// The summary on stdout.
fn print_summary(
    rec: &HealthRecord,
    files: &[PathBuf],
    db: &str,
    run_id: i64,
    json: bool,
) -> anyhow::Result<()> {
    let c = &rec.check;
    if json {
        let v = serde_json::json!({
            "axis": rec.axis,
            "status": c.status,
            "experiment_time_s": c.experiment_time_s,
            "baseline_dir": rec.baseline_dir,
            "quantities": c.comparisons,
            "failures": c.measured.failures,
            "recommendations": rec.recommendations,
            "files": files.iter().map(|f| f.display().to_string()).collect::<Vec<_>>(),
            "history": { "database": db, "run": run_id },
        });
        println!("{}", serde_json::to_string_pretty(&v)?);
        return Ok(());
    }
    println!(
        "health of {}: {} (against {}; axis busy {:.2} s)",
        rec.axis,
        c.status.word(),
        rec.baseline_dir,
        c.experiment_time_s
    );
    for f in &c.measured.failures {
        println!("  not fitted: {f}");
    }
    for q in &c.comparisons {
        println!(
            "  {:<44} {:>12.5e} {:<9} {:<22} {}",
            q.quantity.description(),
            q.measured.value,
            q.quantity.unit(),
            q.change_text(),
            q.status.word()
        );
    }
    for r in &rec.recommendations {
        println!("  - {r}");
    }
    if let Some(dir) = files.first().and_then(|f| f.parent()) {
        println!("wrote {}; history: run {run_id} in {db}", dir.display());
    }
    Ok(())
}
