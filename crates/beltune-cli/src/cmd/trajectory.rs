//! `beltune trajectory`: plan a jerk-limited time-optimal move (thesis 6.3)
//! and print its duration and phases; optionally write the samples at `T_s`.

use anyhow::{bail, Context};
use beltune_rt::trajectory::{Limits, State, Trajectory};
use std::fmt::Write as _;
use std::path::PathBuf;

/// Most samples `--samples` writes (about 0.5 GB of CSV); beyond, raise `--ts`.
const MAX_SAMPLES: f64 = 1e7;

/// Arguments of `beltune trajectory`.
#[derive(clap::Args)]
pub struct Args {
    /// Start state `P,V,A` (m, m/s, m/s^2).
    #[arg(long, value_parser = parse_state, allow_hyphen_values = true)]
    pub start: State,
    /// Target state `P,V,A` (m, m/s, m/s^2).
    #[arg(long, value_parser = parse_state, allow_hyphen_values = true)]
    pub target: State,
    /// Highest velocity, m/s (> 0).
    #[arg(long, allow_hyphen_values = true)]
    pub v_max: f64,
    /// Highest acceleration, m/s^2 (> 0).
    #[arg(long, allow_hyphen_values = true)]
    pub a_max: f64,
    /// Highest jerk, m/s^3 (> 0).
    #[arg(long, allow_hyphen_values = true)]
    pub j_max: f64,
    /// Lowest velocity, m/s (< 0; default -v_max).
    #[arg(long, allow_hyphen_values = true)]
    pub v_min: Option<f64>,
    /// Lowest acceleration, m/s^2 (< 0; default -a_max).
    #[arg(long, allow_hyphen_values = true)]
    pub a_min: Option<f64>,
    /// Lowest jerk, m/s^3 (< 0; default -j_max).
    #[arg(long, allow_hyphen_values = true)]
    pub j_min: Option<f64>,
    /// Position limits `MIN,MAX` in m (default: none).
    #[arg(long, value_parser = parse_pair, allow_hyphen_values = true)]
    pub position_limits: Option<(f64, f64)>,
    /// Write the trajectory sampled every `--ts` to this CSV file.
    #[arg(long)]
    pub samples: Option<PathBuf>,
    /// Sampling period `T_s` for `--samples`, s.
    #[arg(long, default_value_t = 1e-4, allow_hyphen_values = true)]
    pub ts: f64,
    /// Print JSON instead of a table.
    #[arg(long)]
    pub json: bool,
}

fn parse_numbers<const N: usize>(s: &str) -> Result<[f64; N], String> {
    let parts: Vec<&str> = s.split(',').map(str::trim).collect();
    if parts.len() != N {
        return Err(format!("expected {N} comma-separated numbers, got `{s}`"));
    }
    let mut out = [0.0; N];
    for (o, p) in out.iter_mut().zip(parts) {
        *o = p.parse().map_err(|_| format!("`{p}` is not a number"))?;
    }
    Ok(out)
}

fn parse_state(s: &str) -> Result<State, String> {
    let [position, velocity, acceleration] = parse_numbers::<3>(s)?;
    Ok(State {
        position,
        velocity,
        acceleration,
    })
}

fn parse_pair(s: &str) -> Result<(f64, f64), String> {
    let [a, b] = parse_numbers::<2>(s)?;
    Ok((a, b))
}

/// The limits from the arguments (validated by the planner).
fn limits(args: &Args) -> Limits {
    let (position_min, position_max) = args
        .position_limits
        .unwrap_or((f64::NEG_INFINITY, f64::INFINITY));
    Limits {
        v_max: args.v_max,
        v_min: args.v_min.unwrap_or(-args.v_max),
        a_max: args.a_max,
        a_min: args.a_min.unwrap_or(-args.a_max),
        j_max: args.j_max,
        j_min: args.j_min.unwrap_or(-args.j_max),
        position_min,
        position_max,
    }
}

/// CSV of the trajectory sampled at `k ts`, `k = 0 ..= ceil(duration / ts)`.
fn samples_csv(traj: &Trajectory, ts: f64) -> anyhow::Result<String> {
    if !(ts.is_finite() && ts > 0.0) {
        bail!("--ts must be finite and > 0, got {ts}");
    }
    let steps = (traj.duration_s() / ts).ceil();
    if steps > MAX_SAMPLES {
        bail!("{steps} samples at --ts {ts} s is too many (limit {MAX_SAMPLES}); increase --ts");
    }
    let steps = steps as usize;
    let mut out = String::with_capacity(64 * (steps + 2));
    out.push_str("t_s,position_m,velocity_m_s,acceleration_m_s2,jerk_m_s3\n");
    for k in 0..=steps {
        let t = k as f64 * ts;
        let s = traj.sample(t);
        writeln!(
            out,
            "{t},{},{},{},{}",
            s.position, s.velocity, s.acceleration, s.jerk
        )?;
    }
    Ok(out)
}

/// The limits as the flags name them: one line naming the flag (the core's
/// own names, such as `-v_min`, are not what the user typed).
fn check_flags(args: &Args) -> anyhow::Result<()> {
    let bad = |m: String| {
        anyhow::Error::new(crate::exit::Failure::new(
            crate::exit::ExitStatus::BadInput,
            m,
        ))
    };
    let short = beltune::error::short_number;
    // far beyond any machine axis, so that no printed phase overflows into
    // hundreds of digits: m/s, m/s^2, m/s^3
    let bounds = [("velocity", 1e3), ("acceleration", 1e6), ("jerk", 1e9)];
    for ((flag, v), (what, bound)) in [
        ("--v-max", args.v_max),
        ("--a-max", args.a_max),
        ("--j-max", args.j_max),
    ]
    .into_iter()
    .zip(bounds)
    {
        if !(v.is_finite() && v > 0.0 && v <= bound) {
            return Err(bad(format!(
                "{flag} must be a {what} above 0 and at most {}, got {}",
                short(bound),
                short(v)
            )));
        }
    }
    for ((flag, v), (what, bound)) in [
        ("--v-min", args.v_min),
        ("--a-min", args.a_min),
        ("--j-min", args.j_min),
    ]
    .into_iter()
    .zip(bounds)
    {
        if let Some(v) = v {
            if !(v.is_finite() && v < 0.0 && v >= -bound) {
                return Err(bad(format!(
                    "{flag} must be a {what} below 0 and at least {}, got {}",
                    short(-bound),
                    short(v)
                )));
            }
        }
    }
    for (flag, s) in [("--start", &args.start), ("--target", &args.target)] {
        let within = [s.position, s.velocity, s.acceleration]
            .iter()
            .zip([1e3, bounds[0].1, bounds[1].1])
            .all(|(x, b)| x.is_finite() && x.abs() <= b);
        if !within {
            return Err(bad(format!(
                "{flag} must be three finite numbers: a position within +-1000 m, a velocity \
                 within +-1000 m/s and an acceleration within +-1e6 m/s^2"
            )));
        }
    }
    Ok(())
}

/// Run the subcommand.
pub fn run(args: Args) -> anyhow::Result<()> {
    check_flags(&args)?;
    let limits = limits(&args);
    let traj =
        Trajectory::plan(&args.start, &args.target, &limits).context("planning the trajectory")?;
    let phases = traj.phases();
    let range = traj.position_range();

    if let Some(path) = &args.samples {
        let csv = samples_csv(&traj, args.ts)?;
        crate::cmd::util::write_atomic(path, csv.as_bytes())?;
    }

    if args.json {
        let value = serde_json::json!({
            "duration_s": traj.duration_s(),
            "brake_duration_s": traj.brake_duration_s(),
            "brake_durations_s": phases.brake_durations_s,
            "brake_jerks_m_s3": phases.brake_jerks_m_s3,
            "phase_durations_s": phases.durations_s,
            "phase_jerks_m_s3": phases.jerks_m_s3,
            "position_lowest_m": range.lowest,
            "position_highest_m": range.highest,
        });
        println!("{}", serde_json::to_string_pretty(&value)?);
    } else {
        println!("duration: {:.9} s", traj.duration_s());
        println!("positions: {:.9} .. {:.9} m", range.lowest, range.highest);
        println!("{:<8} {:>14} {:>14}", "phase", "duration_s", "jerk_m_s3");
        for (i, (t, j)) in phases
            .brake_durations_s
            .iter()
            .zip(phases.brake_jerks_m_s3)
            .enumerate()
        {
            if *t > 0.0 {
                println!("{:<8} {:>14.9} {:>14.6}", format!("brake{}", i + 1), t, j);
            }
        }
        for (i, (t, j)) in phases.durations_s.iter().zip(phases.jerks_m_s3).enumerate() {
            println!("{:<8} {:>14.9} {:>14.6}", format!("P{}", i + 1), t, j);
        }
    }
    Ok(())
}
