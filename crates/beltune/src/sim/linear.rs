//! Exact zero-order-hold discretization of the linear two-mass model (2.33).
//!
//! State `x = [phi_m, omega_m, xi, xi']`; the matrix uses the
//! transfer-function convention of docs/thesis-map.md (motor viscous torque
//! `i_t^2 d_m omega_m`), so its transfer functions are exactly (2.38)/(2.48).
//! `Phi = e^{A T}`, `Gamma = int_0^T e^{A t} dt b` from the exponential of the
//! augmented matrix `[[A, b], [0, 0]] T`.

use crate::model::TwoMassParams;
use nalgebra::{SMatrix, SVector};

/// Continuous `A`, `b` of (2.33) (convention above).
pub(crate) fn continuous(p: &TwoMassParams) -> (SMatrix<f64, 4, 4>, SVector<f64, 4>) {
    let it = p.i_t;
    let (j, m) = (p.theta_e, p.m_c);
    #[rustfmt::skip]
    let a = SMatrix::<f64, 4, 4>::from_row_slice(&[
        0.0, 1.0, 0.0, 0.0,
        -it * it * p.c / j, -it * it * (p.d + p.d_m) / j, it * p.c / j, it * p.d / j,
        0.0, 0.0, 0.0, 1.0,
        it * p.c / m, it * p.d / m, -p.c / m, -(p.d + p.d_c) / m,
    ]);
    let b = SVector::<f64, 4>::new(0.0, 1.0 / j, 0.0, 0.0);
    (a, b)
}

/// ZOH discretization `x_{k+1} = Phi x_k + Gamma u_k` with sampling time `t_s`.
pub(crate) fn zoh(p: &TwoMassParams, t_s: f64) -> (SMatrix<f64, 4, 4>, SVector<f64, 4>) {
    let (a, b) = continuous(p);
    let mut aug = SMatrix::<f64, 5, 5>::zeros();
    aug.fixed_view_mut::<4, 4>(0, 0).copy_from(&(a * t_s));
    aug.fixed_view_mut::<4, 1>(0, 4).copy_from(&(b * t_s));
    let e = aug.exp();
    let phi: SMatrix<f64, 4, 4> = e.fixed_view::<4, 4>(0, 0).into_owned();
    let gamma: SVector<f64, 4> = e.fixed_view::<4, 1>(0, 4).into_owned();
    (phi, gamma)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lti::C64;
    use crate::model::rigs::sim_a;

    /// The state space (2.33) reproduces (2.38) and (2.48) exactly.
    #[test]
    fn state_space_matches_transfer_functions() {
        let p = sim_a();
        let (a, b) = continuous(&p);
        for w in [2.0, 140.0, 840.0, 5000.0] {
            let s = C64::new(0.0, w);
            let m = SMatrix::<C64, 4, 4>::identity() * s - a.map(|x| C64::new(x, 0.0));
            let x = m.lu().solve(&b.map(|x| C64::new(x, 0.0))).unwrap();
            let g = p.tf_torque_to_motor_angle().eval(s);
            let gx = p.tf_torque_to_cart().eval(s);
            assert!((x[0] - g).norm() / g.norm() < 1e-9);
            assert!((x[2] - gx).norm() / gx.norm() < 1e-9);
        }
    }
}
