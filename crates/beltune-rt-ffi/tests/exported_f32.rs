//! The single-precision Rust export (`beltune export --lang rust --precision
//! f32`) compiles, holds the `f32` nearest to every value of the file, and
//! the f32 controller it builds gives the torques of the f64 controller over
//! the validation move (thesis chapter 5: 0 -> 0.5 m with the limits of
//! Table A.8) to a tolerance derived from f32's resolution of the motor angle.
//! tests/data/controller_f32.rs is the export of tests/data/controller.toml
//! (regenerate with `BELTUNE_BLESS=1`).

use beltune::record::controller::ControllerFile;
use beltune::record::export::{export_as, parse_values, values, Lang, Precision, Value};
use beltune_rt::control::{
    CartSample, CascadeController, MotionSample, Setpoint, SetpointConversion,
};
use beltune_rt::trajectory::{Limits, State, Trajectory};
use std::path::Path;

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

#[test]
fn f32_export_in_c_is_refused_with_a_clear_error() {
    let e = export_as(&fixture(), Lang::C, Precision::F32).unwrap_err();
    assert!(e.to_string().contains("Rust only"), "{e}");
}

/// f32 resolution of the motor angle at the end of the move (0.5 m / i_t =
/// 40.3 rad lies in [32, 64): one ulp is 2^-18 rad).
const ULP_PHI_RAD: f64 = 3.814697265625e-6;

/// The f64 controller of the export closes the loop around a rigid motor
/// (`J phi'' = tau - d phi'`, the file's feedforward inertia and viscous
/// friction, one sample of delay) over the validation move; the f32
/// controller of the f32 export sees the same setpoints and measured angles,
/// rounded to f32 as a firmware would have them. Tolerance: the angle enters
/// the velocity estimate `b0 (phi_k - phi_k-1)` rounded to one ulp of the
/// angle on each of the two samples, the velocity filter's pole `|a1| = 0.95`
/// accumulates such rounding over `1 / (1 - |a1|) = 20` samples, and the
/// velocity gain `K_P` turns it into torque:
/// `K_P * b0 * 2 ulp * 20` = 0.114 * 487.8 * 7.6e-6 * 20 = 8.7e-3 N m
/// (0.28 % of the 3.1 N m torque limit; measured 5e-5 N m). The exception is
/// the discontinuous Coulomb feedforward (a step of `coulomb_nm` when the
/// velocity leaves its deadband), which f32 may switch one sample before or
/// after f64: at most two such samples (start and end of the move), each
/// within `2 coulomb_nm` plus the tolerance.
#[test]
fn f32_controller_torques_agree_with_f64_over_the_validation_move() {
    let c64 = exported::CASCADE;
    let c32 = exported_f32::CASCADE;
    let tol_nm = c64.gains.k_p_nm_s_per_rad * c64.velocity_filter.b0.abs() * 2.0 * ULP_PHI_RAD
        / (1.0 - c64.velocity_filter.a1.abs());
    let mut k64 = CascadeController::new(c64).unwrap();
    let mut k32 = CascadeController::new(c32).unwrap();
    let s64 = SetpointConversion::new(exported::I_T_M_PER_RAD, exported::BELT_STRETCH).unwrap();
    let s32 =
        SetpointConversion::new(exported_f32::I_T_M_PER_RAD, exported_f32::BELT_STRETCH).unwrap();
    let limits = Limits {
        position_min: -0.01,
        position_max: 0.57,
        ..Limits::default()
    };
    let traj = Trajectory::plan(&State::at_rest(0.0), &State::at_rest(0.5), &limits).unwrap();
    let ts = exported::TS_S;
    let n_ahead = exported::PREVIEW_SAMPLES;
    let cart = |k: usize| {
        let s = traj.sample(k as f64 * ts);
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
    let coulomb_nm = exported::FF_COULOMB_NM;
    let (mut worst, mut peak, mut worst_switch) = (0.0_f64, 0.0_f64, 0.0_f64);
    let (mut worst_fb, mut worst_ff, mut ff_switches) = (0.0_f64, 0.0_f64, 0usize);
    for k in 0..samples {
        let (now, ahead) = (cart(k), cart(k + n_ahead));
        let sp64 = Setpoint::with_preview(s64.motor_sample(&now), s64.motor_sample(&ahead));
        let sp32: Setpoint<f32> = Setpoint::with_preview(
            s32.motor_sample(&f32_cart(now)),
            s32.motor_sample(&f32_cart(ahead)),
        );
        let o64 = k64.step(&sp64, phi);
        let o32 = k32.step(&sp32, phi as f32);
        let dtau = (o64.torque_nm - f64::from(o32.torque_nm)).abs();
        let fb = |o_u: f64, o_ff: f64| o_u - o_ff;
        worst_fb = worst_fb.max(
            (fb(o64.torque_unsaturated_nm, o64.feedforward_nm)
                - fb(
                    f64::from(o32.torque_unsaturated_nm),
                    f64::from(o32.feedforward_nm),
                ))
            .abs(),
        );
        let dff = (o64.feedforward_nm - f64::from(o32.feedforward_nm)).abs();
        if dff > tol_nm {
            ff_switches += 1;
            worst_switch = worst_switch.max(dtau);
        } else {
            worst_ff = worst_ff.max(dff);
            worst = worst.max(dtau);
        }
        peak = peak.max(o64.torque_nm.abs());
        // The plant, semi-implicit Euler with the previous sample's torque.
        omega += ts * (tau_applied - d * omega) / j;
        phi += ts * omega;
        tau_applied = o64.torque_nm;
    }
    let _: MotionSample<f64> = s64.motor_sample(&cart(0));
    println!(
        "validation move: {samples} samples, peak torque {peak:.3} N m, \
         max |tau_f64 - tau_f32| = {worst:.3e} N m (tolerance {tol_nm:.3e} N m; feedback part \
         {worst_fb:.3e}, feedforward {worst_ff:.3e}) but for {ff_switches} Coulomb switches \
         one sample apart ({worst_switch:.3e} N m)"
    );
    assert!(peak > 0.1, "the move must load the controller ({peak} N m)");
    assert!(worst <= tol_nm, "{worst} > {tol_nm}");
    assert!(worst_fb <= tol_nm, "{worst_fb} > {tol_nm}");
    // The Coulomb feedforward is discontinuous (a step of coulomb_nm when the
    // velocity leaves the deadband): f32 may switch one sample before or after
    // f64, at the start and the end of the move, never more than that.
    assert!(ff_switches <= 2, "{ff_switches} Coulomb switches apart");
    assert!(
        worst_switch <= 2.0 * coulomb_nm + tol_nm,
        "{worst_switch} > 2 * {coulomb_nm} + {tol_nm}"
    );
}
