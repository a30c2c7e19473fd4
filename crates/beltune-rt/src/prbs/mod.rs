//! Excitation signals for identification (thesis Section 3.1).
//!
//! - [`Prbs`]: the pseudorandom binary signal (3.2)-(3.4) from a maximal-length
//!   linear feedback shift register, with clock period `P_PRBS` and the thesis'
//!   amplitude convention `A (s - 1/2)` (values `+-A/2`).
//!
//! It is driven by the caller once per sample (`step()`), never read a
//! clock, never allocate, and are exactly periodic: sample `k` and sample
//! `k + period_samples()` are bit-identical.

mod lfsr;

pub use lfsr::{Prbs, MAX_ORDER, MIN_ORDER, TAPS};
