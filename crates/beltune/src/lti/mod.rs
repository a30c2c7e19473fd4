//! Frequency-domain toolkit: continuous transfer functions as polynomial
//! ratios evaluated at `s = j w`, the exact dead time, frequency responses,
//! margins, discretization. No Rust crate covers this well (see CRATES.md).

pub mod discrete;
pub mod freq;
pub mod margins;
mod tf;

pub use freq::{bode, db, feedback, from_db, log_grid, BodePoint, Chain, Element};
pub use margins::{margins, StabilityMargins};
pub use tf::{Poly, Tf};

/// Complex numbers used throughout.
pub type C64 = num_complex::Complex64;
