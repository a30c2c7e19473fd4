//! `beltune virtual-drive`: a virtual CiA 402 servo drive on a network
//! interface. It answers as one EtherCAT SubDevice (registers, SII, AL state
//! machine, sync managers, FMMUs, CoE SDO mailbox, distributed clocks, SM
//! watchdog); behind it runs the simulator of the plant (egc70 by default)
//! with its current-loop dead time, and the cart position is offered as the
//! load-side position 0x60E4:01. Stops on SIGINT/SIGTERM.

use anyhow::Context;
use beltune::sim::SimConfig;
use beltune_ethercat::drive::{DriveConfig, VirtualDrive};
use std::sync::atomic::{AtomicBool, Ordering};

/// Arguments of `beltune virtual-drive`.
#[derive(clap::Args)]
pub struct Args {
    /// Network interface to answer on (e.g. one end of a veth pair).
    #[arg(long, required_unless_present = "esi")]
    pub interface: Option<String>,
    /// Write the drive's ESI file (EtherCAT SubDevice Information, ETG.2000
    /// XML, for TwinCAT and other configurators) to FILE and exit.
    #[arg(long, value_name = "FILE")]
    pub esi: Option<std::path::PathBuf>,
    /// Built-in plant name (egc70, sim-a, sim-b, sim-c) or a plant TOML file
    /// (a built-in name always means the built-in plant; write `./egc70` for a file).
    #[arg(long, default_value = "egc70")]
    pub plant: String,
    /// Payload on the cart, kg (egc70 only; default 11.2 kg).
    #[arg(long)]
    pub payload: Option<f64>,
    /// The drive's cycle (SYNC0 period it accepts), us.
    #[arg(long, default_value_t = 1000)]
    pub cycle_us: u32,
    /// Cart position at power-up, m.
    #[arg(long, default_value_t = 0.05, allow_negative_numbers = true)]
    pub start_position: f64,
    /// Seed of the simulated measurement noise.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Offer no distributed clocks: the drive runs SM-synchronous, one cycle
    /// per process-data frame (independent of the host's timing).
    #[arg(long)]
    pub no_dc: bool,
    /// Run the drive under SCHED_FIFO at this priority (1-99; root or
    /// CAP_SYS_NICE): on a busy host a normally scheduled drive is
    /// descheduled for milliseconds and its answers miss their cycle.
    #[arg(long, value_name = "PRIO")]
    pub realtime_priority: Option<u8>,
}

static STOP: AtomicBool = AtomicBool::new(false);

extern "C" fn on_signal(_: libc::c_int) {
    STOP.store(true, Ordering::Relaxed);
}

/// Run the subcommand.
pub fn run(args: Args) -> anyhow::Result<()> {
    if !args.start_position.is_finite() {
        return Err(super::commission::preflight::bad(format!(
            "--start-position {} is not a finite number",
            args.start_position
        )));
    }
    let plant = super::plant::resolve_plant(&args.plant, args.payload)?;
    let cfg = DriveConfig {
        cycle_s: f64::from(args.cycle_us) * 1e-6,
        sim: SimConfig {
            seed: args.seed,
            initial_cart_position_m: Some(args.start_position),
            ..SimConfig::default()
        },
        distributed_clocks: !args.no_dc,
        ..DriveConfig::default()
    };
    // a refused setting is bad input (exit status 2), like the library's own
    let mut drive = VirtualDrive::new(&plant, cfg).map_err(|e| match e {
        beltune_ethercat::Error::Sim(lib) => anyhow::Error::new(lib).context("virtual drive"),
        e @ beltune_ethercat::Error::Config { .. } => {
            super::commission::preflight::bad(format!("virtual drive: {e}"))
        }
        e => anyhow::Error::new(e).context("virtual drive"),
    })?;
    if let Some(path) = &args.esi {
        beltune::io::write_atomic(path, drive.esi().as_bytes())?;
        eprintln!(
            "ESI of `{}` written to {}",
            beltune_ethercat::drive::NAME,
            path.display()
        );
        return Ok(());
    }
    let interface = args.interface.clone().unwrap_or_default();
    if let Some(p) = args.realtime_priority {
        beltune_ethercat::sched::set_realtime_priority(p).context("--realtime-priority")?;
    }
    // SAFETY: installing an async-signal-safe handler (an atomic store).
    unsafe {
        libc::signal(libc::SIGINT, on_signal as *const () as libc::sighandler_t);
        libc::signal(libc::SIGTERM, on_signal as *const () as libc::sighandler_t);
    }
    eprintln!(
        "virtual drive `{}` on {}: plant {}, cycle {} us; Ctrl-C stops",
        beltune_ethercat::drive::NAME,
        interface,
        args.plant,
        args.cycle_us
    );
    let stats = beltune_ethercat::serve::serve(&interface, &mut drive, &STOP)?;
    eprintln!(
        "stopped: {} frames, {} cycles ({} without new outputs), {} watchdog expiries; AL {}{}, status code {:#06x}",
        stats.frames,
        stats.cycles,
        stats.cycles_without_new_outputs,
        stats.watchdog_expiries,
        stats.al_state,
        if stats.al_error { " (error latched)" } else { "" },
        stats.al_status_code
    );
    Ok(())
}
