//! `beltune vibration --commissioning DIR`: the vibration benchmark of a
//! commissioned (simulated) axis ([`beltune::vibration::bench`]): moves of
//! equal duration ending at 7 positions x 3 payloads, contestants `fixed`,
//! `klipper` and `shaped`; a table on stdout, or `--json` as
//! `{"vibration": {...}}`.

use super::commission::preflight::bad;
use beltune::record::controller::ControllerFile;
use beltune::report::folder::ResultFolder;
use beltune::vibration::bench::{self, BenchSetup};
use std::path::PathBuf;

/// Arguments of `beltune vibration`.
#[derive(clap::Args)]
pub struct Args {
    /// The commissioning's result folder (`commissioning.json` and
    /// `controller.toml`; e.g. `commissioning/latest`).
    #[arg(long, value_name = "DIR")]
    pub commissioning: PathBuf,
    /// Payload range the moves cover, `MIN,MAX` in kg (default: half to one
    /// and a half times the commissioned payload).
    #[arg(long, value_name = "MIN,MAX")]
    pub payload_range: Option<String>,
    /// Print the result as JSON.
    #[arg(long)]
    pub json: bool,
}

/// `MIN,MAX` in kg, or one line saying what is wrong.
pub fn parse_payload_range(text: &str) -> anyhow::Result<(f64, f64)> {
    let parts: Vec<&str> = text.split(',').map(str::trim).collect();
    let parsed: Vec<Option<f64>> = parts.iter().map(|p| p.parse::<f64>().ok()).collect();
    match parsed.as_slice() {
        [Some(lo), Some(hi)]
            if lo.is_finite() && hi.is_finite() && *lo >= 0.0 && hi >= lo && *hi <= 1e4 =>
        {
            Ok((*lo, *hi))
        }
        _ => Err(bad(format!(
            "--payload-range must be MIN,MAX in kg with 0 <= MIN <= MAX <= 10000, got `{text}`"
        ))),
    }
}

/// Run the command.
pub fn run(args: Args) -> anyhow::Result<()> {
    let range = args
        .payload_range
        .as_deref()
        .map(parse_payload_range)
        .transpose()?;
    let dir = &args.commissioning;
    if !dir.join(beltune::record::COMMISSIONING_FILE).is_file() {
        return Err(bad(format!(
            "--commissioning {}: no {} there (the result folder of a `beltune commission`)",
            dir.display(),
            beltune::record::COMMISSIONING_FILE
        )));
    }
    let folder = ResultFolder::read(dir)?;
    let controller = ControllerFile::load(&dir.join(beltune::record::CONTROLLER_FILE))?;
    let setup = BenchSetup::from_result(&folder.record, &controller, range)?;
    let b = bench::run(&setup)?;
    if args.json {
        let v = serde_json::json!({ "vibration": b });
        println!("{}", serde_json::to_string_pretty(&v)?);
        return Ok(());
    }
    println!(
        "vibration benchmark: {} moves of {:.0} mm ending at {} positions {:.0}..{:.0} mm x payloads {} kg",
        b.ends_m.len() * b.payloads_kg.len(),
        b.move_length_m * 1e3,
        b.ends_m.len(),
        b.ends_m.first().copied().unwrap_or(0.0) * 1e3,
        b.ends_m.last().copied().unwrap_or(0.0) * 1e3,
        b.payloads_kg
            .iter()
            .map(|p| format!("{p:.1}"))
            .collect::<Vec<_>>()
            .join("/"),
    );
    println!(
        "model cart mode {:.1} Hz at the lowest; residual window {:.3} s (5 / f_z,min); klipper's choice: {} at {:.1} Hz ({:.1} % remaining, {:.3} s)",
        b.f_z_min_hz,
        b.window_s,
        b.klipper.shaper,
        b.klipper.freq_hz,
        b.klipper.vibration * 100.0,
        b.klipper.duration_s
    );
    println!(
        "{:<10} {:>14} {:>15} {:>16} {:>10}",
        "contestant", "worst p-p um", "median p-p um", "worst settle s", "move s"
    );
    for c in &b.contestants {
        let settle = match c.worst_settling_s {
            Some(s) => format!("{s:.3}"),
            None => format!("{}/{} settled", c.settled_moves, c.moves.len()),
        };
        println!(
            "{:<10} {:>14.1} {:>15.1} {:>16} {:>10.3}",
            c.name, c.worst_residual_um, c.median_residual_um, settle, c.move_time_s
        );
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn payload_ranges_parse_or_say_why_not() {
        assert_eq!(parse_payload_range("0,25").unwrap(), (0.0, 25.0));
        assert_eq!(parse_payload_range(" 2.5 , 2.5 ").unwrap(), (2.5, 2.5));
        for bad in ["", "5", "5,1", "-1,3", "a,b", "1,2,3", "NaN,1", "0,inf"] {
            let e = parse_payload_range(bad).unwrap_err().to_string();
            assert!(e.contains("--payload-range"), "{bad}: {e}");
        }
    }
}
