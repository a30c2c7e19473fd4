//! Polynomials and rational transfer functions in `s`.

use super::C64;

/// A real polynomial in `s`, coefficients in **ascending** powers:
/// `coeffs[k]` multiplies `s^k`.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Poly {
    /// Coefficients, `coeffs[k]` for `s^k`.
    pub coeffs: Vec<f64>,
}

impl Poly {
    /// From ascending coefficients.
    pub fn new(coeffs: Vec<f64>) -> Self {
        Poly { coeffs }
    }

    /// From coefficients in **descending** powers (the thesis' and MATLAB's order).
    pub fn from_descending(coeffs: &[f64]) -> Self {
        Poly {
            coeffs: coeffs.iter().rev().copied().collect(),
        }
    }

    /// The polynomial `s`.
    pub fn s() -> Self {
        Poly::new(vec![0.0, 1.0])
    }

    /// Degree, ignoring trailing zero coefficients (0 for the zero polynomial).
    pub fn degree(&self) -> usize {
        self.coeffs.iter().rposition(|c| *c != 0.0).unwrap_or(0)
    }

    /// Value at a complex point (Horner).
    pub fn eval(&self, s: C64) -> C64 {
        self.coeffs
            .iter()
            .rev()
            .fold(C64::new(0.0, 0.0), |acc, c| acc * s + c)
    }

    /// Product of two polynomials.
    pub fn mul(&self, other: &Poly) -> Poly {
        if self.coeffs.is_empty() || other.coeffs.is_empty() {
            return Poly::new(vec![]);
        }
        let mut out = vec![0.0; self.coeffs.len() + other.coeffs.len() - 1];
        for (i, a) in self.coeffs.iter().enumerate() {
            for (j, b) in other.coeffs.iter().enumerate() {
                out[i + j] += a * b;
            }
        }
        Poly::new(out)
    }

    /// Sum of two polynomials.
    pub fn add(&self, other: &Poly) -> Poly {
        let n = self.coeffs.len().max(other.coeffs.len());
        let get = |p: &Poly, k: usize| p.coeffs.get(k).copied().unwrap_or(0.0);
        Poly::new((0..n).map(|k| get(self, k) + get(other, k)).collect())
    }

    /// The polynomial times a scalar.
    pub fn scale(&self, k: f64) -> Poly {
        Poly::new(self.coeffs.iter().map(|c| c * k).collect())
    }
}

/// A rational transfer function `num(s) / den(s)`.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Tf {
    /// Numerator.
    pub num: Poly,
    /// Denominator.
    pub den: Poly,
}

impl Tf {
    /// From numerator and denominator.
    pub fn new(num: Poly, den: Poly) -> Self {
        Tf { num, den }
    }

    /// From coefficient slices in **descending** powers of `s`.
    pub fn from_descending(num: &[f64], den: &[f64]) -> Self {
        Tf::new(Poly::from_descending(num), Poly::from_descending(den))
    }

    /// A constant gain.
    pub fn gain(k: f64) -> Self {
        Tf::new(Poly::new(vec![k]), Poly::new(vec![1.0]))
    }

    /// Value at a complex frequency `s`.
    pub fn eval(&self, s: C64) -> C64 {
        self.num.eval(s) / self.den.eval(s)
    }

    /// Frequency response at `w` in rad/s, i.e. the value at `s = j w`.
    pub fn freq_response(&self, w_rad_s: f64) -> C64 {
        self.eval(C64::new(0.0, w_rad_s))
    }

    /// Series connection `self * other`.
    pub fn series(&self, other: &Tf) -> Tf {
        Tf::new(self.num.mul(&other.num), self.den.mul(&other.den))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn first_order_lowpass_at_corner_is_minus_3db_and_minus_45deg() {
        // 1 / (T s + 1) with T = 0.01 s; at w = 1/T: |G| = 1/sqrt 2, arg = -45 deg.
        let g = Tf::from_descending(&[1.0], &[0.01, 1.0]);
        let h = g.freq_response(100.0);
        assert!((h.norm() - std::f64::consts::FRAC_1_SQRT_2).abs() < 1e-12);
        assert!((h.arg().to_degrees() + 45.0).abs() < 1e-9);
    }

    #[test]
    fn poly_arithmetic() {
        let p = Poly::from_descending(&[1.0, 2.0]); // s + 2
        let q = Poly::from_descending(&[1.0, -2.0]); // s - 2
        assert_eq!(p.mul(&q), Poly::from_descending(&[1.0, 0.0, -4.0]));
        assert_eq!(p.add(&q), Poly::from_descending(&[2.0, 0.0]));
        assert_eq!(p.mul(&q).degree(), 2);
    }
}
