//! A periodic multisine with Schroeder phases.

use crate::error::positive;
use crate::{Error, Real};

/// Sum of `N` sines at harmonics `h_i` of a period of `P` samples,
/// `x(k) = A sum_i sin(2 pi h_i k / P + phi_i)`, with Schroeder's phases
/// `phi_i = -pi i (i - 1) / N` (`i = 1..=N`; M. R. Schroeder, "Synthesis of
/// low-peak-factor signals and binary sequences with low autocorrelation",
/// IEEE Trans. Inf. Theory 16(1), 1970), which keep the crest factor low for
/// a flat amplitude spectrum.
///
/// The phase of each line is taken from the exact integer index
/// `(h_i k) mod P`, so the signal is exactly periodic (bit-identical every
/// `P` samples), has no drift, and its one-period DFT is non-zero only at the
/// chosen lines.
///
/// Cost per sample: `N` times (one integer add/compare, one multiply-add and
/// one sine in `T`), allocation-free.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Multisine<T, const N: usize> {
    amplitude: T,
    period_samples: u32,
    harmonics: [u32; N],
    phases: [T; N],
    /// `(h_i k) mod P` for the next sample.
    index: [u32; N],
    rad_per_index: T,
}

impl<T: Real, const N: usize> Multisine<T, N> {
    /// Lines at `harmonics` (strictly increasing, each `1 <= h < P/2`) of a
    /// period of `period_samples` samples, each with peak amplitude
    /// `amplitude` (`> 0`).
    pub fn new(period_samples: u32, harmonics: [u32; N], amplitude: T) -> Result<Self, Error> {
        positive("amplitude", amplitude.to_f64())?;
        if N == 0 {
            return Err(Error::InvalidParameter {
                name: "harmonics",
                reason: "a multisine needs at least one line",
            });
        }
        if period_samples < 3 {
            return Err(Error::InvalidParameter {
                name: "period_samples",
                reason: "a multisine period needs at least 3 samples",
            });
        }
        let mut prev = 0u32;
        for &h in harmonics.iter() {
            if h <= prev {
                return Err(Error::InvalidParameter {
                    name: "harmonics",
                    reason: "harmonics must be >= 1 and strictly increasing",
                });
            }
            if u64::from(h) * 2 >= u64::from(period_samples) {
                return Err(Error::InvalidParameter {
                    name: "harmonics",
                    reason: "every harmonic must lie below the Nyquist frequency (h < P/2)",
                });
            }
            prev = h;
        }
        let mut phases = [T::ZERO; N];
        for (i, p) in phases.iter_mut().enumerate() {
            let i1 = (i + 1) as f64;
            let phi = -core::f64::consts::PI * i1 * (i1 - 1.0) / N as f64;
            // reduce to (-2 pi, 0] so that f32 keeps full precision
            let two_pi = 2.0 * core::f64::consts::PI;
            *p = T::from_f64(phi - two_pi * libm::ceil(phi / two_pi));
        }
        Ok(Multisine {
            amplitude,
            period_samples,
            harmonics,
            phases,
            index: [0; N],
            rad_per_index: T::from_f64(2.0 * core::f64::consts::PI / f64::from(period_samples)),
        })
    }

    /// Period `P` in samples.
    pub fn period_samples(&self) -> u32 {
        self.period_samples
    }

    /// The harmonics `h_i`.
    pub fn harmonics(&self) -> &[u32; N] {
        &self.harmonics
    }

    /// The Schroeder phases `phi_i`, rad (reduced to `(-2 pi, 0]`).
    pub fn phases_rad(&self) -> &[T; N] {
        &self.phases
    }

    /// Frequency of line `i` in Hz for the sampling time `ts_s` (`None` if `i >= N`).
    pub fn line_hz(&self, i: usize, ts_s: f64) -> Option<f64> {
        self.harmonics
            .get(i)
            .map(|&h| f64::from(h) / (f64::from(self.period_samples) * ts_s))
    }

    /// The next sample. Never fails.
    #[inline]
    pub fn step(&mut self) -> T {
        let mut y = T::ZERO;
        for i in 0..N {
            let m = self.index[i];
            y += (self.rad_per_index * T::from_f64(f64::from(m)) + self.phases[i]).sin();
            // (m + h) mod P without overflow: m < P and h < P/2
            let next = m + self.harmonics[i];
            self.index[i] = if next >= self.period_samples {
                next - self.period_samples
            } else {
                next
            };
        }
        self.amplitude * y
    }

    /// Fill `out` with the next `out.len()` samples.
    pub fn fill(&mut self, out: &mut [T]) {
        for y in out.iter_mut() {
            *y = self.step();
        }
    }

    /// Largest `|x(k)|` over one period, by evaluating it: `O(N P)`, meant for
    /// configuration time (e.g. to scale the amplitude to a torque limit).
    pub fn measure_peak(&self) -> T {
        let mut probe = *self;
        probe.reset();
        let mut peak = T::ZERO;
        for _ in 0..self.period_samples {
            peak = peak.max(probe.step().abs());
        }
        peak
    }

    /// Restart at sample 0.
    pub fn reset(&mut self) {
        self.index = [0; N];
    }
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;
    use std::vec::Vec;

    /// `|X[m]|` of the DFT of `x` at bin `m`, written out (O(P) per bin).
    fn dft_mag(x: &[f64], m: usize) -> f64 {
        let p = x.len() as f64;
        let (mut re, mut im) = (0.0, 0.0);
        for (k, &v) in x.iter().enumerate() {
            let a = -2.0 * core::f64::consts::PI * (m * k % x.len()) as f64 / p;
            re += v * libm::cos(a);
            im += v * libm::sin(a);
        }
        libm::hypot(re, im)
    }

    /// Energy only at the chosen lines: `|X[h_i]| = A P / 2`, every other bin
    /// below `LEAK` of that (rounding of ~1e-16 summed over P = 2000 samples).
    #[test]
    fn spectrum_has_energy_only_at_the_chosen_lines() {
        const LEAK: f64 = 1e-10;
        let p = 2000u32;
        let h = [3u32, 7, 20, 21, 150, 999];
        let a = 0.05;
        let mut m = Multisine::<f64, 6>::new(p, h, a).unwrap();
        let mut x = std::vec![0.0; p as usize];
        m.fill(&mut x);
        let line = a * f64::from(p) / 2.0;
        for bin in 0..=(p as usize / 2) {
            let mag = dft_mag(&x, bin);
            if h.contains(&(bin as u32)) {
                assert!((mag - line).abs() < LEAK * line, "bin {bin}: {mag}");
            } else {
                assert!(mag < LEAK * line, "bin {bin}: {mag}");
            }
        }
    }

    #[test]
    fn multisine_is_exactly_periodic_in_f64_and_f32() {
        let p = 997u32;
        let h: [u32; 5] = [1, 2, 5, 100, 498];
        let mut m = Multisine::<f64, 5>::new(p, h, 1.0).unwrap();
        let mut f = Multisine::<f32, 5>::new(p, h, 1.0).unwrap();
        let x: Vec<f64> = (0..3 * p).map(|_| m.step()).collect();
        let y: Vec<f32> = (0..3 * p).map(|_| f.step()).collect();
        for k in 0..2 * p as usize {
            assert_eq!(x[k], x[k + p as usize]);
            assert_eq!(y[k], y[k + p as usize]);
            assert!((x[k] - f64::from(y[k])).abs() < 1e-5);
        }
    }

    /// Schroeder phases for 16 consecutive harmonics give a much lower crest
    /// factor than zero phases (`sqrt(2 N) = 5.66` for cosines in phase);
    /// Schroeder's 1970 paper reports about 1.7 for a flat spectrum.
    #[test]
    fn schroeder_phases_keep_the_crest_factor_low() {
        let p = 4096u32;
        let h: [u32; 16] = core::array::from_fn(|i| i as u32 + 1);
        let m = Multisine::<f64, 16>::new(p, h, 1.0).unwrap();
        let rms = libm::sqrt(16.0 / 2.0);
        let crest = m.measure_peak() / rms;
        assert!(crest < 2.0, "{crest}");
        assert!(crest > 1.0);
    }

    #[test]
    fn invalid_parameters_are_errors() {
        assert!(Multisine::<f64, 2>::new(100, [1, 49], 1.0).is_ok());
        assert!(Multisine::<f64, 2>::new(100, [1, 50], 1.0).is_err()); // Nyquist
        assert!(Multisine::<f64, 2>::new(100, [0, 3], 1.0).is_err());
        assert!(Multisine::<f64, 2>::new(100, [5, 5], 1.0).is_err());
        assert!(Multisine::<f64, 2>::new(100, [7, 5], 1.0).is_err());
        assert!(Multisine::<f64, 0>::new(100, [], 1.0).is_err());
        assert!(Multisine::<f64, 1>::new(2, [1], 1.0).is_err());
        assert!(Multisine::<f64, 1>::new(100, [1], f64::NAN).is_err());
        let m = Multisine::<f64, 2>::new(1000, [10, 20], 1.0).unwrap();
        assert_eq!(m.line_hz(1, 1e-4), Some(200.0));
        assert_eq!(m.line_hz(2, 1e-4), None);
    }
}
