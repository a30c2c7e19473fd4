//! Torque feedforward (4.16): `tau_FF = m_e alpha_d + d_v omega_d + tau_c sign(omega_d)`,
//! each term switchable so that the "no", "linear" and "nonlinear" feedforward of
//! chapter 5 can be compared.
//!
//! The thesis' *linear* feedforward approximates the friction by a viscous term
//! only (fitted without a Coulomb part), so [`Feedforward::linear`] and
//! [`Feedforward::nonlinear`] take their own coefficient values.

use crate::error::Error;
use crate::Real;

/// Default half-width of the velocity dead band of the Coulomb term, in rad/s.
///
/// Inside `|omega_d| <= deadband` the Coulomb feedforward is zero, so that a
/// desired velocity that is zero up to rounding (a trajectory at standstill)
/// does not make the feedforward chatter between `+tau_c` and `-tau_c`.
/// `1e-3 rad/s` is 12 um/s at the cart for `i_t = 12.4 mm/rad`; a 40 m/s^3
/// jerk-limited start leaves the band within 8 samples of 100 us.
pub const DEFAULT_COULOMB_DEADBAND_RAD_S: f64 = 1e-3;

/// Coefficients of (4.15)/(4.16), all in motor coordinates.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FeedforwardParams<T = f64> {
    /// `m_e~ = Theta_e + i_t^2 m_c` in kg m^2 (4.15): acceleration -> torque.
    pub inertia_kg_m2: T,
    /// `d_v~` in N m s/rad: velocity -> viscous torque.
    pub viscous_nm_s_per_rad: T,
    /// `tau_c~` in N m: Coulomb friction torque.
    pub coulomb_nm: T,
    /// Half-width of the dead band of `sign(omega_d)` in rad/s
    /// (see [`DEFAULT_COULOMB_DEADBAND_RAD_S`]).
    pub coulomb_deadband_rad_s: T,
    /// Breakaway threshold of the Coulomb hold, rad (refinement (c) of
    /// [`crate::control::cascade`]): with the trajectory at rest, a position
    /// error `|phi_d - phi_m|` beyond it engages the hold toward the target.
    /// `0` switches the breakaway off (the hold then only completes a move).
    pub coulomb_breakaway_rad: T,
}

impl<T: Real> Default for FeedforwardParams<T> {
    /// All coefficients zero, default dead band.
    fn default() -> Self {
        FeedforwardParams {
            inertia_kg_m2: T::ZERO,
            viscous_nm_s_per_rad: T::ZERO,
            coulomb_nm: T::ZERO,
            coulomb_deadband_rad_s: T::from_f64(DEFAULT_COULOMB_DEADBAND_RAD_S),
            coulomb_breakaway_rad: T::ZERO,
        }
    }
}

/// Which terms of (4.16) are active.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub struct FeedforwardTerms {
    /// `m_e alpha_d`.
    pub inertia: bool,
    /// `d_v omega_d`.
    pub viscous: bool,
    /// `tau_c sign(omega_d)` with dead band.
    pub coulomb: bool,
}

/// The torque feedforward (4.16): coefficients plus term switches.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Feedforward<T = f64> {
    /// Coefficients.
    pub params: FeedforwardParams<T>,
    /// Active terms.
    pub terms: FeedforwardTerms,
}

impl<T: Real> Default for Feedforward<T> {
    /// No feedforward: all terms off, coefficients zero.
    fn default() -> Self {
        Feedforward {
            params: FeedforwardParams::default(),
            terms: FeedforwardTerms::default(),
        }
    }
}

impl<T: Real> Feedforward<T> {
    /// No feedforward (`tau_FF = 0`), chapter 5 "without feedforward".
    pub fn none() -> Self {
        Self::default()
    }

    /// Chapter 5 "linear" feedforward: inertia and a viscous term fitted
    /// without Coulomb friction.
    pub fn linear(inertia_kg_m2: T, viscous_nm_s_per_rad: T) -> Self {
        Feedforward {
            params: FeedforwardParams {
                inertia_kg_m2,
                viscous_nm_s_per_rad,
                ..FeedforwardParams::default()
            },
            terms: FeedforwardTerms {
                inertia: true,
                viscous: true,
                coulomb: false,
            },
        }
    }

    /// Chapter 5 "nonlinear" feedforward: inertia, viscous and Coulomb friction
    /// (Table A.10-style friction from Section 3.6), default dead band.
    pub fn nonlinear(inertia_kg_m2: T, viscous_nm_s_per_rad: T, coulomb_nm: T) -> Self {
        Feedforward {
            params: FeedforwardParams {
                inertia_kg_m2,
                viscous_nm_s_per_rad,
                coulomb_nm,
                ..FeedforwardParams::default()
            },
            terms: FeedforwardTerms {
                inertia: true,
                viscous: true,
                coulomb: true,
            },
        }
    }

    /// Check that every coefficient is finite and `>= 0`.
    pub fn validate(&self) -> Result<(), Error> {
        let p = &self.params;
        for (name, v) in [
            ("feedforward.inertia_kg_m2", p.inertia_kg_m2),
            ("feedforward.viscous_nm_s_per_rad", p.viscous_nm_s_per_rad),
            ("feedforward.coulomb_nm", p.coulomb_nm),
            (
                "feedforward.coulomb_deadband_rad_s",
                p.coulomb_deadband_rad_s,
            ),
            ("feedforward.coulomb_breakaway_rad", p.coulomb_breakaway_rad),
        ] {
            if !(v.is_finite() && v >= T::ZERO) {
                return Err(Error::InvalidParameter {
                    name,
                    reason: "must be finite and >= 0",
                });
            }
        }
        Ok(())
    }

    /// The coefficients with switched-off terms set to zero.
    pub fn effective(&self) -> FeedforwardParams<T> {
        let p = self.params;
        let on = |b: bool, v: T| if b { v } else { T::ZERO };
        FeedforwardParams {
            inertia_kg_m2: on(self.terms.inertia, p.inertia_kg_m2),
            viscous_nm_s_per_rad: on(self.terms.viscous, p.viscous_nm_s_per_rad),
            coulomb_nm: on(self.terms.coulomb, p.coulomb_nm),
            coulomb_deadband_rad_s: p.coulomb_deadband_rad_s,
            coulomb_breakaway_rad: p.coulomb_breakaway_rad,
        }
    }

    /// The feedforward torque (4.16) in N m for a desired velocity (rad/s) and
    /// acceleration (rad/s^2).
    pub fn torque_nm(&self, velocity_rad_s: T, acceleration_rad_s2: T) -> T {
        self.effective()
            .torque_nm(velocity_rad_s, acceleration_rad_s2)
    }

    /// The same feedforward in another scalar type.
    pub fn cast<U: Real>(&self) -> Feedforward<U> {
        let p = &self.params;
        Feedforward {
            params: FeedforwardParams {
                inertia_kg_m2: U::from_f64(p.inertia_kg_m2.to_f64()),
                viscous_nm_s_per_rad: U::from_f64(p.viscous_nm_s_per_rad.to_f64()),
                coulomb_nm: U::from_f64(p.coulomb_nm.to_f64()),
                coulomb_deadband_rad_s: U::from_f64(p.coulomb_deadband_rad_s.to_f64()),
                coulomb_breakaway_rad: U::from_f64(p.coulomb_breakaway_rad.to_f64()),
            },
            terms: self.terms,
        }
    }
}

impl<T: Real> FeedforwardParams<T> {
    /// (4.16) with all three terms: `m_e alpha + d_v omega + tau_c sign_db(omega)`,
    /// where `sign_db` is 0 inside the dead band. Cost: 2 multiplications,
    /// 3 additions, 2 comparisons.
    #[inline]
    pub fn torque_nm(&self, velocity_rad_s: T, acceleration_rad_s2: T) -> T {
        let coulomb = if velocity_rad_s > self.coulomb_deadband_rad_s {
            self.coulomb_nm
        } else if velocity_rad_s < -self.coulomb_deadband_rad_s {
            -self.coulomb_nm
        } else {
            T::ZERO
        };
        self.inertia_kg_m2 * acceleration_rad_s2
            + self.viscous_nm_s_per_rad * velocity_rad_s
            + coulomb
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn presets_switch_the_terms_of_4_16() {
        let (m, d, c) = (2.14e-3, 2.53e-3, 0.125);
        let (v, a) = (30.0, 1000.0);
        assert_eq!(Feedforward::<f64>::none().torque_nm(v, a), 0.0);
        let lin = Feedforward::linear(m, 5e-3).torque_nm(v, a);
        assert!((lin - (m * a + 5e-3 * v)).abs() < 1e-15);
        let nl = Feedforward::nonlinear(m, d, c);
        assert!((nl.torque_nm(v, a) - (m * a + d * v + c)).abs() < 1e-15);
        assert!((nl.torque_nm(-v, -a) + (m * a + d * v + c)).abs() < 1e-15);
        let mut only_coulomb = nl;
        only_coulomb.terms.inertia = false;
        only_coulomb.terms.viscous = false;
        assert_eq!(only_coulomb.torque_nm(v, a), c);
    }

    #[test]
    fn coulomb_term_is_zero_inside_the_dead_band() {
        let nl = Feedforward::nonlinear(0.0, 0.0, 0.125);
        let band = DEFAULT_COULOMB_DEADBAND_RAD_S;
        for v in [0.0, 1e-15, -1e-15, 0.5 * band, -band] {
            assert_eq!(nl.torque_nm(v, 0.0), 0.0, "v = {v}");
        }
        assert_eq!(nl.torque_nm(2.0 * band, 0.0), 0.125);
        assert_eq!(nl.torque_nm(-2.0 * band, 0.0), -0.125);
    }

    #[test]
    fn negative_or_non_finite_coefficients_are_rejected() {
        assert!(Feedforward::nonlinear(1.0, -1.0, 0.0).validate().is_err());
        assert!(Feedforward::linear(f64::NAN, 0.0).validate().is_err());
        assert!(Feedforward::nonlinear(1e-3, 1e-3, 0.1).validate().is_ok());
    }
}
