//! `beltune design`: the cascaded P-PI controller with prefilter and feedforward
//! from an identified model (thesis chapter 4).
//!
//! Knob precedence: defaults (thesis: Butterworth, 60 deg / 80 deg, -10 dB), then
//! `--dynamics` (one-knob mode), then the explicit expert flags.

use anyhow::Context;
use beltune::design::{self, ControllerDesign, DesignSummary};
use beltune::record::model::ModelFile;
use std::path::PathBuf;

/// Arguments of `beltune design`.
#[derive(clap::Args)]
pub struct Args {
    /// Identified model (docs/schema.md): `commissioning.json`, the JSON written by
    /// `beltune identify --json`, or a TOML with theta_e, m_c, c, d_m, d_c, i_t and optional
    /// dead_time_s, t_r_s, d, viscous_nm_s_per_rad, coulomb_nm.
    #[arg(long)]
    model: PathBuf,
    #[command(flatten)]
    knobs: super::knobs::KnobArgs,
    /// Sampling time of the controller in s, 1e-6 ..= 0.1 (default: the model's `ts_s`, else 100 us).
    #[arg(long, allow_negative_numbers = true)]
    ts: Option<f64>,
    /// Write the design as JSON to this file.
    #[arg(long)]
    json: Option<PathBuf>,
}

/// The JSON document: the flat summary keys, the discrete coefficients and the full design.
#[derive(serde::Serialize)]
struct JsonOut<'a> {
    #[serde(flatten)]
    summary: DesignSummary,
    discrete: &'a design::DiscreteController,
    feedforward: &'a design::Feedforward,
    drive_form: design::DriveForm,
    design: &'a ControllerDesign,
}

/// Run the subcommand.
pub fn run(args: Args) -> anyhow::Result<()> {
    let check_ts = |ts: f64, what: &str| -> anyhow::Result<()> {
        beltune::model::params::check_sample_time(ts).map_err(|e| {
            let why = match e {
                beltune::Error::InvalidParameter { reason, .. } => reason,
                e => e.to_string(),
            };
            anyhow::Error::new(crate::exit::Failure::new(
                crate::exit::ExitStatus::BadInput,
                format!("{what} {}: {why}", beltune::error::short_number(ts)),
            ))
        })
    };
    if let Some(ts) = args.ts {
        check_ts(ts, "--ts")?;
    }
    if let Some(out) = &args.json {
        super::util::check_not_an_input("--json", out, &[&args.model])?;
    }
    let model = ModelFile::load(&args.model)?;
    check_ts(
        model.design_ts_s(args.ts),
        &format!("{}: the sampling time ts_s", args.model.display()),
    )?;
    let knobs = args.knobs.knobs()?;
    let d = model
        .design(args.ts, &knobs, args.knobs.rule())
        .map_err(|e| super::util::in_flag_words(e.into(), &super::util::KNOB_FLAGS))?
        .design;
    if !model.identified.dead_time_measured {
        println!(
            "dead time:  not measured; {} ms assumed (thesis 3.30)",
            model.identified.dead_time_s * 1e3
        );
    }
    print!("{}", human_summary(&d, model.identified.units));
    if let Some(path) = &args.json {
        let doc = JsonOut {
            summary: d.summary(),
            discrete: &d.discrete,
            feedforward: &d.feedforward,
            drive_form: design::DriveForm::of(&d),
            design: &d,
        };
        let text = serde_json::to_string_pretty(&doc).context("serializing the design")?;
        super::util::write_atomic(path, text.as_bytes())?;
        println!("wrote {}", path.display());
    }
    Ok(())
}

fn human_summary(d: &ControllerDesign, units: beltune::ident::ModelUnits) -> String {
    let s = d.summary();
    let l = beltune::units::labels(units);
    let (tv, ta, inertia, torque) = (
        l.torque_per_velocity,
        l.torque_per_angle,
        l.inertia,
        l.torque,
    );
    let filter = match d.prefilter {
        design::Prefilter::Butterworth { omega_bw_rad_s } => {
            format!("Butterworth, w_bw = {omega_bw_rad_s:.2} rad/s")
        }
        design::Prefilter::Notch { omega_r_rad_s, d_n } => {
            format!("notch at w_r = {omega_r_rad_s:.2} rad/s, d_n = {d_n:.3}")
        }
        design::Prefilter::None => "none".to_string(),
    };
    let rule = match d.velocity_rule {
        design::VelocityRule::ResonanceSuppression => "resonance suppression (4.7) met",
        design::VelocityRule::MaxIntegralGain => {
            "phase-limited loop: resonance below A_sup everywhere, K_I maximized"
        }
    };
    format!(
        "model:      w_r = {:.2} rad/s ({:.2} Hz), w_z = {:.2} rad/s ({:.2} Hz)\n\
         prefilter:  {filter}\n\
         velocity:   K_P = {:.5} {tv}, K_I = {:.5} {ta}\n\
         \x20           w_c = {:.2} rad/s, PM = {:.2} deg, GM = {:.2} dB, |L(j w_r)| = {:.2} dB ({rule})\n\
         position:   K_PP = {:.4} 1/s, w_c = {:.2} rad/s, PM = {:.2} deg, GM = {:.2} dB\n\
         feedforward: m_e = {:.4e} {inertia}, d_v = {:.4e} {tv}, tau_c = {:.4} {torque}, K_v = 1\n\
         discrete:   T_s = {} s, closed-loop pole radius {:.6} (velocity), {:.6} (position)\n",
        d.omega_r_rad_s,
        d.omega_r_rad_s / std::f64::consts::TAU,
        d.omega_z_rad_s,
        d.omega_z_rad_s / std::f64::consts::TAU,
        s.k_p,
        s.k_i,
        s.omega_c_velocity,
        s.phase_margin_velocity_deg,
        s.gain_margin_velocity_db,
        s.gain_at_resonance_db,
        s.k_pp,
        s.omega_c_position,
        s.phase_margin_position_deg,
        s.gain_margin_position_db,
        d.feedforward.inertia_kg_m2,
        d.feedforward.viscous_nm_s_per_rad,
        d.feedforward.coulomb_nm,
        s.ts_s,
        d.discrete_stability.velocity_max_pole_magnitude,
        d.discrete_stability.position_max_pole_magnitude,
    )
}
