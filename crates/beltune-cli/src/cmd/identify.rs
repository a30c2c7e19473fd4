//! `beltune identify`: a two-mass model from a recorded periodic excitation
//! (CSV): ETFE with Clary's method II and coherence, LM fit of the two-mass
//! model, optional current-loop dead time. Thesis chapter 3.

use super::util::write_atomic;
use beltune::ident::recorded::ClosedLoopRecord;
use beltune::ident::{
    fit::model_magnitude_db, identify_recorded, ClosedLoopMethod, DeadTime, EtfeConfig, FitConfig,
    IdentificationStrategy, KnownController, ModelUnits, RecordedExcitation,
    RecordedIdentification, ReferenceKind, TwoMassFit,
};
use beltune::record::model::{IdentifiedModel, ModelFile, DEFAULT_DEAD_TIME_S};
use beltune::record::provenance::Provenance;
use std::fmt::Write as _;
use std::path::PathBuf;

/// Arguments of `beltune identify`.
#[derive(clap::Args)]
pub struct Args {
    /// CSV file with a header row.
    #[arg(long)]
    pub csv: PathBuf,
    /// Time column, s.
    #[arg(long)]
    pub time: String,
    /// Input column: torque in N m (or motor current with --current-units);
    /// with --reference, the torque command the drive applied (excitation plus controller output).
    #[arg(long)]
    pub input: String,
    /// Output column: motor angle, rad.
    #[arg(long)]
    pub output: String,
    /// Samples per excitation period (default: detected from an exactly periodic input).
    #[arg(long, value_parser = super::commission::parse_period)]
    pub period_samples: Option<usize>,
    /// Leading periods discarded as transient.
    #[arg(long, default_value_t = 1, value_parser = super::commission::parse_skip)]
    pub skip_periods: usize,
    /// Known motor-side inertia Theta_e (kg m^2, or A s^2/rad in current units); without it, it is fitted.
    #[arg(long, allow_negative_numbers = true)]
    pub inertia: Option<f64>,
    /// Transmission i_t = r / i_g in m/rad (1 for a rotary two-mass system).
    #[arg(long, default_value_t = 1.0, allow_negative_numbers = true)]
    pub transmission: f64,
    /// Fit Theta_e too (starting from --inertia if given).
    #[arg(long)]
    pub free_inertia: bool,
    /// The input is a motor current in A (torque constant unknown): parameters in current units.
    #[arg(long)]
    pub current_units: bool,
    /// Actual-torque column: estimate the current-loop dead time (3.27) against --input as desired torque.
    #[arg(long)]
    pub actual_torque: Option<String>,
    /// Lowest frequency used, Hz.
    #[arg(long, allow_negative_numbers = true)]
    pub min_freq_hz: Option<f64>,
    /// Highest frequency used, Hz.
    #[arg(long, allow_negative_numbers = true)]
    pub max_freq_hz: Option<f64>,
    /// Lines with a lower magnitude-squared coherence are not fitted.
    #[arg(long, default_value_t = 0.5, allow_negative_numbers = true)]
    pub min_coherence: f64,
    /// Lines whose input power is this many dB below the strongest are "not excited".
    #[arg(long, default_value_t = -40.0, allow_hyphen_values = true)]
    pub excitation_floor_db: f64,
    /// Lines whose input power is this many dB below the strongest of their 8
    /// neighbours either side are "not excited" (the gaps of a sparse multisine).
    #[arg(long, default_value_t = -20.0, allow_hyphen_values = true)]
    pub local_floor_db: f64,
    #[command(flatten)]
    pub closed_loop: ClosedLoopArgs,
    /// Write the FRF with coherence and line status here (CSV).
    #[arg(long)]
    pub frf_csv: Option<PathBuf>,
    /// Write the fitted model here (JSON; the model file of `beltune design`, docs/schema.md).
    #[arg(long)]
    pub json: Option<PathBuf>,
    /// The drive's torque limit, in the unit of --input (N m, or A with
    /// --current-units), recorded in the --json model.
    #[arg(long)]
    pub torque_limit: Option<f64>,
}

/// Where a closed-loop record's excitation entered (thesis 3.3.2).
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum ReferenceKindArg {
    /// An excitation torque (N m, or A) added to the controller output.
    Torque,
    /// The velocity setpoint omega_d, motor rad/s.
    Velocity,
    /// The position setpoint phi_d, motor rad.
    Position,
}

/// Direct or indirect closed-loop identification (thesis 3.3.2).
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum MethodArg {
    /// Torque command -> angle; needs no controller.
    Direct,
    /// Reference -> angle, inverted with the known controller (--controller).
    Indirect,
}

/// The flags of a closed-loop record (`identify` and `commission --csv`).
#[derive(clap::Args, Clone, Debug)]
pub struct ClosedLoopArgs {
    /// Closed-loop record: the column the periodic excitation was added to
    /// (see --reference-kind); --input is then the applied torque command.
    #[arg(long)]
    pub reference: Option<String>,
    /// What --reference holds.
    #[arg(long, value_enum, default_value_t = ReferenceKindArg::Velocity, requires = "reference")]
    pub reference_kind: ReferenceKindArg,
    /// Direct (torque command -> angle) or indirect (reference -> angle with the known controller).
    #[arg(long, value_enum, default_value_t = MethodArg::Direct, requires = "reference")]
    pub method: MethodArg,
    /// The controller the drive ran during the record (controller.toml); the indirect method needs it.
    #[arg(long, requires = "reference")]
    pub controller: Option<PathBuf>,
}

/// The closed-loop part of a record, checked: `None` for an open-loop record.
pub fn closed_loop_record<'a>(
    a: &'a ClosedLoopArgs,
    input: &str,
    output: &str,
) -> anyhow::Result<Option<ClosedLoopRecord<'a>>> {
    let Some(reference) = a.reference.as_deref() else {
        return Ok(None);
    };
    let bad = |m: String| {
        anyhow::Error::new(crate::exit::Failure::new(
            crate::exit::ExitStatus::BadInput,
            m,
        ))
    };
    for (flag, other) in [("--input", input), ("--output", output)] {
        if reference == other {
            return Err(bad(format!(
                "--reference `{reference}` is the same column as {flag}; give the column the excitation was added to"
            )));
        }
    }
    let method = match a.method {
        MethodArg::Direct => ClosedLoopMethod::Direct,
        MethodArg::Indirect => ClosedLoopMethod::Indirect,
    };
    let controller = match &a.controller {
        Some(path) => {
            let file = beltune::record::controller::ControllerFile::load(path)?;
            Some(KnownController::new(file.cascade_config()?)?)
        }
        None if method == ClosedLoopMethod::Indirect => {
            return Err(bad(
                "--method indirect needs --controller: the controller.toml the drive ran during the record"
                    .to_string(),
            ))
        }
        None => None,
    };
    Ok(Some(ClosedLoopRecord {
        reference,
        kind: match a.reference_kind {
            ReferenceKindArg::Torque => ReferenceKind::Torque,
            ReferenceKindArg::Velocity => ReferenceKind::Velocity,
            ReferenceKindArg::Position => ReferenceKind::Position,
        },
        method,
        controller,
    }))
}

/// The model file (docs/schema.md): an identified-model record that `beltune
/// design --model` reads, plus the fit details.
#[derive(serde::Serialize)]
struct ModelJson {
    #[serde(flatten)]
    record: ModelFile,
    fit: FitDetails,
}

/// What the fit saw beyond the model.
#[derive(serde::Serialize)]
struct FitDetails {
    /// Open loop or direct / indirect closed loop, with the reference kind.
    identification: IdentificationStrategy,
    free_inertia: bool,
    n_periods: usize,
    /// Dead time in samples; null when no actual-torque column was given.
    dead_time_samples: Option<usize>,
    uncertainty: Option<beltune::ident::ParamUncertainty>,
    features: beltune::ident::FrfFeatures,
}

/// Run the subcommand.
pub fn run(args: Args) -> anyhow::Result<()> {
    let mut inputs = vec![args.csv.as_path()];
    if let Some(c) = &args.closed_loop.controller {
        inputs.push(c.as_path());
    }
    for (flag, out) in [("--json", &args.json), ("--frf-csv", &args.frf_csv)] {
        if let Some(out) = out {
            super::util::check_not_an_input(flag, out, &inputs)?;
        }
    }
    if let (Some(json), Some(frf)) = (&args.json, &args.frf_csv) {
        if super::util::same_file(json, frf) {
            return Err(anyhow::Error::new(crate::exit::Failure::new(
                crate::exit::ExitStatus::BadInput,
                format!(
                    "--json and --frf-csv name the same file {}: one would replace the other",
                    json.display()
                ),
            )));
        }
    }
    if let Some(a) = &args.actual_torque {
        for (flag, other) in [
            ("--time", &args.time),
            ("--input", &args.input),
            ("--output", &args.output),
        ] {
            if a == other {
                return Err(anyhow::Error::new(crate::exit::Failure::new(
                    crate::exit::ExitStatus::BadInput,
                    format!("--actual-torque `{a}` is the same column as {flag}; give the measured-torque column"),
                )));
            }
        }
    }
    for (flag, v) in [
        ("--inertia", args.inertia),
        ("--transmission", Some(args.transmission)),
    ] {
        if let Some(v) = v {
            if !(v.is_finite() && v > 0.0 && v <= 1e3) {
                return Err(anyhow::Error::new(crate::exit::Failure::new(
                    crate::exit::ExitStatus::BadInput,
                    format!(
                        "{flag} {} is out of range (0, 1000]",
                        beltune::error::short_number(v)
                    ),
                )));
            }
        }
    }
    if let Some(t) = args.torque_limit {
        super::util::check_torque_limit_flag("--torque-limit", t)?;
    }
    let torque_max = args.torque_limit;
    let band = match (args.min_freq_hz, args.max_freq_hz) {
        (None, None) => None,
        (lo, hi) => Some((lo.unwrap_or(0.0), hi.unwrap_or(f64::MAX))),
    };
    let closed_loop = closed_loop_record(&args.closed_loop, &args.input, &args.output)?;
    let id = identify_recorded(&RecordedExcitation {
        csv: &args.csv,
        time: &args.time,
        input: &args.input,
        output: &args.output,
        actual_torque: args.actual_torque.as_deref(),
        period_samples: args.period_samples,
        skip_periods: args.skip_periods,
        etfe: EtfeConfig {
            integrator: true,
            excitation_floor_db: args.excitation_floor_db,
            local_floor_db: args.local_floor_db,
            min_coherence: args.min_coherence,
            band_hz: band,
            ..EtfeConfig::default()
        },
        fit: FitConfig {
            theta_e: args.inertia,
            free_inertia: args.free_inertia || args.inertia.is_none(),
            i_t: args.transmission,
            units: if args.current_units {
                ModelUnits::Current
            } else {
                ModelUnits::Torque
            },
            ..Default::default()
        },
        closed_loop,
    })?;
    let (frf, fit, dead_time) = (&id.frf, &id.fit, id.dead_time);
    print_summary(&id);
    if let Some(path) = &args.frf_csv {
        write_atomic(path, frf_csv(frf, fit).as_bytes())?;
    }
    if let Some(path) = &args.json {
        let mut identified = IdentifiedModel::from_fit(
            fit,
            frf,
            dead_time.map_or(DEFAULT_DEAD_TIME_S, |d| d.seconds),
            f64::NAN,
        );
        identified.dead_time_measured = dead_time.is_some();
        identified.ts_s = Some(id.ts_s);
        identified.torque_max_nm = torque_max;
        let json = ModelJson {
            record: ModelFile::new(identified, None, Provenance::of_this_process(None)),
            fit: FitDetails {
                identification: id.method,
                free_inertia: fit.free_inertia,
                n_periods: frf.n_periods,
                dead_time_samples: dead_time.map(|d| d.samples),
                uncertainty: fit.uncertainty,
                features: fit.features,
            },
        };
        let mut v = serde_json::to_value(&json)?;
        if fit.units == ModelUnits::Current {
            beltune::units::relabel_keys(&mut v, &beltune::units::current_key);
        }
        let mut text = serde_json::to_string_pretty(&v)?;
        text.push('\n');
        write_atomic(path, text.as_bytes())?;
    }
    Ok(())
}

fn print_summary(id: &RecordedIdentification) {
    let (fit, dead_time, n_periods) = (&id.fit, id.dead_time.as_ref(), id.frf.n_periods);
    let p = fit.params;
    let u = if fit.units == ModelUnits::Current {
        " (current units: N m read as A)"
    } else {
        ""
    };
    println!(
        "two-mass model{u}, {n_periods} periods averaged, {} lines fitted",
        fit.n_lines
    );
    println!("  method: {}", id.method.words());
    println!("  lines: {}", id.frf.line_summary());
    println!(
        "  period {} samples ({})",
        id.period_samples,
        if id.period_detected {
            "detected"
        } else {
            "given"
        }
    );
    println!(
        "  f_r = {:.3} Hz, f_z = {:.3} Hz, fit RMS {:.3} dB",
        fit.f_r_hz, fit.f_z_hz, fit.fit_rms_db
    );
    let sig = |f: fn(&beltune::ident::ParamUncertainty) -> f64| {
        fit.uncertainty
            .map_or(String::from("?"), |s| format!("{:.3e}", f(&s)))
    };
    println!("  theta_e = {:.6e} +- {}", p.theta_e, sig(|s| s.theta_e));
    println!("  m_c     = {:.6e} +- {}", p.m_c, sig(|s| s.m_c));
    println!("  c       = {:.6e} +- {}", p.c, sig(|s| s.c));
    println!("  d_m     = {:.6e} +- {}", p.d_m, sig(|s| s.d_m));
    println!("  d_c     = {:.6e} +- {}", p.d_c, sig(|s| s.d_c));
    println!("  i_t     = {:.6e}", p.i_t);
    if let Some(d) = dead_time {
        print_dead_time(d);
    }
    if let Ok(r) = beltune::ident::fit_residual(&id.frf, fit) {
        println!("  {}", r.words());
    }
}

fn print_dead_time(d: &DeadTime) {
    if d.fractional_samples == d.samples as f64 {
        println!("  dead time {} samples = {:.6e} s", d.samples, d.seconds);
    } else {
        println!(
            "  dead time {:.2} +- {:.2} samples = {:.6e} s (whole-sample (3.29): {})",
            d.fractional_samples, d.sigma_samples, d.seconds, d.samples
        );
    }
}

fn frf_csv(frf: &beltune::ident::Frf, fit: &TwoMassFit) -> String {
    let mut s = String::from(
        "freq_hz,magnitude_db,phase_deg,re,im,coherence,status,model_magnitude_db,residual_db\n",
    );
    for i in 0..frf.freq_hz.len() {
        let g = frf.response[i];
        let w = frf.omega_rad_s(i);
        let (mag, model, residual) = if i == 0 {
            (String::new(), String::new(), String::new())
        } else {
            let model = model_magnitude_db(&fit.params, fit.model, w);
            let (m, r) = if g.norm() > 0.0 {
                (
                    format!("{}", frf.magnitude_db(i)),
                    format!("{}", frf.magnitude_db(i) - model),
                )
            } else {
                (String::new(), String::new())
            };
            (m, format!("{model}"), r)
        };
        let _ = writeln!(
            s,
            "{},{},{},{},{},{},{},{},{}",
            frf.freq_hz[i],
            mag,
            g.arg().to_degrees(),
            g.re,
            g.im,
            frf.coherence[i],
            frf.line_status[i].label(),
            model,
            residual
        );
    }
    s
}
