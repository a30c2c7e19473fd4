//! Velocity from a quadrature encoder (thesis Section 6.1, Appendix C).
//!
//! Four estimators, each with one `update(...) -> velocity` per control sample:
//!
//! | type | thesis | input per sample |
//! | --- | --- | --- |
//! | [`HighPassDifferentiator`] | (6.1) `G_R = s/(T_R s + 1)` | net counts |
//! | [`EventCounter`] | (6.4) | [`EdgeWindow`](crate::encoder::EdgeWindow) |
//! | [`GateMeasurement`] | (6.14), timeout (6.17)-(6.18) | edge window + sample time stamp |
//! | [`Blended`] | (6.19)-(6.21) | edge window + sample time stamp |
//!
//! The edge windows come from [`QuadratureDecoder`](crate::encoder::QuadratureDecoder).
//! [`EncoderResolution`] holds the three time/position quanta and evaluates
//! the thesis' characteristic speeds and error formulas.
//!
//! Units: positions are in the encoder's unit `u` (m for a linear, rad for a
//! rotary encoder; the thesis drops the distinction), speeds in `u/s`, times in
//! s, time stamps in timer ticks.

mod blend;
mod differentiator;
mod event_counter;
mod gate;
mod resolution;

pub use blend::{switching_weight, Blended};
pub use differentiator::HighPassDifferentiator;
pub use event_counter::EventCounter;
pub use gate::GateMeasurement;
pub use resolution::EncoderResolution;

#[cfg(test)]
mod stream;
