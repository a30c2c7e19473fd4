//! Closed-loop identification from a record (thesis 3.3.2, Figure 3.4(b)/(c)):
//! the axis stays under its cascade controller (a vertical axis, a machine
//! that may not run uncontrolled) while a periodic excitation is added to one
//! of the controller's inputs.
//!
//! - Where the excitation enters, [`ReferenceKind`]: the torque command
//!   (`tau_e` added to the controller output, (3.20)), the velocity setpoint
//!   `omega_d` ((3.23)), or the position setpoint `phi_d` (the same inversion
//!   with `K_PP C_omega` in place of `C_omega`).
//! - How the plant is found, [`ClosedLoopMethod`]: *direct*, the ETFE from the
//!   logged torque command (the whole plant input `tau_e + tau_c`) to the
//!   motor angle, no controller needed; *indirect*, the ETFE from the
//!   excitation to the angle (a closed-loop response `S_r`) inverted with the
//!   known controller: `G = S_r / (K_r - S_r C)`, which is (3.22) for
//!   `K_r = 1` and (3.24) for `K_r = C_omega`.
//!
//! [`KnownController`] gives the frequency responses of the discrete cascade
//! the drive ran (`beltune_rt::control::CascadeController` with the
//! coefficients of its [`CascadeConfig`]), evaluated exactly on the unit
//! circle `z = e^{j w T_s}`:
//!
//! ```text
//! G_R(z)     = b0 (1 - z^-1) / (1 + a1 z^-1)                  velocity filter
//! L_R(z)     = (1 + a1)/2 (1 + z^-1) / (1 + a1 z^-1)          desired-velocity low-pass (refinement (a))
//! C_PI(z)    = K_P + K_I T_s z^-1 / (1 - z^-1)                 forward-Euler integrator (6.25)
//! C_omega(z) = C_PI(z) G_pre(z)                                PI with the prefilter (Figure 6.9)
//! C          = C_omega (G_R + K_PP)                            (3.21)
//! K_r        = 1 | K_v C_omega [L_R] + d_v | K_PP C_omega      torque | velocity | position setpoint
//! ```
//!
//! The inversion holds for the linear controller: no saturation and no
//! anti-windup action during the record, and no inertia feedforward (its
//! acceleration input is the trajectory's, not derivable from the
//! reference). The Coulomb feedforward is constant while the velocity keeps
//! its sign (the thesis' operating point, 100 mm/s, 3.4) and only moves the
//! DC line.

use super::etfe::{etfe, EtfeConfig, Frf, LineStatus};
use super::strategy::indirect_closed_loop_reference;
use crate::lti::C64;
use crate::{Error, Result};
use beltune_rt::control::CascadeConfig;

/// Where the periodic excitation was added to the closed loop.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ReferenceKind {
    /// An excitation torque `tau_e` (N m) added to the controller output, Figure 3.4(c).
    Torque,
    /// The velocity setpoint `omega_d` (motor rad/s), (3.23).
    Velocity,
    /// The position setpoint `phi_d` (motor rad).
    Position,
}

impl ReferenceKind {
    /// Words for summaries.
    pub fn words(self) -> &'static str {
        match self {
            ReferenceKind::Torque => "excitation torque added to the controller output",
            ReferenceKind::Velocity => "velocity setpoint omega_d",
            ReferenceKind::Position => "position setpoint phi_d",
        }
    }
}

/// Direct or indirect closed-loop identification (3.3.2).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ClosedLoopMethod {
    /// ETFE from the logged torque command (the plant input) to the angle.
    Direct,
    /// ETFE from the excitation to the angle, inverted with the known controller.
    Indirect,
}

/// How a recorded identification was made (reported by `identify`, `--json`
/// and the commissioning report).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case", tag = "method")]
pub enum IdentificationStrategy {
    /// Open loop (3.18): torque command -> angle.
    OpenLoop,
    /// Direct closed loop: torque command -> angle, lines chosen by the reference.
    DirectClosedLoop {
        /// Where the excitation entered.
        reference: ReferenceKind,
    },
    /// Indirect closed loop: reference -> angle, inverted with the known controller.
    IndirectClosedLoop {
        /// Where the excitation entered.
        reference: ReferenceKind,
    },
}

impl IdentificationStrategy {
    /// One line of words, with the thesis' equation.
    pub fn words(self) -> String {
        match self {
            IdentificationStrategy::OpenLoop => {
                "open loop (3.18): torque command -> motor angle".to_string()
            }
            IdentificationStrategy::DirectClosedLoop { reference } => format!(
                "direct closed loop (3.3.2): torque command -> motor angle, lines chosen by the {}",
                reference.words()
            ),
            IdentificationStrategy::IndirectClosedLoop { reference } => format!(
                "indirect closed loop ({}): {} -> motor angle, inverted with the known controller",
                match reference {
                    ReferenceKind::Torque => "3.20-3.22",
                    ReferenceKind::Velocity => "3.23-3.24",
                    ReferenceKind::Position => "3.23-3.24 with K_PP C_omega",
                },
                reference.words()
            ),
        }
    }

    /// Short label: `open_loop`, `direct_closed_loop`, `indirect_closed_loop`.
    pub fn label(self) -> &'static str {
        match self {
            IdentificationStrategy::OpenLoop => "open_loop",
            IdentificationStrategy::DirectClosedLoop { .. } => "direct_closed_loop",
            IdentificationStrategy::IndirectClosedLoop { .. } => "indirect_closed_loop",
        }
    }
}

/// The frequency responses of a known discrete cascade controller (module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct KnownController {
    cfg: CascadeConfig<f64>,
}

impl KnownController {
    /// From the configuration the drive ran. Errors: an invalid configuration.
    pub fn new(cfg: CascadeConfig<f64>) -> Result<Self> {
        cfg.validate()?;
        Ok(KnownController { cfg })
    }

    /// The configuration.
    pub fn config(&self) -> &CascadeConfig<f64> {
        &self.cfg
    }

    /// Sampling time of the controller, s.
    pub fn ts_s(&self) -> f64 {
        self.cfg.ts_s
    }

    fn z_inv(&self, w_rad_s: f64) -> C64 {
        C64::from_polar(1.0, -w_rad_s * self.cfg.ts_s)
    }

    /// `G_R(e^{j w T_s})`, (rad/s)/rad.
    pub fn velocity_filter(&self, w_rad_s: f64) -> C64 {
        let v = &self.cfg.velocity_filter;
        let zi = self.z_inv(w_rad_s);
        (v.b0 + v.b1 * zi) / (1.0 + v.a1 * zi)
    }

    /// `C_omega = C_PI G_pre`, N m/(rad/s).
    pub fn velocity_controller(&self, w_rad_s: f64) -> C64 {
        let zi = self.z_inv(w_rad_s);
        let g = &self.cfg.gains;
        let pi = g.k_p_nm_s_per_rad + g.k_i_nm_per_rad * self.cfg.ts_s * zi / (1.0 - zi);
        let pre = self
            .cfg
            .prefilter
            .iter()
            .fold(C64::new(1.0, 0.0), |acc, s| {
                acc * (s.b0 + s.b1 * zi + s.b2 * zi * zi) / (1.0 + s.a1 * zi + s.a2 * zi * zi)
            });
        pi * pre
    }

    /// `C = C_omega (G_R + K_PP)` (3.21): from the motor angle to the
    /// negated torque command, N m/rad.
    pub fn feedback(&self, w_rad_s: f64) -> C64 {
        self.velocity_controller(w_rad_s)
            * (self.velocity_filter(w_rad_s) + self.cfg.gains.k_pp_per_s)
    }

    /// `K_r`: from the reference to the torque command with the loop open
    /// (module docs); N m per unit of the reference.
    pub fn reference_gain(&self, kind: ReferenceKind, w_rad_s: f64) -> C64 {
        let g = &self.cfg.gains;
        match kind {
            ReferenceKind::Torque => C64::new(1.0, 0.0),
            ReferenceKind::Velocity => {
                let lp = if self.cfg.filter_desired_velocity {
                    let a1 = self.cfg.velocity_filter.a1;
                    let zi = self.z_inv(w_rad_s);
                    0.5 * (1.0 + a1) * (1.0 + zi) / (1.0 + a1 * zi)
                } else {
                    C64::new(1.0, 0.0)
                };
                let ff = &self.cfg.feedforward;
                let viscous = if ff.terms.viscous {
                    ff.params.viscous_nm_s_per_rad
                } else {
                    0.0
                };
                g.k_v * self.velocity_controller(w_rad_s) * lp + viscous
            }
            ReferenceKind::Position => g.k_pp_per_s * self.velocity_controller(w_rad_s),
        }
    }

    /// Refuse what the inversion cannot represent for this reference: an
    /// inertia feedforward on a setpoint reference, a position reference
    /// without a position loop, a sampling time other than the record's (1 %).
    pub fn check_for(&self, kind: ReferenceKind, record_ts_s: f64) -> Result<()> {
        if (self.cfg.ts_s / record_ts_s - 1.0).abs() > 0.01 {
            return Err(Error::invalid(
                "controller sampling time",
                self.cfg.ts_s,
                format!("differs from the record's {record_ts_s} s by more than 1 %"),
            ));
        }
        let ff = &self.cfg.feedforward;
        if kind != ReferenceKind::Torque && ff.terms.inertia && ff.params.inertia_kg_m2 != 0.0 {
            return Err(Error::invalid(
                "inertia feedforward",
                ff.params.inertia_kg_m2,
                "must be off for a setpoint excitation (its acceleration is not in the record)",
            ));
        }
        if kind == ReferenceKind::Position && self.cfg.gains.k_pp_per_s <= 0.0 {
            return Err(Error::invalid(
                "K_PP",
                self.cfg.gains.k_pp_per_s,
                "a position-setpoint excitation needs a position loop",
            ));
        }
        Ok(())
    }
}

/// Direct closed loop on a record: the ETFE from the torque command (the
/// whole plant input) to the angle, keeping only lines the reference
/// excites (the torque command carries the loop's noise at every line).
pub fn direct_from_record(
    reference: &[f64],
    torque_command: &[f64],
    angle: &[f64],
    cfg: &EtfeConfig,
) -> Result<Frf> {
    let mut frf = etfe(torque_command, angle, cfg)?;
    let by_reference = etfe(reference, angle, cfg)?;
    restrict_to_reference(&mut frf, &by_reference);
    Ok(frf)
}

/// Mark the lines the reference does not excite (or where it is not
/// periodic) as such in `frf`.
fn restrict_to_reference(frf: &mut Frf, by_reference: &Frf) {
    for (s, r) in frf.line_status.iter_mut().zip(&by_reference.line_status) {
        if matches!(r, LineStatus::NotExcited | LineStatus::InputNoise) && *s == LineStatus::Usable
        {
            *s = *r;
        }
    }
}

/// Indirect closed loop on a record: the ETFE from the reference to the
/// angle, inverted with the known controller (module docs).
pub fn indirect_from_record(
    reference: &[f64],
    angle: &[f64],
    kind: ReferenceKind,
    controller: &KnownController,
    cfg: &EtfeConfig,
) -> Result<Frf> {
    controller.check_for(kind, cfg.ts_s)?;
    indirect_closed_loop_reference(
        reference,
        angle,
        |w| controller.reference_gain(kind, w),
        |w| controller.feedback(w),
        cfg,
    )
}
