//! `beltune montecarlo`: the robustness study (docs/robustness.md). Generates `--plants`
//! seeded random axes from egc70's data sheet, commissions each in
//! simulation (in parallel, rayon), prints the table with every failure
//! classified (correct refusal of an infeasible plant vs defect), and writes
//! one JSON line per plant with `--out`.

use beltune::commission::CommissioningConfig;
use beltune::study::{run_plant, Class, Outcome, Ranges, Table};
use indicatif::{ProgressBar, ProgressStyle};
use rayon::prelude::*;
use std::io::Write;
use std::path::PathBuf;

/// Arguments of `beltune montecarlo`.
#[derive(clap::Args)]
pub struct Args {
    /// Number of plants.
    #[arg(long, default_value_t = 1000)]
    pub plants: u64,
    /// Seed of the study (plant i of seed s is the same in every run).
    #[arg(long, default_value_t = 12)]
    pub seed: u64,
    /// First plant index (to re-run a single plant: --first 824 --plants 1).
    #[arg(long, default_value_t = 0)]
    pub first: u64,
    /// Worker threads, 1 ..= 256 (default: all cores; never more than plants).
    #[arg(long, value_parser = clap::value_parser!(u16).range(1..=MAX_THREADS as i64))]
    pub threads: Option<u16>,
    /// Write one JSON line per plant to this file.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// No progress bar.
    #[arg(long)]
    pub quiet: bool,
    /// Commission with the thesis' design on the fit as identified instead of
    /// the robust design rule (to compare the two).
    #[arg(long)]
    pub thesis_design: bool,
    /// Also draw the dynamics real axes have beyond the model (current loop,
    /// frame mode, cogging, ripple, encoder line errors, tooth mesh;
    /// docs/robustness.md gives the ranges).
    #[arg(long)]
    pub unmodeled: bool,
}

/// Most worker threads (`--threads`): beyond the cores they only cost memory.
pub const MAX_THREADS: u16 = 256;

fn bad(msg: impl Into<String>) -> anyhow::Error {
    anyhow::Error::new(crate::exit::Failure::new(
        crate::exit::ExitStatus::BadInput,
        msg,
    ))
}

/// Run the subcommand.
pub fn run(args: Args) -> anyhow::Result<()> {
    if args.plants == 0 {
        return Err(bad("--plants must be at least 1"));
    }
    // the plant indices `first .. first + plants` must exist
    let Some(end) = args.first.checked_add(args.plants) else {
        return Err(bad(format!(
            "--first {} with --plants {} runs past the last plant index {}",
            args.first,
            args.plants,
            u64::MAX
        )));
    };
    // the output is checked before the study runs, not after
    if let Some(path) = &args.out {
        super::util::check_writable_file("--out", path)?;
    }
    let pool = {
        let mut b = rayon::ThreadPoolBuilder::new();
        if let Some(n) = args.threads {
            b = b.num_threads(u64::from(n).min(args.plants) as usize);
        }
        b.build()?
    };
    let bar = if args.quiet {
        ProgressBar::hidden()
    } else {
        ProgressBar::new(args.plants)
    };
    bar.set_style(ProgressStyle::with_template(
        "{bar:40} {pos}/{len} plants, {elapsed} (eta {eta}) {msg}",
    )?);
    let ranges = Ranges {
        unmodeled: args.unmodeled,
        ..Ranges::default()
    };
    let cfg = CommissioningConfig {
        design_rule: if args.thesis_design {
            beltune::design::robust::DesignRule::Thesis
        } else {
            beltune::design::robust::DesignRule::Robust
        },
        ..CommissioningConfig::default()
    };
    let first = args.first;
    let results: Vec<beltune::Result<Outcome>> = pool.install(|| {
        (first..end)
            .into_par_iter()
            .map(|i| {
                let r = run_plant(args.seed, i, &ranges, &cfg);
                bar.inc(1);
                r
            })
            .collect()
    });
    bar.finish_and_clear();
    let mut outcomes = Vec::with_capacity(results.len());
    for r in results {
        outcomes.push(r?);
    }
    if let Some(path) = &args.out {
        let mut text = String::new();
        for o in &outcomes {
            text.push_str(&serde_json::to_string(o)?);
            text.push('\n');
        }
        beltune::io::write_atomic(path, text.as_bytes())?;
    }
    let table = Table::new(&outcomes);
    let mut out = std::io::stdout().lock();
    writeln!(out, "{}", table.markdown())?;
    for o in outcomes.iter().filter(|o| o.class != Class::Success) {
        writeln!(
            out,
            "plant #{} [{}] payload {:.1} kg, tilt {:+.0} deg, c_b x{:.2}, viscous x{:.2}, Coulomb x{:.2}, noise x{:.1}, stroke {:.2} m; A.8 torque {:.2} of {:.2} N m, holding {:+.2} N m: {}{}",
            o.index,
            match o.class {
                Class::Success => "success",
                Class::CorrectRefusal => "correct refusal",
                Class::Defect => "DEFECT",
            },
            o.plant.payload_kg,
            o.plant.tilt_deg,
            o.plant.stiffness_factor,
            o.plant.viscous_factor,
            o.plant.coulomb_factor,
            o.plant.noise_factor,
            o.plant.params.stroke_m,
            o.feasibility.table_a8_torque_nm,
            o.feasibility.torque_limit_nm,
            o.feasibility.holding_nm,
            if o.message.is_empty() { "(no message)" } else { &o.message },
            if o.travel_violation {
                format!("; the cart left the window by {:.1} mm", o.travel_excess_m * 1e3)
            } else {
                String::new()
            }
        )?;
    }
    Ok(())
}
