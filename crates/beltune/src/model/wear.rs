//! Ageing of a belt axis (the `[wear]` table of a physical plant file): what
//! a health check ([`crate::health`]) has to find. All zero (the default) is
//! a new axis: the plant is exactly the plant without the table.
//!
//! | key | what ages | in the model |
//! | --- | --- | --- |
//! | `belt_stiffness_loss` | belt tension loss: a toothed belt that lost pretension seats its teeth less firmly | the specific belt stiffness `c_b` (2.10) times `1 - x`, so every segment and the replacement stiffness (2.26) lose the fraction `x` |
//! | `friction_growth` | friction growth: dry or contaminated lubricant, bearings | every friction coefficient (Coulomb and viscous, motor, end pulley, cart; (2.21), (2.23)) times `1 + x` |
//! | `belt_pretension_n` | a slack span: the pretension has dropped below the forces the belt carries | each span of the three-mass model (2.20) carries `T = P + c e + d e'` (`e` its elongation); a belt cannot push, so a span whose `T` would fall below zero carries nothing: the stiffness drops with the amplitude |
//! | `guide_wear_n`, `guide_wear_section_m` | a worn guide: the cart rubs where the rail is worn | extra Coulomb friction of the cart (2.23) over the worn section of the stroke |
//!
//! Without a pretension the spans are taut at any load (the linear springs
//! of (2.20), whose pretension cancels around the closed belt).

use crate::error::require_range;
use crate::Result;

/// Ageing of a physical plant (see the module docs). Units in the names;
/// `Default` (all zero, no pretension) is a new axis.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Wear {
    /// Belt tension loss, as the fraction of the belt stiffness `c_b` it
    /// costs (0 new, at most [`MAX_STIFFNESS_LOSS`]).
    pub belt_stiffness_loss: f64,
    /// Friction growth: every friction coefficient times `1 + x` (0 new, at
    /// most [`MAX_FRICTION_GROWTH`]).
    pub friction_growth: f64,
    /// Pretension of the belt, N: a span whose tension would fall below
    /// zero goes slack (`None`: the spans never slacken, a new belt).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub belt_pretension_n: Option<f64>,
    /// Worn guide: extra Coulomb friction of the cart on the worn section, N.
    pub guide_wear_n: f64,
    /// The worn section of the guide, cart positions `[from, to]`, m
    /// (`None`: the whole stroke).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub guide_wear_section_m: Option<(f64, f64)>,
}

/// Largest `belt_stiffness_loss`: a belt with a tenth of its stiffness left
/// is no longer an axis.
pub const MAX_STIFFNESS_LOSS: f64 = 0.9;
/// Largest `friction_growth`: eleven times the friction.
pub const MAX_FRICTION_GROWTH: f64 = 10.0;
/// Smallest pretension, N (below it the belt slackens at rest).
pub const MIN_PRETENSION_N: f64 = 1e-3;
/// Largest pretension, N.
pub const MAX_PRETENSION_N: f64 = 1e6;

impl Wear {
    /// Whether nothing has aged (the default): the plant file leaves the table out.
    pub fn is_new(&self) -> bool {
        *self == Wear::default()
    }

    /// The factor of the belt stiffness `c_b`, `1 - belt_stiffness_loss`.
    pub fn stiffness_factor(&self) -> f64 {
        1.0 - self.belt_stiffness_loss
    }

    /// The factor of every friction coefficient, `1 + friction_growth`.
    pub fn friction_factor(&self) -> f64 {
        1.0 + self.friction_growth
    }

    /// Whether cart position `xi_m` lies on the worn section of the guide.
    pub fn on_worn_guide(&self, xi_m: f64) -> bool {
        match self.guide_wear_section_m {
            None => true,
            Some((from, to)) => (from..=to).contains(&xi_m),
        }
    }

    /// The cart's extra Coulomb friction at `xi_m`, N.
    pub fn guide_friction_n(&self, xi_m: f64) -> f64 {
        if self.guide_wear_n > 0.0 && self.on_worn_guide(xi_m) {
            self.guide_wear_n
        } else {
            0.0
        }
    }

    /// Typed error for a value out of range; `stroke_m` bounds the worn section.
    pub fn validate(&self, stroke_m: f64) -> Result<()> {
        require_range(
            "wear.belt_stiffness_loss",
            self.belt_stiffness_loss,
            0.0,
            MAX_STIFFNESS_LOSS,
        )?;
        require_range(
            "wear.friction_growth",
            self.friction_growth,
            0.0,
            MAX_FRICTION_GROWTH,
        )?;
        if let Some(p) = self.belt_pretension_n {
            require_range(
                "wear.belt_pretension_n",
                p,
                MIN_PRETENSION_N,
                MAX_PRETENSION_N,
            )?;
        }
        require_range(
            "wear.guide_wear_n",
            self.guide_wear_n,
            0.0,
            super::params::bounds::FORCE_MAX_N,
        )?;
        if let Some((from, to)) = self.guide_wear_section_m {
            if !(from.is_finite() && to.is_finite() && 0.0 <= from && from < to && to <= stroke_m) {
                return Err(crate::Error::invalid(
                    "wear.guide_wear_section_m",
                    if from.is_finite() { to } else { from },
                    format!("the worn section [from, to] must lie inside the stroke [0, {stroke_m}] m with from < to"),
                ));
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_new_axis_has_no_wear_and_bad_values_are_refused() {
        let w = Wear::default();
        assert!(w.is_new() && w.validate(0.6).is_ok());
        assert_eq!((w.stiffness_factor(), w.friction_factor()), (1.0, 1.0));
        assert_eq!(w.guide_friction_n(0.3), 0.0);
        for (bad, name) in [
            (
                Wear {
                    belt_stiffness_loss: 0.95,
                    ..w
                },
                "wear.belt_stiffness_loss",
            ),
            (
                Wear {
                    friction_growth: -0.1,
                    ..w
                },
                "wear.friction_growth",
            ),
            (
                Wear {
                    belt_pretension_n: Some(0.0),
                    ..w
                },
                "wear.belt_pretension_n",
            ),
            (
                Wear {
                    guide_wear_n: f64::NAN,
                    ..w
                },
                "wear.guide_wear_n",
            ),
            (
                Wear {
                    guide_wear_section_m: Some((0.4, 0.2)),
                    ..w
                },
                "wear.guide_wear_section_m",
            ),
            (
                Wear {
                    guide_wear_section_m: Some((0.1, 0.7)),
                    ..w
                },
                "wear.guide_wear_section_m",
            ),
        ] {
            match bad.validate(0.6) {
                Err(crate::Error::InvalidParameter { name: n, .. }) => assert_eq!(n, name),
                other => panic!("{name}: {other:?}"),
            }
        }
        let worn = Wear {
            guide_wear_n: 5.0,
            guide_wear_section_m: Some((0.2, 0.4)),
            ..w
        };
        assert_eq!(worn.guide_friction_n(0.3), 5.0);
        assert_eq!(worn.guide_friction_n(0.5), 0.0);
    }
}
