use super::*;
use crate::design::{design, DesignInput, DesignKnobs};
use crate::model::TwoMassParams;

fn thesis_design() -> ControllerDesign {
    design(
        &DesignInput::new(TwoMassParams::thesis_table_a4(), 1e-3),
        &DesignKnobs::default(),
    )
    .unwrap()
}

fn good_move() -> MoveSummary {
    MoveSummary {
        max_tracking_error_m: 0.4e-3,
        static_error_m: 20e-6,
        settling_time_s: Some(0.1),
        max_motor_error_m: 1e-3,
        max_torque_nm: 1.5,
    }
}

fn margins(pm_deg: f64) -> GuaranteedMargins {
    GuaranteedMargins {
        velocity_phase_margin_deg: pm_deg,
        velocity_gain_margin_db: 8.0,
        position_phase_margin_deg: 70.0,
        models: 18,
    }
}

/// The verdict on the thesis design with `limits`, the move `m` judged on
/// `on` (none: no move), a guaranteed margin of 45 deg.
fn judge_with(
    m: Option<&MoveSummary>,
    on: ValidatedOn,
    limits: &Limits,
    identified: Option<&IdentifiedModel>,
) -> Verdict {
    judge_margin(m, on, limits, identified, 45.0)
}

/// [`judge_with`] with a guaranteed margin of `pm_deg`.
fn judge_margin(
    m: Option<&MoveSummary>,
    on: ValidatedOn,
    limits: &Limits,
    identified: Option<&IdentifiedModel>,
    pm_deg: f64,
) -> Verdict {
    let d = thesis_design();
    let g = margins(pm_deg);
    judge(&VerdictInput {
        limits,
        validation: m.map(|summary| MoveInput {
            summary,
            record_after_move_s: 1.0,
            torque_max_nm: 3.1,
            on,
        }),
        guaranteed: Some(&g),
        design: &d,
        identified,
        controller_file: "controller.toml",
    })
}

fn judged(m: &MoveSummary, pm_deg: f64) -> Verdict {
    judge_margin(Some(m), ValidatedOn::Axis, &Limits::default(), None, pm_deg)
}

fn failed(v: &Verdict) -> Vec<CheckName> {
    v.checks
        .iter()
        .filter(|c| !c.passed)
        .map(|c| c.name)
        .collect()
}

#[test]
fn a_good_move_with_guaranteed_margins_passes() {
    let v = judged(&good_move(), 45.0);
    assert!(v.passed && v.limits_met(), "{v:?}");
    assert_eq!(v.checks.len(), 5);
    assert_eq!(v.word(), "PASS");
    // a step a technician can follow: what to enter, where it is listed, how to check it
    assert!(v
        .next_step
        .starts_with("Enter the gains and the filter of controller.toml"));
    assert!(v
        .next_step
        .contains("beltune export --controller controller.toml"));
    assert!(v.next_step.contains("repeat the validation move"));
}

#[test]
fn each_limit_fails_the_verdict_on_its_own() {
    let cases: [(MoveSummary, f64, CheckName); 5] = [
        (
            MoveSummary {
                max_tracking_error_m: 1.2e-3,
                ..good_move()
            },
            45.0,
            CheckName::MaxTrackingError,
        ),
        (
            MoveSummary {
                static_error_m: 150e-6,
                ..good_move()
            },
            45.0,
            CheckName::StaticError,
        ),
        (
            MoveSummary {
                settling_time_s: None,
                ..good_move()
            },
            45.0,
            CheckName::Settling,
        ),
        (
            MoveSummary {
                max_torque_nm: 3.1,
                ..good_move()
            },
            45.0,
            CheckName::Saturation,
        ),
        (good_move(), 12.0, CheckName::GuaranteedPhaseMargin),
    ];
    for (m, pm, name) in cases {
        let v = judged(&m, pm);
        assert!(!v.passed && !v.limits_met(), "{name:?}: {v:?}");
        assert_eq!(failed(&v), [name], "{v:?}");
        assert_eq!(v.word(), "FAIL");
        assert!(v.next_step.starts_with("Do not load"), "{}", v.next_step);
        assert_eq!(v.failures().len(), 1);
    }
}

#[test]
fn exactly_at_a_limit_or_nan_fails() {
    let at = MoveSummary {
        max_tracking_error_m: 1e-3,
        ..good_move()
    };
    assert_eq!(failed(&judged(&at, 45.0)), [CheckName::MaxTrackingError]);
    let nan = MoveSummary {
        static_error_m: f64::NAN,
        ..good_move()
    };
    let v = judged(&nan, 45.0);
    assert_eq!(failed(&v), [CheckName::StaticError]);
    assert_eq!(v.check(CheckName::StaticError).unwrap().value, None);
    assert_eq!(
        failed(&judged(&good_move(), f64::NAN)),
        [CheckName::GuaranteedPhaseMargin]
    );
    // a margin exactly at its limit reaches it
    assert!(judged(&good_move(), 30.0).passed);
}

#[test]
fn the_check_texts_read_as_the_terminal_shows_them() {
    let m = MoveSummary {
        max_tracking_error_m: 0.64e-3,
        static_error_m: 31.3e-6,
        ..good_move()
    };
    let v = judged(&m, 45.0);
    assert_eq!(
        v.check(CheckName::MaxTrackingError).unwrap().text(),
        "max cart error 0.640 mm < 1 mm"
    );
    assert_eq!(
        v.check(CheckName::StaticError).unwrap().text(),
        "static error 31.3 um < 100 um"
    );
    assert_eq!(
        v.check(CheckName::GuaranteedPhaseMargin).unwrap().text(),
        "guaranteed phase margin 45.0 deg >= 30 deg"
    );
    let v = judged(
        &MoveSummary {
            max_tracking_error_m: 1.2e-3,
            settling_time_s: None,
            ..good_move()
        },
        12.0,
    );
    assert_eq!(
        v.failures(),
        [
            "max cart error 1.200 mm >= 1 mm",
            "the cart did not settle within the 1 s recorded after the move",
            "guaranteed phase margin 12.0 deg < 30 deg",
        ]
    );
}

#[test]
fn without_a_move_the_verdict_is_not_validated() {
    let v = judge_with(None, ValidatedOn::None, &Limits::default(), None);
    assert!(!v.passed && v.limits_met(), "{v:?}");
    assert_eq!(v.word(), "NOT VALIDATED");
    assert_eq!(v.validated_on, ValidatedOn::None);
    assert!(v.next_step.starts_with("No validation move"));
}

#[test]
fn a_simulated_move_does_not_say_load_into_the_drive() {
    let v = judge_with(
        Some(&good_move()),
        ValidatedOn::Simulation,
        &Limits::default(),
        None,
    );
    assert!(v.passed);
    assert!(v.next_step.contains("simulated"), "{}", v.next_step);
    // the verdict itself says where it comes from
    assert_eq!(v.word(), "PASS (simulated move)");
    assert!(
        v.text().starts_with("PASS (simulated move): "),
        "{}",
        v.text()
    );
}

#[test]
fn tighter_limits_from_the_user_decide() {
    let limits = Limits {
        max_tracking_error_m: 2e-5,
        ..Limits::default()
    };
    let v = judge_with(Some(&good_move()), ValidatedOn::Axis, &limits, None);
    assert_eq!(failed(&v), [CheckName::MaxTrackingError]);
    assert_eq!(
        v.failures(),
        ["max cart error 400.0 um >= 20 um"],
        "a limit below 1 mm reads in um"
    );
}

#[test]
fn warnings_name_their_reason_and_do_not_fail() {
    let p = TwoMassParams::thesis_table_a4();
    let id: IdentifiedModel = serde_json::from_value(serde_json::json!({
        "theta_e": p.theta_e, "m_c": p.m_c, "c": p.c, "d_m": p.d_m, "d_c": p.d_c, "i_t": p.i_t,
        "mean_coherence": 0.5, "fit_rms_db": 5.0
    }))
    .unwrap();
    let v = judge_with(
        Some(&good_move()),
        ValidatedOn::Axis,
        &Limits::default(),
        Some(&id),
    );
    let topics: Vec<&str> = v.warnings.iter().map(|w| w.topic.as_str()).collect();
    assert_eq!(topics, ["coherence", "fit residual"]);
    assert!(v.passed);
}

#[test]
fn limits_refuse_non_physical_values() {
    assert!(Limits::default().validate().is_ok());
    for bad in [0.0, -1e-3, f64::NAN, f64::INFINITY] {
        let l = Limits {
            max_tracking_error_m: bad,
            ..Limits::default()
        };
        assert!(l.validate().is_err(), "{bad}");
    }
}
