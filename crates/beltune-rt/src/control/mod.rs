//! The cascaded position/velocity controller of the drive (thesis chapter 4,
//! Section 6.2, Appendix B).
//!
//! - [`cascade`]: the P-PI cascade of Figure 4.1 / 6.9 with prefilter, torque
//!   saturation and conditional-integration anti-windup (6.26);
//! - [`feedforward`]: the torque feedforward (4.16) with switchable terms;
//! - [`setpoint`]: setpoints in motor coordinates and the cart -> motor
//!   conversion with optional belt-stretch compensation;
//! - [`pid`]: P-PI <-> PID gain conversion (B.6).
//!
//! Firmware-style use (one call per 100 us interrupt):
//!
//! ```
//! use beltune_rt::control::{CascadeConfig, CascadeController, CascadeGains, Feedforward, Setpoint};
//! use beltune_rt::filter::butterworth_lowpass;
//!
//! # fn main() -> Result<(), beltune_rt::Error> {
//! let gains = CascadeGains::new(6.29, 0.12, 1.39); // K_PP 1/s, K_P N m s/rad, K_I N m/rad
//! let mut cfg = CascadeConfig::<f32>::new(gains.cast(), 1e-4, 2e-3, 2.0)?; // T_s, T_R, tau_max
//! cfg.prefilter[0] = butterworth_lowpass(123.24, 1e-4)?.cast();
//! cfg.feedforward = Feedforward::nonlinear(2.14e-3, 2.53e-3, 0.125);
//! let mut ctrl = CascadeController::new(cfg)?;
//! ctrl.reset_to(0.0); // encoder angle at switch-on
//! // in the interrupt:
//! let out = ctrl.step(&Setpoint::hold(0.0), 0.0);
//! assert_eq!(out.torque_nm, 0.0);
//! # Ok(())
//! # }
//! ```

pub mod cascade;
pub mod feedforward;
pub mod pid;
pub mod setpoint;

pub use cascade::{AntiWindup, CascadeConfig, CascadeController, CascadeGains, ControlOutput};
pub use feedforward::{
    Feedforward, FeedforwardParams, FeedforwardTerms, DEFAULT_COULOMB_DEADBAND_RAD_S,
};
pub use pid::{pid_to_ppi, position_gain_root, ppi_to_pid, PidGains, PositionGainRoot};
pub use setpoint::{BeltStretch, CartSample, MotionSample, Setpoint, SetpointConversion};

#[cfg(test)]
mod closed_loop_tests;
