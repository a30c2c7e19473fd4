//! The high-pass differentiator (6.1) `G_R(s) = s / (T_R s + 1)`.

use super::EncoderResolution;
use crate::filter::velocity_filter;
use crate::{Error, Real};

/// Velocity by the velocity filter (6.1) `G_R = s/(T_R s + 1)`, discretized by
/// Tustin ([`velocity_filter`]).
///
/// The Tustin section of `G_R` has `b1 = -b0`, so it is evaluated on the
/// position *difference* of the sample (`net_counts`) instead of the absolute
/// position: `v(k) = b0 Delta xi_min n(k) - a1 v(k-1)`. This is the same
/// filter, but exact in `f32` however large the position grows.
/// Its resolution is `Delta xi_min / T_s` (6.3) per count, filtered.
///
/// Cost per sample: 2 multiplications, 1 addition, 1 integer-to-float conversion.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HighPassDifferentiator<T = f64> {
    /// `b0 * Delta xi_min`, u/s per count.
    gain: T,
    a1: T,
    velocity: T,
}

impl<T: Real> HighPassDifferentiator<T> {
    /// Differentiator with time constant `t_r_s` (`T_R > 0`, s) for the
    /// encoder `resolution` (only `increment` and `ts_s` are used).
    pub fn new(resolution: &EncoderResolution, t_r_s: f64) -> Result<Self, Error> {
        let r = EncoderResolution::new(resolution.increment, resolution.tick_s, resolution.ts_s)?;
        let c = velocity_filter(t_r_s, r.ts_s)?;
        Ok(HighPassDifferentiator {
            gain: T::from_f64(c.b0 * r.increment),
            a1: T::from_f64(c.a1),
            velocity: T::ZERO,
        })
    }

    /// One sample: `net_counts` increments since the last call; returns the
    /// velocity estimate in u/s.
    #[inline]
    pub fn update(&mut self, net_counts: i32) -> T {
        self.velocity = self.gain * T::from_f64(f64::from(net_counts)) - self.a1 * self.velocity;
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
    use crate::filter::FirstOrder;

    const T_R: f64 = 2e-3; // Table A.4

    /// The difference form equals the textbook filter on absolute position.
    #[test]
    fn difference_form_equals_the_velocity_filter_on_position() {
        let r = EncoderResolution::thesis();
        let mut d = HighPassDifferentiator::<f64>::new(&r, T_R).unwrap();
        let mut f = FirstOrder::new(velocity_filter(T_R, r.ts_s).unwrap());
        let mut pos = 0i64;
        for k in 0..3000i64 {
            let n = ((k * 7919) % 13 - 5) as i32; // deterministic jumble
            pos += i64::from(n);
            let a = d.update(n);
            let b = f.step(pos as f64 * r.increment);
            assert!((a - b).abs() < 1e-9 * (1.0 + b.abs()), "{k}: {a} {b}");
        }
    }

    /// A constant count rate `c` per sample is the speed `c Delta xi_min / T_s`
    /// exactly once the transient (time constant T_R = 20 samples) has decayed.
    #[test]
    fn constant_count_rate_gives_the_exact_speed() {
        let r = EncoderResolution::thesis();
        for c in [-40i32, -1, 1, 3, 200] {
            let mut d = HighPassDifferentiator::<f64>::new(&r, T_R).unwrap();
            let mut df = HighPassDifferentiator::<f32>::new(&r, T_R).unwrap();
            let (mut v, mut vf) = (0.0, 0.0f32);
            for _ in 0..2000 {
                v = d.update(c);
                vf = df.update(c);
            }
            let expect = f64::from(c) * r.differentiator_min_speed();
            assert!((v - expect).abs() < 1e-12 * expect.abs().max(1.0), "{v}");
            assert!((f64::from(vf) - expect).abs() < 1e-5 * expect.abs(), "{vf}");
        }
    }

    #[test]
    fn invalid_time_constant_is_an_error() {
        let r = EncoderResolution::thesis();
        assert!(HighPassDifferentiator::<f64>::new(&r, 0.0).is_err());
        assert!(HighPassDifferentiator::<f64>::new(&r, f64::NAN).is_err());
    }
}
