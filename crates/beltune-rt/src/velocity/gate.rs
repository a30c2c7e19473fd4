//! The gate measurement (6.14) with timeout (6.17)-(6.18).

use super::EncoderResolution;
use crate::encoder::EdgeWindow;
use crate::error::positive;
use crate::{Error, Real};

/// Gate measurement (6.14): `v_l = Delta xi_min / T_inc` with `T_inc` the time
/// between the two most recent increments (of the same direction), however
/// many samples ago they were.
///
/// Timeout (6.17)-(6.18): with `tau` the time from the last increment to the
/// current sample, if `tau > T_s` and `tau > T_inc` the speed is at most
/// `Delta xi_min / tau` (6.17), which is then the estimate; once
/// `tau >= T_out` (or `T_inc >= T_out`) the estimate is 0, so the smallest
/// non-zero speed is `Delta xi_min / T_out` (6.18).
///
/// Before two increments in the same direction have been seen (start, or the
/// first increment after a reversal) the estimate is 0.
///
/// Error: within (6.16), see [`EncoderResolution::gate_error_percent`].
///
/// Cost per sample: 1 division, 1 multiplication, 1 integer-to-float
/// conversion, a few integer comparisons.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GateMeasurement<T = f64> {
    increment: T,
    tick_s: T,
    ticks_per_sample: u64,
    timeout_ticks: u64,
    velocity: T,
}

impl<T: Real> GateMeasurement<T> {
    /// Gate measurement for the encoder `resolution` with timeout `t_out_s`
    /// (`T_out > T_s`, s).
    pub fn new(resolution: &EncoderResolution, t_out_s: f64) -> Result<Self, Error> {
        let r = EncoderResolution::new(resolution.increment, resolution.tick_s, resolution.ts_s)?;
        let t_out = positive("t_out_s", t_out_s)?;
        if t_out <= r.ts_s || t_out / r.tick_s >= 1.8e19 {
            return Err(Error::InvalidParameter {
                name: "t_out_s",
                reason: "the timeout must exceed the sampling time (and fit in 64-bit ticks)",
            });
        }
        Ok(GateMeasurement {
            increment: T::from_f64(r.increment),
            tick_s: T::from_f64(r.tick_s),
            ticks_per_sample: r.ticks_per_sample(),
            timeout_ticks: libm::ceil(t_out / r.tick_s) as u64,
            velocity: T::ZERO,
        })
    }

    /// One sample ending at time stamp `now_ticks` (same timer as the edges);
    /// returns the velocity estimate in u/s.
    #[inline]
    pub fn update(&mut self, window: &EdgeWindow, now_ticks: u64) -> T {
        self.velocity = match (window.last_increment, window.gate_interval_ticks) {
            (Some(last), Some(t_inc)) => {
                let tau = now_ticks.saturating_sub(last.ticks);
                if tau >= self.timeout_ticks || t_inc >= self.timeout_ticks {
                    T::ZERO
                } else {
                    let ticks = if tau > self.ticks_per_sample && tau > t_inc {
                        tau // (6.17)
                    } else {
                        t_inc.max(1) // (6.14)
                    };
                    let v = self.increment / (T::from_f64(ticks as f64) * self.tick_s);
                    if last.direction.sign() > 0 {
                        v
                    } else {
                        -v
                    }
                }
            }
            _ => T::ZERO,
        };
        self.velocity
    }

    /// The most recent estimate, u/s.
    pub fn velocity(&self) -> T {
        self.velocity
    }

    /// Restart at zero velocity.
    pub fn reset(&mut self) {
        self.velocity = T::ZERO;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::velocity::stream::ConstantSpeedStream;
    use rand::{Rng, SeedableRng};
    use rand_xoshiro::Xoshiro256PlusPlus;

    /// Floating-point slack on a percentage bound (bounds are >= 1e-5 % here).
    const FP_SLACK: f64 = 1e-9;
    const T_OUT: f64 = 20e-3;

    /// Constant speeds from 1.5x the timeout speed (6.18) to 20 m/s, both signs:
    /// every estimate after the second increment is within (6.16).
    #[test]
    fn error_stays_within_6_16_over_a_speed_sweep() {
        let r = EncoderResolution::thesis();
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(616);
        let lo = 1.5 * r.gate_min_speed(T_OUT);
        let mut worst_ratio = 0.0f64;
        for i in 0..60 {
            let mag = lo * libm::pow(20.0 / lo, i as f64 / 59.0);
            for sign in [1.0, -1.0] {
                let v = sign * mag;
                let mut s =
                    ConstantSpeedStream::new(&r, v, rng.random_range(0.0..10_000.0), f64::INFINITY);
                let mut g = GateMeasurement::<f64>::new(&r, T_OUT).unwrap();
                let samples_per_edge = r.increment / mag / r.ts_s;
                let n = 300 + (6.0 * samples_per_edge) as usize;
                let bound = r.gate_error_percent(v);
                let mut measured = 0;
                for _ in 0..n {
                    let (w, now) = s.next_sample();
                    let est = g.update(&w, now);
                    if w.gate_interval_ticks.is_none() {
                        assert_eq!(est, 0.0);
                        continue;
                    }
                    measured += 1;
                    let err = 100.0 * (est - v).abs() / mag;
                    assert!(err <= bound + FP_SLACK, "v {v}: {err} > {bound}");
                    worst_ratio = worst_ratio.max(err / bound);
                    assert_eq!(est.signum(), sign);
                }
                assert!(measured > 100);
            }
        }
        assert!(worst_ratio > 0.5, "{worst_ratio}");
    }

    /// Figure 6.7: speed `Delta xi_min / T_s` drops to zero; with T_out = 5 T_s the
    /// estimate follows `Delta xi_min / tau` (6.17) and is exactly 0 from the
    /// first sample with `tau >= T_out` on (6.18).
    #[test]
    fn timeout_drives_the_estimate_to_zero() {
        let r = EncoderResolution::thesis();
        let t_out = 5.0 * r.ts_s;
        let v0 = r.differentiator_min_speed();
        // edges at 0.5 T_s, 1.5 T_s, ..., the last one before 10 T_s
        let stop = 10.0 * 10_000.0;
        let mut s = ConstantSpeedStream::new(&r, v0, 5_000.0, stop);
        let mut g = GateMeasurement::<f64>::new(&r, t_out).unwrap();
        let mut last_edge = 0u64;
        let mut prev = f64::INFINITY;
        let mut zero_from = None;
        for k in 1..=30u64 {
            let (w, now) = s.next_sample();
            let est = g.update(&w, now);
            if let Some(inc) = w.last_increment {
                last_edge = inc.ticks;
            }
            if k <= 10 {
                if k >= 3 {
                    assert!((est - v0).abs() < 1e-12 * v0, "{k}: {est}");
                }
                continue;
            }
            let tau_s = (now - last_edge) as f64 * r.tick_s;
            if tau_s >= t_out {
                assert_eq!(est, 0.0, "sample {k}, tau {tau_s}");
                zero_from.get_or_insert(k);
            } else {
                assert!(tau_s > r.ts_s);
                let expect = r.increment / tau_s; // (6.17)
                assert!((est - expect).abs() < 1e-12 * expect, "{k}: {est} {expect}");
                assert!(est < prev && est >= r.gate_min_speed(t_out));
                prev = est;
            }
        }
        // last edge at 9.5 T_s: tau >= 5 T_s first at sample 15
        assert_eq!(zero_from, Some(15));
    }

    #[test]
    fn invalid_timeout_is_an_error() {
        let r = EncoderResolution::thesis();
        assert!(GateMeasurement::<f64>::new(&r, r.ts_s).is_err());
        assert!(GateMeasurement::<f64>::new(&r, f64::NAN).is_err());
        assert!(GateMeasurement::<f64>::new(&r, 1e30).is_err());
    }
}
