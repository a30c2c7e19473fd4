//! `beltune commission`: the one-command self-commissioning of the built-in
//! simulated axis (or a plant file), with progress bars, safety supervision,
//! validation and the report.

use crate::progress::BarProgress;
use anyhow::Context;
use beltune::design::{DesignKnobs, PrefilterKind};
use beltune::model::rigs::{self, Plant};
use beltune::procedure::commission::{commission, CommissioningConfig, DataSheet};
use beltune::procedure::outputs::{
    build_report, commissioning_json, controller_toml, write_outputs,
};
use beltune::procedure::result::Truth;
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
    #[arg(long)]
    pub payload: Option<f64>,
    /// Tilt of the axis, degrees (0 horizontal, 90 vertical).
    #[arg(long)]
    pub tilt: Option<f64>,
    /// Seed of the simulated measurement noise.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Output folder.
    #[arg(long, default_value = "commissioning")]
    pub out: PathBuf,
    /// Prefilter in the velocity loop.
    #[arg(long, value_enum, default_value = "butterworth")]
    pub prefilter: PrefilterArg,
    /// Velocity-loop phase margin, deg.
    #[arg(long)]
    pub pm_velocity: Option<f64>,
    /// Position-loop phase margin, deg.
    #[arg(long)]
    pub pm_position: Option<f64>,
    /// Resonance suppression A_sup, dB (negative).
    #[arg(long, allow_hyphen_values = true)]
    pub resonance_suppression_db: Option<f64>,
    /// Prefilter gain at the antiresonance, dB (negative).
    #[arg(long, allow_hyphen_values = true)]
    pub filter_attenuation_db: Option<f64>,
    /// Travel window MIN,MAX in m (default: inside the stroke).
    #[arg(long, value_parser = parse_pair, allow_hyphen_values = true)]
    pub travel_window: Option<(f64, f64)>,
    /// Cart position at start (the homing result), m.
    #[arg(long, default_value_t = 0.05)]
    pub start_position: f64,
    /// No progress bars or log lines.
    #[arg(long)]
    pub quiet: bool,
}

/// Prefilter choice on the command line.
#[derive(Clone, Copy, clap::ValueEnum)]
pub enum PrefilterArg {
    /// 2nd-order Butterworth low-pass (4.3).
    Butterworth,
    /// Notch (4.1) at the resonance.
    Notch,
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

/// The data sheet the commissioning may use: what a technician would enter.
fn datasheet(plant: &Plant, args: &Args) -> anyhow::Result<DataSheet> {
    let info = plant.info();
    let (theta_e, i_t, mass, stroke) = match plant {
        Plant::Physical(p) => (p.theta_e(), p.i_t(), p.m_c(), p.stroke_m),
        Plant::Linear(l) => (l.two_mass.theta_e, l.two_mass.i_t, l.two_mass.m_c, 0.6),
    };
    let (lo, hi) = args.travel_window.unwrap_or((-0.01, stroke - 0.03));
    Ok(DataSheet {
        theta_e_kg_m2: theta_e,
        i_t_m: i_t,
        moving_mass_kg: mass,
        origin_m: args.start_position,
        travel_min_m: lo,
        travel_max_m: hi,
        torque_max_nm: info.torque_limit_nm,
        velocity_max_m_s: 2.5,
    })
}

/// Run the subcommand.
pub fn run(args: Args) -> anyhow::Result<()> {
    let plant = load_plant(&args)?;
    let ds = datasheet(&plant, &args)?;
    let mut cfg = CommissioningConfig {
        knobs: DesignKnobs {
            prefilter: match args.prefilter {
                PrefilterArg::Butterworth => PrefilterKind::Butterworth,
                PrefilterArg::Notch => PrefilterKind::Notch,
            },
            ..DesignKnobs::default()
        },
        ..CommissioningConfig::default()
    };
    if let Some(v) = args.pm_velocity {
        cfg.knobs.pm_velocity_deg = v;
    }
    if let Some(v) = args.pm_position {
        cfg.knobs.pm_position_deg = v;
    }
    if let Some(v) = args.resonance_suppression_db {
        cfg.knobs.resonance_suppression_db = v;
    }
    cfg.knobs.filter_attenuation_db = args.filter_attenuation_db;
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
    let report = build_report(&run, &name, before.as_ref(), Some(&truth));
    let html = render_html(&report)?;
    let files = write_outputs(&args.out, &json, &toml, &html)?;
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
