//! The PRBS (3.1)-(3.6): a maximal-length Fibonacci LFSR held for `P_PRBS`
//! samples per value, scaled as `A_PRBS (s - 1/2)`.

use crate::error::positive;
use crate::{Error, Real};

/// Smallest supported order `n_PRBS`.
pub const MIN_ORDER: u32 = 2;
/// Largest supported order `n_PRBS`.
pub const MAX_ORDER: u32 = 32;

/// Feedback taps of a maximal-length LFSR for every order `n = 2..=32`
/// (`TAPS[n - 2]`), as 1-based delays: the recursion (3.2) is
/// `s(k) = s(k - t_1) xor s(k - t_2) xor ...`, i.e. `a_{t,PRBS} = 1` exactly
/// for the listed `t`.
///
/// Source: Xilinx application note XAPP052 (P. Alfke, "Efficient Shift
/// Registers, LFSR Counters, and Long Pseudo-Random Sequence Generators",
/// 1996), Table 3, for `n = 3..=32`; `n = 2` is the only primitive trinomial
/// `x^2 + x + 1`. Each entry is checked in the tests two ways: by running a
/// full period (`n <= 20`) and by proving its characteristic polynomial
/// primitive over GF(2) (all `n`).
pub const TAPS: [&[u8]; 31] = [
    &[2, 1],
    &[3, 2],
    &[4, 3],
    &[5, 3],
    &[6, 5],
    &[7, 6],
    &[8, 6, 5, 4],
    &[9, 5],
    &[10, 7],
    &[11, 9],
    &[12, 6, 4, 1],
    &[13, 4, 3, 1],
    &[14, 5, 3, 1],
    &[15, 14],
    &[16, 15, 13, 4],
    &[17, 14],
    &[18, 11],
    &[19, 6, 2, 1],
    &[20, 17],
    &[21, 19],
    &[22, 21],
    &[23, 18],
    &[24, 23, 22, 17],
    &[25, 22],
    &[26, 6, 2, 1],
    &[27, 5, 2, 1],
    &[28, 25],
    &[29, 27],
    &[30, 6, 4, 1],
    &[31, 28],
    &[32, 22, 2, 1],
];

/// Pseudorandom binary signal `PRBS^n_P` (3.2)-(3.4).
///
/// Each bit `s(k)` of the maximal-length sequence (period `M = 2^n - 1`, (3.1))
/// is held for `P_PRBS` samples and output as `A_PRBS (s(k) - 1/2)`, i.e. the
/// signal takes the values `+A/2` and `-A/2` (docs/thesis-map.md: `A = 0.3 N m`
/// gives `+-0.15 N m`). One period has `2^(n-1)` values `+A/2` and
/// `2^(n-1) - 1` values `-A/2`, so its mean is `A / (2 M)`, not zero (thesis,
/// below (3.4)).
///
/// Start state: the initial values `s(-1) ... s(-n)` are all 1 unless another
/// non-zero state is given ([`Prbs::with_state`]), so the signal is
/// deterministic and repeatable.
///
/// Cost per sample: one comparison and one multiply-add while a value is held;
/// once every `P_PRBS` samples additionally one AND, one popcount and one shift.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Prbs<T = f64> {
    order: u32,
    tap_mask: u64,
    full_mask: u64,
    initial_state: u64,
    state: u64,
    clock_period: u32,
    hold_left: u32,
    bit: bool,
    amplitude: T,
}

impl<T: Real> Prbs<T> {
    /// A PRBS of order `order` (`n_PRBS`, 2..=32), clock period `clock_period`
    /// (`P_PRBS >= 1`, samples per value) and peak-to-peak amplitude
    /// `amplitude` (`A_PRBS > 0`, in the unit of the excited quantity, e.g.
    /// N m), starting from the all-ones state.
    pub fn new(order: u32, clock_period: u32, amplitude: T) -> Result<Self, Error> {
        Self::with_state(order, clock_period, amplitude, u32::MAX)
    }

    /// As [`Prbs::new`] but with the start state `s(-i) = bit (i-1) of state`,
    /// `i = 1..=n`; bits above `n` are ignored, the remaining `n` bits must
    /// not all be zero (the LFSR would stay at zero).
    pub fn with_state(
        order: u32,
        clock_period: u32,
        amplitude: T,
        state: u32,
    ) -> Result<Self, Error> {
        if !(MIN_ORDER..=MAX_ORDER).contains(&order) {
            return Err(Error::InvalidParameter {
                name: "order",
                reason: "PRBS order must lie in 2..=32",
            });
        }
        if clock_period == 0 {
            return Err(Error::InvalidParameter {
                name: "clock_period",
                reason: "PRBS clock period must be at least 1 sample",
            });
        }
        positive("amplitude", amplitude.to_f64())?;
        let full_mask = (1u64 << order) - 1;
        let initial_state = u64::from(state) & full_mask;
        if initial_state == 0 {
            return Err(Error::InvalidParameter {
                name: "state",
                reason: "the lowest `order` bits of the PRBS start state must not all be zero",
            });
        }
        let tap_mask = TAPS[(order - MIN_ORDER) as usize]
            .iter()
            .fold(0u64, |m, &t| m | (1u64 << (t - 1)));
        Ok(Prbs {
            order,
            tap_mask,
            full_mask,
            initial_state,
            state: initial_state,
            clock_period,
            hold_left: 0,
            bit: false,
            amplitude,
        })
    }

    /// Order `n_PRBS`.
    pub fn order(&self) -> u32 {
        self.order
    }

    /// Clock period `P_PRBS` in samples.
    pub fn clock_period(&self) -> u32 {
        self.clock_period
    }

    /// Amplitude `A_PRBS` (peak to peak).
    pub fn amplitude(&self) -> T {
        self.amplitude
    }

    /// Number of distinct values per period, `M = 2^n - 1` (3.1).
    pub fn sequence_length(&self) -> u64 {
        self.full_mask
    }

    /// Period of the output in samples, `M * P_PRBS`.
    pub fn period_samples(&self) -> u64 {
        self.full_mask * u64::from(self.clock_period)
    }

    /// First zero of the spectrum (3.5), `f_PRBS,max = 1 / (P_PRBS T_s)`, in Hz,
    /// for the sampling time `ts_s` in s.
    pub fn f_max_hz(&self, ts_s: f64) -> f64 {
        1.0 / (f64::from(self.clock_period) * ts_s)
    }

    /// Lowest frequency (3.6), `f_PRBS,min = 1 / ((2^n - 1) P_PRBS T_s)`, in Hz,
    /// for the sampling time `ts_s` in s: the frequency resolution of one period.
    pub fn f_min_hz(&self, ts_s: f64) -> f64 {
        1.0 / (self.period_samples() as f64 * ts_s)
    }

    /// Duration of one period in s for the sampling time `ts_s` in s.
    pub fn period_s(&self, ts_s: f64) -> f64 {
        self.period_samples() as f64 * ts_s
    }

    /// Next bit `s(k)` of (3.2) (advances the register).
    #[inline]
    fn next_bit(&mut self) -> bool {
        let b = (self.state & self.tap_mask).count_ones() & 1;
        self.state = ((self.state << 1) | u64::from(b)) & self.full_mask;
        b == 1
    }

    /// The next output sample `A_PRBS (s(k) - 1/2)` (3.4). Never fails.
    #[inline]
    pub fn step(&mut self) -> T {
        if self.hold_left == 0 {
            self.bit = self.next_bit();
            self.hold_left = self.clock_period;
        }
        self.hold_left -= 1;
        self.value()
    }

    /// The value of the most recent sample (`-A/2` before the first `step()`).
    #[inline]
    pub fn value(&self) -> T {
        let half = T::from_f64(0.5) * self.amplitude;
        if self.bit {
            half
        } else {
            -half
        }
    }

    /// The bit `s(k)` of the most recent sample.
    pub fn bit(&self) -> bool {
        self.bit
    }

    /// Fill `out` with the next `out.len()` samples.
    pub fn fill(&mut self, out: &mut [T]) {
        for y in out.iter_mut() {
            *y = self.step();
        }
    }

    /// Restart at sample 0 with the start state.
    pub fn reset(&mut self) {
        self.state = self.initial_state;
        self.hold_left = 0;
        self.bit = false;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Floating-point tolerance for sums of a few thousand products of
    /// `+-0.15`: many orders of magnitude above the rounding error (~1e-15),
    /// far below the smallest correlation value tested (0.0225).
    const SUM_TOL: f64 = 1e-9;

    /// `a * b mod p` over GF(2), polynomials as bit masks, `deg p = n <= 32`.
    fn mulmod(a: u64, b: u64, p: u64, n: u32) -> u64 {
        let mut r = 0u64;
        let mut a = a;
        let mut b = b;
        while b != 0 {
            if b & 1 == 1 {
                r ^= a;
            }
            b >>= 1;
            a <<= 1;
            if a >> n & 1 == 1 {
                a ^= p;
            }
        }
        r
    }

    fn powmod_x(e: u64, p: u64, n: u32) -> u64 {
        let mut result = 1u64;
        let mut base = 2u64; // x
        let mut e = e;
        while e > 0 {
            if e & 1 == 1 {
                result = mulmod(result, base, p, n);
            }
            base = mulmod(base, base, p, n);
            e >>= 1;
        }
        result
    }

    fn prime_factors(mut m: u64) -> ([u64; 16], usize) {
        let mut f = [0u64; 16];
        let mut k = 0;
        let mut d = 2u64;
        while d * d <= m {
            if m % d == 0 {
                f[k] = d;
                k += 1;
                while m % d == 0 {
                    m /= d;
                }
            }
            d += 1;
        }
        if m > 1 {
            f[k] = m;
            k += 1;
        }
        (f, k)
    }

    /// Independent check of the tap table: the characteristic polynomial
    /// `x^n + sum_t x^(n-t)` of (3.2) is primitive over GF(2) iff the order of
    /// `x` modulo it is exactly `2^n - 1`.
    #[test]
    fn every_tap_set_has_a_primitive_characteristic_polynomial() {
        for n in MIN_ORDER..=MAX_ORDER {
            let mut p = 1u64 << n;
            for &t in TAPS[(n - 2) as usize] {
                p |= 1u64 << (n - u32::from(t));
            }
            assert_eq!(
                TAPS[(n - 2) as usize][0] as u32,
                n,
                "first tap is the order"
            );
            let m = (1u64 << n) - 1;
            assert_eq!(powmod_x(m, p, n), 1, "order {n}: x^M != 1");
            let (f, k) = prime_factors(m);
            for &q in &f[..k] {
                assert_ne!(powmod_x(m / q, p, n), 1, "order {n}: x^(M/{q}) == 1");
            }
        }
    }

    /// Maximal length by running a full period of the register: the state
    /// returns to the start after exactly `M = 2^n - 1` steps and not before,
    /// and the period has exactly one more 1 than 0s.
    #[test]
    fn full_period_is_maximal_and_ones_exceed_zeros_by_one() {
        for n in MIN_ORDER..=20 {
            let mut g = Prbs::<f64>::new(n, 1, 1.0).unwrap();
            let m = g.sequence_length();
            assert_eq!(m, (1u64 << n) - 1);
            let start = g.state;
            let mut ones = 0u64;
            for k in 1..=m {
                if g.next_bit() {
                    ones += 1;
                }
                if k < m {
                    assert_ne!(g.state, start, "order {n}: period {k} < M");
                }
            }
            assert_eq!(g.state, start, "order {n}: not back after M steps");
            let zeros = m - ones;
            assert_eq!(ones, zeros + 1, "order {n}");
        }
    }

    /// Period `M * P_PRBS` samples, each value held `P_PRBS` samples, values
    /// exactly `+-A/2`, and no shorter period.
    #[test]
    fn period_is_m_times_clock_period_with_held_values() {
        for &(n, p) in &[(2u32, 1u32), (5, 3), (7, 4), (9, 2)] {
            let a = 0.3;
            let mut g = Prbs::<f64>::new(n, p, a).unwrap();
            let len = g.period_samples() as usize;
            assert_eq!(len, ((1usize << n) - 1) * p as usize);
            let mut x = [0.0f64; 2 * 1023 * 4];
            g.fill(&mut x[..2 * len]);
            for k in 0..len {
                assert_eq!(x[k], x[k + len]);
                assert!(x[k] == 0.15 || x[k] == -0.15);
                if k % p as usize != 0 {
                    assert_eq!(x[k], x[k - 1], "value changes inside a clock period");
                }
            }
            // no shorter period: every proper divisor shift differs somewhere
            for d in 1..len {
                if len % d == 0 {
                    assert!((0..len).any(|k| x[k] != x[(k + d) % len]), "period {d}");
                }
            }
            // the mean over one period is A/(2M) (thesis below (3.4))
            let mean: f64 = x[..len].iter().sum::<f64>() / len as f64;
            let m = ((1u64 << n) - 1) as f64;
            assert!((mean - a / (2.0 * m)).abs() < SUM_TOL);
        }
    }

    /// The periodic autocorrelation of `+-A/2` values (P = 1) is two-valued:
    /// `M (A/2)^2` at lag 0 and `-(A/2)^2` at every other lag.
    #[test]
    fn periodic_autocorrelation_is_two_valued() {
        for n in 2..=10u32 {
            let a = 0.3;
            let mut g = Prbs::<f64>::new(n, 1, a).unwrap();
            let m = g.sequence_length() as usize;
            let mut x = [0.0f64; 1023];
            g.fill(&mut x[..m]);
            let h2 = 0.25 * a * a;
            for lag in 0..m {
                let r: f64 = (0..m).map(|k| x[k] * x[(k + lag) % m]).sum();
                let expect = if lag == 0 { m as f64 * h2 } else { -h2 };
                assert!((r - expect).abs() < SUM_TOL, "n {n} lag {lag}: {r}");
            }
        }
    }

    /// (3.5)/(3.6) for the thesis' open-loop PRBS^7_128 at T_s = 100 us:
    /// f_max = 1/(128 * 100 us) = 78.125 Hz, f_min = 78.125 Hz / 127.
    #[test]
    fn band_helpers_match_closed_form() {
        let g = Prbs::<f64>::new(7, 128, 0.3).unwrap();
        assert_eq!(g.period_samples(), 127 * 128);
        assert!((g.f_max_hz(1e-4) - 78.125).abs() < 1e-9);
        assert!((g.f_min_hz(1e-4) - 78.125 / 127.0).abs() < 1e-12);
        assert!((g.period_s(1e-4) - 1.6256).abs() < 1e-12);
    }

    #[test]
    fn start_state_is_deterministic_and_reset_restarts() {
        let mut a = Prbs::<f64>::new(11, 2, 1.0).unwrap();
        let mut b = Prbs::<f64>::new(11, 2, 1.0).unwrap();
        let mut first = [0.0; 100];
        a.fill(&mut first);
        for &v in first.iter() {
            assert_eq!(v, b.step());
        }
        a.reset();
        for &v in first.iter() {
            assert_eq!(v, a.step());
        }
        // a different start state is a shifted version of the same sequence
        let mut c = Prbs::<f64>::with_state(11, 2, 1.0, 0x5a5).unwrap();
        let mut other = [0.0; 100];
        c.fill(&mut other);
        assert_ne!(first, other);
    }

    #[test]
    fn f32_matches_f64() {
        let mut a = Prbs::<f64>::new(16, 3, 0.3).unwrap();
        let mut b = Prbs::<f32>::new(16, 3, 0.3).unwrap();
        for _ in 0..10_000 {
            assert_eq!(a.step() as f32, b.step());
        }
    }

    #[test]
    fn invalid_parameters_are_errors() {
        assert!(Prbs::<f64>::new(1, 1, 1.0).is_err());
        assert!(Prbs::<f64>::new(33, 1, 1.0).is_err());
        assert!(Prbs::<f64>::new(7, 0, 1.0).is_err());
        assert!(Prbs::<f64>::new(7, 1, 0.0).is_err());
        assert!(Prbs::<f64>::new(7, 1, f64::NAN).is_err());
        assert!(Prbs::<f64>::new(7, 1, f64::INFINITY).is_err());
        assert!(Prbs::<f64>::with_state(7, 1, 1.0, 0x80).is_err()); // low 7 bits zero
        assert!(Prbs::<f64>::new(32, u32::MAX, 1.0).is_ok());
    }
}
