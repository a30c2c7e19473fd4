//! `beltune plant show`: a plant's parameters and derived quantities;
//! `beltune plant template`: an annotated plant file (`plant_template.rs`).

use anyhow::Context;
use beltune::model::rigs::{PlantSummary, BUILTIN_NAMES};
use beltune::model::{builtin, load_toml, Plant};
use std::path::Path;

/// `beltune plant` subcommands.
#[derive(clap::Subcommand)]
pub enum PlantCommand {
    /// Print the parameters and derived quantities of a plant.
    Show(ShowArgs),
    /// Write an annotated plant TOML (every key with its meaning and unit) to edit for your axis.
    Template(super::plant_template::TemplateArgs),
}

/// Arguments of `beltune plant show`.
#[derive(clap::Args)]
pub struct ShowArgs {
    /// A built-in plant (egc70, sim-a, sim-b, sim-c) or a TOML file.
    #[arg(long, default_value = "egc70")]
    pub plant: String,
    /// Payload on the cart, kg (physical plants only; egc70 default 11.2).
    #[arg(long, allow_negative_numbers = true)]
    pub payload: Option<f64>,
    /// Print JSON instead of a table.
    #[arg(long)]
    pub json: bool,
}

/// Run the subcommand.
pub fn run(cmd: PlantCommand) -> anyhow::Result<()> {
    match cmd {
        PlantCommand::Show(args) => show(args),
        PlantCommand::Template(args) => super::plant_template::run(args),
    }
}

/// A built-in name, or a file if the argument is not a built-in name. A
/// built-in name always wins over a file or folder of that name in the
/// current directory (write `./egc70` for the file).
pub fn resolve_plant(name_or_file: &str, payload_kg: Option<f64>) -> anyhow::Result<Plant> {
    let is_file = name_or_file.ends_with(".toml") || Path::new(name_or_file).exists();
    let hint = || {
        similar_builtin(name_or_file)
            .map(|n| format!("; did you mean `{n}`?"))
            .unwrap_or_default()
    };
    if BUILTIN_NAMES.contains(&name_or_file) || !is_file {
        return builtin(name_or_file, payload_kg).map_err(|e| match e {
            beltune::Error::UnknownPlant { .. } => anyhow::anyhow!("{e}{}", hint()),
            e => e.into(),
        });
    }
    if Path::new(name_or_file).is_dir() {
        anyhow::bail!(
            "--plant {name_or_file}: a folder, not a plant file (TOML) nor a built-in plant              ({}){}",
            BUILTIN_NAMES.join(", "),
            hint()
        );
    }
    let plant = load_toml(Path::new(name_or_file))?;
    match payload_kg {
        Some(p) => Ok(plant
            .with_payload(p)
            .with_context(|| format!("{name_or_file}: --payload"))?),
        None => Ok(plant),
    }
}

fn show(args: ShowArgs) -> anyhow::Result<()> {
    let plant = resolve_plant(&args.plant, args.payload)?;
    let summary = plant.summary()?;
    if args.json {
        let mut value = serde_json::to_value(&summary)?;
        value["plant"] = serde_json::Value::String(args.plant.clone());
        println!("{}", serde_json::to_string_pretty(&value)?);
    } else {
        print!("{}", table(&args.plant, &summary));
    }
    Ok(())
}

fn table(name: &str, s: &PlantSummary) -> String {
    let mut out = String::new();
    let mut row = |label: &str, value: String| {
        out.push_str(&format!("{label:<44} {value}\n"));
    };
    row("plant", format!("{name} ({})", s.kind));
    if let Some(p) = &s.physical {
        row("payload", format!("{:.2} kg", p.payload_kg));
        row("stroke", format!("{:.3} m", p.stroke_m));
        row("tilt", format!("{:.2} deg", p.tilt_rad.to_degrees()));
    }
    row(
        "worst-case cart position",
        format!("{:.3} m", s.worst_case_position_m),
    );
    row("resonance f_r (2.44)", format!("{:.2} Hz", s.f_r_hz));
    row("antiresonance f_z (2.45)", format!("{:.2} Hz", s.f_z_hz));
    row("inertia ratio kappa (2.46)", format!("{:.3}", s.kappa));
    row(
        "resonance ratio R (2.47)",
        format!("{:.3}", s.resonance_ratio),
    );
    row("Theta_e", format!("{:.2} kg mm^2", s.theta_e_kg_m2 * 1e6));
    row("m_c", format!("{:.3} kg", s.m_c_kg));
    row("c (2.26)", format!("{:.2} kN/m", s.c_n_per_m * 1e-3));
    row("d (2.27)", format!("{:.3} N s/m", s.d_n_s_per_m));
    row(
        "d_m (translational)",
        format!("{:.3} N s/m", s.d_m_n_s_per_m),
    );
    row("d_c", format!("{:.3} N s/m", s.d_c_n_s_per_m));
    row("i_t = r / i_g", format!("{:.4} mm/rad", s.i_t_m * 1e3));
    row(
        "rigid inertia Theta_e + i_t^2 m_c",
        format!("{:.4e} kg m^2", s.rigid_inertia_kg_m2),
    );
    row(
        "friction d_v~ (3.36)",
        format!("{:.3} mN m s/rad", s.friction.viscous_nm_s_per_rad * 1e3),
    );
    row(
        "friction tau_c~ (3.36)",
        format!("{:.4} N m", s.friction.coulomb_nm),
    );
    row("dead time", format!("{:.2} ms", s.dead_time_s * 1e3));
    row("torque limit", format!("{:.2} N m", s.torque_max_nm));
    row(
        "encoder",
        format!(
            "{:.4e} rad/count ({:.2} um belt travel, {:.0} counts/rev)",
            s.motor_rad_per_count,
            s.belt_travel_per_count_m * 1e6,
            std::f64::consts::TAU / s.motor_rad_per_count
        ),
    );
    row("sampling time", format!("{:.1} us", s.ts_s * 1e6));
    if !s.position_sweep.is_empty() {
        out.push_str("\nposition dependency (linearized at xi):\n");
        out.push_str(&format!(
            "{:>8} {:>10} {:>10} {:>12}\n",
            "xi [m]", "f_r [Hz]", "f_z [Hz]", "c [kN/m]"
        ));
        for p in &s.position_sweep {
            out.push_str(&format!(
                "{:>8.3} {:>10.2} {:>10.2} {:>12.2}\n",
                p.xi_m,
                p.f_r_hz,
                p.f_z_hz,
                p.c_n_per_m * 1e-3
            ));
        }
    }
    out
}

/// The built-in plant name `name` was probably meant to be: equal once case,
/// `-` and `_` are ignored, or at most two edits away (`simc` -> `sim-c`).
pub fn similar_builtin(name: &str) -> Option<&'static str> {
    let norm = |s: &str| -> Vec<char> {
        s.chars()
            .filter(|c| *c != '-' && *c != '_')
            .map(|c| c.to_ascii_lowercase())
            .collect()
    };
    let edits = |a: &[char], b: &[char]| -> usize {
        let mut prev: Vec<usize> = (0..=b.len()).collect();
        for (i, ca) in a.iter().enumerate() {
            let mut cur = vec![i + 1];
            for (j, cb) in b.iter().enumerate() {
                let sub = prev[j] + usize::from(ca != cb);
                cur.push(sub.min(prev[j + 1] + 1).min(cur[j] + 1));
            }
            prev = cur;
        }
        prev[b.len()]
    };
    let n = norm(name);
    BUILTIN_NAMES
        .iter()
        .map(|b| (edits(&n, &norm(b)), *b))
        .filter(|(d, _)| *d <= 2)
        .min_by_key(|(d, _)| *d)
        .map(|(_, b)| b)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_misspelled_plant_name_suggests_the_built_in_one() {
        assert_eq!(similar_builtin("simc"), Some("sim-c"));
        assert_eq!(similar_builtin("SIM_A"), Some("sim-a"));
        assert_eq!(similar_builtin("egc-70"), Some("egc70"));
        assert_eq!(similar_builtin("egc07"), Some("egc70"));
        assert_eq!(similar_builtin("linear-motor"), None);
        let e = resolve_plant("simc", None).unwrap_err().to_string();
        assert!(e.contains("did you mean `sim-c`"), "{e}");
    }
}
