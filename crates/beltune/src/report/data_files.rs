//! The report's data files beside `report.html`, each with one writer and one
//! reader: the full measured FRF (`frf.csv`), the loops (`loops.csv`), the
//! validation moves as plotted (`moves.csv`), the identification experiment as
//! plotted (`excitation.csv`) and the friction runs (`friction.csv`). Numbers
//! are written in their shortest round-trip form, so a file read back holds
//! the same numbers.

use super::data::{BodeCurve, ExcitationPlot, FrictionPlot, MovePlot};
use super::plot_data::{FrfLines, LoopData};
use crate::ident::csv_columns::{read_csv_columns, read_csv_header};
use crate::{Error, Result};
use std::path::Path;

/// File name of the full measured FRF.
pub const FRF_CSV: &str = "frf.csv";
/// File name of the loop frequency responses.
pub const LOOPS_CSV: &str = "loops.csv";
/// File name of the validation moves.
pub const MOVES_CSV: &str = "moves.csv";
/// File name of the identification experiment's trace (as plotted).
pub const EXCITATION_CSV: &str = "excitation.csv";
/// File name of the friction runs (velocity, mean torque).
pub const FRICTION_CSV: &str = "friction.csv";
/// Every data file's name, in the order of [`DataFiles::texts`].
pub const DATA_FILE_NAMES: [&str; 5] =
    [FRF_CSV, LOOPS_CSV, MOVES_CSV, EXCITATION_CSV, FRICTION_CSV];

/// The data files of a result folder, each `None` (or empty) where absent.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct DataFiles {
    /// `frf.csv`.
    pub frf: Option<FrfLines>,
    /// `loops.csv`.
    pub loops: Option<LoopData>,
    /// `moves.csv`: one move per feedforward variant (or the simulated one).
    pub moves: Vec<MovePlot>,
    /// `excitation.csv`.
    pub excitation: Option<ExcitationPlot>,
    /// `friction.csv` (the fitted curve is not in the file: `viscous_nm_s_per_rad`
    /// and `coulomb_nm` are 0 until the caller sets them from the record).
    pub friction: Option<FrictionPlot>,
}

impl DataFiles {
    /// Read the data files in `dir` (each optional; a file that is there but
    /// broken is an error naming it).
    pub fn read(dir: &Path) -> Result<DataFiles> {
        let at = |name: &str| {
            let p = dir.join(name);
            std::fs::symlink_metadata(&p).is_ok().then_some(p)
        };
        Ok(DataFiles {
            frf: at(FRF_CSV).map(|p| read_frf_csv(&p)).transpose()?,
            loops: at(LOOPS_CSV).map(|p| read_loops_csv(&p)).transpose()?,
            moves: at(MOVES_CSV)
                .map(|p| read_moves_csv(&p))
                .transpose()?
                .unwrap_or_default(),
            excitation: at(EXCITATION_CSV)
                .map(|p| read_excitation_csv(&p))
                .transpose()?,
            friction: at(FRICTION_CSV)
                .map(|p| read_friction_csv(&p))
                .transpose()?,
        })
    }

    /// The files as (name, text), in the order above; absent ones are left out.
    pub fn texts(&self) -> Vec<(String, String)> {
        let mut out = Vec::new();
        if let Some(f) = &self.frf {
            out.push((FRF_CSV.to_string(), frf_csv(f)));
        }
        if let Some(l) = &self.loops {
            out.push((LOOPS_CSV.to_string(), loops_csv(l)));
        }
        if !self.moves.is_empty() {
            out.push((MOVES_CSV.to_string(), moves_csv(&self.moves)));
        }
        if let Some(e) = &self.excitation {
            out.push((EXCITATION_CSV.to_string(), excitation_csv(e)));
        }
        if let Some(f) = &self.friction {
            out.push((FRICTION_CSV.to_string(), friction_csv(f)));
        }
        out
    }

    /// What each present file holds, for the report's list of data files.
    pub fn notes(&self) -> Vec<(String, String)> {
        let mut v = Vec::new();
        let mut note = |present: bool, name: &str, what: &str| {
            if present {
                v.push((name.to_string(), what.to_string()));
            }
        };
        note(
            self.frf.is_some(),
            FRF_CSV,
            "every measured line of the FRF (the plot shows it decimated) with the fitted model",
        );
        note(
            self.loops.is_some(),
            LOOPS_CSV,
            "the open and closed loops, sensitivities and controller on the plot grid",
        );
        note(
            !self.moves.is_empty(),
            MOVES_CSV,
            "the validation moves (desired position, errors, torque) as plotted",
        );
        note(
            self.excitation.is_some(),
            EXCITATION_CSV,
            "the identification experiment (torque, position) as plotted, with its limits",
        );
        note(
            self.friction.is_some(),
            FRICTION_CSV,
            "the constant-velocity friction runs (velocity, mean torque)",
        );
        v
    }
}

/// A CSV table: header row, then one row per sample, `{:?}` (shortest
/// round-trip) numbers.
pub fn csv_text(columns: &[(&str, &[f64])]) -> String {
    let rows = columns.iter().map(|c| c.1.len()).min().unwrap_or(0);
    let mut out = columns.iter().map(|c| c.0).collect::<Vec<_>>().join(",");
    out.push('\n');
    for r in 0..rows {
        let row: Vec<String> = columns.iter().map(|c| format!("{:?}", c.1[r])).collect();
        out.push_str(&row.join(","));
        out.push('\n');
    }
    out
}

fn missing(path: &Path, n: &str) -> Error {
    Error::Csv {
        path: path.display().to_string(),
        message: format!("missing column `{n}`"),
    }
}

/// Columns of `frf.csv`.
const FRF_COLUMNS: [&str; 7] = [
    "freq_hz",
    "magnitude_db",
    "phase_deg",
    "coherence",
    "used_by_fit",
    "model_magnitude_db",
    "model_phase_deg",
];

/// `frf.csv`: every measured line with the fitted model at its frequency.
pub fn frf_csv(lines: &FrfLines) -> String {
    let used: Vec<f64> = lines
        .used_by_fit
        .iter()
        .map(|u| if *u { 1.0 } else { 0.0 })
        .collect();
    csv_text(&[
        (FRF_COLUMNS[0], &lines.freq_hz),
        (FRF_COLUMNS[1], &lines.magnitude_db),
        (FRF_COLUMNS[2], &lines.phase_deg),
        (FRF_COLUMNS[3], &lines.coherence),
        (FRF_COLUMNS[4], &used),
        (FRF_COLUMNS[5], &lines.model_magnitude_db),
        (FRF_COLUMNS[6], &lines.model_phase_deg),
    ])
}

/// Read `frf.csv` back.
pub fn read_frf_csv(path: &Path) -> Result<FrfLines> {
    let cols = read_csv_columns(path, &FRF_COLUMNS)?;
    let col = |n: &str| -> Result<Vec<f64>> {
        cols.column(n)
            .map(|c| c.to_vec())
            .ok_or_else(|| missing(path, n))
    };
    Ok(FrfLines {
        freq_hz: col("freq_hz")?,
        magnitude_db: col("magnitude_db")?,
        phase_deg: col("phase_deg")?,
        coherence: col("coherence")?,
        used_by_fit: col("used_by_fit")?.iter().map(|u| *u > 0.5).collect(),
        model_magnitude_db: col("model_magnitude_db")?,
        model_phase_deg: col("model_phase_deg")?,
    })
}

/// Column names of `loops.csv` after `freq_hz`: `<curve>_db`, `<curve>_deg`.
pub const LOOP_CURVES: [&str; 7] = [
    "velocity_open_loop",
    "velocity_closed_loop",
    "velocity_sensitivity",
    "position_open_loop",
    "position_closed_loop",
    "position_sensitivity",
    "controller",
];

/// `loops.csv`: every loop curve on the loop grid.
pub fn loops_csv(loops: &LoopData) -> String {
    let names: Vec<(String, String)> = LOOP_CURVES
        .iter()
        .map(|c| (format!("{c}_db"), format!("{c}_deg")))
        .collect();
    let mut cols: Vec<(&str, &[f64])> = vec![("freq_hz", &loops.freq_hz)];
    for (c, (db, deg)) in loops.curves().iter().zip(&names) {
        cols.push((db, &c.magnitude_db));
        cols.push((deg, &c.phase_deg));
    }
    csv_text(&cols)
}

/// Read `loops.csv` back.
pub fn read_loops_csv(path: &Path) -> Result<LoopData> {
    let mut names = vec!["freq_hz".to_string()];
    for c in LOOP_CURVES {
        names.push(format!("{c}_db"));
        names.push(format!("{c}_deg"));
    }
    let refs: Vec<&str> = names.iter().map(|s| s.as_str()).collect();
    let cols = read_csv_columns(path, &refs)?;
    let col = |n: &str| cols.column(n).map(|c| c.to_vec()).unwrap_or_default();
    let mut out = LoopData {
        freq_hz: col("freq_hz"),
        ..LoopData::default()
    };
    let freq = out.freq_hz.clone();
    for (c, name) in out.curves_mut().into_iter().zip(LOOP_CURVES) {
        *c = BodeCurve {
            label: name.replace('_', " "),
            freq_hz: freq.clone(),
            magnitude_db: col(&format!("{name}_db")),
            phase_deg: col(&format!("{name}_deg")),
            ..BodeCurve::default()
        };
    }
    Ok(out)
}

/// The column key of a move's label: lower-case letters, digits and `_`
/// (`nonlinear feedforward` -> `nonlinear_feedforward`; a label such as
/// `simulated on egc70, nonlinear feedforward` loses its comma, which would
/// split the CSV column).
pub fn move_key(label: &str) -> String {
    let mut key = String::new();
    for c in label.chars() {
        if c.is_ascii_alphanumeric() {
            key.push(c.to_ascii_lowercase());
        } else if !key.ends_with('_') && !key.is_empty() {
            key.push('_');
        }
    }
    key.trim_end_matches('_').to_string()
}

/// `moves.csv`: the moves as plotted, on the first move's time base: `time_s`,
/// `desired_m`, then per move `error_<key>_m` (the cart error, or the motor
/// error where the cart is not measured) and `torque_<key>_nm`
/// ([`move_key`] of its label).
pub fn moves_csv(moves: &[MovePlot]) -> String {
    let Some(first) = moves.first() else {
        return String::new();
    };
    let error = |m: &MovePlot| -> Vec<f64> {
        if m.cart_error_m.len() == m.time_s.len() {
            m.cart_error_m.clone()
        } else {
            m.motor_error_m.clone()
        }
    };
    let names: Vec<(String, String)> = moves
        .iter()
        .map(|m| {
            let key = move_key(&m.label);
            (format!("error_{key}_m"), format!("torque_{key}_nm"))
        })
        .collect();
    let errors: Vec<Vec<f64>> = moves.iter().map(error).collect();
    let mut cols: Vec<(&str, &[f64])> =
        vec![("time_s", &first.time_s), ("desired_m", &first.desired_m)];
    for (i, m) in moves.iter().enumerate() {
        cols.push((&names[i].0, &errors[i]));
        cols.push((&names[i].1, &m.torque_nm));
    }
    csv_text(&cols)
}

/// Read `moves.csv` back: one [`MovePlot`] per `error_<key>_m` column (with
/// its `torque_<key>_nm`), labelled `<key>` with spaces; the errors are read
/// as cart errors.
pub fn read_moves_csv(path: &Path) -> Result<Vec<MovePlot>> {
    let header = read_csv_header(path)?;
    let keys: Vec<String> = header
        .iter()
        .filter_map(|h| h.strip_prefix("error_")?.strip_suffix("_m"))
        .map(str::to_string)
        .collect();
    let mut names = vec!["time_s".to_string(), "desired_m".to_string()];
    for k in &keys {
        names.push(format!("error_{k}_m"));
        names.push(format!("torque_{k}_nm"));
    }
    let refs: Vec<&str> = names.iter().map(|s| s.as_str()).collect();
    let cols = read_csv_columns(path, &refs)?;
    let col = |n: &str| cols.column(n).map(|c| c.to_vec()).unwrap_or_default();
    Ok(keys
        .iter()
        .map(|k| MovePlot {
            label: k.replace('_', " "),
            time_s: col("time_s"),
            desired_m: col("desired_m"),
            cart_error_m: col(&format!("error_{k}_m")),
            motor_error_m: Vec::new(),
            torque_nm: col(&format!("torque_{k}_nm")),
        })
        .collect())
}

/// Columns of `excitation.csv`: the trace as plotted (envelope), and the
/// torque limit and travel window drawn with it (the same on every row).
const EXCITATION_COLUMNS: [&str; 6] = [
    "time_s",
    "torque_nm",
    "position_m",
    "torque_limit_nm",
    "travel_min_m",
    "travel_max_m",
];

/// `excitation.csv`: the identification experiment as the report plots it.
pub fn excitation_csv(e: &ExcitationPlot) -> String {
    let n = e.time_s.len();
    let same = |v: f64| vec![v; n];
    // the torque and position envelopes share their time base (same samples, same buckets)
    let position: Vec<f64> = if e.position_time_s == e.time_s {
        e.position_m.clone()
    } else {
        e.time_s
            .iter()
            .map(|t| {
                let k = e.position_time_s.partition_point(|x| x < t);
                e.position_m
                    .get(k.min(e.position_m.len().saturating_sub(1)))
                    .copied()
                    .unwrap_or(f64::NAN)
            })
            .collect()
    };
    csv_text(&[
        (EXCITATION_COLUMNS[0], &e.time_s),
        (EXCITATION_COLUMNS[1], &e.torque_nm),
        (EXCITATION_COLUMNS[2], &position),
        (EXCITATION_COLUMNS[3], &same(e.torque_limit_nm)),
        (EXCITATION_COLUMNS[4], &same(e.travel_min_m)),
        (EXCITATION_COLUMNS[5], &same(e.travel_max_m)),
    ])
}

/// Read `excitation.csv` back.
pub fn read_excitation_csv(path: &Path) -> Result<ExcitationPlot> {
    let cols = read_csv_columns(path, &EXCITATION_COLUMNS)?;
    let col = |n: &str| -> Vec<f64> { cols.column(n).map(|c| c.to_vec()).unwrap_or_default() };
    let first = |n: &str| col(n).first().copied().unwrap_or(f64::NAN);
    let time_s = col("time_s");
    Ok(ExcitationPlot {
        position_time_s: time_s.clone(),
        time_s,
        torque_nm: col("torque_nm"),
        position_m: col("position_m"),
        torque_limit_nm: first("torque_limit_nm"),
        travel_min_m: first("travel_min_m"),
        travel_max_m: first("travel_max_m"),
    })
}

/// Columns of `friction.csv`.
const FRICTION_COLUMNS: [&str; 2] = ["velocity_rad_s", "mean_torque_nm"];

/// `friction.csv`: each constant-velocity run of the friction stage.
pub fn friction_csv(f: &FrictionPlot) -> String {
    csv_text(&[
        (FRICTION_COLUMNS[0], &f.velocity_rad_s),
        (FRICTION_COLUMNS[1], &f.torque_nm),
    ])
}

/// Read `friction.csv` back (the fitted curve is not in the file: 0).
pub fn read_friction_csv(path: &Path) -> Result<FrictionPlot> {
    let cols = read_csv_columns(path, &FRICTION_COLUMNS)?;
    let col = |n: &str| -> Vec<f64> { cols.column(n).map(|c| c.to_vec()).unwrap_or_default() };
    Ok(FrictionPlot {
        velocity_rad_s: col("velocity_rad_s"),
        torque_nm: col("mean_torque_nm"),
        viscous_nm_s_per_rad: 0.0,
        coulomb_nm: 0.0,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn temp_dir(tag: &str) -> std::path::PathBuf {
        let d = std::env::temp_dir().join(format!("beltune-data-{tag}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    fn a_move(label: &str, k: f64) -> MovePlot {
        MovePlot {
            label: label.into(),
            time_s: vec![0.0, 0.1, 0.2],
            desired_m: vec![0.0, 0.25, 0.5],
            cart_error_m: vec![1e-4 * k, -2e-4, 3e-5],
            motor_error_m: vec![9.0, 9.0, 9.0],
            torque_nm: vec![0.5, -0.25 * k, 0.125],
        }
    }

    #[test]
    fn every_data_file_reads_back_what_was_written() {
        let dir = temp_dir("roundtrip");
        let moves = vec![
            a_move("no feedforward", 1.0),
            a_move("nonlinear feedforward", 2.0),
        ];
        let files = DataFiles {
            frf: Some(FrfLines {
                freq_hz: vec![1.0, 2.0],
                magnitude_db: vec![-10.0, -20.5],
                phase_deg: vec![-180.0, -190.25],
                coherence: vec![0.99, 0.5],
                used_by_fit: vec![true, false],
                model_magnitude_db: vec![-10.1, -20.4],
                model_phase_deg: vec![-181.0, -189.0],
            }),
            loops: None,
            moves: moves.clone(),
            excitation: Some(ExcitationPlot {
                time_s: vec![0.0, 1e-4],
                torque_nm: vec![0.1, -0.1],
                position_time_s: vec![0.0, 1e-4],
                position_m: vec![0.5, 0.5001],
                torque_limit_nm: 3.1,
                travel_min_m: -0.01,
                travel_max_m: 0.57,
            }),
            friction: Some(FrictionPlot {
                velocity_rad_s: vec![-10.0, 10.0],
                torque_nm: vec![-0.15, 0.15],
                viscous_nm_s_per_rad: 0.0,
                coulomb_nm: 0.0,
            }),
        };
        for (name, text) in files.texts() {
            std::fs::write(dir.join(name), text).unwrap();
        }
        let back = DataFiles::read(&dir).unwrap();
        assert_eq!(back.frf, files.frf);
        assert_eq!(back.excitation, files.excitation);
        assert_eq!(back.friction, files.friction);
        assert_eq!(back.moves.len(), 2);
        for (b, m) in back.moves.iter().zip(&moves) {
            assert_eq!(b.label, m.label);
            assert_eq!(b.cart_error_m, m.cart_error_m);
            assert_eq!(b.torque_nm, m.torque_nm);
            assert_eq!(b.time_s, m.time_s);
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn a_move_label_with_a_comma_keeps_the_moves_file_readable() {
        let dir = temp_dir("comma");
        let m = a_move("simulated on egc70, nonlinear feedforward (11.2 kg)", 1.0);
        let text = moves_csv(std::slice::from_ref(&m));
        let header = text.lines().next().unwrap();
        let data = text.lines().nth(1).unwrap();
        assert_eq!(header.split(',').count(), data.split(',').count(), "{text}");
        std::fs::write(dir.join(MOVES_CSV), &text).unwrap();
        let back = read_moves_csv(&dir.join(MOVES_CSV)).unwrap();
        assert_eq!(back.len(), 1);
        assert_eq!(
            back[0].label,
            "simulated on egc70 nonlinear feedforward 11 2 kg"
        );
        assert_eq!(back[0].cart_error_m, m.cart_error_m);
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
