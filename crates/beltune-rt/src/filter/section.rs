//! Second- and first-order sections: coefficients and per-sample state.

use crate::Real;

/// Coefficients of one second-order section with `a0 = 1`:
/// `H(z) = (b0 + b1 z^-1 + b2 z^-2) / (1 + a1 z^-1 + a2 z^-2)`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SosCoeffs<T = f64> {
    /// Numerator coefficient of `z^0`.
    pub b0: T,
    /// Numerator coefficient of `z^-1`.
    pub b1: T,
    /// Numerator coefficient of `z^-2`.
    pub b2: T,
    /// Denominator coefficient of `z^-1`.
    pub a1: T,
    /// Denominator coefficient of `z^-2`.
    pub a2: T,
}

/// A point of a frequency response, `re + j im`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FreqPoint {
    /// Real part.
    pub re: f64,
    /// Imaginary part.
    pub im: f64,
}

impl FreqPoint {
    /// Magnitude `|H|`.
    pub fn magnitude(self) -> f64 {
        libm::hypot(self.re, self.im)
    }
    /// Phase `arg H` in rad, in `(-pi, pi]`.
    pub fn phase_rad(self) -> f64 {
        libm::atan2(self.im, self.re)
    }
}

/// `(re, im)` of `sum_k c_k z^-k` at `z = e^{j w T_s}`.
fn poly_in_zinv(c: &[f64], w_rad_s: f64, ts_s: f64) -> (f64, f64) {
    let mut re = 0.0;
    let mut im = 0.0;
    for (k, ck) in c.iter().enumerate() {
        let phi = -(k as f64) * w_rad_s * ts_s;
        re += ck * libm::cos(phi);
        im += ck * libm::sin(phi);
    }
    (re, im)
}

fn ratio(num: (f64, f64), den: (f64, f64)) -> FreqPoint {
    let d = den.0 * den.0 + den.1 * den.1;
    FreqPoint {
        re: (num.0 * den.0 + num.1 * den.1) / d,
        im: (num.1 * den.0 - num.0 * den.1) / d,
    }
}

impl<T: Real> SosCoeffs<T> {
    /// The pass-through section `H(z) = 1`.
    pub const IDENTITY: Self = SosCoeffs {
        b0: T::ONE,
        b1: T::ZERO,
        b2: T::ZERO,
        a1: T::ZERO,
        a2: T::ZERO,
    };

    /// The same coefficients in another scalar type (e.g. `f64` -> `f32`).
    pub fn cast<U: Real>(&self) -> SosCoeffs<U> {
        SosCoeffs {
            b0: U::from_f64(self.b0.to_f64()),
            b1: U::from_f64(self.b1.to_f64()),
            b2: U::from_f64(self.b2.to_f64()),
            a1: U::from_f64(self.a1.to_f64()),
            a2: U::from_f64(self.a2.to_f64()),
        }
    }

    /// Frequency response `H(e^{j w T_s})` at `w_rad_s` for sampling time `ts_s`.
    pub fn freq_response(&self, w_rad_s: f64, ts_s: f64) -> FreqPoint {
        let num = [self.b0.to_f64(), self.b1.to_f64(), self.b2.to_f64()];
        let den = [1.0, self.a1.to_f64(), self.a2.to_f64()];
        ratio(
            poly_in_zinv(&num, w_rad_s, ts_s),
            poly_in_zinv(&den, w_rad_s, ts_s),
        )
    }

    /// Static gain `H(1)`.
    pub fn dc_gain(&self) -> T {
        (self.b0 + self.b1 + self.b2) / (T::ONE + self.a1 + self.a2)
    }

    /// `true` if both poles lie strictly inside the unit circle
    /// (Jury: `|a2| < 1` and `|a1| < 1 + a2`).
    pub fn is_stable(&self) -> bool {
        let (a1, a2) = (self.a1.to_f64(), self.a2.to_f64());
        a2.abs() < 1.0 && a1.abs() < 1.0 + a2
    }
}

/// A second-order section with state (transposed direct form II).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sos<T = f64> {
    /// The coefficients; may be replaced at run time (the state is kept).
    pub coeffs: SosCoeffs<T>,
    s1: T,
    s2: T,
}

impl<T: Real> Sos<T> {
    /// A section with zero state.
    pub fn new(coeffs: SosCoeffs<T>) -> Self {
        Sos {
            coeffs,
            s1: T::ZERO,
            s2: T::ZERO,
        }
    }

    /// Filter one sample. Cost: 5 multiplications, 4 additions.
    #[inline]
    pub fn step(&mut self, x: T) -> T {
        let c = &self.coeffs;
        let y = c.b0 * x + self.s1;
        self.s1 = c.b1 * x - c.a1 * y + self.s2;
        self.s2 = c.b2 * x - c.a2 * y;
        y
    }

    /// Zero the state.
    pub fn reset(&mut self) {
        self.s1 = T::ZERO;
        self.s2 = T::ZERO;
    }

    /// Set the state to the steady state for a constant input `x`
    /// (no transient when the filter is switched on at a non-zero input).
    pub fn reset_to(&mut self, x: T) {
        let c = &self.coeffs;
        let y = x * c.dc_gain();
        self.s2 = c.b2 * x - c.a2 * y;
        self.s1 = y - c.b0 * x;
    }
}

/// `N` second-order sections in series (e.g. notch followed by a low-pass).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cascade<T, const N: usize> {
    /// The sections, applied in index order.
    pub sections: [Sos<T>; N],
}

impl<T: Real, const N: usize> Cascade<T, N> {
    /// A cascade with zero state.
    pub fn new(coeffs: [SosCoeffs<T>; N]) -> Self {
        Cascade {
            sections: coeffs.map(Sos::new),
        }
    }

    /// Filter one sample through all sections. Cost: `N` times a [`Sos`].
    #[inline]
    pub fn step(&mut self, x: T) -> T {
        let mut y = x;
        for s in self.sections.iter_mut() {
            y = s.step(y);
        }
        y
    }

    /// Zero all states.
    pub fn reset(&mut self) {
        for s in self.sections.iter_mut() {
            s.reset();
        }
    }

    /// Frequency response of the whole cascade.
    pub fn freq_response(&self, w_rad_s: f64, ts_s: f64) -> FreqPoint {
        let mut acc = FreqPoint { re: 1.0, im: 0.0 };
        for s in self.sections.iter() {
            let h = s.coeffs.freq_response(w_rad_s, ts_s);
            acc = FreqPoint {
                re: acc.re * h.re - acc.im * h.im,
                im: acc.re * h.im + acc.im * h.re,
            };
        }
        acc
    }
}

/// Coefficients of a first-order section with `a0 = 1`:
/// `H(z) = (b0 + b1 z^-1) / (1 + a1 z^-1)`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FirstOrderCoeffs<T = f64> {
    /// Numerator coefficient of `z^0`.
    pub b0: T,
    /// Numerator coefficient of `z^-1`.
    pub b1: T,
    /// Denominator coefficient of `z^-1`.
    pub a1: T,
}

impl<T: Real> FirstOrderCoeffs<T> {
    /// Frequency response `H(e^{j w T_s})`.
    pub fn freq_response(&self, w_rad_s: f64, ts_s: f64) -> FreqPoint {
        let num = [self.b0.to_f64(), self.b1.to_f64()];
        let den = [1.0, self.a1.to_f64()];
        ratio(
            poly_in_zinv(&num, w_rad_s, ts_s),
            poly_in_zinv(&den, w_rad_s, ts_s),
        )
    }

    /// The same coefficients in another scalar type.
    pub fn cast<U: Real>(&self) -> FirstOrderCoeffs<U> {
        FirstOrderCoeffs {
            b0: U::from_f64(self.b0.to_f64()),
            b1: U::from_f64(self.b1.to_f64()),
            a1: U::from_f64(self.a1.to_f64()),
        }
    }
}

/// A first-order section with state (transposed direct form II).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FirstOrder<T = f64> {
    /// The coefficients.
    pub coeffs: FirstOrderCoeffs<T>,
    s1: T,
}

impl<T: Real> FirstOrder<T> {
    /// A section with zero state.
    pub fn new(coeffs: FirstOrderCoeffs<T>) -> Self {
        FirstOrder {
            coeffs,
            s1: T::ZERO,
        }
    }

    /// Filter one sample. Cost: 3 multiplications, 2 additions.
    #[inline]
    pub fn step(&mut self, x: T) -> T {
        let c = &self.coeffs;
        let y = c.b0 * x + self.s1;
        self.s1 = c.b1 * x - c.a1 * y;
        y
    }

    /// Set the state so that the next output for input `x` equals `y`
    /// (for the velocity filter: start at the current position with zero speed,
    /// `x = position`, `y = 0`).
    pub fn reset_to(&mut self, x: T, y: T) {
        // next: y_next = b0 x + s1, with s1 chosen so that y_next = y for the same x.
        self.s1 = y - self.coeffs.b0 * x;
    }

    /// Zero the state.
    pub fn reset(&mut self) {
        self.s1 = T::ZERO;
    }
}
