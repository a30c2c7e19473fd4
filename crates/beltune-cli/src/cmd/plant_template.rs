//! `beltune plant template`: an annotated plant TOML, every key with its
//! meaning and unit, that `--plant FILE` reads unchanged. The values are those
//! of a built-in plant (egc70 by default), so the file is a working start.

use crate::term;
use beltune::model::rigs::Plant;
use std::path::PathBuf;

/// Arguments of `beltune plant template`.
#[derive(clap::Args)]
pub struct TemplateArgs {
    /// The built-in plant whose values the file starts from (egc70 physical;
    /// sim-a, sim-b, sim-c linear two-mass sets).
    #[arg(long, default_value = "egc70")]
    pub plant: String,
    /// Payload on the cart, kg (egc70 only; default 11.2 kg).
    #[arg(long, allow_negative_numbers = true)]
    pub payload: Option<f64>,
    /// Write the file here (atomically) instead of printing it.
    #[arg(long, value_name = "FILE.toml")]
    pub out: Option<PathBuf>,
}

/// A group heading, or a key with its comment.
enum Line {
    Group(&'static str),
    Key(&'static str, &'static str),
}
use Line::{Group, Key};

/// The keys of a physical plant in the order of `PhysicalParams`, with comments.
const PHYSICAL: &[Line] = &[
    Group("drive train (thesis 2.8)"),
    Key("theta_motor_kg_m2", "Theta_m: motor rotor inertia, kg m^2"),
    Key("theta_coupling_kg_m2", "coupling (connection kit) inertia, kg m^2; counts on the motor side"),
    Key("theta_gearbox_kg_m2", "Theta_g: gearbox inertia, kg m^2 (0 without gearbox)"),
    Key("theta_driving_pulley_kg_m2", "Theta_r: inertia of the driving pulley, kg m^2"),
    Key("theta_end_pulley_kg_m2", "inertia of the end (driven) pulley, kg m^2"),
    Key("r_m", "r: effective pulley radius, m (feed per revolution / 2 pi)"),
    Key("i_g", "i_g = omega_m / omega_g: gear ratio, 1 without gearbox"),
    Group("belt (thesis 2.10)"),
    Key("c_b_n", "c_b = E A: specific belt stiffness, N (a free segment of length l has c_b / l N/m)"),
    Key("d_b_n_s", "specific belt damping, N s (a segment of length l has d_b / l N s/m)"),
    Key("end_compliance_length_m", "l_e: equivalent free-belt length of tooth engagement and clamp per segment, m"),
    Group("geometry"),
    Key("pulley_distance_m", "l_3: distance between the pulley centres, m"),
    Key("l_xi_m", "l_xi: driving pulley centre to cart centre at xi = 0, m"),
    Key("cart_belt_span_m", "distance between the two belt clamps on the cart, m"),
    Key("stroke_m", "usable stroke, m: the cart position xi ranges over [0, stroke_m]"),
    Group("masses"),
    Key("m_cart_kg", "moving mass of the empty cart (slide, mounting parts), kg"),
    Key("payload_kg", "payload mounted on the cart, kg"),
    Group("friction (thesis 2.21, 2.23)"),
    Key("d_m_n_s_per_m", "d_m: motor-side viscous friction as translational equivalent, N s/m"),
    Key("tau_c_motor_nm", "tau_c: motor-side Coulomb friction torque, N m"),
    Key("d_c_n_s_per_m", "d_c: cart viscous friction, N s/m"),
    Key("f_c_cart_n", "f_c: cart Coulomb friction force, N"),
    Key("d_end_pulley_n_s_per_m", "end-pulley viscous friction, translational equivalent, N s/m"),
    Key("tau_c_end_pulley_nm", "end-pulley Coulomb friction torque, N m"),
    Group("installation and drive"),
    Key("tilt_rad", "alpha: tilt against the horizontal, rad (optional, default 0; positive lifts the cart as xi grows)"),
    Key("dead_time_s", "current-loop dead time, s (thesis 3.30)"),
    Key("torque_max_nm", "torque limit of the drive, N m"),
    Key("motor_rad_per_count", "motor encoder resolution, rad per count (2 pi / counts per revolution)"),
    Key("ts_s", "sampling time of the drive, s"),
];

/// The keys of a linear plant, top level first, then the `[two_mass]` table.
const LINEAR: &[Line] = &[
    Group("drive"),
    Key("dead_time_s", "current-loop dead time, s (thesis 3.30)"),
    Key("torque_max_nm", "torque limit of the drive, N m"),
    Key(
        "motor_rad_per_count",
        "motor encoder resolution, rad per count",
    ),
    Key("ts_s", "sampling time of the drive, s"),
];

/// The keys of the `[two_mass]` table of a linear plant (thesis 2.33, Table A.4).
const TWO_MASS: &[Line] = &[
    Key(
        "theta_e",
        "Theta_e: motor-side inertia (motor, coupling, gearbox, driving pulley), kg m^2",
    ),
    Key("m_c", "m_c: moving mass (cart and payload), kg"),
    Key("c", "c: replacement belt stiffness (2.26), N/m"),
    Key("d", "d: belt damping (2.27), N s/m (optional, default 0)"),
    Key(
        "d_m",
        "d_m: motor viscous damping as translational equivalent, N s/m",
    ),
    Key("d_c", "d_c: cart viscous damping, N s/m"),
    Key("i_t", "i_t = r / i_g: motor angle to belt travel, m/rad"),
];

/// The keys of the optional `[noise]` table (both plant kinds).
const NOISE: &[Line] = &[
    Key(
        "torque_nm",
        "standard deviation of the noise on the measured actual torque, N m (0: none)",
    ),
    Key(
        "encoder_counts",
        "standard deviation of the motor encoder noise before quantization, counts (0: ideal)",
    ),
];

/// The `[noise]` table of `table` with its heading and comments.
fn noise_section(out: &mut String, table: &toml::Table) -> anyhow::Result<()> {
    let noise = table
        .get("noise")
        .and_then(|t| t.as_table())
        .ok_or_else(|| anyhow::anyhow!("plant template: no [noise] table"))?;
    out.push_str(
        "\n# ---- measurement noise of the simulator (optional table; seeded by --seed) ----\n[noise]\n",
    );
    section(out, NOISE, noise, &[])
}

/// The optional `[wear]` table of a physical plant, commented out (a new
/// axis): what ages, for the simulator and `beltune health` (docs/health.md).
const WEAR: &str = "
# ---- ageing (optional table, simulator; none is a new axis: docs/health.md) ----
# [wear]
# belt tension loss: the fraction of the belt stiffness c_b lost (0 .. 0.9)
# belt_stiffness_loss = 0.1
# friction growth: every friction coefficient times 1 + this (0 .. 10)
# friction_growth = 0.3
# a slack span: the belt's pretension, N (a span cannot push; absent: never slack)
# belt_pretension_n = 40.0
# a worn guide: extra Coulomb friction of the cart, N, on the worn section, m
# (absent: the whole stroke)
# guide_wear_n = 3.0
# guide_wear_section_m = [0.2, 0.4]
";

/// The optional `[unmodeled]` table of a physical plant, commented out (every
/// key 0 is off: the plant is the two-mass/three-mass model alone). The
/// values shown are physical starting points for an egc70-class axis.
const UNMODELED: &str = "
# ---- dynamics real axes have beyond the model (optional table, simulator; every key
# ---- 0 or absent is off; docs/robustness.md gives the Monte Carlo ranges) ----
# [unmodeled]
# closed current loop as a 2nd-order low-pass behind dead_time_s: bandwidth, Hz
# (servo drives 1-4 kHz), damping ratio (0: 0.707)
# current_loop_bandwidth_hz = 2000.0
# current_loop_damping = 0.7
# second mechanical mode: a compliant frame the motor stator sits on, Hz (2-6 x f_r),
# its damping ratio (0: 0.02) and its inertia as a multiple of Theta_e
# frame_mode_hz = 400.0
# frame_mode_damping = 0.02
# frame_inertia_ratio = 5.0
# cogging torque amplitude, N m (0.5-2 % of rated), periods per revolution (0: 24)
# cogging_torque_nm = 0.01
# cogging_per_rev = 24.0
# torque ripple, fraction of the torque (0.5-3 %), periods per revolution (0: 24)
# torque_ripple = 0.01
# torque_ripple_per_rev = 24.0
# encoder line errors once and twice per revolution, amplitude, rad (1e-5 .. 5e-4)
# encoder_error_once_rad = 1e-4
# encoder_error_twice_rad = 5e-5
# belt tooth-mesh force amplitude, N, periodic in belt travel with the tooth pitch, m
# (0: 5 mm)
# tooth_mesh_force_n = 2.0
# tooth_pitch_m = 0.005
";

/// A float as TOML: 12 significant digits ([`term::tidy`]), always with a
/// fraction or an exponent so that it reads back as a float.
fn toml_float(v: f64) -> String {
    let s = term::tidy(v);
    if s.contains(['.', 'e', 'E']) || !v.is_finite() {
        s
    } else {
        format!("{s}.0")
    }
}

fn toml_value(v: &toml::Value) -> anyhow::Result<String> {
    Ok(match v {
        toml::Value::Float(f) => toml_float(*f),
        toml::Value::Integer(_) | toml::Value::String(_) | toml::Value::Boolean(_) => v.to_string(),
        other => anyhow::bail!("plant template: unexpected value {other}"),
    })
}

/// Write `lines` for the keys of `table`; every key of the table must have a
/// line and every line a key (so that the comments follow the struct).
fn section(
    out: &mut String,
    lines: &[Line],
    table: &toml::Table,
    skip: &[&str],
) -> anyhow::Result<()> {
    let documented: Vec<&str> = lines
        .iter()
        .filter_map(|l| match l {
            Key(k, _) => Some(*k),
            Group(_) => None,
        })
        .collect();
    if let Some(k) = table
        .keys()
        .find(|k| !skip.contains(&k.as_str()) && !documented.contains(&k.as_str()))
    {
        anyhow::bail!("plant template: key `{k}` has no comment");
    }
    for line in lines {
        match line {
            Group(g) => out.push_str(&format!("\n# ---- {g} ----\n")),
            Key(k, comment) => {
                let v = table
                    .get(*k)
                    .ok_or_else(|| anyhow::anyhow!("plant template: the plant has no `{k}`"))?;
                out.push_str(&format!("# {comment}\n{k} = {}\n", toml_value(v)?));
            }
        }
    }
    Ok(())
}

/// The annotated TOML of `plant`; `name` says where its values come from.
pub fn template(plant: &Plant, name: &str) -> anyhow::Result<String> {
    let table = toml::Table::try_from(plant)?;
    let kind = table
        .get("kind")
        .and_then(|k| k.as_str())
        .unwrap_or("physical")
        .to_string();
    let mut out = format!(
        "# beltune plant file ({kind}), written by `beltune plant template` with the values of `{name}`.\n\
         # Edit the values for your axis, check them with `beltune plant show --plant FILE.toml`,\n\
         # then commission with `beltune commission --plant FILE.toml`. SI units throughout;\n\
         # every key is required unless its comment says otherwise, an unknown key is an error.\n\n\
         kind = \"{kind}\"\n"
    );
    match plant {
        Plant::Physical(_) => {
            section(
                &mut out,
                PHYSICAL,
                &table,
                &["kind", "noise", "wear", "unmodeled"],
            )?;
            noise_section(&mut out, &table)?;
            out.push_str(UNMODELED);
            out.push_str(WEAR);
        }
        Plant::Linear(_) => {
            section(&mut out, LINEAR, &table, &["kind", "two_mass", "noise"])?;
            let two_mass = table
                .get("two_mass")
                .and_then(|t| t.as_table())
                .ok_or_else(|| anyhow::anyhow!("plant template: no [two_mass] table"))?;
            out.push_str("\n# ---- two-mass model (thesis 2.33) ----\n[two_mass]\n");
            section(&mut out, TWO_MASS, two_mass, &[])?;
            noise_section(&mut out, &table)?;
        }
    }
    Ok(out)
}

/// Run `beltune plant template`.
pub fn run(args: TemplateArgs) -> anyhow::Result<()> {
    let plant = beltune::model::builtin(&args.plant, args.payload)?;
    let text = template(&plant, &args.plant)?;
    match &args.out {
        Some(path) => {
            super::util::write_atomic(path, text.as_bytes())?;
            eprintln!("wrote {}", path.display());
        }
        None => print!("{text}"),
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use beltune::model::rigs::BUILTIN_NAMES;

    /// Relative difference allowed after the 12-digit print: 5e-12 of rounding,
    /// with margin.
    const REL_TOL: f64 = 1e-11;

    fn close(a: &toml::Value, b: &toml::Value, path: &str) {
        match (a, b) {
            (toml::Value::Table(x), toml::Value::Table(y)) => {
                assert_eq!(
                    x.keys().collect::<Vec<_>>(),
                    y.keys().collect::<Vec<_>>(),
                    "{path}"
                );
                for (k, v) in x {
                    close(v, &y[k], &format!("{path}.{k}"));
                }
            }
            (toml::Value::Float(x), toml::Value::Float(y)) => {
                assert!(
                    (x - y).abs() <= REL_TOL * x.abs().max(y.abs()),
                    "{path}: {x} vs {y}"
                );
            }
            _ => assert_eq!(a, b, "{path}"),
        }
    }

    /// Every built-in plant: the template parses back to the same plant (to
    /// the printed precision) and every key carries a comment.
    #[test]
    fn the_template_reads_back_as_the_plant_it_was_made_from() {
        for name in BUILTIN_NAMES {
            let plant = beltune::model::builtin(name, None).unwrap();
            let text = template(&plant, name).unwrap();
            let back: Plant =
                toml::from_str(&text).unwrap_or_else(|e| panic!("{name}: {e}\n{text}"));
            back.validate().unwrap();
            close(
                &toml::Value::try_from(&plant).unwrap(),
                &toml::Value::try_from(&back).unwrap(),
                name,
            );
            for line in text.lines() {
                assert!(line.chars().count() <= term::WIDTH, "{name}: {line}");
            }
            // Each `key = value` line follows a comment line.
            let lines: Vec<&str> = text.lines().collect();
            for (i, l) in lines.iter().enumerate() {
                if l.contains(" = ") && !l.starts_with('#') && !l.starts_with("kind") {
                    assert!(
                        lines[i - 1].starts_with("# "),
                        "{name}: `{l}` has no comment"
                    );
                }
            }
        }
    }

    /// The commented `[wear]` table of the template, uncommented, is read
    /// as the ageing it describes.
    #[test]
    fn the_wear_table_of_the_template_reads_as_ageing() {
        let plant = beltune::model::builtin("egc70", None).unwrap();
        let text = template(&plant, "egc70").unwrap();
        let start = text.find("# [wear]").unwrap();
        let aged: String = text[..start].to_string()
            + &text[start..]
                .lines()
                .map(|l| {
                    if l.starts_with("# [") || l.contains(" = ") {
                        l.trim_start_matches("# ").to_string()
                    } else {
                        l.to_string()
                    }
                })
                .collect::<Vec<_>>()
                .join("\n");
        let back: Plant = toml::from_str(&aged).unwrap_or_else(|e| panic!("{e}\n{aged}"));
        back.validate().unwrap();
        let Plant::Physical(p) = back else {
            panic!("physical")
        };
        assert_eq!(
            p.wear,
            beltune::model::Wear {
                belt_stiffness_loss: 0.1,
                friction_growth: 0.3,
                belt_pretension_n: Some(40.0),
                guide_wear_n: 3.0,
                guide_wear_section_m: Some((0.2, 0.4)),
            }
        );
    }

    /// The commented `[unmodeled]` table of the template, uncommented, is
    /// read as the dynamics it describes, and they validate and simulate.
    #[test]
    fn the_unmodeled_table_of_the_template_reads_back() {
        let plant = beltune::model::builtin("egc70", None).unwrap();
        let text = template(&plant, "egc70").unwrap();
        let start = text.find("# [unmodeled]").unwrap();
        let end = text.find("# ---- ageing").unwrap();
        let on: String = text[..start].to_string()
            + &text[start..end]
                .lines()
                .map(|l| {
                    if l.starts_with("# [") || l.contains(" = ") {
                        l.trim_start_matches("# ").to_string()
                    } else {
                        l.to_string()
                    }
                })
                .collect::<Vec<_>>()
                .join("\n")
            + "\n"
            + &text[end..];
        let back: Plant = toml::from_str(&on).unwrap_or_else(|e| panic!("{e}\n{on}"));
        back.validate().unwrap();
        let Plant::Physical(p) = &back else {
            panic!("physical")
        };
        assert_eq!(p.unmodeled.current_loop_bandwidth_hz, 2000.0);
        assert_eq!(p.unmodeled.frame_mode_hz, 400.0);
        assert_eq!(p.unmodeled.tooth_pitch_m, 0.005);
        let mut axis = beltune::sim::SimAxis::new(&back, Default::default()).unwrap();
        for k in 0..2000 {
            let m = axis.step(if k % 200 < 100 { 0.3 } else { -0.3 });
            assert!(m.torque_actual_nm.is_finite());
        }
    }

    #[test]
    fn floats_stay_floats_in_toml() {
        assert_eq!(toml_float(1.0), "1.0");
        assert_eq!(toml_float(0.0), "0.0");
        assert_eq!(toml_float(4.5e-5), "4.5e-5");
        assert_eq!(
            toml_float(0.078 / (2.0 * std::f64::consts::PI)),
            "0.0124140855612"
        );
    }
}
