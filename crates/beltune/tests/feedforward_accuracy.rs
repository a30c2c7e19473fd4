//! The max cart error of the nonlinear-feedforward validation move
//! (thesis chapter 5: below 1 mm): plants of the seeded study (seed 12)
//! whose feedforward inertia came from an FRF fit that was far too heavy.

use beltune::commission::NoProgress;
use beltune::commission::{commission, Commissioning, CommissioningConfig, DataSheet};
use beltune::model::rigs::Plant;
use beltune::sim::SimAxis;
use beltune::study::{generate, GeneratedPlant, Ranges};

/// Plant `index` of the seeded study (seed 12), commissioned with the
/// defaults from 50 mm as `beltune montecarlo` does.
fn commission_study_plant(index: u64) -> (GeneratedPlant, Commissioning) {
    let g = generate(12, index, &Ranges::default()).unwrap();
    let plant = Plant::Physical(g.params.clone());
    let ds = DataSheet::for_plant(&plant, 0.05, None);
    let mut axis = SimAxis::new(&plant, g.sim_config(0.05)).unwrap();
    let run = commission(
        &mut axis,
        &ds,
        &CommissioningConfig::default(),
        &mut NoProgress,
    )
    .unwrap();
    (g, run)
}

/// The thesis' limit of the max cart error (chapter 5), m.
const MAX_CART_ERROR_M: f64 = 1e-3;
/// Accepted relative error of the feedforward inertia: the target
/// for the identified `f_z` (2 %); the FRF fit of these plants was 24-32 %
/// off.
const INERTIA_TOLERANCE: f64 = 0.02;

/// Plants #270 (22.2 kg, belt x0.70) and #751 (24.3 kg, belt x0.78): the
/// FRF fit's m_c came out 24 % and 33 % heavy (one-sigma 8 % and 4 %), the
/// inertia feedforward pushed the cart 2.8 and 2.0 mm ahead of the
/// trajectory. With the true inertia in the feedforward (and everything else
/// as identified) the error was 0.40 and 0.59 mm. The feedforward's inertia
/// came from the momentum balance of the friction runs, and now comes from
/// the friction-aware fit of stage 5 (the momentum balance where that fit is
/// not used): the FRF fit stays wrong on these plants, the feedforward does not.
#[test]
fn feedforward_inertia_is_the_rigid_body_s_not_the_frf_fit_s() {
    for index in [270, 751] {
        let (g, run) = commission_study_plant(index);
        let p = &g.params;
        let truth =
            p.theta_e() + p.theta_end_pulley_kg_m2 / (p.i_g * p.i_g) + p.i_t() * p.i_t() * p.m_c();
        let fitted = run.frf_fit.params.rigid_inertia();
        let used = run.design.feedforward.inertia_kg_m2;
        assert!(
            (fitted / truth - 1.0).abs() > 0.1,
            "#{index}: the example needs a wrong fit: {fitted:e} vs {truth:e}"
        );
        assert!(
            (used / truth - 1.0).abs() < INERTIA_TOLERANCE,
            "#{index}: feedforward inertia {used:e} vs true {truth:e} (fit {fitted:e})"
        );
        let e = run.validation.nonlinear.max_tracking_error_m;
        assert!(
            e < MAX_CART_ERROR_M,
            "#{index}: max cart error {:.3} mm",
            e * 1e3
        );
    }
}

/// Accepted error of the holding torque, N m: a tenth of what the slow
/// position loop turned into a millimetre of lag (0.015 N m).
const HOLDING_TOLERANCE_NM: f64 = 1.5e-3;
/// The thesis' limit of the static error (chapter 5), m.
const STATIC_ERROR_M: f64 = 100e-6;

/// Plants #353 (10 kg on a -29 deg slope) and #129 (6.9 kg, -15 deg), soft
/// belts (x0.50, x0.57) with sticky carts (Coulomb x2.75, x2.23). Stage 3's
/// short runs put the holding torque 0.044 N m beyond gravity on both; the
/// cascade's slow position loop integrated that into 1.26 and 1.10 mm of lag
/// during the acceleration. The friction runs' fit with a torque offset now
/// gives it (stage 7). #129's cart then stopped 20 um from its target, and a
/// breakaway push at 20 um of motor error (the motor rests up to the cart's
/// Coulomb stretch beyond its setpoint when the lead retreats) made the motor
/// hunt and dragged the cart 128 um off; the threshold now lies beyond that
/// stretch. The move starts where the cart rests (it jumped by the static
/// stretch at its first sample).
#[test]
fn the_holding_torque_comes_from_the_friction_runs() {
    for index in [353, 129] {
        let (g, run) = commission_study_plant(index);
        let p = &g.params;
        let gravity_nm = -p.gravity_force_n() * p.i_t();
        let held = run.friction.holding_torque_nm;
        assert!(
            (held - gravity_nm).abs() < HOLDING_TOLERANCE_NM,
            "#{index}: holding torque {held:.4} N m vs gravity {gravity_nm:.4} N m"
        );
        assert!(
            run.friction.cart_coulomb_n > 0.0,
            "#{index}: the cart's friction goes into the stretch lead"
        );
        let v = &run.validation.nonlinear;
        assert!(
            v.max_tracking_error_m < 0.5 * MAX_CART_ERROR_M,
            "#{index}: max cart error {:.3} mm",
            v.max_tracking_error_m * 1e3
        );
        assert!(
            v.static_error_m < STATIC_ERROR_M,
            "#{index}: static error {:.1} um",
            v.static_error_m * 1e6
        );
    }
}
