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
//! Firmware-style use (one call per 100 us interrupt; the same example as in the crate README):
//!
//! ```
//! use beltune_rt::control::{
//!     BeltStretch, CartSample, CascadeConfig, CascadeController, CascadeGains, Feedforward, Setpoint,
//!     SetpointConversion,
//! };
//! use beltune_rt::filter::butterworth_lowpass;
//!
//! # fn main() -> Result<(), beltune_rt::Error> {
//! const TS: f64 = 1e-4; // 10 kHz
//! // K_PP 1/s, K_P N m s/rad, K_I N m/rad (K_v = 1 by (4.17))
//! let gains = CascadeGains::new(6.29, 0.12, 1.39);
//! // velocity filter G_R = s/(T_R s + 1) with T_R = 2 ms, torque limit 2 N m
//! let mut cfg = CascadeConfig::<f64>::new(gains, TS, 2e-3, 2.0)?;
//! cfg.prefilter[0] = butterworth_lowpass(123.24, TS)?;              // G_pre (4.3)
//! cfg.feedforward = Feedforward::nonlinear(2.14e-3, 2.53e-3, 0.125); // m_e, d_v, tau_c (4.16)
//! cfg.feedforward_preview = true;      // feedforward from the trajectory n_T samples ahead
//! cfg.filter_desired_velocity = true;  // omega_d through the same lag as the measurement
//! let mut ctrl = CascadeController::<f32>::new(cfg.cast())?;
//!
//! // cart trajectory (m) -> motor setpoint (rad), with belt-stretch compensation
//! let conv = SetpointConversion::<f32>::new(12.414e-3, BeltStretch::On { m_c_kg: 13.44, c_n_per_m: 203.74e3 })?;
//!
//! let encoder_angle_rad: f32 = 0.0; // read from the encoder at switch-on
//! ctrl.reset_to(encoder_angle_rad); // bumpless start
//!
//! // --- in the 100 us interrupt ---
//! let cart_now = CartSample::default();   // trajectory sample k
//! let cart_ahead = CartSample::default(); // trajectory sample k + n_T (dead time 1 ms: n_T = 10)
//! let sp = Setpoint::with_preview(conv.motor_sample(&cart_now), conv.motor_sample(&cart_ahead));
//! let out = ctrl.step(&sp, encoder_angle_rad);
//! let torque_command_nm = out.torque_nm; // to the current controller
//! # assert!(out.finite && torque_command_nm.abs() <= 2.0);
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
pub use setpoint::{
    BeltProfile, BeltStretch, CartSample, MotionSample, Setpoint, SetpointConversion,
};

#[cfg(test)]
mod closed_loop_tests;
