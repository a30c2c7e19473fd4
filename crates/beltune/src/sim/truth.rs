//! What the simulator knows and a real axis does not: the true two-mass
//! parameters of a simulated plant where it was identified, written beside the
//! identified ones (`commissioning.json` key `truth`, the report's "simulation
//! truth" column) so that the identification's accuracy can be read off.

use crate::model::Plant;
use crate::Result;
use serde::{Deserialize, Serialize};

/// The true values of a simulated plant at the identification position.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Truth {
    /// Resonance frequency, Hz.
    pub f_r_hz: f64,
    /// Antiresonance frequency, Hz.
    pub f_z_hz: f64,
    /// Motor-side inertia, kg m^2.
    pub theta_e: f64,
    /// Moving mass, kg.
    pub m_c: f64,
    /// Belt stiffness, N/m.
    pub c: f64,
    /// Dead time, s.
    pub dead_time_s: f64,
    /// Viscous friction at the motor, N m s/rad.
    #[serde(alias = "viscous")]
    pub viscous_nm_s_per_rad: f64,
    /// Coulomb friction at the motor, N m.
    #[serde(alias = "coulomb")]
    pub coulomb_nm: f64,
}

impl Truth {
    /// The truth of `plant` linearized at the cart position `position_m`
    /// (the identification position), with its friction totals and dead time.
    pub fn of_plant(plant: &Plant, position_m: f64) -> Result<Truth> {
        let p = plant.linearize(position_m)?;
        let friction = plant.friction_totals();
        Ok(Truth {
            f_r_hz: p.f_r_hz(),
            f_z_hz: p.f_z_hz(),
            theta_e: p.theta_e,
            m_c: p.m_c,
            c: p.c,
            dead_time_s: plant.dead_time_s(),
            viscous_nm_s_per_rad: friction.viscous_nm_s_per_rad,
            coulomb_nm: friction.coulomb_nm,
        })
    }
}
