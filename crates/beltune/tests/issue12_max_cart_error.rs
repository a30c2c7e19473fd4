//! Issue 12, the max cart error of the nonlinear-feedforward validation move
//! (thesis chapter 5: below 1 mm): plants of the seeded study (seed 12)
//! whose feedforward inertia came from an FRF fit that was far too heavy.

use beltune::model::rigs::Plant;
use beltune::procedure::commission::{commission, CommissioningConfig, DataSheet};
use beltune::procedure::NoProgress;
use beltune::sim::SimAxis;
use beltune::study::{generate, Ranges};

/// The thesis' limit of the max cart error (chapter 5), m.
const MAX_CART_ERROR_M: f64 = 1e-3;
/// Accepted relative error of the feedforward inertia: the issue's target
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
fn feedforward_inertia_is_the_rigid_body_s_not_the_frf_fit_s_issue_12() {
    for index in [270, 751] {
        let g = generate(12, index, &Ranges::default()).unwrap();
        let p = &g.params;
        let truth =
            p.theta_e() + p.theta_end_pulley_kg_m2 / (p.i_g * p.i_g) + p.i_t() * p.i_t() * p.m_c();
        let plant = Plant::Physical(p.clone());
        let ds = DataSheet::for_plant(&plant, 0.05, None);
        let mut axis = SimAxis::new(&plant, g.sim_config(0.05)).unwrap();
        let run = commission(
            &mut axis,
            &ds,
            &CommissioningConfig::default(),
            &mut NoProgress,
        )
        .unwrap();
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
