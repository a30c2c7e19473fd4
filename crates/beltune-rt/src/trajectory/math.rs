//! Scalar helpers for the trajectory generator: `libm` functions as `f64`
//! methods (so that the ported formulas read as in the reference) and the
//! closed-form integration of a constant-jerk phase.

/// `libm` functions on `f64` under their usual method names (no_std).
/// In `cfg(test)` builds std's inherent methods take precedence.
#[cfg_attr(test, allow(dead_code))]
pub(crate) trait F64Math {
    /// Square root.
    fn sqrt(self) -> Self;
    /// Cube root.
    fn cbrt(self) -> Self;
    /// Arc cosine.
    fn acos(self) -> Self;
    /// Cosine.
    fn cos(self) -> Self;
    /// Sine.
    fn sin(self) -> Self;
}

impl F64Math for f64 {
    #[inline]
    fn sqrt(self) -> f64 {
        libm::sqrt(self)
    }
    #[inline]
    fn cbrt(self) -> f64 {
        libm::cbrt(self)
    }
    #[inline]
    fn acos(self) -> f64 {
        libm::acos(self)
    }
    #[inline]
    fn cos(self) -> f64 {
        libm::cos(self)
    }
    #[inline]
    fn sin(self) -> f64 {
        libm::sin(self)
    }
}

/// Kinematic state after a phase of constant jerk.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Kinematics {
    /// Position in m.
    pub position: f64,
    /// Velocity in m/s.
    pub velocity: f64,
    /// Acceleration in m/s^2.
    pub acceleration: f64,
}

/// Integrate a constant jerk `j` (m/s^3) for `t` seconds from `(p0, v0, a0)`:
/// `p = p0 + v0 t + a0 t^2/2 + j t^3/6`, `v = v0 + a0 t + j t^2/2`, `a = a0 + j t`.
#[inline]
pub(crate) fn integrate(t: f64, p0: f64, v0: f64, a0: f64, j: f64) -> Kinematics {
    Kinematics {
        position: p0 + t * (v0 + t * (a0 / 2.0 + t * j / 6.0)),
        velocity: v0 + t * (a0 + t * j / 2.0),
        acceleration: a0 + t * j,
    }
}
