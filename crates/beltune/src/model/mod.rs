//! Plant models of thesis chapter 2.
//!
//! - [`two_mass`]: the linear two-mass model and its transfer functions (2.33)-(2.49).

pub mod two_mass;

pub use two_mass::TwoMassParams;
