//! The quanta of an encoder measurement and the thesis' speeds and error
//! formulas derived from them.

use crate::error::positive;
use crate::Error;

/// Position increment, timer tick and control sampling time.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EncoderResolution {
    /// Position per increment `Delta xi_min`, in `u` (m or rad).
    pub increment: f64,
    /// Timer tick `Delta t_min`, s.
    pub tick_s: f64,
    /// Control sampling time `T_s`, s.
    pub ts_s: f64,
}

impl EncoderResolution {
    /// Checked constructor: all three finite and positive, `tick_s < ts_s`.
    pub fn new(increment: f64, tick_s: f64, ts_s: f64) -> Result<Self, Error> {
        positive("increment", increment)?;
        positive("tick_s", tick_s)?;
        positive("ts_s", ts_s)?;
        if tick_s >= ts_s {
            return Err(Error::InvalidParameter {
                name: "tick_s",
                reason: "the timer tick must be shorter than the sampling time",
            });
        }
        Ok(EncoderResolution {
            increment,
            tick_s,
            ts_s,
        })
    }

    /// The thesis' test rig: 2.5 um linear encoder, 10 ns timer, `T_s = 100 us`.
    pub fn thesis() -> Self {
        EncoderResolution {
            increment: 2.5e-6,
            tick_s: 10e-9,
            ts_s: 100e-6,
        }
    }

    /// Timer ticks per control sample, `T_s / Delta t_min`, rounded.
    pub fn ticks_per_sample(&self) -> u64 {
        libm::round(self.ts_s / self.tick_s) as u64
    }

    /// Resolution of a differentiator (6.3) and smallest speed of the event
    /// counter (6.5): `Delta xi_min / T_s`, u/s.
    pub fn differentiator_min_speed(&self) -> f64 {
        self.increment / self.ts_s
    }

    /// Largest speed of the event counter (6.6) and of the gate measurement
    /// (6.15): `Delta xi_min / Delta t_min`, u/s (250 m/s for 2.5 um / 10 ns).
    pub fn max_speed(&self) -> f64 {
        self.increment / self.tick_s
    }

    /// Smallest speed of the gate measurement with timeout (6.18):
    /// `Delta xi_min / T_out`, u/s.
    pub fn gate_min_speed(&self, t_out_s: f64) -> f64 {
        self.increment / t_out_s
    }

    /// Switching speed (6.19) `2 Delta xi_min / (T_s - Delta t_min)`, u/s,
    /// where the worst-case errors (6.12) and (6.16) intersect.
    pub fn switching_speed(&self) -> f64 {
        2.0 * self.increment / (self.ts_s - self.tick_s)
    }

    /// Relative error bound of the event counter (6.11), in percent, at speed
    /// `speed` (u/s, sign ignored): `100 |v| / (floor(|v| T_s / Delta xi_min) v_max)`.
    /// Infinite below (6.5), where `n_inc < 2`.
    pub fn event_counter_error_percent(&self, speed: f64) -> f64 {
        let v = speed.abs();
        let m = libm::floor(v * self.ts_s / self.increment);
        100.0 * v / (m * self.max_speed())
    }

    /// Envelope (6.12) of (6.11), in percent:
    /// `100 |v| / ((|v| T_s / Delta xi_min - 1) v_max)`.
    pub fn event_counter_error_envelope_percent(&self, speed: f64) -> f64 {
        let v = speed.abs();
        100.0 * v / ((v * self.ts_s / self.increment - 1.0) * self.max_speed())
    }

    /// Exact bound (C.5) of the event counter for a measurement over
    /// `n_inc >= 2` increments, in percent: a time error of less than one tick
    /// on `T_n,inc = (n_inc - 1) Delta xi_min / |v|` gives at most
    /// `100 Delta t_min |v| / ((n_inc - 1) Delta xi_min - Delta t_min |v|)`.
    pub fn event_counter_error_exact_percent(&self, speed: f64, n_inc: u32) -> f64 {
        let v = speed.abs();
        let dxi = f64::from(n_inc.saturating_sub(1)) * self.increment;
        100.0 * self.tick_s * v / (dxi - self.tick_s * v)
    }

    /// Relative error bound of the gate measurement (6.16), in percent, at
    /// speed `speed` (u/s, sign ignored), the larger of its two branches:
    /// `100 |v| / (v_max - |v|)` (the time measured one tick short).
    pub fn gate_error_percent(&self, speed: f64) -> f64 {
        let v = speed.abs();
        100.0 * v / (self.max_speed() - v)
    }

    /// The other branch of (6.16), `100 |v| / (v_max + |v|)` (time measured
    /// one tick long); the one the switching speed (6.19) is derived from.
    pub fn gate_error_lower_branch_percent(&self, speed: f64) -> f64 {
        let v = speed.abs();
        100.0 * v / (self.max_speed() + v)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Relative tolerance for closed-form evaluations (a handful of flops).
    const REL: f64 = 1e-12;

    #[test]
    fn gate_maximum_speed_is_250_m_per_s_for_the_thesis_rig() {
        // (6.15): 2.5 um / 10 ns = 250 m/s
        let r = EncoderResolution::new(2.5e-6, 10e-9, 100e-6).unwrap();
        assert!((r.max_speed() - 250.0).abs() < 250.0 * REL);
        assert_eq!(r, EncoderResolution::thesis());
        assert_eq!(r.ticks_per_sample(), 10_000);
        // (6.3)/(6.5): 2.5 um / 100 us = 25 mm/s
        assert!((r.differentiator_min_speed() - 0.025).abs() < 0.025 * REL);
    }

    /// (6.19) is where the envelope (6.12) meets the `+` branch of (6.16):
    /// solving `v/((v T_s/dxi - 1) V) = v/(V + v)` gives `v = 2 dxi/(T_s - dt)`.
    #[test]
    fn switching_speed_is_the_intersection_of_the_error_envelopes() {
        for r in [
            EncoderResolution::thesis(),
            EncoderResolution::new(2.0 * core::f64::consts::PI / 4096.0, 1e-7, 1.25e-4).unwrap(),
        ] {
            let v = r.switching_speed();
            let h = r.event_counter_error_envelope_percent(v);
            let l = r.gate_error_lower_branch_percent(v);
            assert!((h - l).abs() < h * 1e-9, "{h} {l}");
            // below it the gate is better, above it the event counter
            for f in [0.6, 0.9, 0.99] {
                assert!(
                    r.event_counter_error_envelope_percent(f * v)
                        > r.gate_error_lower_branch_percent(f * v)
                );
            }
            for f in [1.01, 1.1, 2.0, 10.0] {
                assert!(
                    r.event_counter_error_envelope_percent(f * v)
                        < r.gate_error_lower_branch_percent(f * v)
                );
            }
        }
        let v = EncoderResolution::thesis().switching_speed();
        assert!((v - 2.0 * 2.5e-6 / (100e-6 - 10e-9)).abs() < v * REL);
        assert!((v - 0.050005).abs() < 1e-6);
    }

    #[test]
    fn invalid_resolutions_are_errors() {
        assert!(EncoderResolution::new(0.0, 1e-8, 1e-4).is_err());
        assert!(EncoderResolution::new(1e-6, f64::NAN, 1e-4).is_err());
        assert!(EncoderResolution::new(1e-6, 1e-4, 1e-4).is_err());
        assert!(EncoderResolution::new(1e-6, 1e-8, -1e-4).is_err());
    }
}
