//! # beltune-rt: what runs in the drive every sample
//!
//! `#![no_std]`, allocation-free and panic-free on finite input. Every type is
//! generic over [`Real`] (`f64`, or `f32` for MCUs with a single-precision FPU),
//! time is passed in by the caller (never read from a clock), and fixed
//! capacities are const generics.
//!
//! Modules follow the thesis (Gruber, "Self-Commissioning of Linear Toothed Belt
//! Drives", TU Wien 2017):
//!
//! | module | thesis | what |
//! | --- | --- | --- |
//! | [`prbs`] | 3.1 | PRBS (3.2)-(3.4), periodic chirp and multisine excitation |
//! | [`filter`] | 4.2.1, 6.1 | second-order sections, Tustin with pre-warping, notch (4.1), Butterworth (4.3), velocity filter (6.1) |
//! | [`encoder`] | 6.1 | quadrature decoding with the debouncing state machine (Figure 6.3) |
//! | [`velocity`] | 6.1 | high-pass differentiator, event counter, gate measurement, blend (6.1)-(6.21) |
//! | [`control`] | 4, 6.2, App. B | cascaded P-PI controller, anti-windup (6.26), feedforward (4.16), PID conversion (B.6) |
//! | [`trajectory`] | 6.3 | jerk-limited time-optimal 1-DOF trajectory generator |
//!
//! Units are SI throughout: positions in m or rad, torques in N m, time in s.
#![no_std]
#![deny(missing_docs)]
#![forbid(unsafe_code)]

pub mod control;
pub mod encoder;
mod error;
pub mod filter;
pub mod prbs;
pub mod real;
pub mod trajectory;
pub mod velocity;

pub use error::Error;
pub use real::Real;
