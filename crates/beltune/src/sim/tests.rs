//! Tests of the simulator against independent references: the analytical
//! transfer functions, the three-mass state space, rigid-body mechanics.

use super::*;
use crate::lti::C64;
use crate::model::params::GRAVITY_M_S2 as GRAVITY;
use crate::model::rigs::{builtin, egc70_params};
use crate::model::three_mass::ThreeMass;
use std::f64::consts::PI;

/// The simulated FRF equals the analytical one within 0.5 dB and 3 deg.
const FRF_TOL_DB: f64 = 0.5;
const FRF_TOL_DEG: f64 = 3.0;

/// One period of 1 s at 10 kHz: 1 Hz lines.
const PERIOD_SAMPLES: usize = 10_000;

/// Excited lines: about 12 per decade from 1 to 400 Hz (integer Hz, distinct).
fn lines_hz() -> Vec<usize> {
    let mut v: Vec<usize> = (0..=32)
        .map(|k| (10f64.powf(k as f64 * 2.60206 / 32.0)).round() as usize)
        .collect();
    v.dedup();
    v
}

/// Simulated FRF torque command -> motor angle (encoder counts times rad per
/// count, as a drive measures it) at the excited lines of a Schroeder-phased
/// periodic multisine: `transient` periods discarded, `periods` averaged, DFT
/// evaluated at the lines. The multisine must stay below the torque limit
/// (saturation would make the response non-periodic).
fn simulated_frf(
    axis: &mut SimAxis,
    amplitude_nm: f64,
    transient: usize,
    periods: usize,
) -> Vec<(f64, C64)> {
    let lines = lines_hz();
    let n_l = lines.len() as f64;
    let phases: Vec<f64> = (0..lines.len())
        .map(|k| -PI * (k * (k + 1)) as f64 / n_l)
        .collect();
    let t_s = axis.info().ts_s;
    let q = axis.info().motor_rad_per_count;
    let u_of = |i: usize| -> f64 {
        let t = (i % PERIOD_SAMPLES) as f64 * t_s;
        lines
            .iter()
            .zip(&phases)
            .map(|(f, p)| amplitude_nm * (2.0 * PI * *f as f64 * t + p).cos())
            .sum()
    };
    let peak = (0..PERIOD_SAMPLES)
        .map(|i| u_of(i).abs())
        .fold(0.0, f64::max);
    assert!(
        peak < axis.info().torque_max_nm,
        "the multisine would saturate: {peak} N m"
    );
    let mut u_sum = vec![0.0; PERIOD_SAMPLES];
    let mut y_sum = vec![0.0; PERIOD_SAMPLES];
    for p in 0..(transient + periods) {
        for i in 0..PERIOD_SAMPLES {
            let u = u_of(i);
            let m = axis.step(u);
            if p >= transient {
                u_sum[i] += u;
                y_sum[i] += m.motor_counts as f64 * q;
            }
        }
    }
    lines
        .iter()
        .map(|&f| {
            let mut uu = C64::new(0.0, 0.0);
            let mut yy = C64::new(0.0, 0.0);
            for i in 0..PERIOD_SAMPLES {
                let e = C64::from_polar(1.0, -2.0 * PI * (f * i) as f64 / PERIOD_SAMPLES as f64);
                uu += e * u_sum[i];
                yy += e * y_sum[i];
            }
            (f as f64, yy / uu)
        })
        .collect()
}

/// What the sampled simulation should show for a continuous `G(jw)`: the dead
/// time `n T_s`, the ZOH's half-sample lag and the measurement at the end of
/// the sample (one sample ahead): `G(jw) e^{-jw (n - 1/2) T_s}` (module docs).
fn expected(g: C64, w: f64, dead_time_s: f64, t_s: f64) -> C64 {
    g * C64::from_polar(1.0, -w * (dead_time_s - 0.5 * t_s))
}

fn assert_frf_close(name: &str, sim: &[(f64, C64)], model: impl Fn(f64) -> C64) {
    for &(f, g_sim) in sim {
        let g = model(2.0 * PI * f);
        let db = 20.0 * (g_sim.norm() / g.norm()).log10();
        let deg = (g_sim / g).arg().to_degrees();
        assert!(
            db.abs() < FRF_TOL_DB && deg.abs() < FRF_TOL_DEG,
            "{name} at {f} Hz: {db:.3} dB, {deg:.3} deg"
        );
    }
}

#[test]
fn linear_sets_frf_matches_transfer_function_1_to_400_hz() {
    for name in ["sim-a", "sim-b", "sim-c"] {
        let plant = builtin(name, None).unwrap();
        let cfg = SimConfig {
            noise: Some(MeasurementNoise::NONE),
            ..SimConfig::default()
        };
        let mut axis = SimAxis::new(&plant, cfg).unwrap();
        let (td, ts) = (axis.dead_time_s(), axis.info().ts_s);
        assert!((td - 1e-3).abs() < 1e-12);
        let sim = simulated_frf(&mut axis, 0.2, 2, 3);
        let g = plant
            .worst_case_two_mass()
            .unwrap()
            .tf_torque_to_motor_angle();
        assert_frf_close(name, &sim, |w| expected(g.freq_response(w), w, td, ts));
    }
}

/// The RK4 integration of the three-mass model, Coulomb friction off, against
/// the frequency response of its linearization (same position, the cart moves
/// only micrometres).
#[test]
fn three_mass_simulation_frf_matches_its_linearization() {
    let p = PhysicalParams {
        tau_c_motor_nm: 0.0,
        f_c_cart_n: 0.0,
        tau_c_end_pulley_nm: 0.0,
        ..egc70_params(11.2)
    };
    let xi = 0.55;
    let cfg = SimConfig {
        noise: Some(MeasurementNoise::NONE),
        initial_cart_position_m: Some(xi),
        ..SimConfig::default()
    };
    let plant = Plant::Physical(p.clone());
    let mut axis = SimAxis::new(&plant, cfg).unwrap();
    let (td, ts) = (axis.dead_time_s(), axis.info().ts_s);
    // the rigid-body pole i_t^2 (d_m + d_c) / J is at 1.3 rad/s: 8 s of
    // transient leave e^-10 of the start-up drift
    let sim = simulated_frf(&mut axis, 0.02, 8, 2);
    // the cart stays near the linearization point (the start transient of the
    // rigid-body mode shifts it by a few millimetres)
    assert!(
        (axis.cart_position_m() - xi).abs() < 0.02,
        "cart drifted to {}",
        axis.cart_position_m()
    );
    let lin = ThreeMass::new(&p).unwrap().linearize(xi);
    assert_frf_close("egc70 three-mass", &sim, |w| {
        expected(lin.frf_motor_angle(w), w, td, ts)
    });
}

/// The same for the nonlinear two-mass model (2.30) against the transfer
/// function (2.38) of `PhysicalParams::linearize` (Coulomb friction off).
#[test]
fn two_mass_simulation_frf_matches_2_38() {
    let p = PhysicalParams {
        tau_c_motor_nm: 0.0,
        f_c_cart_n: 0.0,
        tau_c_end_pulley_nm: 0.0,
        ..egc70_params(0.0)
    };
    let xi = 0.5;
    let cfg = SimConfig {
        noise: Some(MeasurementNoise::NONE),
        initial_cart_position_m: Some(xi),
        model: SimModel::TwoMass,
        ..SimConfig::default()
    };
    let plant = Plant::Physical(p.clone());
    let mut axis = SimAxis::new(&plant, cfg).unwrap();
    let (td, ts) = (axis.dead_time_s(), axis.info().ts_s);
    let sim = simulated_frf(&mut axis, 0.01, 8, 2);
    assert!(
        (axis.cart_position_m() - xi).abs() < 0.02,
        "cart drifted to {}",
        axis.cart_position_m()
    );
    let g = p.linearize(xi).unwrap().tf_torque_to_motor_angle();
    assert_frf_close("egc70 two-mass", &sim, |w| {
        expected(g.freq_response(w), w, td, ts)
    });
}

/// The simulator's fast segment updates equal (2.10)/(2.26)/(2.27).
#[test]
fn fast_segment_updates_equal_the_model() {
    let p = egc70_params(4.0);
    for k in 0..=20 {
        let xi = -0.05 + 0.7 * k as f64 / 20.0; // also outside the stroke (clamped)
        let seg = p.belt_segments(xi);
        let mut m3 = three_mass_mech(&p, 0.3);
        m3.q[2] = xi;
        set_three_mass_segments(&mut m3, &p, &FixedSegment::of(&p));
        let want3 = [
            (seg.c_1_n_per_m, m3.c[0]),
            (seg.c_2_n_per_m, m3.c[1]),
            (seg.c_3_n_per_m, m3.c[2]),
            (seg.d_1_n_s_per_m, m3.d[0]),
            (seg.d_2_n_s_per_m, m3.d[1]),
            (seg.d_3_n_s_per_m, m3.d[2]),
        ];
        let mut m2 = two_mass_mech(&p, 0.3);
        m2.q[1] = xi;
        set_two_mass_segments(&mut m2, &p);
        let want2 = [
            (seg.replacement_stiffness_n_per_m(), m2.c[0]),
            (seg.replacement_damping_n_s_per_m(), m2.d[0]),
        ];
        for (a, b) in want3.iter().chain(want2.iter()) {
            assert!((a - b).abs() <= 1e-12 * a.abs(), "xi {xi}: {a} vs {b}");
        }
    }
}

/// The generalized form the simulator integrates is (2.20): compare the
/// accelerations with `ThreeMass::derivative` at seeded random states
/// (Coulomb friction off: the simulator treats it in the stick-slip step).
#[test]
fn simulator_equations_are_2_20() {
    use rand::{Rng, SeedableRng};
    let p = PhysicalParams {
        tau_c_motor_nm: 0.0,
        f_c_cart_n: 0.0,
        tau_c_end_pulley_nm: 0.0,
        tilt_rad: 0.2,
        i_g: 1.5,
        ..egc70_params(3.0)
    };
    let model = ThreeMass::new(&p).unwrap();
    let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(11);
    for _ in 0..100 {
        let xi = rng.random_range(0.0..0.6);
        let mut m = three_mass_mech(&p, xi);
        let q = [
            m.q[0] + rng.random_range(-0.01..0.01),
            m.q[1] + rng.random_range(-0.01..0.01),
            xi,
        ];
        let v = [
            rng.random_range(-50.0..50.0),
            rng.random_range(-50.0..50.0),
            rng.random_range(-1.0..1.0),
        ];
        m.q = q;
        set_three_mass_segments(&mut m, &p, &FixedSegment::of(&p));
        let u = rng.random_range(-3.0..3.0);
        let a = m.accel(&q, &v, u);
        let x = ThreeMassState {
            phi_m_rad: q[0],
            omega_m_rad_s: v[0],
            phi_2_rad: q[1],
            omega_2_rad_s: v[1],
            xi_m: q[2],
            xi_dot_m_s: v[2],
        };
        let f = model.derivative(&x, u);
        for (got, want) in [
            (a[0], f.omega_m_rad_s),
            (a[1], f.omega_2_rad_s),
            (a[2], f.xi_dot_m_s),
        ] {
            assert!(
                (got - want).abs() <= 1e-9 * want.abs().max(1.0),
                "{got} vs {want}"
            );
        }
    }
}

/// Rigid-body inertia seen by the motor in the three-mass model, kg m^2.
fn rigid_inertia(p: &PhysicalParams) -> f64 {
    p.theta_e() + p.theta_end_pulley_kg_m2 / (p.i_g * p.i_g) + p.i_t() * p.i_t() * p.m_c()
}

/// Run `seconds` with a constant torque command.
fn run_constant(axis: &mut SimAxis, tau: f64, seconds: f64) -> Vec<Measurement> {
    let n = (seconds / axis.info().ts_s).round() as usize;
    (0..n).map(|_| axis.step(tau)).collect()
}

/// Ramp the command linearly from 0 to `tau` in `ramp_s`, then hold it for `hold_s`.
fn run_ramp_then_constant(
    axis: &mut SimAxis,
    tau: f64,
    ramp_s: f64,
    hold_s: f64,
) -> Vec<Measurement> {
    let t_s = axis.info().ts_s;
    let n_ramp = (ramp_s / t_s).round() as usize;
    let mut out: Vec<Measurement> = (0..n_ramp)
        .map(|k| axis.step(tau * (k + 1) as f64 / n_ramp as f64))
        .collect();
    out.extend(run_constant(axis, tau, hold_s));
    out
}

/// Stick: a constant torque below the total Coulomb friction (3.36) moves the
/// motor only by the belt stretch and the cart not at all; both come to rest
/// exactly (no chattering, no creep). The torque is ramped up in 0.1 s: a step
/// would excite the belt mode, whose overshoot can break the cart loose
/// (physically right, but then the torque is not "constant below breakaway").
#[test]
fn stick_below_total_coulomb_friction() {
    for model in [SimModel::ThreeMass, SimModel::TwoMass] {
        let plant = builtin("egc70", None).unwrap();
        let tc = plant.friction_totals().coulomb_nm;
        let cfg = SimConfig {
            model,
            ..SimConfig::default()
        };
        for tau in [0.8 * tc, -0.95 * tc] {
            let mut axis = SimAxis::new(&plant, cfg.clone()).unwrap();
            let xi0 = axis.cart_position_m();
            let ms = run_ramp_then_constant(&mut axis, tau, 0.1, 1.0);
            assert_eq!(
                axis.cart_position_m(),
                xi0,
                "{model:?} {tau}: the cart must not move at all"
            );
            assert_eq!(axis.cart_velocity_m_s(), 0.0, "{model:?}");
            assert_eq!(
                axis.motor_velocity_rad_s(),
                0.0,
                "{model:?}: the motor sticks"
            );
            // the last half second: not a single count of motion
            let last = &ms[ms.len() / 2..];
            assert!(
                last.iter().all(|m| m.motor_counts == last[0].motor_counts),
                "{model:?}: creep/chatter"
            );
            // motor motion bounded by the belt stretch at the applied torque:
            // (tau / i_t) / c_min in belt travel, with c_min the worst-case stiffness
            let two = plant.worst_case_two_mass().unwrap();
            let stretch_counts =
                tau.abs() / two.i_t / two.c / axis.info().motor_rad_per_count / two.i_t;
            assert!(
                (last[0].motor_counts.abs() as f64) <= stretch_counts + 1.0,
                "{model:?}: {} counts > belt stretch {stretch_counts}",
                last[0].motor_counts
            );
        }
    }
}

/// Relative tolerance of the slip acceleration against the rigid-body
/// prediction (the belt mode adds a decaying oscillation; averaged out).
const SLIP_ACCEL_TOL: f64 = 0.02;

/// Slip: above the total Coulomb friction the axis accelerates as
/// `(tau - tau_c~) / J` (viscous friction off, so the prediction is exact for
/// the rigid body; `J` includes the end pulley).
#[test]
fn slip_above_total_coulomb_accelerates_as_rigid_body() {
    let p = PhysicalParams {
        d_m_n_s_per_m: 0.0,
        d_c_n_s_per_m: 0.0,
        d_end_pulley_n_s_per_m: 0.0,
        ..egc70_params(11.2)
    };
    let plant = Plant::Physical(p.clone());
    let tc = plant.friction_totals().coulomb_nm;
    for tau in [1.5 * tc, 3.0 * tc, -2.0 * tc] {
        let cfg = SimConfig {
            initial_cart_position_m: Some(0.3),
            ..SimConfig::default()
        };
        let mut axis = SimAxis::new(&plant, cfg).unwrap();
        // accelerations measured on the motor velocity between 0.1 s and 0.2 s after the dead time
        run_constant(&mut axis, tau, 0.1);
        let mut w1 = 0.0;
        for _ in 0..100 {
            axis.step(tau);
            w1 += axis.motor_velocity_rad_s() / 100.0;
        }
        run_constant(&mut axis, tau, 0.09);
        let mut w2 = 0.0;
        for _ in 0..100 {
            axis.step(tau);
            w2 += axis.motor_velocity_rad_s() / 100.0;
        }
        let a_sim = (w2 - w1) / 0.1;
        let a_rigid = (tau - tc * tau.signum()) / rigid_inertia(&p);
        assert!(
            (a_sim / a_rigid - 1.0).abs() < SLIP_ACCEL_TOL,
            "tau {tau}: {a_sim} vs {a_rigid} rad/s^2"
        );
    }
}

/// Tilted axis: a constant torque within `i_t m_c g sin(alpha) +- tau_c~`
/// holds the axis (after the start transient it comes to rest for good),
/// outside the band it keeps moving; without Coulomb friction the holding
/// torque is exactly `i_t m_c g sin(alpha)`.
#[test]
fn tilted_axis_holding_torque() {
    let alpha = 20f64.to_radians();
    let base = egc70_params(11.2);
    let hold = base.i_t() * base.m_c() * GRAVITY * alpha.sin();
    let tc = base.friction_totals().coulomb_nm;
    let cfg = SimConfig {
        tilt_rad: Some(alpha),
        initial_cart_position_m: Some(0.3),
        noise: Some(MeasurementNoise::NONE),
        ..SimConfig::default()
    };
    let plant = Plant::Physical(base.clone());
    for (tau, holds) in [
        (hold, true),
        (hold + 0.9 * tc, true),
        (hold - 0.9 * tc, true),
        (hold + 1.2 * tc, false),
        (hold - 1.2 * tc, false),
    ] {
        let mut axis = SimAxis::new(&plant, cfg.clone()).unwrap();
        run_constant(&mut axis, tau, 0.3);
        let xi_a = axis.cart_position_m();
        run_constant(&mut axis, tau, 0.2);
        let xi_b = axis.cart_position_m();
        if holds {
            assert_eq!(axis.cart_velocity_m_s(), 0.0, "tau {tau} should hold");
            assert_eq!(xi_a, xi_b, "tau {tau}: still moving");
        } else {
            assert!(
                (xi_b - xi_a).abs() > 1e-3,
                "tau {tau}: should move, moved {} m",
                xi_b - xi_a
            );
            assert_eq!(xi_b > xi_a, tau > hold, "tau {tau}: wrong direction");
        }
    }
    // without Coulomb friction: the exact holding torque keeps the cart at rest
    // after the belt has stretched; 1 % more or less makes it drift.
    let frictionless = Plant::Physical(PhysicalParams {
        tau_c_motor_nm: 0.0,
        f_c_cart_n: 0.0,
        tau_c_end_pulley_nm: 0.0,
        ..base.clone()
    });
    // 5 s: the start-up impulse (gravity acts during the 1 ms dead time) decays
    // with the rigid-body pole d_v~ / J = 1.3 rad/s to e^-6.4; 1 % off the
    // holding torque gives a terminal velocity of 0.005 N m / d_v~ = 2 rad/s = 25 mm/s.
    let velocity_after_5_s = |tau: f64| {
        let mut axis = SimAxis::new(&frictionless, cfg.clone()).unwrap();
        run_constant(&mut axis, tau, 5.0);
        axis.cart_velocity_m_s()
    };
    let v = velocity_after_5_s(hold);
    assert!(v.abs() < 2e-5, "{v}");
    assert!(velocity_after_5_s(1.01 * hold) > 1e-2);
    assert!(velocity_after_5_s(0.99 * hold) < -1e-2);
}

/// The encoder count is `floor((phi_m - phi_m(0)) / q)` at every sample, and
/// the cart encoder quantizes to its resolution.
#[test]
fn counts_quantize_the_motor_angle() {
    let plant = builtin("egc70", None).unwrap();
    let mut axis = SimAxis::new(&plant, SimConfig::default()).unwrap();
    let phi0 = axis.motor_angle_rad();
    let q = axis.info().motor_rad_per_count;
    let res = axis.config().cart_encoder_resolution_m;
    // belt travel per count: the documented 2.5 um
    assert!((q * plant.worst_case_two_mass().unwrap().i_t - 2.5e-6).abs() < 1e-15);
    let mut seen = std::collections::BTreeSet::new();
    for k in 0..5000 {
        let m = axis.step(0.5 * (k as f64 * 2e-3).sin());
        let expect = ((axis.motor_angle_rad() - phi0) / q).floor() as i64;
        assert_eq!(m.motor_counts, expect);
        let cart = m.cart_position_m.unwrap();
        assert!(
            cart <= axis.cart_position_m() && axis.cart_position_m() - cart < res * (1.0 + 1e-9)
        );
        seen.insert(m.motor_counts);
    }
    assert!(
        seen.len() > 100,
        "the axis should have moved over many counts"
    );
}

/// Relative change of the lowest resonance over the stroke that counts as a
/// decrease (guards against flat numerical noise).
const MONOTONE_EPS: f64 = 1e-9;

/// Position dependency (thesis 2.1.4, 2.2): f_r and f_z of the linearized
/// two-mass model, and the lowest mode of the three-mass model, fall as the
/// cart moves away from the motor (l_1 grows); the minimum is at the
/// worst-case position, the end of the stroke.
#[test]
fn lowest_resonances_with_cart_farthest_from_motor() {
    for payload in [0.0, 11.2] {
        let plant = builtin("egc70", Some(payload)).unwrap();
        let Plant::Physical(p) = &plant else {
            unreachable!()
        };
        let three = ThreeMass::new(p).unwrap();
        let mut prev: Option<(f64, f64, f64, f64)> = None;
        for k in 0..=12 {
            let xi = p.stroke_m * k as f64 / 12.0;
            let two = plant.linearize(xi).unwrap();
            // lowest oscillatory eigenvalue of the three-mass linearization
            let ev = three.linearize(xi).a.complex_eigenvalues();
            let w3 = ev
                .iter()
                .filter(|e| e.im > 1.0)
                .map(|e| e.norm())
                .fold(f64::INFINITY, f64::min);
            let l1 = p.segment_lengths(xi).l_1_m;
            if let Some((fr, fz, w3p, l1p)) = prev {
                assert!(l1 > l1p);
                assert!(two.f_r_hz() < fr * (1.0 - MONOTONE_EPS), "xi {xi}");
                assert!(two.f_z_hz() < fz * (1.0 - MONOTONE_EPS), "xi {xi}");
                assert!(w3 < w3p * (1.0 - MONOTONE_EPS), "xi {xi}: {w3} >= {w3p}");
            }
            prev = Some((two.f_r_hz(), two.f_z_hz(), w3, l1));
        }
        assert_eq!(plant.worst_case_position_m(), p.stroke_m);
    }
}

/// Dead time and saturation: a step command reaches the measured torque
/// exactly `n` samples later, clipped at the torque limit.
#[test]
fn dead_time_and_saturation() {
    let plant = builtin("egc70", None).unwrap();
    let cfg = SimConfig {
        noise: Some(MeasurementNoise::NONE),
        ..SimConfig::default()
    };
    let mut axis = SimAxis::new(&plant, cfg).unwrap();
    let n = (axis.dead_time_s() / axis.info().ts_s).round() as usize;
    assert_eq!(n, 10);
    let lim = axis.info().torque_max_nm;
    for k in 0..30 {
        let m = axis.step(10.0);
        let expect = if k < n { 0.0 } else { lim };
        assert_eq!(m.torque_actual_nm, expect, "sample {k}");
    }
    assert_eq!(axis.step(f64::NAN).torque_actual_nm, lim);
    assert_eq!(axis.rejected_commands(), 1);
}

/// Equal seeds give identical runs; the noise has the configured level.
#[test]
fn seeded_runs_are_reproducible() {
    let plant = builtin("egc70", None).unwrap();
    let run = |seed: u64| {
        let cfg = SimConfig {
            seed,
            noise: Some(MeasurementNoise {
                torque_nm: 0.01,
                encoder_counts: 0.0,
            }),
            ..SimConfig::default()
        };
        let mut axis = SimAxis::new(&plant, cfg).unwrap();
        (0..3000)
            .map(|k| axis.step(0.3 * (k as f64 * 0.01).sin()))
            .collect::<Vec<_>>()
    };
    let (a, b, c) = (run(1), run(1), run(2));
    assert_eq!(a, b);
    assert_ne!(a, c);
    // noise standard deviation (torque is noise-free at zero command in the
    // first 10 samples only, so estimate from the difference of two seeds)
    let var: f64 = a
        .iter()
        .zip(&c)
        .map(|(x, y)| (x.torque_actual_nm - y.torque_actual_nm).powi(2))
        .sum::<f64>()
        / (2.0 * a.len() as f64);
    assert!((var.sqrt() / 0.01 - 1.0).abs() < 0.1, "{}", var.sqrt());
}

#[test]
fn invalid_configurations_are_errors() {
    let plant = builtin("egc70", None).unwrap();
    let bad = [
        SimConfig {
            initial_cart_position_m: Some(0.7),
            ..SimConfig::default()
        },
        SimConfig {
            initial_cart_position_m: Some(f64::NAN),
            ..SimConfig::default()
        },
        SimConfig {
            noise: Some(MeasurementNoise {
                torque_nm: -1.0,
                encoder_counts: 0.0,
            }),
            ..SimConfig::default()
        },
        SimConfig {
            tilt_rad: Some(3.0),
            ..SimConfig::default()
        },
        SimConfig {
            max_substep_s: Some(0.0),
            ..SimConfig::default()
        },
    ];
    for cfg in bad {
        assert!(SimAxis::new(&plant, cfg.clone()).is_err(), "{cfg:?}");
    }
    let lin = builtin("sim-a", None).unwrap();
    assert!(SimAxis::new(
        &lin,
        SimConfig {
            tilt_rad: Some(0.1),
            ..SimConfig::default()
        }
    )
    .is_err());
    let mut axis = SimAxis::new(&plant, SimConfig::default()).unwrap();
    assert!(axis.set_cart_position(-0.1).is_err());
    assert!(axis.set_cart_position(0.6).is_ok());
    assert!(!axis.cart_outside_stroke());
    // pushing beyond the end of the stroke is reported, not a panic
    run_constant(&mut axis, 1.0, 0.05);
    assert!(axis.cart_outside_stroke());
    assert!(axis.cart_position_m().is_finite());
    axis.set_cart_position(0.6).unwrap();
    assert_eq!(
        axis.linearized_truth(),
        plant.worst_case_two_mass().unwrap()
    );
}

/// Table A.10, G_A (11.2 kg payload): total viscous friction at the motor, N m s/rad.
pub(super) const TABLE_A10_VISCOUS_NM_S_PER_RAD: f64 = 2.53e-3;
/// Table A.10, G_A: total Coulomb friction at the motor, N m.
pub(super) const TABLE_A10_COULOMB_NM: f64 = 0.125;

/// Mean torque minus (3.36) at the run's mean velocity, N m. The sim's
/// friction is exact; what remains is the PI loop's settling and the decaying
/// belt mode inside the averaging window (measured below 1e-4 N m). 5e-4 N m
/// is 0.4 % of the total Coulomb friction, ten times finer than the 5 % an
/// identification is held to, and far below the 0.05 N m deficit a chattering
/// probe shows.
pub(super) const CONSTANT_VELOCITY_TORQUE_TOL_NM: f64 = 5e-4;

/// Hold the true motor velocity at `w_rad_s` with a PI loop (rigid-body
/// bandwidth 2 Hz) over `travel_m` of cart travel, starting 20 mm inside the
/// stroke end behind the motion. Returns `(mean velocity, mean applied
/// torque, smallest |velocity|)` over the last two thirds of the run.
///
/// The loop is deliberately slow: above the antiresonance the motor alone
/// (`Theta_e`, 1/27 of the rigid inertia) is in the loop, so a rigid-body
/// bandwidth of 20 Hz puts the local crossover near 550 Hz, where the 1 ms
/// dead time makes the loop limit-cycle with +-50 rad/s velocity swings;
/// the motor then reverses every cycle and its Coulomb friction averages out
/// (measured: 0.086 N m instead of 0.138 N m at 5 rad/s). The smallest
/// `|velocity|` returned lets the caller check the run never reversed.
pub(super) fn constant_velocity_run(
    plant: &Plant,
    model: SimModel,
    w_rad_s: f64,
    travel_m: f64,
) -> (f64, f64, f64) {
    let Plant::Physical(p) = plant else {
        panic!("a physical plant is needed")
    };
    let start = if w_rad_s > 0.0 {
        0.02
    } else {
        p.stroke_m - 0.02
    };
    let cfg = SimConfig {
        model,
        noise: Some(MeasurementNoise::NONE),
        initial_cart_position_m: Some(start),
        ..SimConfig::default()
    };
    let mut axis = SimAxis::new(plant, cfg).unwrap();
    let j = rigid_inertia(p);
    let ts = axis.info().ts_s;
    let w_c = 2.0 * PI * 2.0;
    let (k_p, k_i) = (j * w_c, j * w_c * w_c / 4.0);
    let n = (travel_m / (w_rad_s.abs() * p.i_t()) / ts) as usize;
    let (mut integral, mut sum_tau, mut sum_w, mut count) = (0.0, 0.0, 0.0, 0usize);
    let mut min_speed = f64::INFINITY;
    for k in 0..n {
        let e = w_rad_s - axis.motor_velocity_rad_s();
        integral += k_i * e * ts;
        axis.step(k_p * e + integral);
        assert!(!axis.cart_outside_stroke(), "the run left the stroke");
        if k > n / 3 {
            sum_tau += axis.applied_torque_nm();
            sum_w += axis.motor_velocity_rad_s();
            min_speed = min_speed.min(axis.motor_velocity_rad_s().abs());
            count += 1;
        }
    }
    (sum_w / count as f64, sum_tau / count as f64, min_speed)
}

/// The friction the simulated egc70 shows at constant velocity is (3.36)
/// with `friction_totals()`, the same in both directions, for both models,
/// and the totals are Table A.10's; a least-squares fit over the runs (the
/// constant-velocity method of 3.6) returns Table A.10 within 1 %.
#[test]
fn friction_is_symmetric_and_matches_the_totals_at_constant_velocity() {
    let plant = builtin("egc70", None).unwrap();
    let totals = plant.friction_totals();
    // the totals themselves reproduce Table A.10 (rounded to its 3 digits)
    assert!((totals.viscous_nm_s_per_rad - TABLE_A10_VISCOUS_NM_S_PER_RAD).abs() < 1e-9);
    assert!((totals.coulomb_nm - TABLE_A10_COULOMB_NM).abs() < 1e-9);
    const FIT_TOL: f64 = 0.01;
    for model in [SimModel::ThreeMass, SimModel::TwoMass] {
        let mut runs = Vec::new();
        for speed in [2.0, 5.0, 10.0] {
            let mut means = [0.0; 2];
            for (i, w) in [speed, -speed].into_iter().enumerate() {
                let (w_mean, tau_mean, min_speed) = constant_velocity_run(&plant, model, w, 0.5);
                assert!(
                    min_speed > 0.5 * speed,
                    "{model:?} {w}: the velocity dipped to {min_speed}"
                );
                let expected =
                    totals.viscous_nm_s_per_rad * w_mean + totals.coulomb_nm * w.signum();
                assert!(
                    (tau_mean - expected).abs() < CONSTANT_VELOCITY_TORQUE_TOL_NM,
                    "{model:?} {w} rad/s: mean torque {tau_mean} N m, (3.36) {expected} N m"
                );
                means[i] = tau_mean;
                runs.push(crate::ident::friction::ConstantVelocityRun {
                    velocity_rad_s: w_mean,
                    mean_torque_nm: tau_mean,
                });
            }
            assert!(
                (means[0] + means[1]).abs() < 2.0 * CONSTANT_VELOCITY_TORQUE_TOL_NM,
                "{model:?} {speed} rad/s: asymmetric {means:?}"
            );
        }
        let fit = crate::ident::friction::fit_constant_velocity(&runs).unwrap();
        let rel = |a: f64, b: f64| (a / b - 1.0).abs();
        assert!(
            rel(fit.viscous_nm_s_per_rad, TABLE_A10_VISCOUS_NM_S_PER_RAD) < FIT_TOL,
            "{model:?} {fit:?}"
        );
        assert!(
            rel(fit.coulomb_nm, TABLE_A10_COULOMB_NM) < FIT_TOL,
            "{model:?} {fit:?}"
        );
    }
}

/// The faster integrator step (products of the geometry formed once, the
/// symmetric half of `K` and `D`, zero products skipped, the segment between
/// the pulleys once per sample, dot products from the first term) gives the
/// states of the step as it was written before (`Mech::step_reference`,
/// which keeps that code) on a seeded run: egc70's three-mass and two-mass
/// models with stick-slip friction and gravity (30 deg tilt), 5 simulated
/// seconds at 10 kHz of a PRBS-like torque (the cart slides throughout; the stick branch is not exercised), and
/// the belt segments updated per sub-step as `SimAxis::advance` does.
/// Every position and velocity is equal (`==`, which leaves only the sign of
/// a zero free) on every sample.
#[test]
fn fast_step_gives_the_reference_states_on_a_seeded_run() {
    let mut p = egc70_params(11.2);
    p.tilt_rad = 30f64.to_radians();
    let p = p.aged();
    let (h, n_sub) = (p.ts_s, 2);
    let h = h / n_sub as f64;
    let mut state = 0x05EE_D31B_u64;
    let mut torque = || {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        if (state >> 63) == 1 {
            0.6
        } else {
            -0.45
        }
    };
    let torques: Vec<f64> = (0..50_000).map(|_| torque()).collect();
    let (mut fast, mut slow) = (three_mass_mech(&p, 0.3), three_mass_mech(&p, 0.3));
    let fixed = FixedSegment::of(&p);
    let (mut stuck, mut moved) = (0usize, 0.0_f64);
    for (k, &u) in torques.iter().enumerate() {
        for _ in 0..n_sub {
            set_three_mass_segments(&mut fast, &p, &fixed);
            fast.step(u, h);
            // the segments as computed before (all three per sub-step)
            let xi = slow.q[2].clamp(0.0, p.stroke_m);
            let half = 0.5 * p.cart_belt_span_m;
            let le = p.end_compliance_length_m;
            let inv1 = 1.0 / (p.l_xi_m + xi - half + le);
            let inv2 = 1.0 / (p.pulley_distance_m - p.l_xi_m - xi - half + le);
            let inv3 = 1.0 / (p.pulley_distance_m + le);
            slow.c = [p.c_b_n * inv1, p.c_b_n * inv2, p.c_b_n * inv3];
            slow.d = [p.d_b_n_s * inv1, p.d_b_n_s * inv2, p.d_b_n_s * inv3];
            slow.step_reference(u, h);
        }
        assert!(
            fast.q == slow.q && fast.v == slow.v,
            "sample {k}: {:?} {:?} against {:?} {:?}",
            fast.q,
            fast.v,
            slow.q,
            slow.v
        );
        stuck += usize::from(fast.v[2] == 0.0);
        moved = moved.max((fast.q[2] - 0.3).abs());
    }
    // Measured: the cart never sticks in this run (0 samples), so the stick
    // branch of the Coulomb step is not exercised here; printed, not asserted.
    println!("cart stuck on {stuck} samples, moved up to {moved} m");

    let (mut fast, mut slow) = (two_mass_mech(&p, 0.3), two_mass_mech(&p, 0.3));
    for (k, &u) in torques.iter().enumerate() {
        set_two_mass_segments(&mut fast, &p);
        fast.step(u, p.ts_s);
        set_two_mass_segments(&mut slow, &p);
        slow.step_reference(u, p.ts_s);
        assert!(fast.q == slow.q && fast.v == slow.v, "two-mass, sample {k}");
    }
}
