//! What a commissioning run produces (`commissioning.json`), as named structs.

use serde::{Deserialize, Serialize};

/// The identified two-mass model (thesis Table A.4 layout) and fit quality.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct IdentifiedModel {
    /// Resonance frequency (2.44), Hz.
    pub f_r_hz: f64,
    /// Antiresonance frequency (2.45), Hz.
    pub f_z_hz: f64,
    /// Motor-side inertia, kg m^2.
    pub theta_e: f64,
    /// Moving mass, kg.
    pub m_c: f64,
    /// Belt stiffness, N/m.
    pub c: f64,
    /// Motor damping (translational equivalent), N s/m.
    pub d_m: f64,
    /// Cart damping, N s/m.
    pub d_c: f64,
    /// Transmission `i_t`, m/rad.
    pub i_t: f64,
    /// Current-loop dead time (3.30), s.
    pub dead_time_s: f64,
    /// RMS error of the magnitude fit (3.33), dB.
    pub fit_rms_db: f64,
    /// One-sigma uncertainty of `m_c`, kg.
    pub m_c_sigma: f64,
    /// One-sigma uncertainty of `c`, N/m.
    pub c_sigma: f64,
    /// Mean magnitude-squared coherence over the lines used by the fit.
    pub mean_coherence: f64,
    /// Number of FRF lines used by the fit.
    pub lines_used: usize,
    /// Cart position at which the FRF was measured, m.
    pub position_m: f64,
}

impl IdentifiedModel {
    /// The summary of a fit on `frf`, with the dead time used and the cart
    /// position of the measurement (NaN when unknown, e.g. recorded data).
    pub fn from_fit(
        fit: &crate::ident::TwoMassFit,
        frf: &crate::ident::Frf,
        dead_time_s: f64,
        position_m: f64,
    ) -> Self {
        let used = frf.usable_indices();
        let mean_coherence = if used.is_empty() {
            0.0
        } else {
            used.iter().map(|&i| frf.coherence[i]).sum::<f64>() / used.len() as f64
        };
        let p = fit.params;
        IdentifiedModel {
            f_r_hz: fit.f_r_hz,
            f_z_hz: fit.f_z_hz,
            theta_e: p.theta_e,
            m_c: p.m_c,
            c: p.c,
            d_m: p.d_m,
            d_c: p.d_c,
            i_t: p.i_t,
            dead_time_s,
            fit_rms_db: fit.fit_rms_db,
            m_c_sigma: fit.uncertainty.map(|u| u.m_c).unwrap_or(f64::NAN),
            c_sigma: fit.uncertainty.map(|u| u.c).unwrap_or(f64::NAN),
            mean_coherence,
            lines_used: fit.n_lines,
            position_m,
        }
    }
}

/// Friction seen at the motor (3.36).
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct FrictionResult {
    /// Viscous coefficient `d_v~`, N m s/rad (key `viscous` before schema 1).
    #[serde(alias = "viscous")]
    pub viscous_nm_s_per_rad: f64,
    /// Coulomb torque `tau_c~`, N m (key `coulomb` before schema 1).
    #[serde(alias = "coulomb")]
    pub coulomb_nm: f64,
    /// Viscous-only fit (the "linear" feedforward), N m s/rad (key
    /// `linear_viscous` before schema 1).
    #[serde(alias = "linear_viscous")]
    pub linear_viscous_nm_s_per_rad: f64,
    /// Relative residual of the (3.36) fit.
    pub relative_residual: f64,
    /// Holding torque (gravity on a tilted axis), N m.
    pub holding_torque_nm: f64,
}

/// Result of one validation move.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct MoveSummary {
    /// Largest cart tracking error `|xi_d - xi|` during and after the move, m
    /// (motor-side `|xi_d - i_t phi_m|` when the axis has no cart encoder).
    pub max_tracking_error_m: f64,
    /// Mean `|xi_d - xi|` over the last 100 ms of the record, m.
    pub static_error_m: f64,
    /// Time from the end of the trajectory until the error stays within the
    /// settling band, s; `None` (JSON `null`) if it never settles within the record.
    pub settling_time_s: Option<f64>,
    /// Largest motor-side error `|xi_d - i_t phi_m|`, m.
    pub max_motor_error_m: f64,
    /// Largest torque command magnitude, N m.
    pub max_torque_nm: f64,
}

/// The validation with the three feedforward variants of chapter 5.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct Validation {
    /// Without feedforward.
    pub none: MoveSummary,
    /// Linear feedforward (inertia and a viscous-only friction fit).
    pub linear: MoveSummary,
    /// Nonlinear feedforward (inertia, viscous and Coulomb).
    pub nonlinear: MoveSummary,
}

/// The true values of a simulated plant at the identification position.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
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
