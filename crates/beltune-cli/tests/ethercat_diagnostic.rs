//! A failed bus exchange during `beltune commission --ethercat`
//! (lost frames, a drive fault, the drive's watchdog) ends like a safety
//! stop: the drive's quick stop, exit status 3, one line naming the stage and
//! the diagnostic `DIR-safety-stop/` (what was running, the last second of
//! samples), and no results. In-process (no privileges): the command's own
//! code runs on the virtual drive plugged into ethercrab, faults injected
//! after a number of drive cycles.

use beltune::model::rigs;
use beltune::sim::SimConfig;
use beltune_cli::cmd::commission::{run_on_bus, Args, Bus};
use beltune_cli::exit::{self, ExitStatus};
use beltune_ethercat::drive::{DriveConfig, Faults, VirtualDrive, ERROR_WATCHDOG};
use beltune_ethercat::master::inprocess::InProcess;
use beltune_ethercat::master::{BusAxis, EthercatAxis, MasterConfig, Storage};
use clap::Parser;
use std::path::PathBuf;
use std::sync::atomic::Ordering;

const START_M: f64 = 0.05;
/// Drive cycles (1 ms) before the fault: inside the commissioning, after
/// the start-up of the bus.
const FAULT_AFTER_CYCLES: u64 = 3000;
/// CiA 402 error code injected: continuous over current (device internal).
const OVERCURRENT: u16 = 0x2310;

#[derive(Parser)]
struct Cli {
    #[command(flatten)]
    args: Args,
}

fn out_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("beltune-ecat-diag-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    let _ = std::fs::remove_dir_all(sibling(&d));
    d
}

fn sibling(d: &std::path::Path) -> PathBuf {
    let mut s = d.as_os_str().to_owned();
    s.push("-safety-stop");
    PathBuf::from(s)
}

/// Commission the in-process virtual drive through the command's code with
/// `inject` applied to its faults; `master` adjusts the master settings.
fn commission_with(
    name: &str,
    inject: impl FnOnce(&Faults),
    master: impl FnOnce(&mut MasterConfig),
) -> (anyhow::Error, PathBuf) {
    let dir = out_dir(name);
    let args = Cli::parse_from([
        "commission",
        "--ethercat",
        "in-process",
        "--quiet",
        "--start-position",
        &START_M.to_string(),
        "--out",
        dir.to_str().unwrap(),
    ])
    .args;
    let plant = rigs::builtin("egc70", None).unwrap();
    let drive = VirtualDrive::new(
        &plant,
        DriveConfig {
            sim: SimConfig {
                seed: 1,
                initial_cart_position_m: Some(START_M),
                ..SimConfig::default()
            },
            ..DriveConfig::default()
        },
    )
    .unwrap();
    let faults = drive.faults();
    faults
        .after_cycles
        .store(FAULT_AFTER_CYCLES, Ordering::Relaxed);
    inject(&faults);
    let storage = Storage::new();
    let bus = Bus {
        label: "EtherCAT in-process".into(),
        open: Box::new(|mut m: MasterConfig| {
            master(&mut m);
            let axis = EthercatAxis::open(&storage, m, |tx, rx| Ok(InProcess::new(tx, rx, drive)))?;
            Ok(Box::new(axis) as Box<dyn BusAxis>)
        }),
    };
    let err = run_on_bus(args, bus).expect_err("a failed exchange must end the commissioning");
    (err, dir)
}

/// The checks common to every fault: status 3, one line naming the stage and
/// the diagnostic, no results, the diagnostic's `limit` "axis" with `error`,
/// a second of samples that ends at the failure.
fn check_diagnostic(err: &anyhow::Error, dir: &std::path::Path, error: &str) -> serde_json::Value {
    assert_eq!(exit::status_of(err), ExitStatus::SafetyStop, "{err:#}");
    let line = exit::one_line(err);
    assert!(!line.contains('\n'), "{line}");
    assert!(line.contains("commissioning stopped in stage"), "{line}");
    assert!(line.contains("safety-stop.json"), "{line}");
    assert!(!dir.exists(), "no results in {}", dir.display());
    let diag = sibling(dir);
    let json: serde_json::Value =
        serde_json::from_slice(&std::fs::read(diag.join("safety-stop.json")).unwrap()).unwrap();
    assert_eq!(json["schema"], "beltune-safety-stop/1");
    assert_eq!(json["limit"], "axis", "{json:#}");
    assert_eq!(json["violation"]["Axis"]["error"], error, "{json:#}");
    assert!(!json["stage"].as_str().unwrap().is_empty());
    assert!(json["limits"]["travel_max_m"].as_f64().unwrap() > START_M);
    let csv = std::fs::read_to_string(diag.join("safety-stop.csv")).unwrap();
    let rows: Vec<&str> = csv.lines().skip(1).collect();
    // one second at 1 kHz (the ring holds ceil(1 s / T) samples)
    assert!((999..=1001).contains(&rows.len()), "{} samples", rows.len());
    assert_eq!(json["samples"].as_u64(), Some(rows.len() as u64));
    let last_t: f64 = rows
        .last()
        .unwrap()
        .split(',')
        .next()
        .unwrap()
        .parse()
        .unwrap();
    let t = json["time_s"].as_f64().unwrap();
    assert!(
        (last_t - t).abs() < 1e-9,
        "the samples end at the failure: {last_t} vs {t}"
    );
    // the failure came at the injected cycle count (less the bus start-up,
    // plus the cycles until it shows)
    let armed_s = FAULT_AFTER_CYCLES as f64 * 1e-3;
    assert!(
        (armed_s - 0.5..armed_s + 0.5).contains(&t),
        "failed at {t} s"
    );
    let _ = std::fs::remove_dir_all(&diag);
    json
}

#[test]
fn a_drive_fault_on_the_bus_ends_with_the_safety_stop_diagnostic() {
    let (err, dir) = commission_with(
        "fault",
        |f| {
            f.drive_fault
                .store(u32::from(OVERCURRENT), Ordering::Relaxed)
        },
        |_| {},
    );
    let json = check_diagnostic(&err, &dir, "drive_fault");
    assert_eq!(
        json["violation"]["Axis"]["error_code"].as_u64(),
        Some(u64::from(OVERCURRENT))
    );
    assert!(exit::one_line(&err).contains("0x2310"));
}

#[test]
fn frames_lost_on_the_bus_end_with_the_safety_stop_diagnostic() {
    // the master bridges 3 lost frames; 6 in a row are too many
    let (err, dir) = commission_with(
        "lost",
        |f| f.drop_frames.store(6, Ordering::Relaxed),
        |_| {},
    );
    let json = check_diagnostic(&err, &dir, "timeout");
    // the frames came back for the quick stop
    assert!(
        json["violation"]["Axis"]["quick_stop"].is_null(),
        "{json:#}"
    );
}

#[test]
fn the_drives_watchdog_ends_with_the_safety_stop_diagnostic() {
    // the drive hears nothing for 120 cycles (a master that stops sending);
    // this master bridges that many lost frames, so that it sees what the
    // drive did meanwhile: its SM watchdog (100 ms) removed the torque
    let (err, dir) = commission_with(
        "watchdog",
        |f| f.drop_requests.store(120, Ordering::Relaxed),
        |m| m.max_lost_frames = 200,
    );
    let json = check_diagnostic(&err, &dir, "drive_fault");
    assert_eq!(
        json["violation"]["Axis"]["error_code"].as_u64(),
        Some(u64::from(ERROR_WATCHDOG))
    );
}
