//! The exported C configuration runs through the staticlib exactly as the Rust
//! controller does: `beltune export --lang c` of tests/data/controller.toml is
//! compiled with `cc` against include/beltune_rt.h and libbeltune_rt_ffi.a, and
//! the torques of a planned move with a lagging, ringing measured angle equal
//! the Rust `CascadeController`'s bit for bit (same code, same inputs: any
//! difference is an ABI or export error).

use beltune::record::controller::ControllerFile;
use beltune::record::export::{c_header, Lang};
use beltune_rt::control::{CascadeController, Setpoint};
use beltune_rt::trajectory::{Limits, State, Trajectory};
use std::path::Path;
use std::process::Command;

mod common;
use common::compile_c;

fn manifest() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

#[test]
fn exported_c_header_runs_the_same_torques_as_rust() {
    let which = Command::new("cc").arg("--version").output();
    assert!(which.is_ok(), "a C compiler `cc` is required for this test");
    let file = ControllerFile::load(&manifest().join("tests/data/controller.toml")).unwrap();
    let dir = std::env::temp_dir().join(format!("beltune-ffi-c-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("controller.h"), c_header(&file)).unwrap();
    assert_eq!(
        beltune::record::export::export(&file, Lang::C),
        c_header(&file)
    );

    // The Rust side: the same move, conversion and controller.
    let cfg = file.cascade_config().unwrap();
    let conv = file.setpoint_conversion().unwrap();
    let limits = Limits {
        v_max: 2.0,
        v_min: -2.0,
        a_max: 20.0,
        a_min: -20.0,
        j_max: 400.0,
        j_min: -400.0,
        position_min: f64::NEG_INFINITY,
        position_max: f64::INFINITY,
    };
    let traj = Trajectory::plan(&State::at_rest(0.05), &State::at_rest(0.55), &limits).unwrap();
    let motor = |t: f64| {
        let s = traj.sample(t);
        conv.motor_sample(&beltune_rt::control::CartSample {
            position_m: s.position,
            velocity_m_s: s.velocity,
            acceleration_m_s2: s.acceleration,
            jerk_m_s3: s.jerk,
        })
    };
    let n = ((traj.duration_s() + 0.2) / cfg.ts_s) as usize;
    let ts = cfg.ts_s;
    let preview = file.feedforward.preview_samples as f64 * ts;
    // measured: the desired angle 3 ms late, with a 120 Hz ring of 5 mrad
    let measured: Vec<f64> = (0..n)
        .map(|k| {
            let t = k as f64 * ts;
            motor((t - 3e-3).max(0.0)).angle_rad
                + 5e-3 * (2.0 * std::f64::consts::PI * 120.0 * t).sin()
        })
        .collect();
    let mut c = CascadeController::new(cfg).unwrap();
    c.reset_to(motor(0.0).angle_rad);
    let want: Vec<f64> = measured
        .iter()
        .enumerate()
        .map(|(k, &m)| {
            let t = k as f64 * ts;
            c.step(&Setpoint::with_preview(motor(t), motor(t + preview)), m)
                .torque_nm
        })
        .collect();
    assert!(want.iter().any(|t| t.abs() > 0.05), "the move needs torque");

    let input: String = measured.iter().map(|m| format!("{m:?}\n")).collect();
    std::fs::write(dir.join("measured.txt"), input).unwrap();
    let exe = dir.join("run_controller");
    compile_c(&manifest().join("tests/c/run_controller.c"), &dir, &exe);
    let o = Command::new(&exe)
        .arg(dir.join("measured.txt"))
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
    assert_eq!(duration, traj.duration_s());
    let got: Vec<f64> = lines.map(|l| l.parse().unwrap()).collect();
    assert_eq!(got.len(), want.len());
    for (k, (g, w)) in got.iter().zip(&want).enumerate() {
        assert_eq!(g.to_bits(), w.to_bits(), "sample {k}: C {g}, Rust {w}");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}
