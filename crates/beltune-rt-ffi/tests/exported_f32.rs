//! The single-precision exports (`beltune export --lang rust|c --precision
//! f32`) compile, hold the `f32` nearest to every value of the file, and the
//! f32 controller they build (in Rust, and in C through the float ABI of
//! beltune-rt-ffi) gives the torques of the f64 controller over the
//! validation move (thesis chapter 5: 0 -> 0.5 m with the limits of Table
//! A.8) to a tolerance derived from f32's resolution of the motor angle.
//! tests/data/controller_f32.rs is the export of tests/data/controller.toml
//! (regenerate with `BELTUNE_BLESS=1`).

use beltune::record::controller::ControllerFile;
use beltune::record::export::{export_as, parse_values, values, Lang, Precision, Value};
use beltune_rt::control::{
    CartSample, CascadeController, ControlOutput, Setpoint, SetpointConversion,
};
use beltune_rt::trajectory::{Limits, State, Trajectory};
use std::path::Path;
use std::process::Command;

mod common;
use common::compile_c;

#[allow(dead_code)]
mod exported {
    include!("data/controller.rs");
}

#[allow(dead_code)]
mod exported_f32 {
    include!("data/controller_f32.rs");
}

fn fixture() -> ControllerFile {
    ControllerFile::load(&Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/controller.toml"))
        .unwrap()
}

#[test]
fn f32_rust_export_is_current_and_holds_the_nearest_f32_of_every_value() {
    let file = fixture();
    let text = export_as(&file, Lang::Rust, Precision::F32).unwrap();
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/controller_f32.rs");
    if std::env::var_os("BELTUNE_BLESS").is_some() {
        std::fs::write(&path, &text).unwrap();
    }
    assert_eq!(
        std::fs::read_to_string(&path).unwrap(),
        text,
        "tests/data/controller_f32.rs is stale: BELTUNE_BLESS=1 cargo test -p beltune-rt-ffi --test exported_f32"
    );
    assert!(text.contains("pub const CASCADE: CascadeConfig<f32>"));
    // Every literal reads back (as Rust parses it) to the f32 nearest the file's value.
    let vals = values(&file);
    let lits = parse_values(&text);
    assert_eq!(lits.len(), vals.len());
    for ((name, lit), (_, v)) in lits.iter().zip(&vals) {
        if let Value::Real(x) = v {
            assert_eq!(
                lit.parse::<f32>().unwrap().to_bits(),
                (*x as f32).to_bits(),
                "{name}"
            );
        }
    }
    // The compiled module builds the cast of the loader's configuration.
    assert_eq!(
        exported_f32::CASCADE,
        file.cascade_config().unwrap().cast::<f32>()
    );
    SetpointConversion::<f32>::new(exported_f32::I_T_M_PER_RAD, exported_f32::BELT_STRETCH)
        .unwrap();
    assert!(CascadeController::new(exported_f32::CASCADE).is_ok());
}

/// The C export in single precision holds the same `float`s as the Rust
/// one (both the nearest `f32` of each value), as `float` constants.
#[test]
fn f32_c_export_holds_the_nearest_f32_of_every_value() {
    let file = fixture();
    let c = export_as(&file, Lang::C, Precision::F32).unwrap();
    assert!(c.contains("static const BtCascadeConfigF32 BELTUNE_CASCADE"));
    assert!(c.contains("static const BtSetpointConfigF32 BELTUNE_SETPOINT"));
    let rust = parse_values(&export_as(&file, Lang::Rust, Precision::F32).unwrap());
    let c_values = parse_values(&c);
    assert_eq!(c_values, rust);
    let vals = values(&file);
    for ((name, lit), (_, v)) in c_values.iter().zip(&vals) {
        if let Value::Real(x) = v {
            // every real is a `float` constant (suffix f)
            assert!(
                c.contains(&format!(
                    "#define BELTUNE_{} {lit}f\n",
                    name.to_ascii_uppercase()
                )),
                "{name}"
            );
            assert_eq!(lit.parse::<f32>().unwrap().to_bits(), (*x as f32).to_bits());
        }
    }
}
/// f32 resolution of the motor angle at the end of the move (0.5 m / i_t =
/// 40.3 rad lies in [32, 64): one ulp is 2^-18 rad).
const ULP_PHI_RAD: f64 = 3.814697265625e-6;

/// The validation move (thesis chapter 5: 0 -> 0.5 m with the limits of
/// Table A.8), as `tests/c/run_controller_f32.c` plans it.
fn validation_move() -> Trajectory {
    let limits = Limits {
        position_min: -0.01,
        position_max: 0.57,
        ..Limits::default()
    };
    Trajectory::plan(&State::at_rest(0.0), &State::at_rest(0.5), &limits).unwrap()
}

/// One run of the f64 and f32 controllers over the validation move.
struct Run {
    /// Time of each sample and of its preview sample, s.
    times_s: Vec<(f64, f64)>,
    /// The motor angle each controller measured, rad (f64; the f32
    /// controller gets it rounded to f32).
    angles_rad: Vec<f64>,
    o64: Vec<ControlOutput<f64>>,
    o32: Vec<ControlOutput<f32>>,
}

/// The f64 controller of the export closes the loop around a rigid motor
/// (`J phi'' = tau - d phi'`, the file's feedforward inertia and viscous
/// friction, one sample of delay) over the validation move; the f32
/// controller of the f32 export sees the same setpoints and measured angles,
/// rounded to f32 as a firmware would have them.
fn validation_run() -> Run {
    let c64 = exported::CASCADE;
    let c32 = exported_f32::CASCADE;
    let mut k64 = CascadeController::new(c64).unwrap();
    let mut k32 = CascadeController::new(c32).unwrap();
    let s64 = SetpointConversion::new(exported::I_T_M_PER_RAD, exported::BELT_STRETCH).unwrap();
    let s32 =
        SetpointConversion::new(exported_f32::I_T_M_PER_RAD, exported_f32::BELT_STRETCH).unwrap();
    let traj = validation_move();
    let ts = exported::TS_S;
    let n_ahead = exported::PREVIEW_SAMPLES;
    let time = |k: usize| k as f64 * ts;
    let cart = |t: f64| {
        let s = traj.sample(t);
        CartSample {
            position_m: s.position,
            velocity_m_s: s.velocity,
            acceleration_m_s2: s.acceleration,
            jerk_m_s3: s.jerk,
        }
    };
    let f32_cart = |c: CartSample<f64>| CartSample {
        position_m: c.position_m as f32,
        velocity_m_s: c.velocity_m_s as f32,
        acceleration_m_s2: c.acceleration_m_s2 as f32,
        jerk_m_s3: c.jerk_m_s3 as f32,
    };
    let (j, d) = (
        exported::FF_INERTIA_KG_M2,
        exported::FF_VISCOUS_NM_S_PER_RAD,
    );
    let (mut phi, mut omega, mut tau_applied) = (0.0_f64, 0.0_f64, 0.0_f64);
    k64.reset_to(phi);
    k32.reset_to(phi as f32);
    let samples = ((traj.duration_s() + 0.3) / ts) as usize;
    let mut run = Run {
        times_s: Vec::with_capacity(samples),
        angles_rad: Vec::with_capacity(samples),
        o64: Vec::with_capacity(samples),
        o32: Vec::with_capacity(samples),
    };
    for k in 0..samples {
        let (t_now, t_ahead) = (time(k), time(k + n_ahead));
        let (now, ahead) = (cart(t_now), cart(t_ahead));
        let sp64 = Setpoint::with_preview(s64.motor_sample(&now), s64.motor_sample(&ahead));
        let sp32: Setpoint<f32> = Setpoint::with_preview(
            s32.motor_sample(&f32_cart(now)),
            s32.motor_sample(&f32_cart(ahead)),
        );
        let o64 = k64.step(&sp64, phi);
        run.o32.push(k32.step(&sp32, phi as f32));
        run.times_s.push((t_now, t_ahead));
        run.angles_rad.push(phi);
        run.o64.push(o64);
        // The plant, semi-implicit Euler with the previous sample's torque.
        omega += ts * (tau_applied - d * omega) / j;
        phi += ts * omega;
        tau_applied = o64.torque_nm;
    }
    run
}

/// Tolerance of the f32 controller against the f64 one (the run of
/// [`validation_run`]): the angle enters the velocity estimate `b0 (phi_k -
/// phi_k-1)` rounded to one ulp of the angle on each of the two samples, the
/// velocity filter's pole `|a1| = 0.95` accumulates such rounding over `1 /
/// (1 - |a1|) = 20` samples, and the velocity gain `K_P` turns it into torque:
/// `K_P * b0 * 2 ulp * 20` = 0.114 * 487.8 * 7.6e-6 * 20 = 8.7e-3 N m
/// (0.28 % of the 3.1 N m torque limit; measured 5e-5 N m). The exception is
/// the discontinuous Coulomb feedforward (a step of `coulomb_nm` when the
/// velocity leaves its deadband), which f32 may switch one sample before or
/// after f64: at most two such samples (start and end of the move), each
/// within `2 coulomb_nm` plus the tolerance.
fn tolerance_nm() -> f64 {
    let c64 = exported::CASCADE;
    c64.gains.k_p_nm_s_per_rad * c64.velocity_filter.b0.abs() * 2.0 * ULP_PHI_RAD
        / (1.0 - c64.velocity_filter.a1.abs())
}

/// `torques_f32` (one per sample of `run`) against the f64 controller's
/// torques within [`tolerance_nm`]; prints and checks.
fn check_against_f64(label: &str, run: &Run, torques_f32: &[f32], feedforward_f32: &[f32]) {
    let tol_nm = tolerance_nm();
    let coulomb_nm = exported::FF_COULOMB_NM;
    let (mut worst, mut peak, mut worst_switch) = (0.0_f64, 0.0_f64, 0.0_f64);
    let (mut worst_ff, mut ff_switches) = (0.0_f64, 0usize);
    for ((o64, &t32), &ff32) in run.o64.iter().zip(torques_f32).zip(feedforward_f32) {
        let dtau = (o64.torque_nm - f64::from(t32)).abs();
        let dff = (o64.feedforward_nm - f64::from(ff32)).abs();
        if dff > tol_nm {
            ff_switches += 1;
            worst_switch = worst_switch.max(dtau);
        } else {
            worst_ff = worst_ff.max(dff);
            worst = worst.max(dtau);
        }
        peak = peak.max(o64.torque_nm.abs());
    }
    println!(
        "{label}: validation move, {} samples, peak torque {peak:.3} N m, \
         max |tau_f64 - tau_f32| = {worst:.3e} N m (tolerance {tol_nm:.3e} N m; feedforward \
         {worst_ff:.3e}) but for {ff_switches} Coulomb switches one sample apart \
         ({worst_switch:.3e} N m)",
        run.o64.len()
    );
    assert_eq!(torques_f32.len(), run.o64.len());
    assert!(peak > 0.1, "the move must load the controller ({peak} N m)");
    assert!(worst <= tol_nm, "{worst} > {tol_nm}");
    // The Coulomb feedforward is discontinuous (a step of coulomb_nm when the
    // velocity leaves the deadband): f32 may switch one sample before or after
    // f64, at the start and the end of the move, never more than that.
    assert!(ff_switches <= 2, "{ff_switches} Coulomb switches apart");
    assert!(
        worst_switch <= 2.0 * coulomb_nm + tol_nm,
        "{worst_switch} > 2 * {coulomb_nm} + {tol_nm}"
    );
}

/// The f32 controller of the Rust f32 export against the f64 controller
/// over the validation move ([`validation_run`], [`tolerance_nm`]); the
/// feedback part alone (torque before saturation minus feedforward) stays
/// within the tolerance on every sample, Coulomb switches included.
#[test]
fn f32_controller_torques_agree_with_f64_over_the_validation_move() {
    let run = validation_run();
    let tol_nm = tolerance_nm();
    let fb = |o_u: f64, o_ff: f64| o_u - o_ff;
    let worst_fb = run
        .o64
        .iter()
        .zip(&run.o32)
        .map(|(a, b)| {
            (fb(a.torque_unsaturated_nm, a.feedforward_nm)
                - fb(
                    f64::from(b.torque_unsaturated_nm),
                    f64::from(b.feedforward_nm),
                ))
            .abs()
        })
        .fold(0.0, f64::max);
    println!("feedback part: max difference {worst_fb:.3e} N m");
    assert!(worst_fb <= tol_nm, "{worst_fb} > {tol_nm}");
    let t32: Vec<f32> = run.o32.iter().map(|o| o.torque_nm).collect();
    let ff32: Vec<f32> = run.o32.iter().map(|o| o.feedforward_nm).collect();
    check_against_f64("Rust f32", &run, &t32, &ff32);
}

/// `beltune export --lang c --precision f32` of tests/data/controller.toml
/// compiled with `cc` into tests/c/run_controller_f32.c, which runs the move
/// through the float ABI (`bt_trajectory_sample_f32`,
/// `bt_setpoint_f32_convert`, `bt_cascade_f32_step`) on the measured angles
/// of [`validation_run`] rounded to f32: its torques equal the Rust f32
/// controller's bit for bit (same code, same inputs: a difference is an ABI
/// or export error) and so stay within [`tolerance_nm`] of the f64
/// controller's.
#[test]
fn c_f32_export_runs_the_f32_torques_through_the_float_abi() {
    let file = fixture();
    let dir = std::env::temp_dir().join(format!("beltune-ffi-c-f32-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let header = export_as(&file, Lang::C, Precision::F32).unwrap();
    std::fs::write(dir.join("controller.h"), header).unwrap();
    let run = validation_run();
    let input: String = run
        .times_s
        .iter()
        .zip(&run.angles_rad)
        .map(|((t, ta), phi)| format!("{t:?} {ta:?} {:?}\n", *phi as f32))
        .collect();
    std::fs::write(dir.join("samples.txt"), input).unwrap();
    let exe = dir.join("run_controller_f32");
    compile_c(
        &Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/c/run_controller_f32.c"),
        &dir,
        &exe,
    );
    let o = Command::new(&exe)
        .arg(dir.join("samples.txt"))
        .output()
        .unwrap();
    assert!(
        o.status.success(),
        "C program failed: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    let text = String::from_utf8(o.stdout).unwrap();
    let mut lines = text.lines();
    let duration: f64 = lines.next().unwrap().parse().unwrap();
    assert_eq!(duration, validation_move().duration_s());
    let got: Vec<f32> = lines.map(|l| l.parse().unwrap()).collect();
    assert_eq!(got.len(), run.o32.len());
    for (k, (g, w)) in got.iter().zip(&run.o32).enumerate() {
        assert_eq!(
            g.to_bits(),
            w.torque_nm.to_bits(),
            "sample {k}: C {g}, Rust f32 {}",
            w.torque_nm
        );
    }
    let ff32: Vec<f32> = run.o32.iter().map(|o| o.feedforward_nm).collect();
    check_against_f64("C f32", &run, &got, &ff32);
    std::fs::remove_dir_all(&dir).unwrap();
}
