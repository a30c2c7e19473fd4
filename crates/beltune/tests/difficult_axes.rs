//! Built-in plants that the thesis' move does not fit, study plants whose
//! antiresonance was hard to find or whose cart stuck short, and the
//! verdict of the result.

use beltune::commission::NoProgress;
use beltune::commission::{commission, commission_simulated, CommissioningConfig, DataSheet};
use beltune::model::rigs;
use beltune::sim::{SimAxis, SimConfig};

fn commission_builtin(name: &str, payload_kg: Option<f64>) -> beltune::commission::Commissioning {
    let plant = rigs::builtin(name, payload_kg).unwrap();
    commission_simulated(
        &plant,
        SimConfig::default(),
        None,
        &CommissioningConfig::default(),
        &mut NoProgress,
    )
    .unwrap_or_else(|e| panic!("{name}: {e}"))
}

/// sim-c's viscous friction (200 N s/m) needs 3.4 N m at the Table A.8
/// move's peak speed, more than the 3.1 N m limit: the validation runs the
/// fastest move the axis can do instead of failing, reports it as such, and
/// meets the thesis' accuracy with it.
#[test]
fn sim_c_validates_with_the_fastest_feasible_move() {
    let run = commission_builtin("sim-c", None);
    assert!(run.validation_move.reduced, "{:?}", run.validation_move);
    assert!(run.validation_move.reduced);
    assert!(run.verdict.passed, "{:?}", run.verdict);
    assert!(run.validation_move.limits.v_max < 5.0);
    assert!(run
        .log
        .iter()
        .any(|l| l.contains("the fastest move the axis can do")));
}

/// egc70 at its heaviest payload of the range commissions and says
/// what it guarantees.
#[test]
fn egc70_with_25_kg_meets_its_limits() {
    let run = commission_builtin("egc70", Some(25.0));
    assert!(run.verdict.passed, "{:?}", run.verdict);
    assert!(run.guaranteed.models > 0);
    assert!(run.log.iter().any(|l| l.starts_with("verdict:")));
}

/// Largest relative error of the belt stiffness measured at the validation
/// target: the target's FRF is fitted like the main identification (whose
/// f_z and m_c targets are 2 % and 5 %, i.e. c = m_c w_z^2 within about
/// 5 %); on the first 40 static-error defects of seed 12 the measured
/// stiffness was within 2.1 % rms of the truth, and on this plant -1.1 %.
const TARGET_STIFFNESS_TOLERANCE: f64 = 0.05;
/// Thesis chapter 5: static positioning error.
const STATIC_ERROR_M: f64 = 100e-6;

/// The static belt stretch the motor setpoint leads by used the
/// stiffness identified at the worst-case position (far end of the stroke),
/// 21 % below the true replacement stiffness (2.26) at the validation target
/// of plant 131 of seed 12 (19 kg on an axis tilted 59 deg: a 0.9 mm
/// stretch), and the cart rested 160 um short of the target. Stage 5b
/// measures the stiffness at the target; with it the static error passes.
#[test]
fn static_stretch_uses_the_stiffness_measured_at_the_target() {
    use beltune::study::{generate, Ranges};
    let g = generate(12, 131, &Ranges::default()).unwrap();
    let plant = rigs::Plant::Physical(g.params.clone());
    let start = 0.05;
    let ds = DataSheet::for_plant(&plant, start, None);
    let mut axis = SimAxis::new(&plant, g.sim_config(start)).unwrap();
    let run = commission(
        &mut axis,
        &ds,
        &CommissioningConfig::default(),
        &mut NoProgress,
    )
    .unwrap_or_else(|e| panic!("plant 131: {e}"));
    let t = run.target_stiffness;
    assert!(t.measured, "{t:?}");
    assert!((t.position_m - 0.5).abs() < 1e-9, "{t:?}");
    let c_true = g.params.replacement_stiffness_n_per_m(t.position_m);
    let c_ident = g
        .params
        .replacement_stiffness_n_per_m(run.identification_position_m);
    assert!(
        c_true > 1.15 * c_ident,
        "the plant shows the defect: c {c_true:.0} N/m at the target, {c_ident:.0} N/m where identified"
    );
    assert!(
        (t.c_n_per_m / c_true - 1.0).abs() < TARGET_STIFFNESS_TOLERANCE,
        "measured {:.0} N/m, true {c_true:.0} N/m",
        t.c_n_per_m
    );
    assert!(
        run.log
            .iter()
            .any(|l| l.starts_with("belt stiffness at the target: at 500.0 mm")),
        "{:#?}",
        run.log
    );
    // The compliance along the stroke (stage 5c and the identification
    // position): the stiffness between the start side and the target is
    // (2.26)'s within the same tolerance.
    let side = beltune::commission::stages::identification::start_side_position_m(&ds, 0.0);
    for x in [side, 0.5 * (side + 0.5)] {
        let c = g.params.replacement_stiffness_n_per_m(x);
        assert!(
            (t.stiffness_at(x) / c - 1.0).abs() < TARGET_STIFFNESS_TOLERANCE,
            "at {x:.3} m: {:.0} N/m, true {c:.0} N/m",
            t.stiffness_at(x)
        );
    }
    let nl = &run.validation.nonlinear;
    assert!(
        nl.static_error_m < STATIC_ERROR_M,
        "static error {:.1} um",
        nl.static_error_m * 1e6
    );
}

/// Where the validation target is the identification position (egc70: the
/// target 500 mm, identified at 500.4 mm), the main fit's stiffness stands
/// for it and no second experiment runs.
#[test]
fn egc70_reuses_the_identified_stiffness_at_its_target() {
    let run = commission_builtin("egc70", None);
    let t = run.target_stiffness;
    assert!(!t.measured, "{t:?}");
    assert_eq!(t.c_n_per_m, run.fit.params.c);
    assert!(run.verdict.passed, "{:?}", run.verdict);
}

/// Plant `index` of the robustness study with seed `seed`, commissioned as
/// `beltune montecarlo` does; it must succeed.
fn study_success(seed: u64, index: u64) -> beltune::study::Outcome {
    use beltune::study::{run_plant, Class, Ranges};
    let o = run_plant(
        seed,
        index,
        &Ranges::default(),
        &CommissioningConfig::default(),
    )
    .unwrap();
    assert_eq!(o.class, Class::Success, "{seed}/#{index}: {}", o.message);
    o
}

/// Seed 13 plant #23 (16.3 kg on a +44 deg slope, belt x0.70, viscous
/// x2.69, Coulomb x2.77) and seed 14 plant #378 (24.6 kg on +16 deg, belt
/// x0.51, Coulomb x2.87) failed "during identification (open loop): fit
/// failed: no antiresonance dip below the resonance inside the usable band".
/// Their dips (15 and 7.3 Hz) were two FRF lines (1.22 Hz) wide in the
/// measured FRF and the five-line running median of the features erased
/// them; the features now take a raw line far below both of its neighbours
/// as a narrow antiresonance. The plants commission with f_z within the
/// issue's 2 %.
#[test]
fn a_narrow_antiresonance_dip_is_found() {
    for (seed, index) in [(13, 23), (14, 378)] {
        let o = study_success(seed, index);
        let f_z_error = o.f_z_error.expect("a success identifies f_z");
        assert!(
            f_z_error < 0.02,
            "{seed}/#{index}: f_z error {:.1} %",
            f_z_error * 100.0
        );
    }
}

/// Seed 14 plant #994 (24.0 kg on +23 deg, belt x0.52, Coulomb x2.89, noise
/// x4.6) failed "fit failed: the fit ran to the edge of its range: `m_c`
/// went a factor 10 away": the sticking cart's friction hid the (about 12 Hz)
/// antiresonance, and a 2 % wiggle on the broad 86 Hz resonance's flank was
/// taken for it (start m_c 3.1 kg of 25). A dip now counts only below half
/// the peak of `|G| w^2`, and without one the antiresonance is read from the
/// resonance's rising flank (`ident::features`). The plant commissions with
/// f_z and m_c within the 2 % and 5 % (measured 0.7 % and 1.6 %).
#[test]
fn a_hidden_antiresonance_is_read_from_the_resonance_flank() {
    let o = study_success(14, 994);
    let f_z_error = o.f_z_error.expect("a success identifies f_z");
    let m_c_error = o.m_c_error.expect("a success identifies m_c");
    assert!(f_z_error < 0.02, "f_z error {:.1} %", f_z_error * 100.0);
    assert!(m_c_error < 0.05, "m_c error {:.1} %", m_c_error * 100.0);
}

/// The thesis' limit of the static error (chapter 5), m.
const STATIC_LIMIT_M: f64 = 100e-6;

/// Seed 12 plant #792 (17.1 kg on a 75 deg slope, belt x0.53, Coulomb x2.9)
/// and seed 13 plants #345 (21.5 kg, belt x0.59, Coulomb x2.9) and #411
/// (1.4 kg, belt x0.51, Coulomb x2.7) rested 143, 128 and 123 um from their
/// targets: a sticky cart on a soft belt stops anywhere in its friction band
/// (`+-K F_c`, 0.13-0.18 mm here) depending on how the fast move's end
/// leaves it. The validation move now ends with a slow final approach from
/// behind with the cart's Coulomb lead held (`final_approach`): 35, 6 and
/// 2 um.
#[test]
fn the_final_approach_rests_sticky_carts_on_their_targets() {
    for (seed, index) in [(12, 792), (13, 345), (13, 411)] {
        let o = study_success(seed, index);
        let e = o.static_error_m.expect("a success has a static error");
        assert!(e < STATIC_LIMIT_M, "{seed}/#{index}: {:.0} um", e * 1e6);
    }
}
