//! What the simulator knows and a real axis does not: the true two-mass
//! parameters of a simulated plant where it was identified, written beside the
//! identified ones (`commissioning.json` key `truth`, the report's "simulation
//! truth" column) so that the identification's accuracy can be read off.
//! For a physical plant the truth is the simulator's three-mass physics, end
//! pulley included ([`crate::model::equivalent`]): the two-mass reduction of
//! thesis 2.1.4 neglects the end pulley's inertia and put egc70's `f_z` 5 %
//! and `m_c` 14 % away from what the simulated axis does.

use crate::model::Plant;
use crate::Result;
use serde::{Deserialize, Serialize};

/// The true values of a simulated plant at the identification position.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Truth {
    /// Resonance frequency (lowest of the three-mass physics), Hz.
    pub f_r_hz: f64,
    /// Antiresonance frequency (lowest of the three-mass physics), Hz.
    pub f_z_hz: f64,
    /// Motor-side inertia, kg m^2.
    pub theta_e: f64,
    /// Moving mass, kg: for a physical plant the two-mass equivalent with the
    /// physics' `f_r`, `f_z` and the data-sheet `Theta_e` (cart and payload
    /// plus the end pulley's share).
    pub m_c: f64,
    /// Belt stiffness, N/m (two-mass equivalent, as `m_c`).
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
    /// The truth of `plant` at the cart position `position_m` (the
    /// identification position, [`Plant::true_two_mass`]), with its friction
    /// totals and dead time.
    pub fn of_plant(plant: &Plant, position_m: f64) -> Result<Truth> {
        let p = plant.true_two_mass(position_m)?;
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::rigs;

    /// `truth` is the simulator's physics: on egc70 (with and without
    /// payload, at the worst case) its `f_r` and `f_z` are where the
    /// three-mass model's frequency response peaks and dips
    /// ([`crate::model::equivalent::swept_modes`], an independent sweep),
    /// within 1 % (the sweep's grid, 0.05 %, and the shift of the damped
    /// response's peak and dip by egc70's belt damping and viscous friction,
    /// measured 0.4 %); without payload the two-mass reduction without the
    /// end pulley is further away from the dip than twice that.
    #[test]
    fn truth_includes_the_end_pulley() {
        for payload in [0.0, 11.2] {
            let plant = rigs::builtin("egc70", Some(payload)).unwrap();
            let Plant::Physical(p) = &plant else {
                unreachable!()
            };
            let t = Truth::of_plant(&plant, 0.6).unwrap();
            let (f_z, f_r) = crate::model::equivalent::swept_modes(p, 0.6);
            let rel = |a: f64, b: f64| (a / b - 1.0).abs();
            assert!(rel(t.f_r_hz, f_r) < 1e-2, "f_r {} vs {f_r}", t.f_r_hz);
            assert!(rel(t.f_z_hz, f_z) < 1e-2, "f_z {} vs {f_z}", t.f_z_hz);
            // the end pulley matters on the light cart (0.15 kg at the belt
            // against 0.96 kg), hardly with 11.2 kg on it
            let reduced = plant.linearize(0.6).unwrap();
            if payload == 0.0 {
                assert!(
                    rel(reduced.f_z_hz(), f_z) > 2e-2,
                    "{} vs {f_z}",
                    reduced.f_z_hz()
                );
            }
        }
    }
}
