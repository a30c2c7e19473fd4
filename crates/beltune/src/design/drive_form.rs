//! The design in the forms drive parameter menus use: speed-loop gain and
//! integral (reset) time `T_n = K_P / K_I`, position-loop gain `K_v`, filters as
//! frequency and damping, velocity-filter time constant.

use super::{ControllerDesign, Prefilter};
use std::f64::consts::{PI, SQRT_2};

/// The drive-menu form of a [`ControllerDesign`]. Torque units follow the
/// design (N m, or A for a current-unit record).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct DriveForm {
    /// Speed-loop proportional gain `K_P`, N m s/rad (A s/rad in current units).
    pub velocity_gain_nm_s_per_rad: f64,
    /// Speed-loop integral time `T_n = K_P / K_I`, ms; `None` without integral action.
    pub integral_time_ms: Option<f64>,
    /// Position-loop gain `K_v = K_PP`, 1/s (velocity per position error).
    pub position_gain_per_s: f64,
    /// The same `K_v` in (m/min)/mm, as many drive menus show it.
    pub position_gain_m_per_min_per_mm: f64,
    /// Prefilter type: "butterworth", "notch" or "none".
    pub filter_kind: String,
    /// Prefilter frequency (Butterworth cut-off, notch centre), Hz; `None` without filter.
    pub filter_frequency_hz: Option<f64>,
    /// Prefilter damping: of the Butterworth poles (`1/sqrt(2)`), of the notch
    /// poles (`d_n`, (4.1)); `None` without filter.
    pub filter_damping: Option<f64>,
    /// Damping of the notch zeros (`1/d_n` in (4.1)); `None` for the other filters.
    pub filter_zero_damping: Option<f64>,
    /// Velocity-filter time constant `T_R` (6.1), ms.
    pub velocity_filter_time_ms: f64,
    /// Sampling time `T_s`, ms.
    pub ts_ms: f64,
}

impl DriveForm {
    /// The drive form of `des`.
    pub fn of(des: &ControllerDesign) -> Self {
        let (kind, f, zeta, zero) = match des.prefilter {
            Prefilter::Butterworth { omega_bw_rad_s } => (
                "butterworth",
                Some(omega_bw_rad_s / (2.0 * PI)),
                Some(1.0 / SQRT_2),
                None,
            ),
            Prefilter::Notch { omega_r_rad_s, d_n } => (
                "notch",
                Some(omega_r_rad_s / (2.0 * PI)),
                Some(d_n),
                Some(1.0 / d_n),
            ),
            Prefilter::None => ("none", None, None, None),
        };
        DriveForm {
            velocity_gain_nm_s_per_rad: des.k_p,
            integral_time_ms: (des.k_i > 0.0).then(|| des.k_p / des.k_i * 1e3),
            position_gain_per_s: des.k_pp,
            position_gain_m_per_min_per_mm: des.k_pp * 60.0 / 1000.0,
            filter_kind: kind.into(),
            filter_frequency_hz: f,
            filter_damping: zeta,
            filter_zero_damping: zero,
            velocity_filter_time_ms: des.input.t_r_s * 1e3,
            ts_ms: des.input.ts_s * 1e3,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::design::{design, DesignInput, DesignKnobs, PrefilterKind};
    use crate::model::TwoMassParams;

    fn table_a4() -> TwoMassParams {
        TwoMassParams::thesis_table_a4()
    }

    /// `T_n = K_P / K_I` by definition; the Butterworth cut-off in Hz is
    /// `w_bw / 2 pi` and its damping `1/sqrt(2)` (the `sqrt(2)/w` of (4.3)).
    #[test]
    fn drive_form_matches_the_definitions() {
        let inp = DesignInput::new(table_a4(), 1e-3);
        for kind in [PrefilterKind::Butterworth, PrefilterKind::Notch] {
            let des = design(
                &inp,
                &DesignKnobs {
                    prefilter: kind,
                    ..DesignKnobs::default()
                },
            )
            .unwrap();
            let f = DriveForm::of(&des);
            let tn = f.integral_time_ms.unwrap() / 1e3;
            assert!((tn * des.k_i / des.k_p - 1.0).abs() < 1e-12);
            assert_eq!(f.position_gain_per_s, des.k_pp);
            let w = 2.0 * PI * f.filter_frequency_hz.unwrap();
            let tf = des.prefilter.tf();
            // the denominator s^2 + 2 zeta w s + w^2 (normalized) has zeta = filter_damping
            let h = tf.freq_response(w);
            match kind {
                PrefilterKind::Butterworth => {
                    // |H(j w_bw)| = 1/sqrt(2) for a 2nd-order Butterworth
                    assert!((h.norm() - 1.0 / SQRT_2).abs() < 1e-12, "{h}");
                }
                _ => {
                    // the notch gain at its centre is zeta_zero / zeta_pole = 1/d_n^2
                    let d = f.filter_damping.unwrap();
                    assert!(
                        (h.norm() - f.filter_zero_damping.unwrap() / d).abs() < 1e-9,
                        "{h}"
                    );
                }
            }
            assert_eq!(f.velocity_filter_time_ms, 2.0);
        }
    }
}
