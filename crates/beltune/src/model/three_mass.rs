//! The nonlinear three-mass-spring-damper model (2.20) with friction
//! (2.21)/(2.23), gravity (2.22)/(2.24) and the position-dependent segment
//! stiffnesses `c_1(xi)`, `c_2(xi)`, `c_3` (2.10); and its linearization
//! (viscous friction only, no gravity) as a state space for frequency responses.
//!
//! State (2.18): `x = [phi_m, omega_m, phi_2, omega_2, xi, xi']`, input `u = tau_m`.

// `sign` with `sign(0) = 0`, as the friction models (2.21), (2.23) need.
use crate::lti::C64;
use crate::model::params::{BeltSegments, PhysicalParams};
use crate::Result;
use beltune_rt::Real;
use nalgebra::{SMatrix, SVector};

/// The state (2.18) of the three-mass model.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct ThreeMassState {
    /// `phi_m`: motor angle, rad.
    pub phi_m_rad: f64,
    /// `omega_m`: motor velocity, rad/s.
    pub omega_m_rad_s: f64,
    /// `phi_2`: end-pulley angle, rad.
    pub phi_2_rad: f64,
    /// `omega_2`: end-pulley velocity, rad/s.
    pub omega_2_rad_s: f64,
    /// `xi`: cart position, m.
    pub xi_m: f64,
    /// `xi'`: cart velocity, m/s.
    pub xi_dot_m_s: f64,
}

impl ThreeMassState {
    /// The belt at rest and unstretched with the cart at `xi_m`.
    pub fn at_rest(p: &PhysicalParams, xi_m: f64) -> Self {
        ThreeMassState {
            phi_m_rad: xi_m / p.i_t(),
            phi_2_rad: xi_m / p.r_m,
            xi_m,
            ..Default::default()
        }
    }
}

/// Linear three-mass model `x' = A x + b u` at one cart position.
#[derive(Clone, Debug, PartialEq)]
pub struct LinearThreeMass {
    /// System matrix, state order (2.18).
    pub a: SMatrix<f64, 6, 6>,
    /// Input vector (torque `tau_m`, N m).
    pub b: SVector<f64, 6>,
}

impl LinearThreeMass {
    fn response(&self, w_rad_s: f64) -> SVector<C64, 6> {
        let s = C64::new(0.0, w_rad_s);
        let m: SMatrix<C64, 6, 6> =
            SMatrix::<C64, 6, 6>::identity() * s - self.a.map(|x| C64::new(x, 0.0));
        let b = self.b.map(|x| C64::new(x, 0.0));
        m.lu()
            .solve(&b)
            .unwrap_or_else(|| SVector::<C64, 6>::from_element(C64::new(f64::NAN, f64::NAN)))
    }

    /// Frequency response torque -> motor angle at `w_rad_s` (> 0), rad/(N m).
    pub fn frf_motor_angle(&self, w_rad_s: f64) -> C64 {
        self.response(w_rad_s)[0]
    }

    /// Frequency response torque -> cart position at `w_rad_s` (> 0), m/(N m).
    pub fn frf_cart(&self, w_rad_s: f64) -> C64 {
        self.response(w_rad_s)[4]
    }
}

/// The nonlinear three-mass model of an axis (2.20).
#[derive(Clone, Debug, PartialEq)]
pub struct ThreeMass {
    params: PhysicalParams,
}

impl ThreeMass {
    /// The model of validated parameters.
    pub fn new(params: &PhysicalParams) -> Result<Self> {
        params.validate()?;
        Ok(ThreeMass {
            params: params.clone(),
        })
    }

    /// The parameters.
    pub fn params(&self) -> &PhysicalParams {
        &self.params
    }

    /// Right-hand side `f_3m(x, u)` of (2.20) with the friction (2.21), (2.23)
    /// (`sign(0) = 0`: the stick phase needs the simulator's stick-slip model)
    /// and gravity (2.22).
    pub fn derivative(&self, x: &ThreeMassState, tau_m_nm: f64) -> ThreeMassState {
        let p = &self.params;
        let (it, r, ig) = (p.i_t(), p.r_m, p.i_g);
        let s = p.belt_segments(x.xi_m);
        let (c1, c2, c3) = (s.c_1_n_per_m, s.c_2_n_per_m, s.c_3_n_per_m);
        let (d1, d2, d3) = (s.d_1_n_s_per_m, s.d_2_n_s_per_m, s.d_3_n_s_per_m);
        // (2.21) with d_m as translational equivalent (docs/thesis-map.md)
        let tau_mr = -it * it * p.d_m_n_s_per_m * x.omega_m_rad_s
            - p.tau_c_motor_nm * Real::sign(x.omega_m_rad_s);
        // end pulley friction "modeled in a similar fashion"
        let tau_2 = -r * r * p.d_end_pulley_n_s_per_m * x.omega_2_rad_s
            - p.tau_c_end_pulley_nm * Real::sign(x.omega_2_rad_s);
        // (2.17): tau_1 / i_g
        let tau_1_over_ig = -it * c1 * (it * x.phi_m_rad - x.xi_m)
            - it * d1 * (it * x.omega_m_rad_s - x.xi_dot_m_s)
            - it * it * c3 * (x.phi_m_rad - ig * x.phi_2_rad)
            - it * it * d3 * (x.omega_m_rad_s - ig * x.omega_2_rad_s);
        let omega_m_dot = (tau_m_nm + tau_mr + tau_1_over_ig) / p.theta_e();
        let omega_2_dot = (tau_2
            - r * c2 * (r * x.phi_2_rad - x.xi_m)
            - r * d2 * (r * x.omega_2_rad_s - x.xi_dot_m_s)
            - r * r * c3 * (x.phi_2_rad - x.phi_m_rad / ig)
            - r * r * d3 * (x.omega_2_rad_s - x.omega_m_rad_s / ig))
            / p.theta_end_pulley_kg_m2;
        // (2.23), (2.24)
        let f = -p.d_c_n_s_per_m * x.xi_dot_m_s - p.f_c_cart_n * Real::sign(x.xi_dot_m_s)
            + p.gravity_force_n();
        let xi_ddot = (f
            + c1 * (it * x.phi_m_rad - x.xi_m)
            + d1 * (it * x.omega_m_rad_s - x.xi_dot_m_s)
            + c2 * (r * x.phi_2_rad - x.xi_m)
            + d2 * (r * x.omega_2_rad_s - x.xi_dot_m_s))
            / p.m_c();
        ThreeMassState {
            phi_m_rad: x.omega_m_rad_s,
            omega_m_rad_s: omega_m_dot,
            phi_2_rad: x.omega_2_rad_s,
            omega_2_rad_s: omega_2_dot,
            xi_m: x.xi_dot_m_s,
            xi_dot_m_s: xi_ddot,
        }
    }

    /// Linearization at cart position `xi_m`: the segments frozen at `xi_m`,
    /// viscous friction only (as (2.31)/(2.32)), no gravity.
    pub fn linearize(&self, xi_m: f64) -> LinearThreeMass {
        self.linearize_with(&self.params.belt_segments(xi_m))
    }

    /// Linearization with explicitly given belt segments (e.g. a very stiff
    /// return strand to check the reduction to the two-mass model).
    pub fn linearize_with(&self, s: &BeltSegments) -> LinearThreeMass {
        let p = &self.params;
        let (it, r, ig) = (p.i_t(), p.r_m, p.i_g);
        let (c1, c2, c3) = (s.c_1_n_per_m, s.c_2_n_per_m, s.c_3_n_per_m);
        let (d1, d2, d3) = (s.d_1_n_s_per_m, s.d_2_n_s_per_m, s.d_3_n_s_per_m);
        let (je, jr, m) = (p.theta_e(), p.theta_end_pulley_kg_m2, p.m_c());
        let mut a = SMatrix::<f64, 6, 6>::zeros();
        a[(0, 1)] = 1.0;
        a[(2, 3)] = 1.0;
        a[(4, 5)] = 1.0;
        // motor row
        a[(1, 0)] = -(it * it * c1 + it * it * c3) / je;
        a[(1, 1)] = -(it * it * p.d_m_n_s_per_m + it * it * d1 + it * it * d3) / je;
        a[(1, 2)] = it * it * c3 * ig / je;
        a[(1, 3)] = it * it * d3 * ig / je;
        a[(1, 4)] = it * c1 / je;
        a[(1, 5)] = it * d1 / je;
        // end pulley row
        a[(3, 0)] = r * r * c3 / ig / jr;
        a[(3, 1)] = r * r * d3 / ig / jr;
        a[(3, 2)] = -(r * r * c2 + r * r * c3) / jr;
        a[(3, 3)] = -(r * r * p.d_end_pulley_n_s_per_m + r * r * d2 + r * r * d3) / jr;
        a[(3, 4)] = r * c2 / jr;
        a[(3, 5)] = r * d2 / jr;
        // cart row
        a[(5, 0)] = c1 * it / m;
        a[(5, 1)] = d1 * it / m;
        a[(5, 2)] = c2 * r / m;
        a[(5, 3)] = d2 * r / m;
        a[(5, 4)] = -(c1 + c2) / m;
        a[(5, 5)] = -(p.d_c_n_s_per_m + d1 + d2) / m;
        let mut b = SVector::<f64, 6>::zeros();
        b[1] = 1.0 / je;
        LinearThreeMass { a, b }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::rigs::egc70_params;
    use rand::{Rng, SeedableRng};

    /// The linear state space reproduces the nonlinear right-hand side (2.20)
    /// exactly when Coulomb friction and gravity are off (seeded random states).
    #[test]
    fn linearization_matches_nonlinear_rhs_without_coulomb() {
        let p = PhysicalParams {
            tau_c_motor_nm: 0.0,
            f_c_cart_n: 0.0,
            tau_c_end_pulley_nm: 0.0,
            i_g: 2.0, // exercise the gear terms
            ..egc70_params(5.0)
        };
        let model = ThreeMass::new(&p).unwrap();
        let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(7);
        for _ in 0..50 {
            let xi = rng.random_range(0.0..0.6);
            let x = ThreeMassState {
                phi_m_rad: rng.random_range(-50.0..50.0),
                omega_m_rad_s: rng.random_range(-100.0..100.0),
                phi_2_rad: rng.random_range(-50.0..50.0),
                omega_2_rad_s: rng.random_range(-100.0..100.0),
                xi_m: xi,
                xi_dot_m_s: rng.random_range(-2.0..2.0),
            };
            let u = rng.random_range(-3.0..3.0);
            let f = model.derivative(&x, u);
            let lin = model.linearize(xi);
            let xv = SVector::<f64, 6>::from([
                x.phi_m_rad,
                x.omega_m_rad_s,
                x.phi_2_rad,
                x.omega_2_rad_s,
                x.xi_m,
                x.xi_dot_m_s,
            ]);
            let g = lin.a * xv + lin.b * u;
            let fv = [
                f.phi_m_rad,
                f.omega_m_rad_s,
                f.phi_2_rad,
                f.omega_2_rad_s,
                f.xi_m,
                f.xi_dot_m_s,
            ];
            for k in 0..6 {
                let scale = fv[k].abs().max(g[k].abs()).max(1.0);
                assert!(
                    (fv[k] - g[k]).abs() / scale < 1e-9,
                    "row {k}: {} vs {}",
                    fv[k],
                    g[k]
                );
            }
        }
    }

    /// Max deviation allowed between the three-mass and the two-mass responses
    /// when the reduction is exact in the limit (the stiff strand is 1e6 times
    /// stiffer than the belt): 0.1 %.
    const REDUCTION_TOL: f64 = 1e-3;

    /// With a (nearly) rigid return strand c_3 the end pulley moves with the
    /// motor: the three-mass model becomes the two-mass model with
    /// `Theta_e + Theta_end / i_g^2`, `c = c_1 + c_2` (the limit of (2.26)) and
    /// `d = d_1 + d_2`, and the frequency responses agree.
    #[test]
    fn stiff_end_segment_reduces_to_two_mass() {
        let p = PhysicalParams {
            d_end_pulley_n_s_per_m: 0.0,
            ..egc70_params(11.2)
        };
        let model = ThreeMass::new(&p).unwrap();
        let xi = 0.4;
        let s = BeltSegments {
            c_3_n_per_m: 1e12,
            d_3_n_s_per_m: 0.0,
            ..p.belt_segments(xi)
        };
        let lin = model.linearize_with(&s);
        let two = crate::model::TwoMassParams {
            theta_e: p.theta_e() + p.theta_end_pulley_kg_m2 / (p.i_g * p.i_g),
            m_c: p.m_c(),
            c: s.c_1_n_per_m + s.c_2_n_per_m,
            d: s.d_1_n_s_per_m + s.d_2_n_s_per_m,
            d_m: p.d_m_n_s_per_m,
            d_c: p.d_c_n_s_per_m,
            i_t: p.i_t(),
        };
        let g = two.tf_torque_to_motor_angle();
        let gx = two.tf_torque_to_cart();
        for k in 0..60 {
            let w = 2.0 * std::f64::consts::PI * 10f64.powf(k as f64 / 20.0); // 1 Hz .. 1 kHz
            let a = lin.frf_motor_angle(w);
            let b = g.freq_response(w);
            assert!(
                (a - b).norm() / b.norm() < REDUCTION_TOL,
                "w {w}: {a} vs {b}"
            );
            let a = lin.frf_cart(w);
            let b = gx.freq_response(w);
            assert!(
                (a - b).norm() / b.norm() < REDUCTION_TOL,
                "w {w}: {a} vs {b}"
            );
        }
    }

    /// The thesis' own reduction (2.1.4): with a negligible end-pulley inertia
    /// the three-mass model equals the two-mass model with (2.26)/(2.27) below
    /// the (then very high) end-pulley mode.
    #[test]
    fn light_end_pulley_reduces_to_two_mass_with_2_26() {
        let p = PhysicalParams {
            theta_end_pulley_kg_m2: 1e-12,
            d_end_pulley_n_s_per_m: 0.0,
            d_b_n_s: 0.0, // (2.27) is exact only for the undamped series combination
            ..egc70_params(11.2)
        };
        let model = ThreeMass::new(&p).unwrap();
        for xi in [0.0, 0.3, 0.6] {
            let lin = model.linearize(xi);
            let two = p.linearize(xi).unwrap();
            let g = two.tf_torque_to_motor_angle();
            for k in 0..54 {
                let w = 2.0 * std::f64::consts::PI * 10f64.powf(k as f64 / 20.0); // 1 Hz .. 500 Hz
                let a = lin.frf_motor_angle(w);
                let b = g.freq_response(w);
                assert!(
                    (a - b).norm() / b.norm() < REDUCTION_TOL,
                    "xi {xi} w {w}: {a} vs {b}"
                );
            }
        }
    }
}
