//! Polynomials of fixed capacity and their real roots on an interval, for the
//! profile equations of asymmetric jerk limits (`asymmetric.rs`).
//!
//! The profile families there reduce "reach the target position" to one
//! polynomial equation in one unknown. Rather than deriving each polynomial's
//! coefficients by hand (as Ruckig does for symmetric jerk), the phases are
//! integrated in polynomial arithmetic ([`Poly`], and [`Surd`] for families
//! whose second unknown is a square root `y = sqrt(q(x))`), so the
//! coefficients come out of the same kinematics that later build the profile.
//! [`real_roots`] then isolates every real root on an interval by splitting
//! it at the roots of the derivative (recursively), so that each piece is
//! monotone and holds at most one root, found by safeguarded Newton steps.
//! No allocation: capacities are fixed.

use core::ops::{Add, Mul, Neg, Sub};

/// Number of coefficients a [`Poly`] holds (degree at most `CAP - 1`): the
/// highest degree `asymmetric.rs` needs is 6 (`a^2 - q b^2` with `a` cubic).
pub(crate) const CAP: usize = 7;

/// A polynomial `c[0] + c[1] x + ... + c[CAP-1] x^(CAP-1)`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Poly {
    /// Coefficients, lowest degree first.
    pub c: [f64; CAP],
}

impl Poly {
    /// The constant `value`.
    pub(crate) fn constant(value: f64) -> Self {
        let mut c = [0.0; CAP];
        c[0] = value;
        Self { c }
    }

    /// The unknown `x` itself.
    pub(crate) fn x() -> Self {
        let mut c = [0.0; CAP];
        c[1] = 1.0;
        Self { c }
    }

    /// Highest index with a non-zero coefficient (`None` for the zero polynomial).
    pub(crate) fn degree(&self) -> Option<usize> {
        (0..CAP).rev().find(|&i| self.c[i] != 0.0)
    }

    /// Value at `x` (Horner).
    pub(crate) fn eval(&self, x: f64) -> f64 {
        self.c.iter().rev().fold(0.0, |acc, &c| acc * x + c)
    }

    /// Sum of the magnitudes of the terms at `x`: the scale against which a
    /// value of `eval(x)` is "zero up to rounding".
    fn magnitude(&self, x: f64) -> f64 {
        let ax = x.abs();
        self.c.iter().rev().fold(0.0, |acc, &c| acc * ax + c.abs())
    }

    /// The derivative.
    pub(crate) fn derivative(&self) -> Self {
        let mut c = [0.0; CAP];
        for i in 1..CAP {
            c[i - 1] = self.c[i] * i as f64;
        }
        Self { c }
    }

    /// `self * k` for a scalar `k`.
    pub(crate) fn scale(&self, k: f64) -> Self {
        let mut c = self.c;
        for v in &mut c {
            *v *= k;
        }
        Self { c }
    }
}

impl Add for Poly {
    type Output = Self;
    fn add(self, rhs: Self) -> Self {
        let mut c = self.c;
        for (v, r) in c.iter_mut().zip(rhs.c) {
            *v += r;
        }
        Self { c }
    }
}

impl Sub for Poly {
    type Output = Self;
    fn sub(self, rhs: Self) -> Self {
        self + rhs.scale(-1.0)
    }
}

impl Neg for Poly {
    type Output = Self;
    fn neg(self) -> Self {
        self.scale(-1.0)
    }
}

impl Mul for Poly {
    type Output = Self;
    /// Product; terms above degree `CAP - 1` are dropped (the callers stay
    /// within it, see [`CAP`]; `asymmetric::tests` compares the family
    /// polynomials with direct integration, which a dropped term would fail).
    fn mul(self, rhs: Self) -> Self {
        let mut c = [0.0; CAP];
        for i in 0..CAP {
            if self.c[i] == 0.0 {
                continue;
            }
            for k in 0..CAP - i {
                c[i + k] += self.c[i] * rhs.c[k];
            }
        }
        Self { c }
    }
}

/// `a(x) + y b(x)` with `y^2 = q(x)`: the arithmetic of a family whose
/// second unknown is `y = +-sqrt(q(x))`. Products reduce `y^2` to `q`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Surd {
    /// Part free of `y`.
    pub a: Poly,
    /// Coefficient of `y`.
    pub b: Poly,
    /// `y^2`.
    pub q: Poly,
}

impl Surd {
    /// The constant `value` (in the algebra of `y^2 = q`).
    pub(crate) fn constant(value: f64, q: Poly) -> Self {
        Self::poly(Poly::constant(value), q)
    }

    /// The polynomial `a(x)` (no `y` part).
    pub(crate) fn poly(a: Poly, q: Poly) -> Self {
        Self {
            a,
            b: Poly::constant(0.0),
            q,
        }
    }

    /// `y` itself.
    pub(crate) fn y(q: Poly) -> Self {
        Self {
            a: Poly::constant(0.0),
            b: Poly::constant(1.0),
            q,
        }
    }

    /// `self * k` for a scalar `k`.
    pub(crate) fn scale(&self, k: f64) -> Self {
        Self {
            a: self.a.scale(k),
            b: self.b.scale(k),
            q: self.q,
        }
    }

    /// `self + k` for a scalar `k`.
    pub(crate) fn plus(&self, k: f64) -> Self {
        Self {
            a: self.a + Poly::constant(k),
            b: self.b,
            q: self.q,
        }
    }

    /// The polynomial whose roots contain every `x` with `a + y b = 0` for
    /// `y = +sqrt(q)` or `y = -sqrt(q)`: `a^2 - q b^2` (just `a` without `y`).
    pub(crate) fn eliminate_y(&self) -> Poly {
        if self.b.degree().is_none() {
            self.a
        } else {
            self.a * self.a - self.q * self.b * self.b
        }
    }
}

impl Add for Surd {
    type Output = Self;
    fn add(self, rhs: Self) -> Self {
        Self {
            a: self.a + rhs.a,
            b: self.b + rhs.b,
            q: self.q,
        }
    }
}

impl Sub for Surd {
    type Output = Self;
    fn sub(self, rhs: Self) -> Self {
        self + rhs.scale(-1.0)
    }
}

impl Mul for Surd {
    type Output = Self;
    fn mul(self, rhs: Self) -> Self {
        Self {
            a: self.a * rhs.a + self.q * self.b * rhs.b,
            b: self.a * rhs.b + self.b * rhs.a,
            q: self.q,
        }
    }
}

/// At most `CAP` real roots in ascending order.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Roots {
    x: [f64; CAP],
    len: usize,
}

impl Roots {
    fn new() -> Self {
        Self {
            x: [0.0; CAP],
            len: 0,
        }
    }

    fn push(&mut self, x: f64) {
        if self.len < CAP && (self.len == 0 || self.x[self.len - 1] != x) {
            self.x[self.len] = x;
            self.len += 1;
        }
    }

    /// The roots found.
    pub(crate) fn as_slice(&self) -> &[f64] {
        &self.x[..self.len]
    }
}

/// A near-double root is reported when `|p(x)|` at an extremum of `p` is
/// below this fraction of the magnitude of its terms (candidates are only
/// candidates: the caller checks the profile they give).
const TANGENT_REL: f64 = 1e-9;

/// Every real root of `p` in `[lo, hi]` in ascending order, plus (as
/// candidates) extrema of `p` where it touches zero up to rounding. The zero
/// polynomial has no isolated roots and gives none.
pub(crate) fn real_roots(p: &Poly, lo: f64, hi: f64) -> Roots {
    let mut out = Roots::new();
    if !lo.is_finite() || !hi.is_finite() || lo > hi {
        return out;
    }
    if let Some(deg) = p.degree() {
        roots_rec(p, deg, lo, hi, true, &mut out);
    }
    out
}

fn roots_rec(p: &Poly, deg: usize, lo: f64, hi: f64, tangent: bool, out: &mut Roots) {
    match deg {
        0 => {}
        1 => {
            let x = -p.c[0] / p.c[1];
            if lo <= x && x <= hi {
                out.push(x);
            }
        }
        _ => {
            let d = p.derivative();
            // `d` has degree `deg - 1` unless the leading term underflowed.
            let crit = match d.degree() {
                Some(dd) => {
                    let mut c = Roots::new();
                    roots_rec(&d, dd, lo, hi, false, &mut c);
                    c
                }
                None => Roots::new(),
            };
            let mut u = lo;
            let mut fu = p.eval(u);
            if fu == 0.0 {
                out.push(u);
            }
            for i in 0..=crit.len {
                let w = if i < crit.len { crit.x[i] } else { hi };
                let fw = p.eval(w);
                if fw == 0.0 {
                    out.push(w);
                } else if fu != 0.0 && (fu < 0.0) != (fw < 0.0) {
                    out.push(monotone_root(p, &d, u, w, fu));
                } else if tangent && i < crit.len && fw.abs() <= TANGENT_REL * p.magnitude(w) {
                    out.push(w);
                }
                u = w;
                fu = fw;
            }
        }
    }
}

/// The root of `p` in `[u, w]` where `p` is monotone and `p(u)` (= `fu`) and
/// `p(w)` have opposite signs: Newton steps kept inside the bracket, bisection
/// when a step would leave it or not shrink it enough.
fn monotone_root(p: &Poly, d: &Poly, mut u: f64, mut w: f64, fu: f64) -> f64 {
    let u_negative = fu < 0.0;
    let mut x = 0.5 * (u + w);
    for _ in 0..200 {
        let fx = p.eval(x);
        if fx == 0.0 {
            return x;
        }
        if (fx < 0.0) == u_negative {
            u = x;
        } else {
            w = x;
        }
        let dx = d.eval(x);
        let newton = x - fx / dx;
        let next = if dx != 0.0 && newton > u && newton < w && (newton - x).abs() < 0.5 * (w - u) {
            newton
        } else {
            0.5 * (u + w)
        };
        if next == x || w - u <= f64::EPSILON * u.abs().max(w.abs()) {
            return next;
        }
        x = next;
    }
    x
}

#[cfg(test)]
mod tests {
    use super::*;

    fn from_roots(roots: &[f64]) -> Poly {
        roots.iter().fold(Poly::constant(1.0), |p, &r| {
            p * (Poly::x() - Poly::constant(r))
        })
    }

    #[test]
    fn recovers_known_roots_of_a_sextic() {
        let want = [-3.0, -0.5, 0.1, 0.2, 1.7, 40.0];
        assert_eq!(want.len(), CAP - 1);
        let p = from_roots(&want).scale(2.5);
        let got = real_roots(&p, -10.0, 100.0);
        assert_eq!(got.as_slice().len(), want.len(), "{got:?}");
        for (g, w) in got.as_slice().iter().zip(want) {
            assert!((g - w).abs() <= 1e-12 * w.abs().max(1.0), "{g} vs {w}");
        }
        // Only the roots inside the interval.
        let inside = real_roots(&p, 0.0, 1.0);
        assert_eq!(inside.as_slice().len(), 2);
    }

    #[test]
    fn reports_double_roots_and_skips_complex_ones() {
        // (x - 1)^2 (x^2 + 1): one double root, no other real root.
        let p = from_roots(&[1.0, 1.0]) * (Poly::x() * Poly::x() + Poly::constant(1.0));
        let got = real_roots(&p, -5.0, 5.0);
        assert_eq!(got.as_slice().len(), 1, "{got:?}");
        assert!((got.as_slice()[0] - 1.0).abs() < 1e-7);
    }

    #[test]
    fn surd_arithmetic_reduces_y_squared() {
        // y^2 = x^2 - 1; (1 + y)(1 - y) = 1 - y^2 = 2 - x^2.
        let q = Poly::x() * Poly::x() - Poly::constant(1.0);
        let one = Surd::constant(1.0, q);
        let y = Surd::y(q);
        let prod = (one + y) * (one - y);
        assert_eq!(prod.b.degree(), None);
        for x in [-2.0, 0.3, 5.0] {
            assert!((prod.a.eval(x) - (2.0 - x * x)).abs() < 1e-12);
        }
        // a + y b = 0 with a = x, b = 1  <=>  x^2 - q = 1 = 0: no root.
        let s = Surd::poly(Poly::x(), q) + y;
        assert_eq!(s.eliminate_y().degree(), Some(0));
    }
}
