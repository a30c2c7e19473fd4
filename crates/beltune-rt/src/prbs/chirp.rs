//! A periodic sine sweep (chirp).

use crate::error::positive;
use crate::{Error, Real};

const TWO_PI: f64 = 2.0 * core::f64::consts::PI;

/// How the instantaneous frequency moves from `f_start` to `f_end`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Sweep {
    /// `f(t) = f_start + (f_end - f_start) t / T_p`.
    Linear,
    /// `f(t) = f_start (f_end / f_start)^(t / T_p)` (equal time per decade).
    Logarithmic,
}

/// A periodic chirp `A sin(phi(t))`, `t = (k mod N) T_s`, sweeping the
/// instantaneous frequency from `f_start` to `f_end` over one period of
/// `N` samples (`T_p = N T_s`), then starting over.
///
/// The phase is computed in closed form from `k mod N` (in `f64`, reduced
/// modulo `2 pi` before the sine), so the signal is exactly periodic
/// (bit-identical every `N` samples) and never drifts:
/// linear `phi = 2 pi (f_s t + (f_e - f_s) t^2 / (2 T_p))`, logarithmic
/// `phi = 2 pi f_s T_p (r^(t/T_p) - 1) / ln r`, `r = f_e / f_s`.
/// The signal is continuous across the period boundary when
/// [`cycles_per_period`](Self::cycles_per_period) is an integer.
///
/// Cost per sample: about 8 `f64` operations, one `floor`, one sine in `T`
/// (plus one `exp` for [`Sweep::Logarithmic`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Chirp<T = f64> {
    amplitude: T,
    period_samples: u32,
    k: u32,
    sweep: Sweep,
    f_start_hz: f64,
    f_end_hz: f64,
    ts_s: f64,
    /// linear: `(f_e - f_s) / (2 T_p)`; logarithmic: `ln r / T_p`.
    rate: f64,
}

impl<T: Real> Chirp<T> {
    /// A chirp of peak amplitude `amplitude` (`> 0`) from `f_start_hz` to
    /// `f_end_hz` (both in `(0, 1/(2 T_s))`; either order) over
    /// `period_samples >= 2` samples of `ts_s` s.
    pub fn new(
        sweep: Sweep,
        f_start_hz: f64,
        f_end_hz: f64,
        period_samples: u32,
        ts_s: f64,
        amplitude: T,
    ) -> Result<Self, Error> {
        let ts = positive("ts_s", ts_s)?;
        positive("amplitude", amplitude.to_f64())?;
        let nyquist = 0.5 / ts;
        for (name, f) in [("f_start_hz", f_start_hz), ("f_end_hz", f_end_hz)] {
            positive(name, f)?;
            if f >= nyquist {
                return Err(Error::InvalidParameter {
                    name,
                    reason: "chirp frequency must lie below the Nyquist frequency 1/(2 T_s)",
                });
            }
        }
        if period_samples < 2 {
            return Err(Error::InvalidParameter {
                name: "period_samples",
                reason: "a chirp period needs at least 2 samples",
            });
        }
        let t_p = f64::from(period_samples) * ts;
        let rate = match sweep {
            Sweep::Linear => (f_end_hz - f_start_hz) / (2.0 * t_p),
            Sweep::Logarithmic => libm::log(f_end_hz / f_start_hz) / t_p,
        };
        Ok(Chirp {
            amplitude,
            period_samples,
            k: 0,
            sweep,
            f_start_hz,
            f_end_hz,
            ts_s: ts,
            rate,
        })
    }

    /// Period in samples `N`.
    pub fn period_samples(&self) -> u32 {
        self.period_samples
    }

    /// Number of oscillations in one period, `phi(T_p) / (2 pi)`:
    /// `(f_s + f_e) T_p / 2` (linear), `(f_e - f_s) T_p / ln(f_e/f_s)` (log).
    pub fn cycles_per_period(&self) -> f64 {
        self.phase_rad(f64::from(self.period_samples) * self.ts_s) / TWO_PI
    }

    /// Instantaneous frequency at time `t_s` into the period, Hz.
    pub fn frequency_hz(&self, t_s: f64) -> f64 {
        match self.sweep {
            Sweep::Linear => self.f_start_hz + 2.0 * self.rate * t_s,
            Sweep::Logarithmic => self.f_start_hz * libm::exp(self.rate * t_s),
        }
    }

    fn phase_rad(&self, t: f64) -> f64 {
        match self.sweep {
            Sweep::Linear => TWO_PI * (self.f_start_hz * t + self.rate * t * t),
            Sweep::Logarithmic => {
                if self.rate == 0.0 {
                    TWO_PI * self.f_start_hz * t
                } else {
                    TWO_PI * self.f_start_hz * (libm::exp(self.rate * t) - 1.0) / self.rate
                }
            }
        }
    }

    /// The next sample `A sin(phi((k mod N) T_s))`. Never fails.
    #[inline]
    pub fn step(&mut self) -> T {
        let phi = self.phase_rad(f64::from(self.k) * self.ts_s);
        let reduced = phi - TWO_PI * libm::floor(phi / TWO_PI);
        self.k += 1;
        if self.k >= self.period_samples {
            self.k = 0;
        }
        self.amplitude * T::from_f64(reduced).sin()
    }

    /// Fill `out` with the next `out.len()` samples.
    pub fn fill(&mut self, out: &mut [T]) {
        for y in out.iter_mut() {
            *y = self.step();
        }
    }

    /// Restart at sample 0.
    pub fn reset(&mut self) {
        self.k = 0;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const TS: f64 = 1e-4;

    fn zero_crossings(x: &[f64]) -> usize {
        x.windows(2)
            .filter(|w| (w[0] < 0.0) != (w[1] < 0.0))
            .count()
    }

    #[test]
    fn chirp_is_exactly_periodic() {
        for sweep in [Sweep::Linear, Sweep::Logarithmic] {
            let mut c = Chirp::<f64>::new(sweep, 2.0, 800.0, 7919, TS, 0.2).unwrap();
            let n = c.period_samples() as usize;
            let mut x = [0.0f64; 3 * 7919];
            c.fill(&mut x);
            for k in 0..2 * n {
                assert_eq!(x[k], x[k + n], "{sweep:?} sample {k}");
            }
            assert_eq!(x[0], 0.0);
            assert!(x.iter().all(|v| v.abs() <= 0.2));
        }
    }

    /// The number of zero crossings of one period is twice the number of
    /// oscillations, which has the closed forms `(f_s + f_e) T_p / 2`
    /// (linear) and `(f_e - f_s) T_p / ln(f_e / f_s)` (logarithmic).
    #[test]
    fn oscillation_count_matches_closed_form() {
        let (fs, fe, n) = (1.0, 100.0, 10_000u32); // T_p = 1 s
        let t_p = f64::from(n) * TS;
        let cases = [
            (Sweep::Linear, 0.5 * (fs + fe) * t_p),
            (Sweep::Logarithmic, (fe - fs) * t_p / libm::log(fe / fs)),
            (Sweep::Linear, 0.5 * (fe + fs) * t_p), // downward sweep, same count
        ];
        for (i, &(sweep, cycles)) in cases.iter().enumerate() {
            let (a, b) = if i == 2 { (fe, fs) } else { (fs, fe) };
            let mut c = Chirp::<f64>::new(sweep, a, b, n, TS, 1.0).unwrap();
            assert!((c.cycles_per_period() - cycles).abs() < 1e-9 * cycles);
            let mut x = [0.0f64; 10_000];
            c.fill(&mut x);
            let z = zero_crossings(&x) as f64;
            // one crossing of slack at each end of the period
            assert!(
                (z - 2.0 * cycles).abs() <= 2.0,
                "{sweep:?}: {z} vs {}",
                2.0 * cycles
            );
        }
        // instantaneous frequency at the ends
        let c = Chirp::<f64>::new(Sweep::Logarithmic, fs, fe, n, TS, 1.0).unwrap();
        assert!((c.frequency_hz(0.0) - fs).abs() < 1e-12);
        assert!((c.frequency_hz(t_p) - fe).abs() < 1e-9);
        assert!((c.frequency_hz(0.5 * t_p) - 10.0).abs() < 1e-9); // geometric mean
    }

    #[test]
    fn invalid_parameters_are_errors() {
        let ok = Chirp::<f64>::new(Sweep::Linear, 1.0, 100.0, 1000, TS, 1.0);
        assert!(ok.is_ok());
        assert!(Chirp::<f64>::new(Sweep::Linear, 0.0, 100.0, 1000, TS, 1.0).is_err());
        assert!(Chirp::<f64>::new(Sweep::Linear, 1.0, 5000.0, 1000, TS, 1.0).is_err());
        assert!(Chirp::<f64>::new(Sweep::Logarithmic, 1.0, f64::NAN, 1000, TS, 1.0).is_err());
        assert!(Chirp::<f64>::new(Sweep::Linear, 1.0, 100.0, 1, TS, 1.0).is_err());
        assert!(Chirp::<f64>::new(Sweep::Linear, 1.0, 100.0, 1000, 0.0, 1.0).is_err());
        assert!(Chirp::<f64>::new(Sweep::Linear, 1.0, 100.0, 1000, TS, -1.0).is_err());
        // f_start == f_end: a pure sine, also for the logarithmic sweep
        let mut c = Chirp::<f32>::new(Sweep::Logarithmic, 50.0, 50.0, 200, TS, 1.0).unwrap();
        assert!((c.cycles_per_period() - 1.0).abs() < 1e-12);
        assert!(c.step().abs() < 1e-6);
    }
}
