//! Vibration after a move: input shapers (Klipper's definitions and its
//! choice from a measured spectrum), model-based shaping of the jerk-limited
//! trajectory with the identified mode where the cart stops, and the
//! vibration benchmark (docs/vibration.md).

pub mod bench;
pub mod klipper;
pub mod shaper;
pub mod shaping;

#[cfg(test)]
mod tests;
