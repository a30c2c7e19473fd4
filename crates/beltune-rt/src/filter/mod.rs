//! Discrete filters: second-order sections and first-order sections obtained
//! from continuous designs by the Tustin (bilinear) transform with frequency
//! pre-warping, and the three continuous designs of the thesis:
//!
//! - the notch (4.1) `(s^2 + 2 w_r/d_n s + w_r^2) / (s^2 + 2 d_n w_r s + w_r^2)`,
//! - the 2nd-order Butterworth low-pass (4.3) `1 / (s^2/w_bw^2 + sqrt(2) s/w_bw + 1)`
//!   (the extra `s` printed in the thesis is a typo, see docs/thesis-map.md),
//! - the velocity filter (6.1) `G_R(s) = s / (T_R s + 1)`.
//!
//! The coefficient structs are plain data that the design code fills in; the
//! state-holding filters ([`Sos`], [`FirstOrder`], [`Cascade`]) run per sample.
//!
//! Cost per sample (f64): a [`Sos`] is 5 multiplications and 4 additions
//! (transposed direct form II), a [`FirstOrder`] 3 and 2.

mod section;
mod tustin;

pub use section::{Cascade, FirstOrder, FirstOrderCoeffs, FreqPoint, Sos, SosCoeffs};
pub use tustin::{
    butterworth_lowpass, first_order_from_continuous, notch, sos_from_continuous, velocity_filter,
    Prewarp,
};
