//! The axis zoo (`data/axes/`, [`beltune::model::zoo`]) commissioned once
//! each on the simulator with the default settings.
//!
//! Where an axis can do a modest move ([`beltune::model::zoo::modest_move`],
//! a physical definition tested beside it), the commissioning must deliver a
//! controller whose margins on the simulator's own physics (the truth with
//! the end pulley, [`beltune::model::Plant::true_two_mass`], at both ends
//! of the stroke, with the true dead time) are at least 6 dB and 45 deg,
//! and whose identified `f_r` and `f_z` lie within 3 % of the truth at the
//! identification position. Where it cannot, the commissioning must refuse
//! in one line. Axes that do not reach this yet are listed in
//! [`KNOWN_FAILURES`] with what they do; the test fails when an axis
//! outside that list fails, and when one on it passes (so that the list
//! stays true).

use beltune::commission::{commission_simulated, CommissioningConfig, NoProgress};
use beltune::design::robust::margins_on;
use beltune::model::zoo::{modest_move, zoo};
use beltune::sim::SimConfig;

/// Smallest true gain margin of the delivered velocity loop, dB.
const GAIN_MARGIN_DB: f64 = 6.0;
/// Smallest true phase margin of the delivered velocity loop, deg.
const PHASE_MARGIN_DEG: f64 = 45.0;
/// Largest relative error of the identified `f_r`, `f_z` against the truth.
const FREQUENCY_TOLERANCE: f64 = 0.03;
/// Largest median axis time of the zoo's commissionings, s (issue 31).
const MEDIAN_AXIS_TIME_S: f64 = 15.0;

/// Axes that can do a modest move but are not commissioned to the
/// criteria above yet: `(name, what happens)`. Measured by this test.
const KNOWN_FAILURES: &[(&str, &str)] = &[
    (
        "gt2-gantry-2900",
        "following-error stop (50 mm) in the friction runs after identification (f_r 35.0, f_z 6.4 Hz found): the designed velocity loop is 1.0 Hz",
    ),
    (
        "preloaded-rail-1.5kg-45N",
        "identified f_z 3.7 % off (Coulomb 45 N on 1.5 kg), static error 210 um",
    ),
    (
        "stiff-short-300",
        "identified f_r +6 %, f_z -9.5 % (resonance 550-1200 Hz)",
    ),
];

/// The outcome of one axis, one line; the axis time of a commissioning
/// that ran to its end goes to `axis_times_s`.
fn check(plant: &beltune::model::Plant, axis_times_s: &mut Vec<f64>) -> Result<String, String> {
    let cfg = CommissioningConfig::default();
    let can = modest_move(plant);
    let run = commission_simulated(plant, SimConfig::default(), None, &cfg, &mut NoProgress);
    if let Ok(r) = &run {
        axis_times_s.push(r.experiment_time_s);
    }
    match (can, run) {
        (Err(why), Err(e)) => {
            let text = e.to_string();
            if text.contains('\n') {
                return Err(format!("refusal in more than one line: {text}"));
            }
            // the refusal names the physical reason (a torque limit that
            // cannot carry the axis once read "record too short")
            for word in ["torque", "stroke", "encoder"] {
                if why.contains(word) && !text.contains(word) {
                    return Err(format!("the refusal does not name the {word}: {text}"));
                }
            }
            Ok(format!("cannot ({why}); refused: {text}"))
        }
        (Err(why), Ok(_)) => Err(format!(
            "commissioned although it cannot do a modest move ({why})"
        )),
        (Ok(()), Err(e)) => Err(format!("failed: {e}")),
        (Ok(()), Ok(run)) => {
            let truth = plant
                .true_two_mass(run.identification_position_m)
                .map_err(|e| e.to_string())?;
            let rel = |a: f64, b: f64| (a / b - 1.0).abs();
            let (e_r, e_z) = (
                rel(run.fit.f_r_hz, truth.f_r_hz()),
                rel(run.fit.f_z_hz, truth.f_z_hz()),
            );
            let mut design = run.design.clone();
            design.input.dead_time_s = plant.dead_time_s();
            let stroke = plant.stroke_m().unwrap_or(0.0);
            let mut worst = (f64::INFINITY, f64::INFINITY);
            for xi in [0.0, stroke] {
                let m = margins_on(
                    &design,
                    &plant.true_two_mass(xi).map_err(|e| e.to_string())?,
                )
                .map_err(|e| e.to_string())?;
                worst.0 = worst.0.min(m.velocity_gain_margin_db);
                worst.1 = worst.1.min(if m.stable {
                    m.velocity_phase_margin_deg
                } else {
                    f64::NEG_INFINITY
                });
            }
            let line = format!(
                "f_r {:.1} Hz ({:+.1} %), f_z {:.1} Hz ({:+.1} %), true margins {:.1} dB / {:.1} deg, move {:.0} -> {:.0} mm, axis busy {:.1} s, verdict {}",
                run.fit.f_r_hz,
                (run.fit.f_r_hz / truth.f_r_hz() - 1.0) * 100.0,
                run.fit.f_z_hz,
                (run.fit.f_z_hz / truth.f_z_hz() - 1.0) * 100.0,
                worst.0,
                worst.1,
                run.validation_move.start_m * 1e3,
                run.validation_move.target_m * 1e3,
                run.experiment_time_s,
                run.verdict.text()
            );
            // what is reported (the record's and the summary's
            // `validation_move`) is the move that ran: its desired path ends
            // at the reported target (strokes under 0.6 m once reported
            // "0 -> 500 mm" for a 0 -> 200 mm move; the path's start carries
            // the setpoint lead of the belt's stretch, its end does not)
            let desired = &run
                .delivered_move()
                .ok_or("no delivered move")?
                .record
                .desired_m;
            let last = desired[desired.len() - 1];
            if (last - run.validation_move.target_m).abs() > 1e-9 {
                return Err(format!(
                    "reported target {:.1} mm, the move ran to {:.1} mm",
                    run.validation_move.target_m * 1e3,
                    last * 1e3
                ));
            }
            // the move that ran lies inside the travel window
            let ds = run.datasheet;
            if !(run.validation_move.target_m <= ds.travel_max_m
                && run.validation_move.start_m >= ds.travel_min_m)
            {
                return Err(format!("the move is outside the window: {line}"));
            }
            if e_r > FREQUENCY_TOLERANCE || e_z > FREQUENCY_TOLERANCE {
                return Err(format!("identification off: {line}"));
            }
            if !(worst.0 >= GAIN_MARGIN_DB && worst.1 >= PHASE_MARGIN_DEG) {
                return Err(format!("thin true margins: {line}"));
            }
            // a success is a delivered controller that passed its move
            if !run.verdict.limits_met() {
                return Err(format!("the validation move failed: {line}"));
            }
            Ok(line)
        }
    }
}

/// Every zoo axis once: success where it can do a modest move, a one-line
/// refusal where it cannot; the known failures stay as listed.
#[test]
fn the_zoo_commissions_or_refuses_with_its_reason() {
    let axes = zoo().unwrap();
    assert!(axes.len() >= 15);
    let mut unexpected = Vec::new();
    let mut axis_times_s = Vec::new();
    for (name, plant) in &axes {
        let started = std::time::Instant::now();
        let outcome = check(plant, &mut axis_times_s);
        let known = KNOWN_FAILURES.iter().find(|(n, _)| n == name);
        eprintln!(
            "zoo {name}: {} ({:.0} s)",
            match &outcome {
                Ok(l) => format!("ok: {l}"),
                Err(l) => format!("FAILS: {l}"),
            },
            started.elapsed().as_secs_f64()
        );
        match (&outcome, known) {
            (Ok(_), None) | (Err(_), Some(_)) => {}
            (Err(e), None) => unexpected.push(format!("{name}: {e}")),
            (Ok(l), Some(_)) => unexpected.push(format!(
                "{name} passes now, remove it from KNOWN_FAILURES: {l}"
            )),
        }
    }
    assert!(unexpected.is_empty(), "{}", unexpected.join("\n"));
    // Issue 31: the default commissioning keeps the axis busy at most 15 s
    // (commercial one-button tuners take 10-30 s; the thesis' FRF alone
    // about 16 s) at the zoo's median. Axis time is simulated time: exact.
    axis_times_s.sort_by(f64::total_cmp);
    let n = axis_times_s.len();
    assert!(n >= 10, "only {n} axes ran to the end");
    let median = if n % 2 == 1 {
        axis_times_s[n / 2]
    } else {
        0.5 * (axis_times_s[n / 2 - 1] + axis_times_s[n / 2])
    };
    eprintln!(
        "zoo axis time: median {median:.1} s over {n} axes, {:.1} .. {:.1} s",
        axis_times_s[0],
        axis_times_s[n - 1]
    );
    assert!(
        median <= MEDIAN_AXIS_TIME_S,
        "median axis time {median:.1} s over {n} axes"
    );
}
