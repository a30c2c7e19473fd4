//! Frequency-domain toolkit: continuous transfer functions as polynomial
//! ratios evaluated at `s = j w`, the exact dead time, frequency responses,
//! margins, discretization. No Rust crate covers this well (see CRATES.md).

mod tf;

pub use tf::{Poly, Tf};

/// Complex numbers used throughout.
pub type C64 = num_complex::Complex64;
