//! One-knob mode: a single "dynamics" setting `x` in `[0, 1]` (or the presets
//! conservative = 0, standard = 0.5, dynamic = 1) that orders the delivered
//! designs from slow to fast. It acts on both design rules:
//!
//! - **The robust rule** (the commissioning's default,
//!   [`super::robust::robust_design`]): `x` sets the margins the design must
//!   keep over the identification's uncertainty box,
//!   `phi_v >= 55 - 20 x` deg and `phi_p >= 70 - 20 x` deg
//!   ([`Dynamics::guaranteed_velocity_phase_margin_deg`]): 55/70 deg
//!   conservative, 45/60 deg standard, 35/50 deg dynamic. The candidates
//!   (prefilters, nominal margins) do not depend on `x`, so a larger `x`
//!   admits a superset of them and the fastest admissible design can only
//!   get faster. The default of every command is standard.
//! - **The thesis' conditions with explicit knobs** ([`super::design`]):
//!   `x` sets the three loop specifications together,
//!
//! | x | velocity PM | position PM | `A_sup` |
//! | --- | --- | --- | --- |
//! | 0 (conservative) | 70 deg | 85 deg | -14 dB |
//! | 0.5 (standard) | 60 deg | 80 deg | -10 dB |
//! | 1 (dynamic) | 50 deg | 75 deg | -6 dB |
//!
//! linearly in between: `pm_v = 70 - 20 x`, `pm_p = 85 - 10 x`, `A_sup = -14 + 8 x`.
//! "standard" is the thesis' setting (Tables A.6/A.7). Moving towards
//! "dynamic" lowers both phase margins and relaxes the resonance suppression.
//! The prefilter and its attenuation are not changed by the knob.

use super::DesignKnobs;
use crate::{Error, Result};

/// The one-knob setting, a validated value in `[0, 1]` (default: standard).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Dynamics(f64);

impl Default for Dynamics {
    fn default() -> Self {
        Dynamics::STANDARD
    }
}

impl Dynamics {
    /// Preset "conservative" (x = 0).
    pub const CONSERVATIVE: Dynamics = Dynamics(0.0);
    /// Preset "standard" (x = 0.5, the thesis' design).
    pub const STANDARD: Dynamics = Dynamics(0.5);
    /// Preset "dynamic" (x = 1).
    pub const DYNAMIC: Dynamics = Dynamics(1.0);

    /// A slider value in `[0, 1]`.
    pub fn new(x: f64) -> Result<Self> {
        if (0.0..=1.0).contains(&x) {
            Ok(Dynamics(x))
        } else {
            Err(Error::invalid("dynamics", x, "must lie in [0, 1]"))
        }
    }

    /// The slider value.
    pub fn value(self) -> f64 {
        self.0
    }

    /// The knobs for this setting, starting from `base` (prefilter and filter
    /// attenuation are kept; the setting itself is recorded in
    /// [`DesignKnobs::dynamics`] for the robust rule).
    pub fn knobs(self, base: &DesignKnobs) -> DesignKnobs {
        let x = self.0;
        DesignKnobs {
            pm_velocity_deg: 70.0 - 20.0 * x,
            pm_position_deg: 85.0 - 10.0 * x,
            resonance_suppression_db: -14.0 + 8.0 * x,
            dynamics: self,
            ..*base
        }
    }

    /// Velocity-loop phase margin the robust rule guarantees over the
    /// identification's uncertainty box, deg: `55 - 20 x` (45 deg standard).
    pub fn guaranteed_velocity_phase_margin_deg(self) -> f64 {
        55.0 - 20.0 * self.0
    }

    /// Position-loop phase margin the robust rule guarantees over the box,
    /// deg: `70 - 20 x` (60 deg standard; a position loop below 50 deg
    /// overshoots its target visibly).
    pub fn guaranteed_position_phase_margin_deg(self) -> f64 {
        70.0 - 20.0 * self.0
    }

    /// Velocity-loop gain margin the robust rule guarantees over the box,
    /// dB: `8 - 4 x` (6 dB standard, the margin a lightly damped resonance
    /// needs against a resonance damping the friction made look larger
    /// than it is).
    pub fn guaranteed_velocity_gain_margin_db(self) -> f64 {
        8.0 - 4.0 * self.0
    }
}

impl std::str::FromStr for Dynamics {
    type Err = Error;
    /// `conservative`, `standard`, `dynamic` or a number in `[0, 1]`.
    fn from_str(s: &str) -> Result<Self> {
        match s.to_ascii_lowercase().as_str() {
            "conservative" => Ok(Dynamics::CONSERVATIVE),
            "standard" => Ok(Dynamics::STANDARD),
            "dynamic" => Ok(Dynamics::DYNAMIC),
            other => match other.parse::<f64>() {
                Ok(x) => Dynamics::new(x),
                Err(_) => Err(Error::Parse {
                    path: "dynamics".into(),
                    message: format!(
                        "`{s}` is neither conservative, standard, dynamic nor a number in [0, 1]"
                    ),
                }),
            },
        }
    }
}
