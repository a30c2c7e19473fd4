//! The linear two-mass-spring-damper model (2.33) and its transfer functions
//! (2.38)-(2.49), with resonance, antiresonance, inertia ratio and resonance
//! ratio (2.44)-(2.47).
//!
//! Convention (docs/thesis-map.md): `d_m` is a translational equivalent in N s/m; the
//! motor viscous torque is `i_t^2 d_m omega_m`. With it the coefficients
//! (2.38b)-(2.38h) follow exactly from the equations of motion
//!
//! ```text
//! Theta_e phi''  = tau - i_t^2 d_m phi' - i_t c (i_t phi - xi) - i_t d (i_t phi' - xi')
//! m_c     xi''   =     - d_c xi'       +     c (i_t phi - xi) +     d (i_t phi' - xi')
//! ```

use crate::error::{require_non_negative, require_positive};
use crate::lti::{Poly, Tf};
use crate::Result;
use std::f64::consts::PI;

/// Parameters of the linear two-mass model (thesis Table A.4 layout).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct TwoMassParams {
    /// `Theta_e`: motor-side replacement inertia (motor, coupling, gearbox, driving pulley), kg m^2.
    pub theta_e: f64,
    /// `m_c`: moving mass (cart and payload), kg.
    pub m_c: f64,
    /// `c`: replacement belt stiffness (2.26), N/m.
    pub c: f64,
    /// `d`: belt damping (2.27), N s/m. Neglected (0) in (2.39); (2.42) keeps it in
    /// its damping terms ([`Self::tf_high_frequency`]), the thesis' form for `d = 0`.
    #[serde(default)]
    pub d: f64,
    /// `d_m`: motor viscous damping as translational equivalent, N s/m
    /// (motor torque `i_t^2 d_m omega_m`).
    pub d_m: f64,
    /// `d_c`: cart viscous damping, N s/m.
    pub d_c: f64,
    /// `i_t = r / i_g`: transmission from motor angle to belt travel, m/rad.
    pub i_t: f64,
}

impl TwoMassParams {
    /// Typed error for any non-physical value (non-finite, non-positive
    /// inertia/mass/stiffness/transmission, negative damping).
    pub fn validate(&self) -> Result<()> {
        require_positive("theta_e [kg m^2]", self.theta_e)?;
        require_positive("m_c [kg]", self.m_c)?;
        require_positive("c [N/m]", self.c)?;
        require_non_negative("d [N s/m]", self.d)?;
        require_non_negative("d_m [N s/m]", self.d_m)?;
        require_non_negative("d_c [N s/m]", self.d_c)?;
        require_positive("i_t [m/rad]", self.i_t)?;
        // Plausibility: finite upper (and lower) bounds, wide enough for
        // rotary sets (i_t = 1, m_c in kg m^2) and current units, narrow
        // enough that (2.44)-(2.47) stay finite.
        use crate::error::require_range;
        require_range("theta_e [kg m^2]", self.theta_e, 1e-12, 1e3)?;
        require_range("m_c [kg]", self.m_c, 1e-12, 1e6)?;
        require_range("c [N/m]", self.c, 1e-6, 1e12)?;
        require_range("d [N s/m]", self.d, 0.0, 1e9)?;
        require_range("d_m [N s/m]", self.d_m, 0.0, 1e9)?;
        require_range("d_c [N s/m]", self.d_c, 0.0, 1e9)?;
        require_range("i_t [m/rad]", self.i_t, 1e-6, 1e3)?;
        Ok(())
    }

    /// Rigid-body inertia seen by the motor, `Theta_e + i_t^2 m_c` in kg m^2
    /// (`m_e~` of (4.15)).
    pub fn rigid_inertia(&self) -> f64 {
        self.theta_e + self.i_t * self.i_t * self.m_c
    }

    /// Rigid-body viscous damping seen by the motor, `i_t^2 (d_m + d_c)` in N m s/rad.
    pub fn rigid_damping(&self) -> f64 {
        self.i_t * self.i_t * (self.d_m + self.d_c)
    }

    /// Damping of the resonance mode, `a3` of (2.38g):
    /// `i_t^2 m_c (d + d_m) + Theta_e (d + d_c)` in kg m^2/s (N m s / rad times kg):
    /// with `Theta_e m_c s^2 + a3 s + c (Theta_e + i_t^2 m_c)` the damping ratio of
    /// the resonance is `a3 / (2 sqrt(Theta_e m_c c (Theta_e + i_t^2 m_c)))`.
    pub fn resonance_damping(&self) -> f64 {
        let it2 = self.i_t * self.i_t;
        it2 * self.m_c * (self.d + self.d_m) + self.theta_e * (self.d + self.d_c)
    }

    /// Damping ratio of the resonance mode of (2.41), dimensionless.
    pub fn resonance_damping_ratio(&self) -> f64 {
        self.resonance_damping()
            / (2.0 * (self.theta_e * self.m_c * self.c * self.rigid_inertia()).sqrt())
    }

    /// Resonance `w_r = sqrt(c (Theta_e + i_t^2 m_c) / (Theta_e m_c))` (2.44), rad/s.
    pub fn resonance_rad_s(&self) -> f64 {
        (self.c * self.rigid_inertia() / (self.theta_e * self.m_c)).sqrt()
    }

    /// Antiresonance `w_z = sqrt(c / m_c)` (2.45), rad/s.
    pub fn antiresonance_rad_s(&self) -> f64 {
        (self.c / self.m_c).sqrt()
    }

    /// Resonance frequency `f_r` in Hz.
    pub fn f_r_hz(&self) -> f64 {
        self.resonance_rad_s() / (2.0 * PI)
    }

    /// Antiresonance frequency `f_z` in Hz.
    pub fn f_z_hz(&self) -> f64 {
        self.antiresonance_rad_s() / (2.0 * PI)
    }

    /// Inertia ratio `kappa = i_t^2 m_c / Theta_e` (2.46).
    pub fn inertia_ratio(&self) -> f64 {
        self.i_t * self.i_t * self.m_c / self.theta_e
    }

    /// Resonance ratio `R = w_r / w_z = sqrt(1 + kappa)` (2.47).
    pub fn resonance_ratio(&self) -> f64 {
        (1.0 + self.inertia_ratio()).sqrt()
    }

    /// Denominator of (2.38a): `a4 s^4 + a3 s^3 + a2 s^2 + a1 s` with the belt damping `d`.
    fn den_full(&self) -> Poly {
        let (j, m, c, d, dm, dc, it2) = (
            self.theta_e,
            self.m_c,
            self.c,
            self.d,
            self.d_m,
            self.d_c,
            self.i_t * self.i_t,
        );
        let a1 = it2 * c * (dc + dm); // (2.38e)
        let a2 = c * (j + it2 * m) + it2 * (d * dm + d * dc + dm * dc); // (2.38f)
        let a3 = it2 * m * (d + dm) + j * (d + dc); // (2.38g)
        let a4 = m * j; // (2.38h)
        Poly::new(vec![0.0, a1, a2, a3, a4])
    }

    /// Torque -> motor angle with belt damping, `G'_{tau_m, phi_m}` (2.38), rad/(N m).
    pub fn tf_torque_to_motor_angle(&self) -> Tf {
        // (2.38b)-(2.38d): b0 = c, b1 = d + d_c, b2 = m_c
        let num = Poly::new(vec![self.c, self.d + self.d_c, self.m_c]);
        Tf::new(num, self.den_full())
    }

    /// Torque -> motor angle without belt damping, `G~_{tau_m, phi_m}` (2.39).
    pub fn tf_torque_to_motor_angle_undamped_belt(&self) -> Tf {
        TwoMassParams { d: 0.0, ..*self }.tf_torque_to_motor_angle()
    }

    /// Low-frequency (rigid) approximation `G^lf` (2.40). With a belt damping
    /// `d > 0` the numerator carries `d + d_c` as in (2.38c); `d = 0` is (2.40).
    pub fn tf_low_frequency(&self) -> Tf {
        let num = Poly::new(vec![1.0, (self.d + self.d_c) / self.c, self.m_c / self.c]);
        let den = Poly::new(vec![0.0, self.rigid_damping(), self.rigid_inertia()]);
        Tf::new(num, den)
    }

    /// High-frequency approximation `G^hf` (2.41). Its damping term is the
    /// `a3` of (2.38g), `i_t^2 m_c (d + d_m) + Theta_e (d + d_c)`, which is
    /// (2.41)'s `i_t^2 m_c d_m + Theta_e d_c` for `d = 0`: a model whose
    /// resonance is damped by the belt (the simulator's truth, or a
    /// design model whose resonance damping is not the rigid-body friction)
    /// keeps that damping.
    pub fn tf_high_frequency(&self) -> Tf {
        let den = Poly::new(vec![
            self.c * self.rigid_inertia(),
            self.resonance_damping(),
            self.m_c * self.theta_e,
        ]);
        let num = Poly::new(vec![self.m_c]);
        Tf::new(num, den)
    }

    /// The rigid/flexible approximation `G_{tau_m, phi_m}` (2.42) that the
    /// identification fits and the design uses: `G^lf G^hf chi` with
    /// `chi = c (Theta_e + i_t^2 m_c) / m_c`.
    pub fn tf_rigid_flexible(&self) -> Tf {
        let chi = self.c * self.rigid_inertia() / self.m_c;
        let g = self.tf_low_frequency().series(&self.tf_high_frequency());
        Tf::new(g.num.scale(chi), g.den)
    }

    /// Torque -> cart position `G_{tau_m, xi}` (2.48): `i_t (d s + c) / den(2.38)`, m/(N m).
    pub fn tf_torque_to_cart(&self) -> Tf {
        let num = Poly::new(vec![self.i_t * self.c, self.i_t * self.d]);
        Tf::new(num, self.den_full())
    }

    /// Motor angle -> cart position `G_{phi_m, xi}` (2.49): `i_t (d s + c) / (m_c s^2 + (d + d_c) s + c)`, m/rad.
    pub fn tf_motor_angle_to_cart(&self) -> Tf {
        let num = Poly::new(vec![self.i_t * self.c, self.i_t * self.d]);
        let den = Poly::new(vec![self.c, self.d + self.d_c, self.m_c]);
        Tf::new(num, den)
    }

    /// Thesis Table A.4 (plant `G_A`, 11.2 kg payload), identified on the test rig.
    /// `i_t = 78 mm / (2 pi)` (docs/thesis-map.md); belt damping not identified (0).
    pub fn thesis_table_a4() -> Self {
        TwoMassParams {
            theta_e: 71.73e-6,
            m_c: 13.44,
            c: 203.74e3,
            d: 0.0,
            d_m: 33.17,
            d_c: 226.42,
            i_t: 0.078 / (2.0 * PI),
        }
    }

    /// Thesis Table A.5 (plant `G_B`, no payload).
    pub fn thesis_table_a5() -> Self {
        TwoMassParams {
            theta_e: 71.73e-6,
            m_c: 0.96,
            c: 222.39e3,
            d: 0.0,
            d_m: 0.01,
            d_c: 53.70,
            i_t: 0.078 / (2.0 * PI),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lti::C64;

    /// docs/thesis-map.md: Table A.4 gives f_r = 107.1 Hz and f_z = 19.60 Hz through (2.44)/(2.45)
    /// (the table prints 107.11 / 19.59, rounded from the identified values).
    #[test]
    fn table_a4_resonance_and_antiresonance() {
        let p = TwoMassParams::thesis_table_a4();
        assert!((p.f_r_hz() - 107.11).abs() < 0.05, "{}", p.f_r_hz());
        assert!((p.f_z_hz() - 19.59).abs() < 0.02, "{}", p.f_z_hz());
        assert!((p.resonance_ratio() - p.f_r_hz() / p.f_z_hz()).abs() < 1e-12);
    }

    #[test]
    fn table_a5_resonance_and_antiresonance() {
        let p = TwoMassParams::thesis_table_a5();
        assert!(
            (p.f_r_hz() - 134.00).abs() / 134.0 < 0.005,
            "{}",
            p.f_r_hz()
        );
        assert!((p.f_z_hz() - 76.51).abs() / 76.51 < 0.005, "{}", p.f_z_hz());
    }

    /// (2.38) against a direct solve of the Laplace-domain equations of motion.
    #[test]
    fn full_tf_matches_equations_of_motion() {
        let p = TwoMassParams {
            d: 20.0,
            ..TwoMassParams::thesis_table_a4()
        };
        let g = p.tf_torque_to_motor_angle();
        let gx = p.tf_torque_to_cart();
        for w in [3.0, 50.0, 123.0, 700.0, 2500.0] {
            let s = C64::new(0.0, w);
            let it = p.i_t;
            // [a b; c e] [phi; xi] = [1; 0]
            let a = p.theta_e * s * s + it * it * p.d_m * s + it * it * (p.c + p.d * s);
            let b = -it * (p.c + p.d * s);
            let cc = -it * (p.c + p.d * s);
            let e = p.m_c * s * s + (p.d + p.d_c) * s + p.c;
            let det = a * e - b * cc;
            let phi = e / det;
            let xi = -cc / det;
            assert!((g.eval(s) - phi).norm() / phi.norm() < 1e-10);
            assert!((gx.eval(s) - xi).norm() / xi.norm() < 1e-10);
            let chain = g.eval(s) * p.tf_motor_angle_to_cart().eval(s);
            assert!((chain - xi).norm() / xi.norm() < 1e-10);
        }
    }

    /// (2.42) is close to (2.39) away from the modes and exact in the undamped case.
    #[test]
    fn rigid_flexible_approximation_is_exact_without_damping() {
        let p = TwoMassParams {
            d: 0.0,
            d_m: 0.0,
            d_c: 0.0,
            ..TwoMassParams::thesis_table_a4()
        };
        for w in [1.0, 10.0, 300.0, 3000.0] {
            let a = p.tf_rigid_flexible().freq_response(w);
            let b = p.tf_torque_to_motor_angle_undamped_belt().freq_response(w);
            assert!((a - b).norm() / b.norm() < 1e-9);
        }
        // low-frequency asymptote: the rigid body 1 / (J s^2 + D s)
        let p = TwoMassParams::thesis_table_a4();
        let w = 0.5;
        let g = p.tf_rigid_flexible().freq_response(w);
        let s = C64::new(0.0, w);
        let rigid = 1.0 / (p.rigid_inertia() * s * s + p.rigid_damping() * s);
        assert!((g - rigid).norm() / rigid.norm() < 1e-3);
    }

    #[test]
    fn validation_rejects_non_physical_values() {
        let ok = TwoMassParams::thesis_table_a4();
        assert!(ok.validate().is_ok());
        for bad in [
            TwoMassParams { m_c: 0.0, ..ok },
            TwoMassParams { c: -1.0, ..ok },
            TwoMassParams { d_c: -1.0, ..ok },
            TwoMassParams {
                theta_e: f64::NAN,
                ..ok
            },
            TwoMassParams {
                i_t: f64::INFINITY,
                ..ok
            },
        ] {
            assert!(bad.validate().is_err(), "{bad:?}");
        }
    }
}
