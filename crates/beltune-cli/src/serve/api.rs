//! JSON types of the tuning page's API and their validation.
//!
//! `POST /api/design` and `POST /api/save` take a [`DesignRequest`]: every knob is
//! optional (a missing or `null` knob takes the design default), unknown fields are
//! rejected, and every given value must lie in its [`KnobRange`]. The answer of
//! `/api/design` is a [`DesignResponse`]; every failure is an [`ErrorBody`]
//! `{ "error": "..." }` with a 4xx/5xx status.

use serde::{Deserialize, Serialize};

/// Resonance filter in the velocity loop (thesis 4.2.1).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PrefilterKind {
    /// Second-order Butterworth low-pass (4.3)-(4.4).
    Butterworth,
    /// Notch centred on the resonance (4.1)-(4.2).
    Notch,
    /// No prefilter (the thesis' comparison in Section 5.1).
    None,
}

/// Allowed interval of one numeric knob, sent to the page so the sliders and the
/// server agree.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct KnobRange {
    /// JSON field name of the knob.
    pub name: &'static str,
    /// Smallest accepted value (inclusive).
    pub min: f64,
    /// Largest accepted value (inclusive).
    pub max: f64,
    /// Slider step.
    pub step: f64,
}

/// Velocity-loop phase margin, degrees. Below 20 deg the loop rings; 90 deg is the
/// limit of a PI controller on an integrating plant.
pub const PM_VELOCITY_DEG: KnobRange = KnobRange {
    name: "pm_velocity_deg",
    min: 20.0,
    max: 89.0,
    step: 0.5,
};
/// Position-loop phase margin, degrees.
pub const PM_POSITION_DEG: KnobRange = KnobRange {
    name: "pm_position_deg",
    min: 20.0,
    max: 89.0,
    step: 0.5,
};
/// Open-loop velocity gain at the resonance, dB (negative = suppression, (4.7)).
pub const RESONANCE_SUPPRESSION_DB: KnobRange = KnobRange {
    name: "resonance_suppression_db",
    min: -40.0,
    max: -0.5,
    step: 0.5,
};
/// Prefilter attenuation at the antiresonance, dB ((4.2) notch, (4.4) Butterworth).
/// Up to -0.01 dB: the robust design rule's Butterworth candidates reach -0.02 dB,
/// and the page sends the design on the screen back with its exact values.
pub const FILTER_ATTENUATION_DB: KnobRange = KnobRange {
    name: "filter_attenuation_db",
    min: -20.0,
    max: -0.01,
    step: 0.5,
};
/// One-knob dynamics setting: 0 = conservative, 1 = dynamic.
pub const DYNAMICS: KnobRange = KnobRange {
    name: "dynamics",
    min: 0.0,
    max: 1.0,
    step: 0.01,
};
/// Payload on the cart in the simulated move, kg (the design keeps the nominal model).
pub const PAYLOAD_KG: KnobRange = KnobRange {
    name: "payload_kg",
    min: 0.0,
    max: 30.0,
    step: 0.1,
};

/// All numeric knob ranges, in page order.
pub const RANGES: [KnobRange; 6] = [
    PM_VELOCITY_DEG,
    PM_POSITION_DEG,
    RESONANCE_SUPPRESSION_DB,
    FILTER_ATTENUATION_DB,
    DYNAMICS,
    PAYLOAD_KG,
];

/// Largest accepted request body, bytes.
pub const MAX_BODY_BYTES: usize = 16 * 1024;

/// Body of `POST /api/design` and `POST /api/save`. Every field is optional.
#[derive(Debug, Clone, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DesignRequest {
    /// Prefilter kind, `"butterworth"` or `"notch"`.
    pub prefilter: Option<PrefilterKind>,
    /// Velocity-loop phase margin, deg.
    pub pm_velocity_deg: Option<f64>,
    /// Position-loop phase margin, deg.
    pub pm_position_deg: Option<f64>,
    /// Open-loop velocity gain at the resonance, dB.
    pub resonance_suppression_db: Option<f64>,
    /// Prefilter attenuation, dB.
    pub filter_attenuation_db: Option<f64>,
    /// One-knob dynamics 0..1; sets both phase margins and the resonance suppression,
    /// so it must not be combined with them.
    pub dynamics: Option<f64>,
    /// Payload of the simulated move, kg.
    pub payload_kg: Option<f64>,
}

/// Validated knobs: what the [`super::tuner::Tuner`] receives. `None` = design default.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize)]
pub struct Knobs {
    /// Prefilter kind.
    pub prefilter: Option<PrefilterKind>,
    /// Velocity-loop phase margin, deg.
    pub pm_velocity_deg: Option<f64>,
    /// Position-loop phase margin, deg.
    pub pm_position_deg: Option<f64>,
    /// Open-loop velocity gain at the resonance, dB.
    pub resonance_suppression_db: Option<f64>,
    /// Prefilter attenuation, dB.
    pub filter_attenuation_db: Option<f64>,
    /// One-knob dynamics 0..1.
    pub dynamics: Option<f64>,
    /// Payload of the simulated move, kg.
    pub payload_kg: Option<f64>,
}

/// A request the server refuses, with the HTTP status to answer.
#[derive(Debug, Clone, PartialEq)]
pub struct ApiError {
    /// HTTP status code (4xx for the client's fault, 5xx for ours).
    pub status: u16,
    /// One-line reason shown to the user.
    pub message: String,
}

impl ApiError {
    /// 400 Bad Request with `message`.
    pub fn bad_request(message: impl Into<String>) -> Self {
        ApiError {
            status: 400,
            message: message.into(),
        }
    }
}

/// JSON body of every error answer.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct ErrorBody {
    /// One-line reason.
    pub error: String,
}

fn check(range: KnobRange, value: Option<f64>) -> Result<Option<f64>, ApiError> {
    match value {
        None => Ok(None),
        // `+ 0.0`: a -0 (a slider dragged to zero from below) reads 0, never "-0 kg"
        Some(v) if v.is_finite() && v >= range.min && v <= range.max => Ok(Some(v + 0.0)),
        Some(v) => Err(ApiError::bad_request(format!(
            "`{}` = {} is out of range [{}, {}]",
            range.name,
            beltune::error::short_number(v),
            range.min,
            range.max
        ))),
    }
}

impl DesignRequest {
    /// Parse a request body: malformed JSON, wrong types and unknown fields are
    /// 400 with serde's message (which names the field and the position).
    pub fn parse(body: &[u8]) -> Result<Self, ApiError> {
        if body.iter().all(u8::is_ascii_whitespace) {
            // An empty body means "all defaults".
            return Ok(DesignRequest::default());
        }
        serde_json::from_slice(body)
            .map_err(|e| ApiError::bad_request(format!("invalid request: {e}")))
    }

    /// Range-check every knob and reject contradictory combinations.
    pub fn validate(&self) -> Result<Knobs, ApiError> {
        let knobs = Knobs {
            prefilter: self.prefilter,
            pm_velocity_deg: check(PM_VELOCITY_DEG, self.pm_velocity_deg)?,
            pm_position_deg: check(PM_POSITION_DEG, self.pm_position_deg)?,
            resonance_suppression_db: check(
                RESONANCE_SUPPRESSION_DB,
                self.resonance_suppression_db,
            )?,
            filter_attenuation_db: check(FILTER_ATTENUATION_DB, self.filter_attenuation_db)?,
            dynamics: check(DYNAMICS, self.dynamics)?,
            payload_kg: check(PAYLOAD_KG, self.payload_kg)?,
        };
        if knobs.dynamics.is_some() {
            let set: Vec<&str> = [
                (PM_VELOCITY_DEG.name, knobs.pm_velocity_deg),
                (PM_POSITION_DEG.name, knobs.pm_position_deg),
                (
                    RESONANCE_SUPPRESSION_DB.name,
                    knobs.resonance_suppression_db,
                ),
            ]
            .iter()
            .filter(|(_, v)| v.is_some())
            .map(|(n, _)| *n)
            .collect();
            if !set.is_empty() {
                return Err(ApiError::bad_request(format!(
                    "`dynamics` sets the phase margins and the resonance suppression; \
                     do not also give {}",
                    set.join(", ")
                )));
            }
        }
        Ok(knobs)
    }
}

/// The knobs as the design used them (defaults and the dynamics mapping applied).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct EffectiveKnobs {
    /// Prefilter kind.
    pub prefilter: PrefilterKind,
    /// Velocity-loop phase margin, deg.
    pub pm_velocity_deg: f64,
    /// Position-loop phase margin, deg.
    pub pm_position_deg: f64,
    /// Open-loop velocity gain at the resonance, dB.
    pub resonance_suppression_db: f64,
    /// Prefilter attenuation, dB.
    pub filter_attenuation_db: f64,
    /// One-knob dynamics, if it was used.
    pub dynamics: Option<f64>,
    /// Payload of the simulated move, kg.
    pub payload_kg: f64,
}

/// Controller gains of the cascade (thesis Figure 4.1).
#[derive(Debug, Clone, Copy, Serialize, Deserialize)]
pub struct Gains {
    /// Velocity P gain K_P, N m s/rad.
    pub k_p: f64,
    /// Velocity I gain K_I, N m/rad.
    pub k_i: f64,
    /// Position P gain K_PP, 1/s.
    pub k_pp: f64,
}

/// Prefilter parameters.
#[derive(Debug, Clone, Copy, Serialize, Deserialize)]
pub struct PrefilterInfo {
    /// Kind.
    pub kind: PrefilterKind,
    /// Butterworth corner (4.4), rad/s.
    pub omega_bw_rad_s: Option<f64>,
    /// Notch damping d_n (4.2).
    pub d_n: Option<f64>,
    /// Notch centre frequency, rad/s.
    pub omega_notch_rad_s: Option<f64>,
}

/// Stability margins of one loop.
#[derive(Debug, Clone, Copy, Serialize, Deserialize)]
pub struct LoopMargins {
    /// Phase margin, deg.
    pub phase_margin_deg: f64,
    /// Gain crossover, rad/s.
    pub crossover_rad_s: f64,
    /// Gain margin, dB (`None` when the phase never crosses -180 deg).
    pub gain_margin_db: Option<f64>,
    /// Phase crossover, rad/s (`None` likewise).
    pub phase_crossover_rad_s: Option<f64>,
}

/// One frequency response on [`BodeData::omega_rad_s`].
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
pub struct Curve {
    /// Magnitude, dB.
    pub magnitude_db: Vec<f64>,
    /// Phase, deg (unwrapped).
    pub phase_deg: Vec<f64>,
}

/// Frequency responses for the plots, from `beltune::report::plot_data::loop_data`
/// (the same numbers the report draws).
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
pub struct BodeData {
    /// Log-spaced frequency grid, rad/s.
    pub omega_rad_s: Vec<f64>,
    /// The same grid, Hz (the page shows Hz).
    #[serde(default)]
    pub freq_hz: Vec<f64>,
    /// Closed velocity loop.
    #[serde(default)]
    pub closed_loop_velocity: Curve,
    /// Sensitivity `1/(1+L)` of the velocity loop.
    #[serde(default)]
    pub sensitivity_velocity: Curve,
    /// Sensitivity of the position loop.
    #[serde(default)]
    pub sensitivity_position: Curve,
    /// Open velocity loop.
    pub open_loop_velocity: Curve,
    /// Open position loop.
    pub open_loop_position: Curve,
    /// Closed position loop, desired to actual motor position.
    pub closed_loop_position: Curve,
}

/// Result of the simulated validation move (decimated traces).
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
pub struct MoveData {
    /// Which plant and feedforward the move was simulated with.
    #[serde(default)]
    pub plant: String,
    /// Payload the simulated plant carried, kg.
    pub payload_kg: f64,
    /// Maximum absolute cart tracking error, m.
    pub max_error_m: f64,
    /// Cart error at the end of the record, m.
    pub static_error_m: f64,
    /// Settling time after the end of the trajectory, s (`None`: did not settle).
    pub settling_time_s: Option<f64>,
    /// Sample times, s.
    pub t_s: Vec<f64>,
    /// Desired cart position, m.
    pub desired_m: Vec<f64>,
    /// Actual cart position, m.
    pub actual_m: Vec<f64>,
    /// Cart tracking error, m.
    pub error_m: Vec<f64>,
    /// Motor torque, N m.
    pub torque_nm: Vec<f64>,
}

/// Answer of `POST /api/design`.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct DesignResponse {
    /// Knobs as used.
    pub knobs: EffectiveKnobs,
    /// Controller gains.
    pub gains: Gains,
    /// Prefilter parameters.
    pub prefilter: PrefilterInfo,
    /// Margins of the velocity loop.
    pub velocity_loop: LoopMargins,
    /// Margins of the position loop.
    pub position_loop: LoopMargins,
    /// Open-loop velocity gain at the resonance, dB.
    pub gain_at_resonance_db: f64,
    /// Plot data.
    pub bode: BodeData,
    /// The simulated validation move, when it ran.
    pub validation_move: Option<MoveData>,
    /// Why there is no move (e.g. the simulated closed loop went unstable).
    pub move_error: Option<String>,
    /// Server time spent on design + move, ms.
    pub compute_ms: f64,
}

/// Answer of `POST /api/save`.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct SaveResponse {
    /// Absolute path of the written `controller.toml`.
    pub path: String,
    /// Bytes of `controller.toml`.
    pub bytes: usize,
    /// The new folder holding the consistent set (controller, json, report, data).
    #[serde(default)]
    pub dir: String,
    /// Names of the files written there.
    #[serde(default)]
    pub files: Vec<String>,
}

/// The measured FRF of a loaded commissioning and its fitted model, decimated
/// for display (`beltune::report::plot_data::frf_display`, as in the report).
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
pub struct FrfOverlay {
    /// Measured points, Hz.
    pub freq_hz: Vec<f64>,
    /// Measured magnitude, dB.
    pub magnitude_db: Vec<f64>,
    /// Measured phase, deg.
    pub phase_deg: Vec<f64>,
    /// `true` where the fit used the point.
    pub used_by_fit: Vec<bool>,
    /// Fitted model with dead time, Hz.
    pub model_freq_hz: Vec<f64>,
    /// Fitted model, dB.
    pub model_magnitude_db: Vec<f64>,
    /// Fitted model, deg.
    pub model_phase_deg: Vec<f64>,
}

/// What the commissioning measured with its own controller (the report's verdict numbers).
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
pub struct CommissionedNumbers {
    /// Max cart tracking error of the move with nonlinear feedforward, m.
    pub max_error_m: f64,
    /// Static error after that move, m.
    pub static_error_m: f64,
}

/// Answer of `GET /api/info`: what the page needs to build its controls.
#[derive(Debug, Clone, Serialize)]
pub struct InfoResponse {
    /// Where the model comes from (commissioning folder or built-in axis).
    pub model_source: String,
    /// Resonance frequency of the design model, Hz.
    pub f_r_hz: f64,
    /// Antiresonance frequency of the design model, Hz.
    pub f_z_hz: f64,
    /// Payload the design model assumes, kg.
    pub nominal_payload_kg: f64,
    /// The knobs' defaults.
    pub defaults: EffectiveKnobs,
    /// Default prefilter attenuation per kind, dB.
    pub default_attenuation_db: DefaultAttenuation,
    /// Numeric knob ranges.
    pub ranges: Vec<KnobRange>,
    /// Folder `controller.toml` is saved into.
    pub save_dir: String,
    /// The measured FRF and its fit, when a commissioning is loaded.
    pub measured_frf: Option<FrfOverlay>,
    /// The commissioning's own validation, when known.
    pub commissioned: Option<CommissionedNumbers>,
    /// The loaded result's verdict as the terminal and the report say it
    /// (`PASS: ...`, `FAIL: ...`, `NOT VALIDATED: ...`), when it has one.
    pub commissioned_verdict: Option<String>,
}

/// Default prefilter attenuation per prefilter kind, dB.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct DefaultAttenuation {
    /// Butterworth (thesis: -3 dB).
    pub butterworth: f64,
    /// Notch (thesis: -6 dB).
    pub notch: f64,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn empty_body_means_defaults() {
        let k = DesignRequest::parse(b"  ").unwrap().validate().unwrap();
        assert_eq!(k, Knobs::default());
    }

    #[test]
    fn null_knob_means_default() {
        let r = DesignRequest::parse(br#"{"pm_velocity_deg": null}"#).unwrap();
        assert_eq!(r.validate().unwrap().pm_velocity_deg, None);
    }

    #[test]
    fn range_limits_are_inclusive_and_outside_is_rejected() {
        for range in RANGES {
            for (v, ok) in [
                (range.min, true),
                (range.max, true),
                (range.min - 1e-9 * (1.0 + range.min.abs()), false),
                (range.max + 1e-9 * (1.0 + range.max.abs()), false),
            ] {
                let body = format!("{{\"{}\": {v:e}}}", range.name);
                let r = DesignRequest::parse(body.as_bytes()).unwrap().validate();
                assert_eq!(r.is_ok(), ok, "{body}: {r:?}");
                if let Err(e) = r {
                    assert_eq!(e.status, 400);
                    assert!(e.message.contains(range.name), "{}", e.message);
                }
            }
        }
    }

    #[test]
    fn malformed_wrong_type_and_unknown_fields_are_400() {
        for body in [
            &b"{"[..],
            br#"{"pm_velocity_deg": "sixty"}"#,
            br#"{"prefilter": "chebyshev"}"#,
            br#"{"pm_velocity": 60}"#,
            br#"[60]"#,
        ] {
            let e = DesignRequest::parse(body).unwrap_err();
            assert_eq!(e.status, 400);
            assert!(e.message.starts_with("invalid request"), "{}", e.message);
        }
    }

    #[test]
    fn dynamics_conflicts_with_explicit_margins() {
        let r = DesignRequest::parse(br#"{"dynamics": 0.5, "pm_position_deg": 70}"#).unwrap();
        let e = r.validate().unwrap_err();
        assert!(e.message.contains("pm_position_deg"), "{}", e.message);
        let zero = DesignRequest::parse(br#"{"payload_kg": -0.0}"#).unwrap();
        let payload = zero.validate().unwrap().payload_kg.unwrap();
        assert!(
            payload == 0.0 && payload.is_sign_positive(),
            "a -0 payload reads 0"
        );
        let e = DesignRequest::parse(br#"{"payload_kg": 1e308}"#)
            .unwrap()
            .validate()
            .unwrap_err();
        assert!(e.message.contains("= 1e308 is out"), "{}", e.message);
        let ok = DesignRequest::parse(br#"{"dynamics": 0.5, "payload_kg": 3}"#).unwrap();
        assert!(ok.validate().is_ok());
    }
}
