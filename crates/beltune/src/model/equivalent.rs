//! The two-mass equivalent of the simulator's physics: the resonance and
//! antiresonance of the linearized three-mass model (2.20) *with* the end
//! pulley's inertia, which the two-mass reduction of thesis 2.1.4 neglects,
//! and the two-mass parameters (2.33) that have exactly these two frequencies
//! with the data-sheet `Theta_e`.
//!
//! Undamped, in the coordinates `q = [phi_m, phi_2, xi]` (motor angle,
//! end-pulley angle, cart position) the linearization is `M q'' + K q = b tau`
//! with `M = diag(Theta_e, Theta_r, m_c)` and
//!
//! ```text
//!     | i_t^2 (c_1 + c_3)    -i_t^2 c_3 i_g      -i_t c_1 |
//! K = | -r^2 c_3 / i_g        r^2 (c_2 + c_3)    -r c_2   |
//!     | -i_t c_1              -r c_2              c_1 + c_2 |
//! ```
//!
//! (the rows of [`super::three_mass::ThreeMass::linearize_with`]). The
//! resonances (poles of torque -> motor angle) are the non-zero eigenvalues of
//! `M^-1 K`; the antiresonances (its zeros) are the eigenvalues of the system
//! with the motor held, the lower-right 2 x 2 block. The lowest of each is
//! what a two-mass fit sees. A two-mass model (2.44)/(2.45) with
//! `w_z^2 = c / m_c` and `w_r^2 = w_z^2 (1 + i_t^2 m_c / Theta_e)` has the
//! same two frequencies for `m_c = Theta_e (w_r^2 / w_z^2 - 1) / i_t^2` and
//! `c = m_c w_z^2`.

use crate::model::{PhysicalParams, TwoMassParams};
use crate::{Error, Result};
use nalgebra::{DMatrix, SymmetricEigen};
use std::f64::consts::PI;

/// The lowest resonance and antiresonance of the simulator's three-mass
/// physics at one cart position.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ThreeMassModes {
    /// Lowest non-zero resonance (torque -> motor angle pole), Hz.
    pub f_r_hz: f64,
    /// Lowest antiresonance (torque -> motor angle zero), Hz.
    pub f_z_hz: f64,
}

/// Eigenvalues of `M^-1 K` for a diagonal `M` (`m`) through the symmetric
/// `M^-1/2 K M^-1/2`, ascending.
fn mass_normalized_eigen(k: DMatrix<f64>, m: &[f64]) -> Vec<f64> {
    let n = m.len();
    let s = DMatrix::from_fn(n, n, |i, j| k[(i, j)] / (m[i] * m[j]).sqrt());
    let mut ev: Vec<f64> = SymmetricEigen::new(s).eigenvalues.iter().copied().collect();
    ev.sort_by(f64::total_cmp);
    ev
}

/// The lowest resonance and antiresonance of `p` at cart position `xi_m`
/// (the belt as aged, [`PhysicalParams::aged`]).
pub fn three_mass_modes(p: &PhysicalParams, xi_m: f64) -> Result<ThreeMassModes> {
    p.validate()?;
    crate::error::require_finite("xi [m]", xi_m)?;
    let s = p.aged().belt_segments(xi_m);
    let (it, r, ig) = (p.i_t(), p.r_m, p.i_g);
    let (c1, c2, c3) = (s.c_1_n_per_m, s.c_2_n_per_m, s.c_3_n_per_m);
    let (je, jr, m) = (p.theta_e(), p.theta_end_pulley_kg_m2, p.m_c());
    let k = DMatrix::from_row_slice(
        3,
        3,
        &[
            it * it * (c1 + c3),
            -it * it * c3 * ig,
            -it * c1,
            -r * r * c3 / ig,
            r * r * (c2 + c3),
            -r * c2,
            -it * c1,
            -r * c2,
            c1 + c2,
        ],
    );
    // The lowest eigenvalue is the rigid-body mode (zero up to rounding).
    let poles = mass_normalized_eigen(k, &[je, jr, m]);
    let held = DMatrix::from_row_slice(2, 2, &[r * r * (c2 + c3), -r * c2, -r * c2, c1 + c2]);
    let zeros = mass_normalized_eigen(held, &[jr, m]);
    let (w_r2, w_z2) = (poles[1], zeros[0]);
    if !(w_r2.is_finite() && w_z2.is_finite() && w_z2 > 0.0 && w_r2 > w_z2) {
        return Err(Error::invalid(
            "belt stiffness [N/m]",
            c1,
            "the three-mass model has no resonance above its antiresonance",
        ));
    }
    Ok(ThreeMassModes {
        f_r_hz: w_r2.sqrt() / (2.0 * PI),
        f_z_hz: w_z2.sqrt() / (2.0 * PI),
    })
}

/// The two-mass parameters with the three-mass model's lowest resonance and
/// antiresonance at `xi_m` (module docs): `Theta_e`, the damping terms and
/// `i_t` of the two-mass linearization ([`PhysicalParams::linearize`]),
/// `m_c` and `c` equivalent (the end pulley's inertia shared between them).
pub fn equivalent_two_mass(p: &PhysicalParams, xi_m: f64) -> Result<TwoMassParams> {
    let lin = p.linearize(xi_m)?;
    let modes = three_mass_modes(p, xi_m)?;
    let (w_r, w_z) = (2.0 * PI * modes.f_r_hz, 2.0 * PI * modes.f_z_hz);
    let m_c = lin.theta_e * ((w_r * w_r) / (w_z * w_z) - 1.0) / (lin.i_t * lin.i_t);
    let eq = TwoMassParams {
        m_c,
        c: m_c * w_z * w_z,
        ..lin
    };
    eq.validate()?;
    Ok(eq)
}

/// Antiresonance and resonance of `p` at `xi_m`, Hz, found without the
/// eigenvalues (a test's independent reference): `|G| f^2` of the three-mass
/// state space's frequency response torque -> motor angle (LU solve of
/// `(jw I - A) x = b`, [`crate::model::three_mass::ThreeMass::linearize`]) is
/// flat on the rigid body; its first dip is the antiresonance, the first peak
/// after it the resonance (0.05 % log grid from 5 Hz to 5 kHz).
#[cfg(test)]
pub(crate) fn swept_modes(p: &PhysicalParams, xi_m: f64) -> (f64, f64) {
    let lin = crate::model::three_mass::ThreeMass::new(p)
        .unwrap()
        .linearize(xi_m);
    let mag = |f: f64| lin.frf_motor_angle(2.0 * PI * f).norm() * f * f;
    let grid: Vec<f64> = (0..14_000).map(|k| 5.0 * 1.0005f64.powi(k)).collect();
    let g: Vec<f64> = grid.iter().map(|&f| mag(f)).collect();
    let dip = (1..g.len() - 1)
        .find(|&i| g[i] < g[i - 1] && g[i] <= g[i + 1])
        .unwrap();
    let peak = (dip + 1..g.len() - 1)
        .find(|&i| g[i] > g[i - 1] && g[i] >= g[i + 1])
        .unwrap();
    (grid[dip], grid[peak])
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::rigs::egc70_params;

    /// Independent of the eigenvalues: the resonance is where the three-mass
    /// state space's frequency response peaks and the antiresonance where it
    /// dips ([`swept_modes`], a tiny belt damping). Tolerance 0.2 %: four
    /// steps of the sweep's grid.
    #[test]
    fn modes_agree_with_the_state_space_frequency_response() {
        for (payload, i_g, xi) in [(0.0, 1.0, 0.6), (11.2, 1.0, 0.3), (5.0, 3.0, 0.0)] {
            let p = PhysicalParams {
                d_b_n_s: 1e-3,
                d_m_n_s_per_m: 0.0,
                d_c_n_s_per_m: 0.0,
                d_end_pulley_n_s_per_m: 0.0,
                theta_end_pulley_kg_m2: 60e-6,
                i_g,
                ..egc70_params(payload)
            };
            let modes = three_mass_modes(&p, xi).unwrap();
            let (best_dip, best_peak) = swept_modes(&p, xi);
            let rel = |a: f64, b: f64| (a / b - 1.0).abs();
            assert!(rel(best_peak, modes.f_r_hz) < 2e-3, "{best_peak} {modes:?}");
            assert!(rel(best_dip, modes.f_z_hz) < 2e-3, "{best_dip} {modes:?}");
        }
    }

    /// With a vanishing end-pulley inertia and a rigid return strand the
    /// three-mass model is the two-mass model (2.44)/(2.45): the same
    /// frequencies and parameters to 0.1 %.
    #[test]
    fn without_end_pulley_the_equivalent_is_the_two_mass_reduction() {
        let mut p = egc70_params(11.2);
        p.theta_end_pulley_kg_m2 = 1e-12;
        let two = p.linearize(0.6).unwrap();
        let eq = equivalent_two_mass(&p, 0.6).unwrap();
        let rel = |a: f64, b: f64| (a / b - 1.0).abs();
        assert!(rel(eq.f_r_hz(), two.f_r_hz()) < 1e-3);
        assert!(rel(eq.f_z_hz(), two.f_z_hz()) < 1e-3);
        assert!(rel(eq.m_c, two.m_c) < 1e-3 && rel(eq.c, two.c) < 1e-3);
    }

    /// The end pulley lowers the antiresonance: the equivalent of egc70 at
    /// its worst case differs from the reduction that neglects it, and keeps
    /// `Theta_e` and the frequencies it was built from.
    #[test]
    fn the_end_pulley_moves_the_antiresonance() {
        let p = egc70_params(0.0);
        let two = p.linearize(0.6).unwrap();
        let modes = three_mass_modes(&p, 0.6).unwrap();
        let eq = equivalent_two_mass(&p, 0.6).unwrap();
        assert!(
            modes.f_z_hz < two.f_z_hz() * 0.99,
            "{modes:?} {}",
            two.f_z_hz()
        );
        assert_eq!(eq.theta_e, two.theta_e);
        assert!((eq.f_r_hz() / modes.f_r_hz - 1.0).abs() < 1e-9);
        assert!((eq.f_z_hz() / modes.f_z_hz - 1.0).abs() < 1e-9);
    }
}
