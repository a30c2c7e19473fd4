//! The delivered controller in the names and units of three drive families'
//! manuals, so that a technician can type it into the drive's parameter
//! menu. The prefilter sits in series with the speed controller, inside the
//! speed loop (it filters the speed controller's torque output): every
//! family calls that a filter of the current (torque) setpoint, not a speed
//! setpoint filter (which would sit outside the loop).
//!
//! Sources of the names and units (the manuals' parameter descriptions):
//! - Beckhoff AX5000 IDN description: S-0-0100 velocity loop proportional
//!   gain (Nm/(rad/s) with feature flag P-0-0010 bit 15, else A/(rad/s)),
//!   S-0-0101 velocity loop integral action time (ms), S-0-0104 position
//!   loop Kv-factor (1000/min), P-0-0513 current command value filter 0
//!   (low pass frequency in Hz and damping, high pass frequency and damping).
//! - Kollmorgen AKD user guide: VL.KP (A/(rad/s)), VL.KI (Hz: the integral
//!   acts as `VL.KP (1 + 2 pi VL.KI / s)`, so `VL.KI = 1 / (2 pi T_n)`).
//! - Siemens SINAMICS: speed controller P gain (Nms/rad) and integral time
//!   (ms), position controller gain Kv (1000/min), current setpoint filter as
//!   a general second-order filter (denominator and numerator natural
//!   frequency and damping). Parameter numbers are not given: they differ
//!   between SINAMICS families and firmware versions.
//!
//! Conversions: `K_v [1000/min] = K_PP [1/s] * 60 / 1000` (1000/min is
//! (m/min)/mm); a filter's quality factor `Q = 1 / (2 damping)`.

use crate::design::{ControllerDesign, DriveForm};
use crate::ident::ModelUnits;
use crate::report::Table;
use std::f64::consts::PI;

/// The controller per drive family: (family, parameter, unit, value).
pub fn vendor_table(des: &ControllerDesign, units: ModelUnits) -> Table {
    let f = DriveForm::of(des);
    let k_p = f.velocity_gain_nm_s_per_rad;
    let kp_unit = crate::units::labels(units).torque_per_velocity;
    let tn = f.integral_time_ms;
    let kv_1000_per_min = f.position_gain_m_per_min_per_mm;
    let num = |v: Option<f64>, d: usize| v.map_or("-".to_string(), |x| format!("{x:.d$}"));
    let notch = f.filter_kind == "notch";
    let none = f.filter_kind == "none";
    let (pole_f, pole_d) = (f.filter_frequency_hz, f.filter_damping);
    let (zero_f, zero_d) = if notch {
        (f.filter_frequency_hz, f.filter_zero_damping)
    } else {
        (None, None)
    };
    let q = |d: Option<f64>| d.map(|d| 1.0 / (2.0 * d));
    let filter_kind = match f.filter_kind.as_str() {
        "butterworth" => "2nd-order low pass (Butterworth)",
        "notch" => "band-stop (notch)",
        _ => "none",
    };
    let mut rows: Vec<Vec<String>> = Vec::new();
    let mut row = |family: &str, name: &str, unit: &str, value: String| {
        rows.push(vec![family.into(), name.into(), unit.into(), value]);
    };
    // Siemens SINAMICS
    let s = "Siemens SINAMICS";
    row(
        s,
        "speed controller P gain Kp",
        kp_unit,
        format!("{k_p:.4}"),
    );
    row(s, "speed controller integral time Tn", "ms", num(tn, 2));
    row(
        s,
        "position controller gain Kv",
        "1000/min",
        format!("{kv_1000_per_min:.4}"),
    );
    row(s, "current setpoint filter, type", "", filter_kind.into());
    if !none {
        row(
            s,
            "current setpoint filter, denominator natural frequency",
            "Hz",
            num(pole_f, 2),
        );
        row(
            s,
            "current setpoint filter, denominator damping",
            "",
            num(pole_d, 4),
        );
    }
    if notch {
        row(
            s,
            "current setpoint filter, numerator natural frequency",
            "Hz",
            num(zero_f, 2),
        );
        row(
            s,
            "current setpoint filter, numerator damping",
            "",
            num(zero_d, 4),
        );
    }
    // Beckhoff AX5000
    let b = "Beckhoff AX5000";
    row(
        b,
        "S-0-0100 velocity loop proportional gain",
        kp_unit,
        format!("{k_p:.4}"),
    );
    row(
        b,
        "S-0-0101 velocity loop integral action time",
        "ms",
        num(tn, 2),
    );
    row(
        b,
        "S-0-0104 position loop Kv-factor",
        "1000/min",
        format!("{kv_1000_per_min:.4}"),
    );
    row(
        b,
        "P-0-0513 current command value filter 0, type",
        "",
        filter_kind.into(),
    );
    if !none {
        row(b, "P-0-0513 low pass frequency", "Hz", num(pole_f, 2));
        row(b, "P-0-0513 low pass damping", "", num(pole_d, 4));
    }
    if notch {
        row(b, "P-0-0513 high pass frequency", "Hz", num(zero_f, 2));
        row(b, "P-0-0513 high pass damping", "", num(zero_d, 4));
    }
    // Kollmorgen AKD
    let k = "Kollmorgen AKD";
    match units {
        ModelUnits::Current => row(k, "VL.KP", "A/(rad/s)", format!("{k_p:.4}")),
        ModelUnits::Torque => row(
            k,
            "VL.KP (divide by the motor's K_t in N m/A)",
            "N m/(rad/s)",
            format!("{k_p:.4}"),
        ),
    }
    row(
        k,
        "VL.KI = 1 / (2 pi T_n)",
        "Hz",
        num(tn.map(|t| 1e3 / (2.0 * PI * t)), 3),
    );
    row(
        k,
        "position loop gain K_v",
        "1/s",
        format!("{:.3}", f.position_gain_per_s),
    );
    row(
        k,
        "velocity-loop anti-resonance filter, type",
        "",
        filter_kind.into(),
    );
    if !none {
        row(
            k,
            "anti-resonance filter pole frequency",
            "Hz",
            num(pole_f, 2),
        );
        row(
            k,
            "anti-resonance filter pole Q = 1 / (2 damping)",
            "",
            num(q(pole_d), 4),
        );
    }
    if notch {
        row(
            k,
            "anti-resonance filter zero frequency",
            "Hz",
            num(zero_f, 2),
        );
        row(
            k,
            "anti-resonance filter zero Q = 1 / (2 damping)",
            "",
            num(q(zero_d), 4),
        );
    }
    Table {
        title: "Drive parameters per drive family (the prefilter is a current setpoint filter: \
                inside the speed loop, after the speed controller)"
            .into(),
        header: ["drive family", "parameter", "unit", "value"]
            .map(String::from)
            .to_vec(),
        rows,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::design::{design, DesignInput, DesignKnobs, PrefilterKind};
    use crate::model::TwoMassParams;

    fn value(t: &Table, family: &str, name: &str) -> f64 {
        t.rows
            .iter()
            .find(|r| r[0] == family && r[1] == name)
            .unwrap_or_else(|| panic!("{family} {name} missing"))[3]
            .parse()
            .unwrap()
    }

    /// The conversions against their definitions: `T_n = K_P / K_I`, AKD's
    /// `VL.KI = 1 / (2 pi T_n)` (its manual: a constant error of 1 rps with
    /// VL.KP = 1, VL.KI = 160 doubles the output after (1000/160) 2 pi ms...
    /// i.e. the integral adds `VL.KP 2 pi VL.KI t`), `K_v [1000/min] =
    /// K_PP 0.06`, notch numerator damping `1/d_n`.
    #[test]
    fn vendor_parameters_follow_their_definitions() {
        let inp = DesignInput::new(TwoMassParams::thesis_table_a4(), 1e-3);
        for kind in [PrefilterKind::Butterworth, PrefilterKind::Notch] {
            let des = design(
                &inp,
                &DesignKnobs {
                    prefilter: kind,
                    ..DesignKnobs::default()
                },
            )
            .unwrap();
            let t = vendor_table(&des, ModelUnits::Torque);
            let tn_s = des.k_p / des.k_i;
            let tn = value(
                &t,
                "Beckhoff AX5000",
                "S-0-0101 velocity loop integral action time",
            );
            assert!((tn / (tn_s * 1e3) - 1.0).abs() < 1e-3, "{tn}");
            let ki_hz = value(&t, "Kollmorgen AKD", "VL.KI = 1 / (2 pi T_n)");
            // the AKD integral term VL.KP 2 pi VL.KI / s equals K_I / s
            assert!(
                (des.k_p * 2.0 * PI * ki_hz / des.k_i - 1.0).abs() < 2e-3,
                "{ki_hz}"
            );
            let kv = value(&t, "Siemens SINAMICS", "position controller gain Kv");
            assert!((kv / (des.k_pp * 0.06) - 1.0).abs() < 1e-3);
            let names: Vec<&str> = t.rows.iter().map(|r| r[1].as_str()).collect();
            assert!(!names.iter().any(|n| n.contains("speed setpoint")));
            if kind == PrefilterKind::Notch {
                let d = value(
                    &t,
                    "Siemens SINAMICS",
                    "current setpoint filter, denominator damping",
                );
                let z = value(
                    &t,
                    "Siemens SINAMICS",
                    "current setpoint filter, numerator damping",
                );
                assert!((d * z - 1.0).abs() < 1e-3, "{d} {z}");
            }
        }
    }
}
