//! How the two-mass model changes along the stroke, from the data sheet's
//! physics: the controller is identified at one cart position but runs at
//! every position of the stroke.
//!
//! A belt axis is softest far from its motor and stiffest near it: the
//! replacement stiffness (2.26) grows several times towards the motor, and
//! with the end pulley the two-mass equivalent's cart mass changes too
//! ([`super::equivalent`]: near the motor the cart moves with the motor on
//! the short span and the end pulley swings against both on the long one).
//! egc120 with 20 kg: `m_c` 22.9 kg and `c` 316 kN/m at the identification
//! position, 12.9 kg and 619 kN/m at the motor end. A controller checked only
//! at the identification position lost 18 deg of phase margin there.
//!
//! The identification calibrates the model at its position; the data sheet
//! gives the shape along the stroke. [`StrokeVariation`] holds, for either
//! end of the stroke, the ratio of the data sheet's two-mass equivalent there
//! to the one at the identification position; [`StrokeVariation::at_ends`]
//! applies them to an identified model. The robust design checks its
//! candidates on these models too
//! ([`crate::design::robust::guaranteed_margins`]).

use super::{Plant, TwoMassParams};
use crate::{Error, Result};
use serde::{Deserialize, Serialize};

/// Largest ratio (and smallest inverse) a stroke end may have against the
/// identification position: (2.26) over a 4 m gantry spans about a factor
/// 20 in stiffness; beyond 100 a file is not describing a belt axis.
pub const STROKE_RATIO_MAX: f64 = 100.0;

/// The two-mass model at one end of the stroke relative to the model at the
/// identification position (dimensionless ratios; `Theta_e` and `i_t` do
/// not change along the stroke).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct StrokeEnd {
    /// Cart position of this end, m.
    pub position_m: f64,
    /// `m_c` there over `m_c` at the identification position.
    pub m_c_ratio: f64,
    /// `c` there over `c` at the identification position.
    pub c_ratio: f64,
    /// Belt damping `d` there over `d` at the identification position.
    pub d_ratio: f64,
}

/// The two-mass model at both ends of the stroke relative to the
/// identification position, from the data sheet's physics.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct StrokeVariation {
    /// Cart position the ratios are relative to (the identification
    /// position), m.
    pub reference_position_m: f64,
    /// The stroke's start (0) and end.
    pub ends: [StrokeEnd; 2],
}

impl StrokeVariation {
    /// The variation of `plant`'s physics (its two-mass equivalent,
    /// [`Plant::true_two_mass`] of the data sheet's values) between
    /// `reference_position_m` and the ends of its stroke; `None` for a
    /// linear set (one model for every position) or where the physics
    /// cannot be evaluated.
    pub fn of(plant: &Plant, reference_position_m: f64) -> Option<StrokeVariation> {
        let stroke = plant.stroke_m()?;
        let reference = plant.true_two_mass(reference_position_m).ok()?;
        let end = |xi: f64| -> Option<StrokeEnd> {
            let m = plant.true_two_mass(xi).ok()?;
            Some(StrokeEnd {
                position_m: xi,
                m_c_ratio: m.m_c / reference.m_c,
                c_ratio: m.c / reference.c,
                d_ratio: if reference.d > 0.0 && m.d > 0.0 {
                    m.d / reference.d
                } else {
                    1.0
                },
            })
        };
        let v = StrokeVariation {
            reference_position_m,
            ends: [end(0.0)?, end(stroke)?],
        };
        v.validate().ok().map(|()| v)
    }

    /// Error unless every ratio is finite, positive and within
    /// [`STROKE_RATIO_MAX`] of one, and the positions are finite.
    pub fn validate(&self) -> Result<()> {
        crate::error::require_finite(
            "stroke_variation.reference_position_m [m]",
            self.reference_position_m,
        )?;
        for e in &self.ends {
            crate::error::require_finite("stroke_variation.ends.position_m [m]", e.position_m)?;
            for (name, r) in [
                ("stroke_variation.ends.m_c_ratio", e.m_c_ratio),
                ("stroke_variation.ends.c_ratio", e.c_ratio),
                ("stroke_variation.ends.d_ratio", e.d_ratio),
            ] {
                if !(r.is_finite() && (1.0 / STROKE_RATIO_MAX..=STROKE_RATIO_MAX).contains(&r)) {
                    return Err(Error::invalid(
                        name,
                        r,
                        format!(
                            "a ratio of the model along the stroke lies between 1/{m} and {m}",
                            m = STROKE_RATIO_MAX
                        ),
                    ));
                }
            }
        }
        Ok(())
    }

    /// `model` (identified at the reference position) carried to both ends
    /// of the stroke: `m_c`, `c` and `d` scaled by each end's ratios.
    pub fn at_ends(&self, model: &TwoMassParams) -> [TwoMassParams; 2] {
        self.ends.map(|e| TwoMassParams {
            m_c: model.m_c * e.m_c_ratio,
            c: model.c * e.c_ratio,
            d: model.d * e.d_ratio,
            ..*model
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::builtin;

    /// Carried to the ends, the data sheet's own model at the reference is
    /// its model at the ends (the ratios are exact for the data sheet), and
    /// the motor end is the stiffer one.
    #[test]
    fn the_data_sheets_model_carried_to_the_ends_is_its_model_there() {
        let plant = builtin("egc70", None).unwrap();
        let at = 0.5;
        let v = StrokeVariation::of(&plant, at).unwrap();
        let reference = plant.true_two_mass(at).unwrap();
        let ends = v.at_ends(&reference);
        for (e, m) in v.ends.iter().zip(ends) {
            let truth = plant.true_two_mass(e.position_m).unwrap();
            for (a, b) in [(m.f_r_hz(), truth.f_r_hz()), (m.f_z_hz(), truth.f_z_hz())] {
                assert!((a / b - 1.0).abs() < 1e-12, "{a} vs {b}");
            }
        }
        assert!(v.ends[0].c_ratio > 1.2, "{v:?}");
        assert_eq!(v.ends[1].position_m, 0.6);
    }

    #[test]
    fn a_linear_set_has_one_model_for_the_whole_stroke() {
        assert!(StrokeVariation::of(&builtin("sim-a", None).unwrap(), 0.3).is_none());
    }

    #[test]
    fn absurd_ratios_are_refused_naming_the_key() {
        let plant = builtin("egc70", None).unwrap();
        let mut v = StrokeVariation::of(&plant, 0.5).unwrap();
        v.ends[1].c_ratio = 1e308;
        assert!(v.validate().unwrap_err().to_string().contains("c_ratio"));
        v.ends[1].c_ratio = f64::NAN;
        assert!(v.validate().is_err());
    }
}
