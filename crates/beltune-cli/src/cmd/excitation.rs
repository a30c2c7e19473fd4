//! `beltune excitation`: the periodic excitation beltune identifies from, as a
//! CSV to play on another drive (function generator, trace import), with the
//! metadata `beltune commission --csv` needs to analyze the recording (period
//! and transient periods to skip) in a JSON file beside it.
//!
//! Signals (beltune_rt::prbs): PRBS (thesis 3.2), chirp and Schroeder-phase
//! multisine. `--amplitude A` is the peak of the file for every kind (the
//! largest setpoint the drive receives): PRBS values `+-A` (the thesis'
//! `A_PRBS` is the peak-to-peak `2 A`), chirp peak `A`, multisine scaled so
//! that its peak is `A`.

use crate::exit::{ExitStatus, Failure};
use beltune_rt::prbs::{Chirp, Multisine, Prbs, Sweep};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// Largest number of rows written (10 million: 1000 s at 10 kHz).
pub const MAX_ROWS: u64 = 10_000_000;

/// Signal kind.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Kind {
    /// Pseudo-random binary sequence (values +-A), period (2^n - 1) P samples.
    Prbs,
    /// Periodic sine sweep of peak A.
    Chirp,
    /// Sum of sines at harmonics of the period, Schroeder phases, peak A in all.
    Multisine,
}

/// Chirp sweep law.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum SweepArg {
    /// Frequency linear in time.
    Linear,
    /// Equal time per decade.
    Log,
}

/// Arguments of `beltune excitation`.
#[derive(clap::Args)]
pub struct Args {
    /// Signal kind.
    #[arg(long, value_enum)]
    pub kind: Kind,
    /// Sampling time of the drive that plays it, s.
    #[arg(long, allow_negative_numbers = true)]
    pub ts: f64,
    /// Peak of the signal in the unit of the drive's setpoint (N m or A), the same for
    /// every kind: the largest absolute value in the file (PRBS values +-A).
    #[arg(long, allow_negative_numbers = true)]
    pub amplitude: f64,
    /// PRBS order n_PRBS (2..=20).
    #[arg(long, default_value_t = 9)]
    pub order: u32,
    /// PRBS clock period P_PRBS, samples per value.
    #[arg(long, default_value_t = 16)]
    pub clock: u32,
    /// Chirp and multisine: samples per period.
    #[arg(long, default_value_t = 8192)]
    pub period_samples: u32,
    /// Chirp: start frequency, Hz.
    #[arg(long, default_value_t = 1.0)]
    pub f_start_hz: f64,
    /// Chirp: end frequency, Hz.
    #[arg(long, default_value_t = 500.0)]
    pub f_end_hz: f64,
    /// Chirp: sweep law.
    #[arg(long, value_enum, default_value_t = SweepArg::Log)]
    pub sweep: SweepArg,
    /// Multisine: number of lines (8, 16, 32, 64, 128, 256 or 512).
    #[arg(long, default_value_t = 128)]
    pub lines: usize,
    /// Multisine: harmonic of the first line.
    #[arg(long, default_value_t = 1)]
    pub first_harmonic: u32,
    /// Multisine: spacing of the lines, in harmonics.
    #[arg(long, default_value_t = 1)]
    pub harmonic_step: u32,
    /// Periods written (the first `--skip-periods` are the transient).
    #[arg(long, default_value_t = 6)]
    pub periods: u32,
    /// Leading periods `commission --csv` should discard as transient.
    #[arg(long, default_value_t = 1)]
    pub skip_periods: u32,
    /// Output CSV (columns t_s, excitation); the metadata go to the same name with `.json`.
    #[arg(long)]
    pub out: PathBuf,
}

/// The metadata beside the CSV.
#[derive(Debug, serde::Serialize)]
pub struct Metadata {
    /// Signal kind.
    pub kind: Kind,
    /// Sampling time, s.
    pub ts_s: f64,
    /// The requested peak, as given (see `--amplitude`).
    pub amplitude: f64,
    /// Largest absolute value in the file.
    pub peak: f64,
    /// Samples per period: `commission --csv --period-samples`.
    pub period_samples: u64,
    /// Periods in the file.
    pub periods: u32,
    /// Transient periods to skip: `commission --csv --skip-periods`.
    pub skip_periods: u32,
    /// Lowest and highest excited frequency, Hz.
    pub band_hz: [f64; 2],
    /// Kind-specific parameters.
    pub parameters: serde_json::Value,
    /// The arguments `beltune commission --csv REC.csv` needs for this excitation.
    pub commission_args: Vec<String>,
}

fn bad(m: impl Into<String>) -> anyhow::Error {
    anyhow::Error::new(Failure::new(ExitStatus::BadInput, m))
}

fn multisine<const N: usize>(a: &Args) -> anyhow::Result<(Vec<f64>, [f64; 2])> {
    let harmonics: [u32; N] = core::array::from_fn(|i| {
        a.first_harmonic
            .saturating_add((i as u32).saturating_mul(a.harmonic_step))
    });
    // unit lines, then scaled so that the period's peak is the amplitude
    let mut m = Multisine::<f64, N>::new(a.period_samples, harmonics, 1.0)
        .map_err(|e| bad(format!("multisine: {e}")))?;
    let mut x = vec![0.0; a.period_samples as usize];
    m.fill(&mut x);
    let peak = x.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    if !(peak.is_finite() && peak > 0.0) {
        return Err(bad("multisine: the lines cancel (peak 0)"));
    }
    let scale = a.amplitude / peak;
    x.iter_mut().for_each(|v| *v *= scale);
    let f = |h: u32| f64::from(h) / (f64::from(a.period_samples) * a.ts);
    Ok((x, [f(harmonics[0]), f(harmonics[N - 1])]))
}

/// One period of the signal and its band.
fn one_period(a: &Args) -> anyhow::Result<(Vec<f64>, [f64; 2], serde_json::Value)> {
    match a.kind {
        Kind::Prbs => {
            if !(2..=20).contains(&a.order) {
                return Err(bad(format!(
                    "--order {}: must lie in 2..=20 (periods of 3 to {} values)",
                    a.order,
                    (1u64 << 20) - 1
                )));
            }
            // the generator's amplitude is the thesis' peak-to-peak A_PRBS (values +-A_PRBS/2)
            let mut p = Prbs::<f64>::new(a.order, a.clock, 2.0 * a.amplitude)
                .map_err(|e| bad(format!("PRBS: {e}")))?;
            let n = p.period_samples();
            if n > MAX_ROWS {
                return Err(bad(format!("PRBS period of {n} samples is too long")));
            }
            let mut x = vec![0.0; n as usize];
            p.fill(&mut x);
            let band = [p.f_min_hz(a.ts), p.f_max_hz(a.ts)];
            let params = serde_json::json!({"order": a.order, "clock_period": a.clock,
                "a_prbs_peak_to_peak": 2.0 * a.amplitude});
            Ok((x, band, params))
        }
        Kind::Chirp => {
            let sweep = match a.sweep {
                SweepArg::Linear => Sweep::Linear,
                SweepArg::Log => Sweep::Logarithmic,
            };
            let mut c = Chirp::<f64>::new(
                sweep,
                a.f_start_hz,
                a.f_end_hz,
                a.period_samples,
                a.ts,
                a.amplitude,
            )
            .map_err(|e| bad(format!("chirp: {e}")))?;
            let mut x = vec![0.0; a.period_samples as usize];
            c.fill(&mut x);
            let lo = a.f_start_hz.min(a.f_end_hz);
            let hi = a.f_start_hz.max(a.f_end_hz);
            let params = serde_json::json!({"f_start_hz": a.f_start_hz, "f_end_hz": a.f_end_hz,
                "sweep": a.sweep, "period_samples": a.period_samples});
            Ok((x, [lo, hi], params))
        }
        Kind::Multisine => {
            let (x, band) = match a.lines {
                8 => multisine::<8>(a)?,
                16 => multisine::<16>(a)?,
                32 => multisine::<32>(a)?,
                64 => multisine::<64>(a)?,
                128 => multisine::<128>(a)?,
                256 => multisine::<256>(a)?,
                512 => multisine::<512>(a)?,
                n => {
                    return Err(bad(format!(
                        "--lines {n}: one of 8, 16, 32, 64, 128, 256, 512"
                    )))
                }
            };
            let params = serde_json::json!({"lines": a.lines, "first_harmonic": a.first_harmonic,
                "harmonic_step": a.harmonic_step, "period_samples": a.period_samples,
                "phases": "Schroeder"});
            Ok((x, band, params))
        }
    }
}

/// The metadata path of `csv`: the same name with `.json`.
pub fn metadata_path(csv: &Path) -> PathBuf {
    csv.with_extension("json")
}

/// Error unless `path` is new or an excitation metadata file beltune wrote
/// (`kind` and `commission_args` at the top): `--out R/commissioning.csv`
/// must not replace `R/commissioning.json` with the excitation's metadata.
fn check_replaceable_metadata(path: &Path) -> anyhow::Result<()> {
    if std::fs::symlink_metadata(path).is_err() {
        return Ok(());
    }
    let ours = beltune::io::read_to_string_capped(path, beltune::io::MAX_TEXT_BYTES)
        .ok()
        .and_then(|t| serde_json::from_str::<serde_json::Value>(&t).ok())
        .is_some_and(|v| v.get("kind").is_some() && v.get("commission_args").is_some());
    if ours {
        return Ok(());
    }
    Err(bad(format!(
        "{} exists and is not excitation metadata: the metadata of --out would replace it; \
         choose another --out name",
        path.display()
    )))
}

/// The CSV text and the metadata.
pub fn generate(a: &Args) -> anyhow::Result<(String, Metadata)> {
    let num = beltune::error::short_number;
    if !(a.ts.is_finite() && (1e-6..=1.0).contains(&a.ts)) {
        return Err(bad(format!("--ts {}: must lie in 1e-6..=1 s", num(a.ts))));
    }
    if !(a.amplitude.is_finite() && a.amplitude > 0.0) {
        return Err(bad(format!(
            "--amplitude {}: must be positive",
            num(a.amplitude)
        )));
    }
    if a.kind != Kind::Prbs {
        let min = beltune::ident::etfe::MIN_PERIOD_SAMPLES;
        if (a.period_samples as usize) < min {
            return Err(bad(format!(
                "--period-samples {}: at least {min} (what `commission --csv` can analyze)",
                a.period_samples
            )));
        }
    }
    if a.kind == Kind::Chirp {
        let nyquist = 0.5 / a.ts;
        let (lo, hi) = (a.f_start_hz.min(a.f_end_hz), a.f_start_hz.max(a.f_end_hz));
        if !(lo.is_finite() && hi.is_finite() && lo > 0.0 && hi <= nyquist) {
            return Err(bad(format!(
                "chirp band {}..{} Hz: must lie in (0, {}] Hz (the Nyquist frequency of --ts)",
                num(lo),
                num(hi),
                num(nyquist)
            )));
        }
    }
    if a.periods == 0 || a.skip_periods >= a.periods {
        return Err(bad(format!(
            "--periods {} must exceed --skip-periods {} (at least one period is analyzed)",
            a.periods, a.skip_periods
        )));
    }
    let (x, band_hz, parameters) = one_period(a)?;
    let n = x.len() as u64;
    let rows = n * u64::from(a.periods);
    if rows > MAX_ROWS {
        return Err(bad(format!(
            "{} periods of {n} samples are {rows} rows, more than {MAX_ROWS}",
            a.periods
        )));
    }
    let mut csv = String::with_capacity(rows as usize * 24);
    csv.push_str("t_s,excitation\n");
    for k in 0..rows {
        let _ = writeln!(csv, "{:?},{:?}", k as f64 * a.ts, x[(k % n) as usize]);
    }
    let peak = x.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let meta = Metadata {
        kind: a.kind,
        ts_s: a.ts,
        amplitude: a.amplitude,
        peak,
        period_samples: n,
        periods: a.periods,
        skip_periods: a.skip_periods,
        band_hz,
        parameters,
        commission_args: vec![
            "--period-samples".into(),
            n.to_string(),
            "--skip-periods".into(),
            a.skip_periods.to_string(),
        ],
    };
    Ok((csv, meta))
}

/// Run the subcommand.
pub fn run(args: Args) -> anyhow::Result<()> {
    let (csv, meta) = generate(&args)?;
    let meta_path = metadata_path(&args.out);
    if meta_path == args.out {
        return Err(bad(
            "--out must not end in .json (the metadata file takes that name)",
        ));
    }
    check_replaceable_metadata(&meta_path)?;
    let mut json = serde_json::to_string_pretty(&meta)?;
    json.push('\n');
    super::util::write_atomic(&args.out, csv.as_bytes())?;
    super::util::write_atomic(&meta_path, json.as_bytes())?;
    println!(
        "wrote {} ({} periods of {} samples, {:.3} s, peak {}, {:.2}..{:.1} Hz) and {}",
        args.out.display(),
        meta.periods,
        meta.period_samples,
        meta.period_samples as f64 * f64::from(meta.periods) * meta.ts_s,
        // four significant digits
        beltune::error::short_number(format!("{:.3e}", meta.peak).parse().unwrap_or(meta.peak)),
        meta.band_hz[0],
        meta.band_hz[1],
        meta_path.display()
    );
    println!(
        "after recording: beltune commission --csv REC.csv --input SETPOINT --output ANGLE {} --torque-limit LIMIT",
        meta.commission_args.join(" ")
    );
    Ok(())
}
