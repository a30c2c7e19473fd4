//! The nonlinear two-mass-spring-damper model (2.30): (2.25a)/(2.25b) with the
//! position-dependent replacement stiffness `c(xi)` (2.26) and damping (2.27),
//! Coulomb and viscous friction (2.21)/(2.23) and gravity (2.22).
//!
//! State (2.28): `x = [phi_m, omega_m, xi, xi']`, input (2.29) `u = tau_m`.
//! The end pulley is neglected (thesis 2.1.4); its friction is counted on the
//! motor side (rigid belt between the pulleys), so the friction totals (3.36)
//! equal those of the three-mass model.

// `sign` with `sign(0) = 0`, as the friction models (2.21), (2.23) need.
use crate::model::params::PhysicalParams;
use crate::Result;
use beltune_rt::Real;

/// The state (2.28).
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct TwoMassState {
    /// `phi_m`: motor angle, rad.
    pub phi_m_rad: f64,
    /// `omega_m`: motor velocity, rad/s.
    pub omega_m_rad_s: f64,
    /// `xi`: cart position, m.
    pub xi_m: f64,
    /// `xi'`: cart velocity, m/s.
    pub xi_dot_m_s: f64,
}

/// The nonlinear two-mass model of an axis (2.30).
#[derive(Clone, Debug, PartialEq)]
pub struct NonlinearTwoMass {
    params: PhysicalParams,
}

impl NonlinearTwoMass {
    /// The model of validated parameters.
    pub fn new(params: &PhysicalParams) -> Result<Self> {
        params.validate()?;
        Ok(NonlinearTwoMass {
            params: params.clone(),
        })
    }

    /// The parameters.
    pub fn params(&self) -> &PhysicalParams {
        &self.params
    }

    /// Motor-side viscous friction, translational equivalent incl. the end pulley, N s/m.
    pub fn d_m_n_s_per_m(&self) -> f64 {
        self.params.d_m_n_s_per_m + self.params.d_end_pulley_n_s_per_m
    }

    /// Motor-side Coulomb torque incl. the end pulley reflected through `i_g`, N m.
    pub fn tau_c_nm(&self) -> f64 {
        self.params.tau_c_motor_nm + self.params.tau_c_end_pulley_nm / self.params.i_g
    }

    /// Right-hand side `f(x, u)` of (2.30) (`sign(0) = 0`).
    pub fn derivative(&self, x: &TwoMassState, tau_m_nm: f64) -> TwoMassState {
        let p = &self.params;
        let it = p.i_t();
        let seg = p.belt_segments(x.xi_m);
        let c = seg.replacement_stiffness_n_per_m();
        let d = seg.replacement_damping_n_s_per_m();
        let tau_mr = -it * it * self.d_m_n_s_per_m() * x.omega_m_rad_s
            - self.tau_c_nm() * Real::sign(x.omega_m_rad_s);
        let f = -p.d_c_n_s_per_m * x.xi_dot_m_s - p.f_c_cart_n * Real::sign(x.xi_dot_m_s)
            + p.gravity_force_n();
        let stretch = it * x.phi_m_rad - x.xi_m;
        let stretch_rate = it * x.omega_m_rad_s - x.xi_dot_m_s;
        TwoMassState {
            phi_m_rad: x.omega_m_rad_s,
            omega_m_rad_s: (tau_m_nm + tau_mr - it * c * stretch - it * d * stretch_rate)
                / p.theta_e(),
            xi_m: x.xi_dot_m_s,
            xi_dot_m_s: (f + c * stretch + d * stretch_rate) / p.m_c(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::rigs::egc70_params;
    use crate::model::TwoMassParams;

    /// Without Coulomb friction and gravity, (2.30) is the linear model (2.33)
    /// with the transfer-function convention for `d_m`: compare the right-hand
    /// side with `A x + b u` built from (2.38)'s equations of motion.
    #[test]
    fn matches_linear_model_without_coulomb() {
        let p = PhysicalParams {
            tau_c_motor_nm: 0.0,
            f_c_cart_n: 0.0,
            tau_c_end_pulley_nm: 0.0,
            ..egc70_params(11.2)
        };
        let m = NonlinearTwoMass::new(&p).unwrap();
        let xi = 0.25;
        let lin: TwoMassParams = p.linearize(xi).unwrap();
        let x = TwoMassState {
            phi_m_rad: 20.0,
            omega_m_rad_s: -3.0,
            xi_m: xi,
            xi_dot_m_s: 0.2,
        };
        let u = 0.7;
        let f = m.derivative(&x, u);
        let it = lin.i_t;
        let stretch = it * x.phi_m_rad - x.xi_m;
        let rate = it * x.omega_m_rad_s - x.xi_dot_m_s;
        let om =
            (u - it * it * lin.d_m * x.omega_m_rad_s - it * lin.c * stretch - it * lin.d * rate)
                / lin.theta_e;
        let xd = (-lin.d_c * x.xi_dot_m_s + lin.c * stretch + lin.d * rate) / lin.m_c;
        assert!((f.omega_m_rad_s - om).abs() < 1e-9 * om.abs().max(1.0));
        assert!((f.xi_dot_m_s - xd).abs() < 1e-9 * xd.abs().max(1.0));
    }

    /// Gravity (2.22) acts on the cart only: at rest, unstretched, no torque.
    #[test]
    fn gravity_pulls_the_cart_down_the_slope() {
        let p = PhysicalParams {
            tilt_rad: 0.3,
            ..egc70_params(11.2)
        };
        let m = NonlinearTwoMass::new(&p).unwrap();
        let x = TwoMassState {
            phi_m_rad: 0.1 / p.i_t(),
            xi_m: 0.1,
            ..Default::default()
        };
        let f = m.derivative(&x, 0.0);
        assert!((f.xi_dot_m_s + super::super::params::GRAVITY_M_S2 * 0.3f64.sin()).abs() < 1e-12);
        assert_eq!(f.omega_m_rad_s, 0.0);
    }
}
