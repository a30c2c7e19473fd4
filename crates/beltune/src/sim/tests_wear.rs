//! The ageing of [`crate::model::wear`] in the simulator, against closed
//! forms: the statics of a hanging cart whose lower span went slack, the
//! friction of (3.36) grown by its factor, a worn guide section.

use super::tests::{
    constant_velocity_run, CONSTANT_VELOCITY_TORQUE_TOL_NM, TABLE_A10_COULOMB_NM,
    TABLE_A10_VISCOUS_NM_S_PER_RAD,
};
use super::*;
use crate::model::params::GRAVITY_M_S2;
use crate::model::rigs::{builtin, egc70_params};
use crate::model::Wear;

/// A vertical egc70 whose motor is locked (a Coulomb friction far beyond
/// what the belt can pull) and whose cart hangs in the belt; where it comes
/// to rest, m, and the plant.
fn hanging_cart(pretension_n: Option<f64>, xi0_m: f64) -> (f64, PhysicalParams) {
    let p = PhysicalParams {
        tilt_rad: std::f64::consts::FRAC_PI_2,
        tau_c_motor_nm: 1e3,
        f_c_cart_n: 0.0,
        tau_c_end_pulley_nm: 0.0,
        // a damped cart comes to rest quickly; statics do not see damping
        d_c_n_s_per_m: 2000.0,
        wear: Wear {
            belt_pretension_n: pretension_n,
            ..Wear::default()
        },
        ..egc70_params(11.2)
    };
    let mut axis = SimAxis::new(
        &Plant::Physical(p.clone()),
        SimConfig {
            noise: Some(MeasurementNoise::NONE),
            initial_cart_position_m: Some(xi0_m),
            ..SimConfig::default()
        },
    )
    .unwrap();
    // the cart mode (23 Hz) rings down with a damping ratio of 0.5
    for _ in 0..40_000 {
        axis.step(0.0);
    }
    assert!(axis.cart_velocity_m_s().abs() < 1e-5);
    (axis.cart_position_m(), p)
}

/// Statics of the hanging cart (motor locked, end pulley free): with every
/// span taut the cart sinks by `m g / (c_1 + c_2 c_3 / (c_2 + c_3))`
/// ((2.26), the pretension cancelling); where the pretension `P` is below
/// the share `m g c_1 / (c_1 + c_23)` the lower span `l_1` goes slack and the
/// cart hangs on `l_2` and `l_3` in series alone: it sinks by
/// `(m g - P) / c_23` (force balance of the cart with `T_1 = 0`, the
/// free end pulley carrying `T_2 = T_3`). Segment stiffnesses at the rest
/// position (the simulator evaluates (2.10) where the cart is).
#[test]
fn a_slack_span_leaves_the_cart_on_the_other_spans() {
    let xi0 = 0.3;
    // the motor is held by the velocity-level stick step of a 1000 N m
    // Coulomb friction, which lets the end pulley creep a little within each
    // step: the rest position comes out 0.4 % off the closed form (measured);
    // the slack span moves it by a factor of three
    const STATIC_TOL: f64 = 0.01;
    for pretension in [None, Some(500.0), Some(30.0)] {
        let (xi, p) = hanging_cart(pretension, xi0);
        let seg = p.belt_segments(xi);
        let (c1, c2, c3) = (seg.c_1_n_per_m, seg.c_2_n_per_m, seg.c_3_n_per_m);
        let c23 = c2 * c3 / (c2 + c3);
        let weight = p.m_c() * GRAVITY_M_S2;
        let slack = pretension.is_some_and(|pt| pt < weight * c1 / (c1 + c23));
        let expected = match (slack, pretension) {
            (true, Some(pt)) => -(weight - pt) / c23,
            _ => -weight / (c1 + c23),
        };
        let got = xi - xi0;
        assert!(
            (got / expected - 1.0).abs() < STATIC_TOL,
            "{pretension:?} (slack {slack}): sank {got} m, closed form {expected} m"
        );
        assert_eq!(slack, pretension == Some(30.0));
    }
}

/// Friction growth multiplies (3.36): the constant-velocity torque of the
/// simulated egc70 with `friction_growth = 0.5` is 1.5 times Table A.10's
/// totals in both directions; a worn guide adds `i_t f` where the cart runs
/// on the worn section, nothing where it does not.
#[test]
fn grown_friction_and_a_worn_guide_show_at_constant_velocity() {
    let base = builtin("egc70", None).unwrap();
    let Plant::Physical(p) = &base else {
        unreachable!()
    };
    let i_t = p.i_t();
    let aged = |wear: Wear| Plant::Physical(PhysicalParams { wear, ..p.clone() });
    let grown = aged(Wear {
        friction_growth: 0.5,
        ..Wear::default()
    });
    let t = grown.friction_totals();
    assert!((t.viscous_nm_s_per_rad - 1.5 * TABLE_A10_VISCOUS_NM_S_PER_RAD).abs() < 1e-9);
    assert!((t.coulomb_nm - 1.5 * TABLE_A10_COULOMB_NM).abs() < 1e-9);
    // the runs start at 20 mm and average from a third of their 0.5 m on
    let guide = |section: Option<(f64, f64)>| {
        aged(Wear {
            guide_wear_n: 4.0,
            guide_wear_section_m: section,
            ..Wear::default()
        })
    };
    for (plant, extra_coulomb_nm, label) in [
        (grown, 0.5 * TABLE_A10_COULOMB_NM, "friction growth"),
        (guide(None), i_t * 4.0, "worn guide"),
        (guide(Some((0.15, 0.6))), i_t * 4.0, "worn section run over"),
        (guide(Some((0.0, 0.1))), 0.0, "worn section left behind"),
    ] {
        let growth = if label == "friction growth" { 1.5 } else { 1.0 };
        for w in [5.0, -5.0] {
            let (w_mean, tau, _) = constant_velocity_run(&plant, SimModel::ThreeMass, w, 0.5);
            let expected = growth * TABLE_A10_VISCOUS_NM_S_PER_RAD * w_mean
                + (TABLE_A10_COULOMB_NM + extra_coulomb_nm) * w.signum();
            // the runs go up from 20 mm and down from the stroke's end: the
            // downward run crosses the sections' edges inside its average
            if label.starts_with("worn section") && w < 0.0 {
                continue;
            }
            assert!(
                (tau - expected).abs() < CONSTANT_VELOCITY_TORQUE_TOL_NM,
                "{label} at {w} rad/s: {tau} N m, expected {expected} N m"
            );
        }
    }
}

/// A pretension far above the belt's forces never slackens a span: the run
/// is exactly that of the new belt; the two-mass model refuses a slack span.
#[test]
fn a_taut_belt_is_the_new_belt_and_the_two_mass_model_refuses_slack() {
    let run = |wear: Wear| {
        let p = PhysicalParams {
            wear,
            ..egc70_params(11.2)
        };
        let mut axis = SimAxis::new(&Plant::Physical(p), SimConfig::default()).unwrap();
        (0..5000)
            .map(|k| {
                axis.step(if (k / 400) % 2 == 0 { 0.8 } else { -0.8 })
                    .motor_counts
            })
            .collect::<Vec<_>>()
    };
    assert_eq!(
        run(Wear::default()),
        run(Wear {
            belt_pretension_n: Some(1e5),
            ..Wear::default()
        })
    );
    let p = PhysicalParams {
        wear: Wear {
            belt_pretension_n: Some(30.0),
            ..Wear::default()
        },
        ..egc70_params(11.2)
    };
    let err = SimAxis::new(
        &Plant::Physical(p),
        SimConfig {
            model: SimModel::TwoMass,
            ..SimConfig::default()
        },
    )
    .unwrap_err();
    assert!(err.to_string().contains("wear.belt_pretension_n"), "{err}");
}
