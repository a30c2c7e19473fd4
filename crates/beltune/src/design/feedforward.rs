//! Feedforward (thesis 4.4, (4.15)-(4.17)): rigid-body inertia from the FRF fit,
//! viscous and Coulomb friction from the friction identification (Section 3.6;
//! docs/thesis-map.md: the FRF fit's `d_m`, `d_c` are small-signal damping, not friction).

use crate::error::require_non_negative;
use crate::model::TwoMassParams;
use crate::Result;

/// Friction seen by the motor, from the constant-velocity runs of Section 3.6 (Table A.10).
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct FrictionParams {
    /// Viscous friction `d_v~`, N m s/rad.
    pub viscous_nm_s_per_rad: f64,
    /// Coulomb friction `tau_c~`, N m.
    pub coulomb_nm: f64,
}

impl FrictionParams {
    /// Typed error for negative, non-finite or implausibly large values
    /// (above [`crate::model::params::bounds::TORQUE_MAX_NM`] N m, or N m s/rad).
    pub fn validate(&self) -> Result<()> {
        require_non_negative("viscous friction [N m s/rad]", self.viscous_nm_s_per_rad)?;
        require_non_negative("coulomb friction [N m]", self.coulomb_nm)?;
        let max = crate::model::params::bounds::TORQUE_MAX_NM;
        crate::error::require_range(
            "viscous friction [N m s/rad]",
            self.viscous_nm_s_per_rad,
            0.0,
            max,
        )?;
        crate::error::require_range("coulomb friction [N m]", self.coulomb_nm, 0.0, max)?;
        Ok(())
    }
}

/// Feedforward parameters of (4.16)/(4.17):
/// `tau_FF = m_e omega_d' + d_v omega_d + tau_c sign(omega_d)`, `K_v = 1`.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Feedforward {
    /// `m_e~ = Theta_e + i_t^2 m_c` (4.15), kg m^2.
    pub inertia_kg_m2: f64,
    /// `d_v~`, N m s/rad.
    pub viscous_nm_s_per_rad: f64,
    /// `tau_c~`, N m.
    pub coulomb_nm: f64,
    /// Velocity feedforward gain `K_v` (4.17), dimensionless (always 1, (B.7)).
    pub k_v: f64,
}

impl Feedforward {
    /// (4.15)-(4.17) from the model and the identified friction (zero friction if `None`:
    /// linear inertia-only feedforward).
    pub fn design(model: &TwoMassParams, friction: Option<&FrictionParams>) -> Result<Self> {
        model.validate()?;
        let f = friction.copied().unwrap_or_default();
        f.validate()?;
        Ok(Feedforward {
            inertia_kg_m2: model.rigid_inertia(),
            viscous_nm_s_per_rad: f.viscous_nm_s_per_rad,
            coulomb_nm: f.coulomb_nm,
            k_v: 1.0,
        })
    }

    /// The feedforward torque (4.16) for a desired motor speed and acceleration.
    pub fn torque_nm(&self, omega_d_rad_s: f64, alpha_d_rad_s2: f64) -> f64 {
        let sign = if omega_d_rad_s > 0.0 {
            1.0
        } else if omega_d_rad_s < 0.0 {
            -1.0
        } else {
            0.0
        };
        self.inertia_kg_m2 * alpha_d_rad_s2
            + self.viscous_nm_s_per_rad * omega_d_rad_s
            + self.coulomb_nm * sign
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// docs/thesis-map.md: (4.15) with Table A.4 gives 2.14e-3 kg m^2 (the table's 0.02 is a typo).
    #[test]
    fn table_a4_inertia_and_table_a10_friction() {
        let fr = FrictionParams {
            viscous_nm_s_per_rad: 2.530e-3,
            coulomb_nm: 0.125,
        };
        let ff = Feedforward::design(&TwoMassParams::thesis_table_a4(), Some(&fr)).unwrap();
        assert!(
            (ff.inertia_kg_m2 - 2.14e-3).abs() < 0.005e-3,
            "{}",
            ff.inertia_kg_m2
        );
        assert_eq!(ff.k_v, 1.0);
        // 100 rad/s, 1000 rad/s^2: 2.14 + 0.253 + 0.125 N m
        let t = ff.torque_nm(100.0, 1000.0);
        assert!((t - (ff.inertia_kg_m2 * 1000.0 + 0.253 + 0.125)).abs() < 1e-12);
        assert!((ff.torque_nm(-1.0, 0.0) + 2.530e-3 + 0.125).abs() < 1e-12);
        let bad = FrictionParams {
            viscous_nm_s_per_rad: -1.0,
            coulomb_nm: 0.0,
        };
        assert!(Feedforward::design(&TwoMassParams::thesis_table_a4(), Some(&bad)).is_err());
    }
}
