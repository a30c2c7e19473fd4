//! Real roots of the quartic polynomials of step 1 (Ferrari's method via the
//! resolvent cubic), without allocation.
//!
//! Ported from Ruckig's `roots.hpp` (via rsruckig 3.0.1).
//! Copyright (c) 2021 Lars Berscheid (Ruckig), Petri Koskinen (rsruckig);
//! MIT License, full notice in `trajectory/mod.rs`.

// In `cfg(test)` builds std is linked and its inherent `f64` methods shadow
// these `libm` ones, so the import is then unused.
#[cfg_attr(test, allow(unused_imports))]
use super::math::F64Math;

const COS_120: f64 = -0.50;
const SIN_120: f64 = 0.866_025_403_784_438_6;

/// A set of at most `N` distinct non-negative roots (fixed capacity).
#[derive(Clone, Copy, Debug)]
pub(crate) struct PositiveSet<const N: usize> {
    data: [f64; N],
    len: usize,
}

impl<const N: usize> PositiveSet<N> {
    /// The empty set.
    pub(crate) fn new() -> Self {
        Self {
            data: [0.0; N],
            len: 0,
        }
    }

    /// Insert `value` if it is `>= 0` (NaN is rejected), not yet present and
    /// there is room.
    pub(crate) fn insert(&mut self, value: f64) {
        if value >= 0.0 && !self.data[..self.len].contains(&value) && self.len < N {
            self.data[self.len] = value;
            self.len += 1;
        }
    }
}

impl<const N: usize> IntoIterator for PositiveSet<N> {
    type Item = f64;
    type IntoIter = core::iter::Take<core::array::IntoIter<f64, N>>;

    /// The roots in ascending order.
    fn into_iter(mut self) -> Self::IntoIter {
        // Insertion sort: at most four finite, non-NaN elements.
        for i in 1..self.len {
            let mut k = i;
            while k > 0 && self.data[k - 1] > self.data[k] {
                self.data.swap(k - 1, k);
                k -= 1;
            }
        }
        self.data.into_iter().take(self.len)
    }
}

/// Solve the resolvent cubic `x^3 + a x^2 + b x + c = 0` of a quartic; writes
/// the roots to `x` and returns how many are real (1, 2 or 3).
#[inline]
fn solve_resolvent(x: &mut [f64; 3], a: f64, b: f64, c: f64) -> usize {
    let a = a / 3.0;
    let a2 = a * a;
    let mut q = a2 - b / 3.0;
    let r = (a * (2.0 * a2 - b) + c) / 2.0;
    let r2 = r * r;
    let q3 = q * q * q;

    if r2 < q3 {
        let q_sqrt = q.sqrt();
        // Same NaN semantics as min/max in the reference.
        #[allow(clippy::manual_clamp)]
        let t = (r / (q * q_sqrt)).min(1.0).max(-1.0);
        q = -2.0 * q_sqrt;

        let theta = t.acos() / 3.0;
        let ux = theta.cos() * q;
        let uyi = theta.sin() * q;
        x[0] = ux - a;
        x[1] = ux * COS_120 - uyi * SIN_120 - a;
        x[2] = ux * COS_120 + uyi * SIN_120 - a;
        3
    } else {
        let mut a_ = (-r.abs() - (r2 - q3).sqrt()).cbrt();
        if r < 0.0 {
            a_ = -a_;
        }
        let b_ = if a_ == 0.0 { 0.0 } else { q / a_ };

        x[0] = (a_ + b_) - a;
        x[1] = -(a_ + b_) / 2.0 - a;
        x[2] = 3.0_f64.sqrt() * (a_ - b_) / 2.0;
        if x[2].abs() < f64::EPSILON {
            x[2] = x[1];
            2
        } else {
            1
        }
    }
}

/// Non-negative real roots of the monic quartic
/// `x^4 + c[0] x^3 + c[1] x^2 + c[2] x + c[3] = 0`.
#[inline]
pub(crate) fn solve_quart_monic_arr(c: &[f64; 4]) -> PositiveSet<4> {
    solve_quart_monic_coeffs(c[0], c[1], c[2], c[3])
}

/// Non-negative real roots of `x^4 + a x^3 + b x^2 + c x + d = 0`.
#[inline]
pub(crate) fn solve_quart_monic_coeffs(a: f64, b: f64, c: f64, d: f64) -> PositiveSet<4> {
    let mut roots = PositiveSet::new();

    let a_squared = a * a;
    let four_b = 4.0 * b;

    if d.abs() < f64::EPSILON {
        if c.abs() < f64::EPSILON {
            roots.insert(0.0);

            let d_ = a_squared - four_b;
            if d_.abs() < f64::EPSILON {
                roots.insert(-a / 2.0);
            } else if d_ > 0.0 {
                let sqrt_d = d_.sqrt();
                roots.insert((-a - sqrt_d) / 2.0);
                roots.insert((-a + sqrt_d) / 2.0);
            }
            return roots;
        }

        if a.abs() < f64::EPSILON && b.abs() < f64::EPSILON {
            roots.insert(0.0);
            roots.insert(-c.cbrt());
            return roots;
        }
    }

    let a3 = -b;
    let b3 = a * c - 4.0 * d;
    let c3 = -a_squared * d - c * c + four_b * d;

    let mut x3 = [0.0; 3];
    let number_zeroes = solve_resolvent(&mut x3, a3, b3, c3);

    let mut y = x3[0];
    // Choose the resolvent root of maximal absolute value.
    if number_zeroes != 1 {
        if x3[1].abs() > y.abs() {
            y = x3[1];
        }
        if x3[2].abs() > y.abs() {
            y = x3[2];
        }
    }

    let q1: f64;
    let q2: f64;
    let p1: f64;
    let p2: f64;

    let mut d_ = y * y - 4.0 * d;
    if d_.abs() < f64::EPSILON {
        q2 = y / 2.0;
        q1 = q2;
        d_ = a_squared - 4.0 * (b - y);
        if d_.abs() < f64::EPSILON {
            p2 = a / 2.0;
            p1 = p2;
        } else {
            let sqrt_d = d_.sqrt();
            p1 = (a + sqrt_d) / 2.0;
            p2 = (a - sqrt_d) / 2.0;
        }
    } else {
        let sqrt_d = d_.sqrt();
        q1 = (y + sqrt_d) / 2.0;
        q2 = (y - sqrt_d) / 2.0;
        p1 = (a * q1 - c) / (q1 - q2);
        p2 = (c - a * q2) / (q1 - q2);
    }

    const EPS_M_BY_16: f64 = 16.0 * f64::EPSILON;
    d_ = p1 * p1 - 4.0 * q1;
    if d_.abs() < EPS_M_BY_16 {
        roots.insert(-p1 / 2.0);
    } else if d_ > 0.0 {
        let sqrt_d = d_.sqrt();
        roots.insert((-p1 - sqrt_d) / 2.0);
        roots.insert((-p1 + sqrt_d) / 2.0);
    }

    d_ = p2 * p2 - 4.0 * q2;
    if d_.abs() < EPS_M_BY_16 {
        roots.insert(-p2 / 2.0);
    } else if d_ > 0.0 {
        let sqrt_d = d_.sqrt();
        roots.insert((-p2 - sqrt_d) / 2.0);
        roots.insert((-p2 + sqrt_d) / 2.0);
    }

    roots
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Roots are exact for small integers; tolerance covers Ferrari's rounding.
    const ROOT_TOL: f64 = 1e-9;

    #[test]
    fn quartic_with_known_roots() {
        // (x-1)(x-2)(x-3)(x+4) = x^4 - 2x^3 - 13x^2 + 38x - 24
        let roots: [f64; 3] = {
            let mut out = [0.0; 3];
            let mut n = 0;
            for r in solve_quart_monic_coeffs(-2.0, -13.0, 38.0, -24.0) {
                out[n] = r;
                n += 1;
            }
            assert_eq!(n, 3, "the negative root -4 is dropped");
            out
        };
        for (r, expected) in roots.iter().zip([1.0, 2.0, 3.0]) {
            assert!((r - expected).abs() < ROOT_TOL, "{r} vs {expected}");
        }
    }

    #[test]
    fn quartic_without_real_roots_is_empty() {
        // x^4 + 1 = 0
        assert_eq!(
            solve_quart_monic_coeffs(0.0, 0.0, 0.0, 1.0)
                .into_iter()
                .count(),
            0
        );
    }
}
