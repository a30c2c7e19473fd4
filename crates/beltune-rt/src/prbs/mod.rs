//! Excitation signals for identification (thesis Section 3.1).
//!
//! - [`Prbs`]: the pseudorandom binary signal (3.2)-(3.4) from a maximal-length
//!   linear feedback shift register, with clock period `P_PRBS` and the thesis'
//!   amplitude convention `A (s - 1/2)` (values `+-A/2`).
//! - [`Chirp`]: a periodic sine sweep (linear or logarithmic) with an integer
//!   number of samples per period.
//! - [`Multisine`]: a periodic sum of `N` sines at chosen harmonics of the
//!   period with Schroeder phases.
//!
//! All three are driven by the caller once per sample (`step()`), never read a
//! clock, never allocate, and are exactly periodic: sample `k` and sample
//! `k + period_samples()` are bit-identical.

mod chirp;
mod lfsr;
mod multisine;

pub use chirp::{Chirp, Sweep};
pub use lfsr::{Prbs, MAX_ORDER, MIN_ORDER, TAPS};
pub use multisine::Multisine;
