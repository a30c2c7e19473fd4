//! What a commissioning run produces (`commissioning.json`), as named structs.

use serde::{Deserialize, Serialize};

pub use crate::design::model_file::{FrictionResult, IdentifiedModel};

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

/// The belt stiffness where the validation move ends (issue 12): the static
/// belt stretch the motor setpoint leads by (`tau_hold / (i_t c)`) is that
/// of the stiffness where the cart rests, and the replacement stiffness
/// (2.26) changes along the stroke (up to 30 % between the identification
/// position and the validation target).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct TargetStiffness {
    /// Cart position the stiffness holds for, m.
    pub position_m: f64,
    /// Replacement belt stiffness `c` there, N/m.
    pub c_n_per_m: f64,
    /// Antiresonance `f_z` measured there, Hz.
    pub f_z_hz: f64,
    /// Whether it was measured by its own experiment at `position_m`;
    /// `false`: the identification position is close enough and its fit's
    /// `c` is used.
    pub measured: bool,
}
